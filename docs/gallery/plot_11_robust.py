"""
Weights known to a few percent
==============================

G1 with every weight anywhere in ``(1 − ρ)|A| ⪯ |A'| ⪯ (1 + ρ)|A|``, the protocol kept at its
nominal design. For each ρ: a proven lower bound on the decay rate and a proven upper
bound on the consensus offset, each with a realisation that attains the other end. The
margin bracket says up to which ρ stability is proven.
"""

import warnings

import matplotlib.pyplot as plt

import ntc_design as nd
from ntc_design.certify.robust import robust, robust_sweep
from ntc_design.reports.figures import robust_figure

EXAMPLES = nd.example_path()

des = nd.design(nd.load(EXAMPLES / "g1.yaml"), [1, 2, -1], thresholds=False)
with warnings.catch_warnings():
    warnings.simplefilter("ignore")  # the solver's accuracy notes; every end is re-checked
    at5 = robust(des, 0.05, starts=2)
    sweep = robust_sweep(des, [0.0, 0.1, 0.2, 0.35, 0.5, 0.7], starts=2)
print(at5.table().text())
fig = robust_figure(sweep, margin=(at5.margin.lower, at5.margin.upper))

plt.show()  # in a notebook or a script: display the figures
