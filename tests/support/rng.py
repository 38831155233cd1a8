"""A small Monte Carlo run of G1 with options, for the generator tests."""

from ntc_design.simulate import NoiseModel, simulate


def _run(g1, **kw):
    return simulate(
        g1, [1, 2, -1], gain="1/(1+t)", noise=NoiseModel(0.4, 0.3), T=1.0, dt=1e-3,
        paths=400, seed=3, save_every=0.5, method="both", **kw,
    )  # fmt: skip
