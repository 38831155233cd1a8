"""
A switching set
===============

The paper's three networks switched periodically: one design per mode, a certificate that
L_B(k) + L_B(k)ᵀ ≻ 0 in every mode with a common P, and the schedule.
"""

import warnings

import matplotlib.pyplot as plt

import ntc_design as nd
from ntc_design.certify import certify
from ntc_design.reports.figures import schedule_figure

# the bundled examples, wherever the package is installed (no checkout needed)
EXAMPLES = nd.example_path()

sw = nd.load(EXAMPLES / "switching.yaml")
print(sw)
with warnings.catch_warnings():
    warnings.simplefilter("ignore", nd.AssumptionWarning)  # G3: replaced, see the verdict
    res = certify(sw, [1, 2, -1], gain="1/(1+t)")
for t in res.tables():
    print(t.text(), end="\n\n")
fig = schedule_figure(sw.schedule)

plt.show()  # in a notebook or a script: display the figures
