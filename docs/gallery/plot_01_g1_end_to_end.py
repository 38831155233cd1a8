"""
The paper's G1, end to end
==========================

Load the paper's first network, design the protocol (Lemma 1), certify it, and simulate the
noisy network: Monte Carlo beside the exact mean-square curves.
"""

import matplotlib.pyplot as plt
import numpy as np

import ntc_design as nd
from ntc_design.certify import certify
from ntc_design.reports.figures import ms_error_figure
from ntc_design.simulate import NoiseModel, simulate

# the bundled examples, wherever the package is installed (no checkout needed)
EXAMPLES = nd.example_path()

top = nd.load(EXAMPLES / "g1.yaml")
des = nd.design(top, [1, 2, -1], margin=0.1)
print(des)
res = certify(top, [1, 2, -1], gain="1/(1+t)")
print(res)
run = simulate(
    top, [1, 2, -1], gain="1/(1+t)", noise=NoiseModel(0.4, 0.3),
    initial=np.random.default_rng(np.random.SeedSequence(1)).uniform(-3, 3, size=21), T=5, paths=200, seed=0,
)  # fmt: skip
print(run.table())
fig = ms_error_figure(run.save_times, run.mc, run.exact.ms_error, run.labels)

plt.show()  # in a notebook or a script: display the figures
