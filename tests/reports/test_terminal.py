"""Tests of :mod:`ntc_design.reports.terminal`."""


def test_progress_heartbeat_off_a_terminal(capsys):
    import time

    from ntc_design.reports.terminal import Progress

    with Progress("ntc x", every=1.0, tty=False) as p:
        p.stage("g1: simulating")  # not printed at once: quick runs stay quiet
        assert capsys.readouterr().err == ""
        p.tick("g1", 1, 2)
        seen = ""
        for _ in range(300):  # the heartbeat prints the current state (wait up to 30 s)
            seen += capsys.readouterr().err
            if "g1: Monte Carlo 50% done" in seen:
                break
            time.sleep(0.1)
        assert "ntc x: [" in seen and "g1: Monte Carlo 50% done" in seen.rstrip().splitlines()[-1]
        p.stage("g1: report")  # after the first interval: printed at once
        assert capsys.readouterr().err.rstrip().endswith("g1: report")
