"""
A noise sweep with the exact moments
====================================

How the final mean-square error grows with the noise σ, by the exact moment equations
(no Monte Carlo noise). ``ntc sweep`` does the same from a file, here or on a Dask cluster.
"""

import matplotlib.pyplot as plt
import numpy as np

import ntc_design as nd
from ntc_design.reports.style import ONE_COLUMN, paper_style
from ntc_design.simulate import NoiseModel, simulate

# the bundled examples, wherever the package is installed (no checkout needed)
EXAMPLES = nd.example_path()

top = nd.load(EXAMPLES / "g1.yaml")
sigmas = np.array([0.1, 0.2, 0.4, 0.8])
final = []
for s in sigmas:
    run = simulate(
        top, [1, 2, -1], gain="1/(1+t)", noise=NoiseModel(s, 0.3), method="exact",
        initial=np.random.default_rng(np.random.SeedSequence(1)).uniform(-3, 3, size=21), T=10,
    )  # fmt: skip
    final.append(run.exact.ms_error[-1].sum())
    print(f"σ = {s}: E Σ_i ‖x_i(10) − θ‖² = {final[-1]:.4f}")
with paper_style():
    fig, ax = plt.subplots(figsize=(ONE_COLUMN, 2.4), layout="constrained")
    ax.plot(sigmas, final, marker="o")
    ax.set_xlabel(r"noise $\sigma$")
    ax.set_ylabel(r"$E\sum_i\|x_i(T)-\theta\|^2$")

plt.show()  # in a notebook or a script: display the figures
