"""
10,000 agents, certified and simulated
======================================

A random network that satisfies Assumption 2 by construction, certified component by
component (nothing dense), then simulated with the implicit scheme for a few paths.
"""

import matplotlib.pyplot as plt

from ntc_design.certify import certify
from ntc_design.model.generate import random_network
from ntc_design.reports.aggregate import degree_figure
from ntc_design.simulate import simulate

top = random_network(10_000, d=3, seed=0)
res = certify(top, [1, 2, -1], gain="1/(1+t)")
print(res)
print(res.results_table().text())
run = simulate(
    top, [1, 2, -1], gain="1/(1+t)", T=0.5, paths=2, stepping="intrinsic", ds=0.05,
    scheme="implicit", method="mc", save_every=0.25,
)  # fmt: skip
print(run)
fig = degree_figure(top)

plt.show()  # in a notebook or a script: display the figures
