"""The agents' law (:mod:`ntc_design.protocol.agents`) as one dependency-free Python module,
``ntc_protocol.py``: the tables, c(t), the schedule rule, the measurement, the agent's
update and a replay (``python ntc_protocol.py < input``, the stdin and stdout of the C
program :mod:`.c` writes). It uses only :mod:`math` and :mod:`sys`; every operation is the
law's, in its order, so it agrees bit for bit with the C and with
:func:`~ntc_design.simulate.replay.replay`. User text (labels, mode names) appears only as
string literals written by :func:`repr`.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from .. import __version__
from ..expr.code import PYTHON_HELPERS, literal
from ..protocol.agents import AgentLaw

FILES = ("ntc_protocol.py",)


def _vec(values: Sequence[float]) -> str:
    return "(" + ", ".join(literal(v) for v in values) + ",)"


def _mat(m: np.ndarray) -> str:
    return "(" + ", ".join(_vec(row) for row in np.asarray(m, dtype=float).tolist()) + ",)"


def _tables(law: AgentLaw) -> str:
    lines = [
        f"N = {law.n}  # agents",
        f"DIM = {law.dim}  # the state dimension d",
        f"DELAY = {law.digital.delay}  # D: a measurement is D samples old",
        f"PERIOD = {literal(law.digital.period)}  # h",
        f"SQRT_PERIOD = {literal(law.sqrt_period)}  # sqrt(h)",
        f"NOISE_F = {_mat(law.noise_f)}  # F of f(x) = F x",
        f"LABELS = {tuple(str(a) for a in law.labels)!r}",
        f"POLICY = {law.policy!r}  # lost messages: None (lossless), 'skip', 'rescale' or 'hold'",
        "",
        "# MODES[m]: (name, E, agents); an agent: (informed, delta_i, delta_i |B_i|, u_i,",
        "# in-edges in file order); an in-edge: (j, its index e in file order, sgn A_ij,",
        "# sigma_e, |A_ij|, keep_e = 1 - p_e)",
        "MODES = (",
    ]
    for ml in law.modes:
        lines.append(f"    ({ml.name!r}, {ml.n_edges}, (")
        for i in range(law.n):
            inf = i in ml.informed
            ins = ", ".join(
                f"({int(ml.src[e])}, {e}, {literal(ml.sign[e])}, {literal(ml.sigma[e])}, "
                f"{_mat(ml.weight[e])}, {literal(1.0 if ml.keep is None else ml.keep[e])})"
                for e in ml.in_edges(i)
            )
            lines.append(
                f"        ({inf}, {literal(ml.delta if inf else 0.0)}, {_mat(ml.bd[i])}, "
                f"{_vec(ml.u[i])}, ({ins}{',' if ins else ''})),"
            )
        lines.append("    )),")
    lines.append(")")
    return "\n".join(lines)


def _gain(law: AgentLaw) -> str:
    g = law.gain
    prog = g.program
    name = "gain_tail" if g.is_schedule else "gain"
    body = "".join(f"    {line}\n" for line in prog.python_lines())
    out = (
        f"def {name}(t):\n"
        f'    """c(t) = {"the tail " if g.is_schedule else ""}{_doc(prog.text)}"""\n'
        f"{body}    return {prog.returned()}\n"
    )
    if not g.is_schedule:
        return out
    if g.interpolation == "linear":
        pick = """    if j < 0:
        return TABLE_C[0]
    if TABLE_T[j] == t:
        return TABLE_C[j]
    s = (TABLE_C[j + 1] - TABLE_C[j]) / (TABLE_T[j + 1] - TABLE_T[j])
    r = s * (t - TABLE_T[j]) + TABLE_C[j]
    if r != r:
        r = s * (t - TABLE_T[j + 1]) + TABLE_C[j + 1]
        if r != r and TABLE_C[j] == TABLE_C[j + 1]:
            r = TABLE_C[j]
    return r
"""
    else:
        pick = "    return TABLE_C[j if j > 0 else 0]\n"
    return (
        out
        + f"""

# the schedule's table ({len(g.t)} points, {g.interpolation} between them), then the tail
TABLE_T = {_vec(g.t)}
TABLE_C = {_vec(g.c)}


def gain(t):
    \"\"\"c(t): the table before its last time, the tail from it.\"\"\"
    if not t < TABLE_T[-1]:
        return gain_tail(t)
    lo, hi = 0, len(TABLE_T)
    while lo < hi:  # the first index with t_i > t
        mid = lo + (hi - lo) // 2
        if t < TABLE_T[mid]:
            hi = mid
        else:
            lo = mid + 1
    j = lo - 1  # the last index with t_j <= t
{pick}"""
    )


def _doc(text: str) -> str:
    """User text safe inside a docstring (printable ASCII, no quotes or backslashes)."""
    return "".join(ch if 32 <= ord(ch) < 127 and ch not in '"\\' else "?" for ch in text)[:200]


def _mode_rule(law: AgentLaw) -> str:
    if not law.schedule:
        return 'def mode_at(k):\n    """The mode of step k."""\n    return 0\n'
    tk = law.schedule_ticks
    return f'''# the schedule decided exactly in integer ticks of 1/{tk.unit} s (h and the durations as
# their decimals): t_k = k h and the switching instants fall on ticks
TICKS_STEP = {tk.step}  # h mod P, in ticks
TICKS_PERIOD = {tk.period}  # P, in ticks
SCHEDULE_ENDS = {tuple(tk.ends)!r}
SCHEDULE_MODE = {tuple(law.schedule_modes)!r}


def mode_at(k):
    """The mode of step k: the schedule entry whose cumulative end first exceeds
    tau = t_k mod P (a switching instant belongs to the next entry), in exact integers."""
    tau = k % TICKS_PERIOD * TICKS_STEP % TICKS_PERIOD
    s = 0
    while s < len(SCHEDULE_ENDS) - 1 and not tau < SCHEDULE_ENDS[s]:
        s += 1
    return SCHEDULE_MODE[s]
'''


_LAW = '''def time_of(k):
    """t_k = k h."""
    return float(k) * PERIOD


def measure(edge, xd_i, xd_j, z1, z2):
    """The measurement of an in-edge from the delayed states and the edge's normals."""
    sign, sigma = edge[2], edge[3]
    diff = [xd_j[b] - xd_i[b] for b in range(DIM)]
    m = []
    for a in range(DIM):
        row = NOISE_F[a]
        fd = row[0] * diff[0]
        for b in range(1, DIM):
            fd += row[b] * diff[b]
        m.append(sign * xd_j[a] - xd_i[a] + (sigma * z1 + fd * z2) / SQRT_PERIOD)
    return m


def agent_update(agent, c, x_i, xd_i, m, arrived=None):
    """The agent's next state from its state, its delayed state and its measurements
    (one list of d per in-edge, in its in-edges' order), with c = c(t_k). On lossy links
    ``arrived[s]`` is 1 when in-edge s's message arrived, 0 when lost (None: every one
    arrived): a lost message adds nothing; under rescale a received one counts m / keep.
    Under hold ``m`` is the held measurements (``hold_update``) and every one counts."""
    informed, _, bd, u, inputs = agent
    hc = PERIOD * c
    out = []
    for a in range(DIM):
        acc = u[a]
        if informed:
            for b in range(DIM):
                acc -= bd[a][b] * xd_i[b]
        for s, edge in enumerate(inputs):
            if POLICY in ("skip", "rescale") and arrived is not None and not arrived[s]:
                continue  # lost: its term and its noise left out
            w, ms = edge[4][a], m[s]
            if POLICY == "rescale":
                keep = edge[5]
                for b in range(DIM):
                    acc += w[b] * (ms[b] / keep)
            else:
                for b in range(DIM):
                    acc += w[b] * ms[b]
        out.append(x_i[a] + hc * acc)
    return out


def hold_update(held, m, arrived):
    """Hold: each in-edge's held measurement (a list of d per in-edge, the agent's state)
    becomes a copy of the new one where its message arrived (``arrived[s]`` 1)."""
    for s, ms in enumerate(m):
        if arrived[s]:
            held[s] = list(ms)
    return held


def replay(x0, steps, normals, arrivals=None):
    """x_K from x(0) (N lists of d), K and an iterator over the normals (step by step,
    each edge of the step's mode in file order: its xi1, then its xi2); on lossy links an
    iterator over the arrival flags (after each step's normals, E flags 0 or 1 in the
    same edge order)."""
    ring = [[list(x) for x in x0] for _ in range(DELAY + 1)]
    held = None  # hold: per agent, its in-edges' held measurements
    if POLICY == "hold":  # before the first arrival, the noiseless measurement of x(0)
        held = [
            [measure(e, x0[i], x0[e[0]], 0.0, 0.0) for e in agent[4]]
            for i, agent in enumerate(MODES[mode_at(0)][2])
        ]
    for k in range(steps):
        name, n_edges, agents = MODES[mode_at(k)]
        c = gain(time_of(k))
        if not math.isfinite(c):
            raise ArithmeticError(f"c(t) = {c!r} is not finite at step {k}")
        z = [next(normals) for _ in range(2 * n_edges)]
        chi = [next(arrivals) for _ in range(n_edges)] if POLICY is not None else None
        now = ring[k % (DELAY + 1)]
        xd = ring[(k + 1) % (DELAY + 1)]
        nxt = []
        for i, agent in enumerate(agents):
            m = [measure(e, xd[i], xd[e[0]], z[2 * e[1]], z[2 * e[1] + 1]) for e in agent[4]]
            got = [chi[e[1]] for e in agent[4]] if chi is not None else None
            if held is not None:
                m, got = hold_update(held[i], m, got), None
            nxt.append(agent_update(agent, c, now[i], xd[i], m, got))
        ring[(k + 1) % (DELAY + 1)] = nxt
    return ring[steps % (DELAY + 1)]


def main():
    """stdin: x(0) (N*d numbers), K, the normals; stdout: x_K, one agent per line."""
    words = sys.stdin.read().split()
    nd = N * DIM
    try:
        flat = [float(w) for w in words[:nd]]
        if len(flat) < nd:
            raise ValueError
    except ValueError:
        print("ntc_protocol: stdin: expected N*d numbers of the initial state", file=sys.stderr)
        return 2
    try:
        steps = int(words[nd])
        if steps < 0:
            raise ValueError
    except (IndexError, ValueError):
        print("ntc_protocol: stdin: expected the number of steps K >= 0", file=sys.stderr)
        return 2
    rest = iter(words[nd + 1 :])
    used = [0]

    def normals():
        for w in rest:
            used[0] += 1
            yield float(w)

    def arrivals():
        for w in rest:
            used[0] += 1
            if w not in ("0", "1"):
                raise KeyError(w)
            yield w == "1"

    x0 = [flat[i * DIM : (i + 1) * DIM] for i in range(N)]
    try:
        x = replay(x0, steps, normals(), arrivals())
    except KeyError:
        print("ntc_protocol: stdin: an arrival flag is not 0 or 1", file=sys.stderr)
        return 2
    except (StopIteration, RuntimeError, ValueError):
        what = "2E normals and E arrival flags" if POLICY is not None else "2E normals"
        print(f"ntc_protocol: stdin: expected {what} for every step", file=sys.stderr)
        return 2
    except ArithmeticError as exc:
        print(f"ntc_protocol: {exc}", file=sys.stderr)
        return 1
    if used[0] != len(words) - nd - 1:
        print("ntc_protocol: stdin: more numbers than the K steps read", file=sys.stderr)
        return 2
    for row in x:
        print(" ".join("%.17g" % v for v in row))
    return 0


if __name__ == "__main__":
    sys.exit(main())
'''


def python_module(law: AgentLaw) -> str:
    """``ntc_protocol.py``.

    Parameters
    ----------
    law : AgentLaw
        The agents' law.

    Returns
    -------
    str
    """
    flags = ",\nthen the E arrival flags of the same edges (1 arrived, 0 lost)" if law.lossy else ""
    head = f'''"""The digital protocol exported by ntc-design {__version__} (h = {literal(law.digital.period)},
D = {law.digital.delay}): a generated, dependency-free module.

Run ``python ntc_protocol.py < input``: stdin holds x(0) (N*d numbers, agent by agent),
the number of steps K, then for every step the 2E normals of its mode's edges in file
order (each edge's additive xi1, then its multiplicative xi2){flags};
stdout gets x_K, one agent per line, %.17g. README.txt describes the law.
"""

import math
import sys

'''
    return (
        "\n\n".join(
            [
                head + _tables(law),
                PYTHON_HELPERS.strip(),
                _gain(law).rstrip(),
                _mode_rule(law).rstrip(),
                _LAW.rstrip(),
            ]
        ).replace("\n\n\n\n", "\n\n\n")
        + "\n"
    )


def python_files(law: AgentLaw) -> dict[str, str]:
    """The Python module, by name.

    Parameters
    ----------
    law : AgentLaw
        The agents' law.

    Returns
    -------
    dict of str to str
        ``ntc_protocol.py``.
    """
    return {"ntc_protocol.py": python_module(law)}


__all__ = ["FILES", "python_files", "python_module"]
