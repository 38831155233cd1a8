"""The mode sources of a Monte Carlo block: where a run of steps stops, the check batch,
and a stepper on given kernel arrays against the mode system's own."""

import numpy as np

from ntc_design.simulate.grid import TimeGrid
from ntc_design.simulate.kernels import kernel_arrays
from ntc_design.simulate.modes import BATCH, XI_BYTES, FixedModes, Stepper, run_ends


def test_a_run_of_steps_stops_at_saves_mode_changes_and_the_end():
    t = np.linspace(0.0, 1.0, 11)
    mode = np.array([0, 0, 0, 1, 1, 0, 0, 0, 0, 0])
    grid = TimeGrid(t=t, mode=mode, save_steps=np.array([0, 4, 10]), save_times=t[[0, 4, 10]])
    want = []
    for k in range(11):  # written out: the first cut after k
        j = k + 1
        while j < 10 and j != 4 and mode[j] == mode[j - 1]:
            j += 1
        want.append(min(j, 10))
    assert run_ends(grid).tolist() == want == [3, 3, 3, 4, 5, 10, 10, 10, 10, 10, 10]


def test_the_check_batch_bounds_the_buffer_of_normals(g1_system):
    _, s = g1_system
    modes = FixedModes((s, s))
    e = s.n_edges
    for p in (1, 500, 10_000, 10**6):
        want = max(1, min(BATCH, XI_BYTES // (8 * p * 2 * e)))
        assert modes.batch(p) == want
    assert modes.e_max() == e and modes.kernel_systems() == (s, s) and not modes.callable_f()


def test_a_stepper_on_kernel_arrays_steps_as_the_modes_own(g1_system):
    _, s = g1_system
    rng = np.random.default_rng(5)
    x0 = rng.normal(size=(4, s.nd))
    xi = rng.normal(size=(3, 4, 2 * s.n_edges))
    ch, cs = np.full(3, 0.01), np.full(3, 0.1)
    a, b = x0.copy(), x0.copy()
    Stepper(s, False).advance(a, xi, 0, 3, ch, cs)
    Stepper.of_arrays(kernel_arrays(s)).advance(b, xi, 0, 3, ch, cs)
    assert np.array_equal(a, b) and not np.array_equal(a, x0)
    # the drift alone, written out: x + c h (u − L_B x) with no noise
    c = x0.copy()
    Stepper(s, False).advance(c, np.zeros_like(xi), 0, 1, ch, cs)
    np.testing.assert_allclose(
        c, x0 + 0.01 * (s.u - x0 @ s.lap_b_dense().T), rtol=1e-12, atol=1e-12
    )
