"""
A time-varying topology
=======================

Weights written as expressions of t (periodic). Lemma 1 holds at every instant, and the
certificate proves a uniform lower bound Λ₂ on λ_min(L_B(t) + L_B(t)ᵀ) over a period,
which Theorems 3-4 need (a sampled minimum is not a proof).
"""

import matplotlib.pyplot as plt
import numpy as np

import ntc_design as nd
from ntc_design.certify import certify
from ntc_design.protocol.timevarying import TimeVaryingDesign
from ntc_design.reports.timevarying import lambda_min_figure

# the bundled examples, wherever the package is installed (no checkout needed)
EXAMPLES = nd.example_path()

tv = nd.load(EXAMPLES / "g1_tv.yaml")
res = certify(tv, [1, 2, -1], gain="1/(1+t)")
lam2 = res.certificate["results"]["time_varying"]["lambda2"]
print(f"certified uniform bound Λ₂ = {lam2:.4g}; {res}")
des = TimeVaryingDesign(tv, np.array([1.0, 2.0, -1.0]), 0.1)
fig = lambda_min_figure(des, lam2, res.certificate["intervals"])

plt.show()  # in a notebook or a script: display the figures
