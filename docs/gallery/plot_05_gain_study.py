"""
Which gain satisfies which theorem
==================================

The theorems ask ∫c = ∞ and c → 0 (mean square) and ∫c² < ∞ (almost sure). The analysis is
symbolic, with a bounded time.
"""

import matplotlib.pyplot as plt

from ntc_design.gain.conditions import analyse_gain
from ntc_design.reports.figures import gain_figure

for expr in ["1/(1+t)", "(1+t)^(-1/3)", "(1+t)^(-2)", "1/log(2+t)"]:
    print(analyse_gain(expr))
fig = gain_figure("(1+t)^(-1/3)", 20.0)

plt.show()  # in a notebook or a script: display the figures
