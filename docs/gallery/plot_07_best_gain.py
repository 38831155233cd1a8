"""
The best gain for a deadline
============================

On G1, the gain schedule c(t) on [0, T] that minimises the exact E Σ‖x_i(T) − θ‖², beside
the best power law a·(b + t)^(−γ) and the paper's 1/(1 + t). T is 4 here to keep the
gallery quick; ``ntc tune examples/scenarios/g1_deadline.yaml --horizon 10 --schedule
optimal`` is the full study.
"""

import matplotlib.pyplot as plt
import numpy as np

import ntc_design as nd
from ntc_design.reports.tune import curves_figure, schedule_gains_figure
from ntc_design.simulate import NoiseModel, SimulationSpec
from ntc_design.tune import ScheduleOptions, tune

# the bundled examples, wherever the package is installed (no checkout needed)
EXAMPLES = nd.example_path()
g1 = nd.load(EXAMPLES / "g1.yaml")
spec = SimulationSpec.build([1, 2, -1], noise=NoiseModel(0.4, 0.3), initial=np.linspace(-3, 3, 21))
best = tune(g1, spec, 4.0, ScheduleOptions(check_paths=0, certificate=False))
print(best.table().text())
print(best.refinement_table().text())

# %%
# The three gains (the schedule's tail after T dotted) and their errors over [0, T].
schedule_gains_figure(best)
curves_figure(best)

plt.show()  # in a notebook or a script: display the figures
