"""Tests of :mod:`ntc_design.reports.terminal`."""


def test_progress_heartbeat_off_a_terminal(capsys, monkeypatch):
    # the progress's clock is the test's: what is printed does not depend on how loaded the
    # machine is (the heartbeat thread only has to wake up within the 30 s waited for it)
    import time
    import types

    from ntc_design.reports import terminal
    from ntc_design.reports.terminal import Progress

    now = [1000.0]
    monkeypatch.setattr(terminal, "time", types.SimpleNamespace(monotonic=lambda: now[0]))
    with Progress("ntc x", every=1.0, tty=False) as p:
        p.stage("g1: simulating")  # not printed at once: quick runs stay quiet
        assert capsys.readouterr().err == ""
        p.tick("g1", 1, 2)
        now[0] += 1.5  # the first interval is over
        seen = ""
        for _ in range(300):  # the heartbeat prints the current state (wait up to 30 s)
            seen += capsys.readouterr().err
            if "g1: Monte Carlo 50% done" in seen:
                break
            time.sleep(0.1)
        assert (
            "ntc x: [2 s] " in seen and "g1: Monte Carlo 50% done" in seen.rstrip().splitlines()[-1]
        )
        p.stage("g1: report")  # after the first interval: printed at once
        assert capsys.readouterr().err.rstrip().endswith("g1: report")
