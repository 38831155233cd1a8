"""
From design to hardware: the agents as C
========================================

``ntc export`` turns a certified design into the code each agent runs: dependency-free
C99 (or one Python module) with the per-agent tables, the gain c(t), the schedule rule
and one function that turns an agent's measured relative states into its next state.
Here the paper's G1, sampled every h = 0.1 with a delay of one sample, is exported,
compiled with ``cc``, and replayed on the same normals as the toolkit's reference
(:func:`ntc_design.simulate.replay.replay`): the trajectories agree to the last bit.
"""

import shutil
import subprocess
import tempfile
import time
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

import ntc_design as nd
from ntc_design.export.run import export, read_state, stdin_text
from ntc_design.export.source import ExportOptions
from ntc_design.simulate.replay import replay

# the bundled examples, wherever the package is installed (no checkout needed)
EXAMPLES = nd.example_path()
folder = Path(tempfile.mkdtemp()) / "g1-c"
res = export(
    EXAMPLES / "scenarios" / "g1_deadline.yaml", "c", folder, ExportOptions(period=0.1, delay=1)
)
law = res.source.law
print("\n".join(res.source.notes))
print("wrote", ", ".join(res.files))
readme = (folder / "README.txt").read_text()
print(next(line for line in readme.splitlines() if "cc -std" in line).strip())

# %%
# Compile with the flags the README gives (no fused multiply-add), and run the program
# once per horizon k = 1 … K on the first k steps' normals: x_k as the C computes it.
# Without a C compiler, the exported Python module (same stdin, same bits) stands in.
cc = shutil.which("cc")
if cc is not None:
    t0 = time.perf_counter()
    subprocess.run(
        [cc, "-std=c99", "-O2", "-ffp-contract=off", "-Wall", "-Wextra", "-o", "ntc_replay",
         "ntc_replay.c", "ntc_protocol.c", "-lm"],
        cwd=folder, check=True,
    )  # fmt: skip
    print(f"compiled in {time.perf_counter() - t0:.2f} s")
    program = [str(folder / "ntc_replay")]
else:
    export(
        EXAMPLES / "scenarios" / "g1_deadline.yaml",
        "python",
        folder,
        ExportOptions(period=0.1, delay=1),
    )
    program = ["python", str(folder / "ntc_protocol.py")]
    print("no C compiler: the Python module replays instead")

steps = 100  # T = 10
x_init = res.source.initial
normals = np.random.default_rng(7).standard_normal(int(law.normals_per_step(steps).sum()))
per_step = np.concatenate([[0], np.cumsum(law.normals_per_step(steps))])
device = [x_init]
for k in range(1, steps + 1):
    run = subprocess.run(
        program,
        input=stdin_text(x_init, k, normals[: per_step[k]]),
        capture_output=True,
        text=True,
        check=True,
    )
    device.append(read_state(run.stdout, law.n * law.dim))
device = np.array(device)
toolkit = replay(law, x_init, normals, steps, record=True)
print("largest |device - toolkit| over every step and agent:", np.max(np.abs(device - toolkit)))

# %%
# The agents' first coordinate, sampled every h (the target θ₁ = 1 dashed), and the
# difference between the compiled agents and the toolkit: zero at every step. With
# h = 0.1 and one sample of delay the first steps, where c(t) is near 1, overshoot; as
# c(t) = 1/(1 + t) decays the agents settle towards θ.
t = np.arange(steps + 1) * law.digital.period
fig, (ax, bx) = plt.subplots(1, 2, figsize=(10, 3.6), constrained_layout=True)
for i, label in enumerate(law.labels):
    ax.step(t, device[:, 3 * i], where="post", lw=1.2, label=f"agent {label}")
ax.axhline(law.theta[0], color="k", ls="--", lw=0.8)
ax.set(xlabel="t", ylabel="x_i,1 (compiled C)", title="G1, h = 0.1, D = 1")
ax.legend(ncol=2, fontsize=7)
bx.plot(t, np.max(np.abs(device - toolkit), axis=1), color="C3")
bx.set(xlabel="t", ylabel="max |C − replay| (all agents, coordinates)", title="difference")
bx.set_ylim(-1, 1)
plt.show()  # in a notebook or a script: display the figure
