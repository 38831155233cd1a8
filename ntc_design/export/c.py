"""The agents' law (:mod:`ntc_design.protocol.agents`) as dependency-free C99:
``ntc_protocol.h`` (the types, the sizes, the functions), ``ntc_protocol.c`` (the tables,
c(t), the schedule rule, the measurement and the agent's update) and ``ntc_replay.c`` (a
program that reads x(0), K and the normals, and on lossy links each step's arrival
flags after its normals, on stdin and prints x_K).

Every number is written with ``%.17g`` (it reads back to the same double), every
operation in the law's order; compiled with ``cc -std=c99 -O2 -ffp-contract=off`` (no
fused multiply-add) the program agrees bit for bit with
:func:`~ntc_design.simulate.replay.replay`. User text (labels, mode names) only appears in
string literals, escaped byte by byte.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from .. import __version__
from ..errors import InputError
from ..expr.code import literal
from ..protocol.agents import AgentLaw, ModeLaw

#: The command the README gives (and the tests run).
COMPILE = (
    "cc -std=c99 -O2 -ffp-contract=off -Wall -Wextra -o ntc_replay ntc_replay.c ntc_protocol.c -lm"
)
FILES = ("ntc_protocol.h", "ntc_protocol.c", "ntc_replay.c")


def c_string(text: str) -> str:
    """A C string literal for any text: letters, digits and a few signs as they are, every
    other byte of its UTF-8 as an octal escape (no trigraph, quote or backslash survives).

    Parameters
    ----------
    text : str
        The text.

    Returns
    -------
    str

    Examples
    --------
    >>> c_string('a"b?')
    '"a\\\\042b\\\\077"'
    """
    safe = set(b"abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789 _-.,:;+=()[]{}<>/")
    out = []
    for byte in str(text).encode("utf-8"):
        out.append(chr(byte) if byte in safe else f"\\{byte:03o}")
    return '"' + "".join(out) + '"'


def _vec(values: Sequence[float]) -> str:
    return "{" + ", ".join(literal(v) for v in values) + "}"


def _mat(m: np.ndarray) -> str:
    return "{" + ", ".join(_vec(row) for row in np.asarray(m, dtype=float).tolist()) + "}"


def _in_array(mi: int, ml: ModeLaw, i: int) -> tuple[str, str]:
    """(the static array of agent i's in-edges in mode mi, its name), or ("", "NULL")."""
    edges = ml.in_edges(i)
    if not edges:
        return "", "NULL"
    name = f"ntc_in_m{mi}_a{i}"
    rows = [
        f"    {{{int(ml.src[e])}, {e}, {literal(ml.sign[e])}, {literal(ml.sigma[e])}, "
        f"{_mat(ml.weight[e])}, {literal(1.0 if ml.keep is None else ml.keep[e])}}}"
        for e in edges
    ]
    return f"static const ntc_in_edge {name}[{len(edges)}] = {{\n" + ",\n".join(
        rows
    ) + "\n};\n", name


#: NTC_POLICY: how the agents treat a lost message.
_POLICY_CODE = {None: 0, "skip": 1, "rescale": 2, "hold": 3}


def header(law: AgentLaw, agent: int | None = None) -> str:
    """``ntc_protocol.h``.

    Parameters
    ----------
    law : AgentLaw
        The agents' law.
    agent : int, optional
        Only this agent's tables (0-based; the agent option of ``ntc export``).

    Returns
    -------
    str
    """
    max_in = max((m.max_in_degree for m in law.modes), default=0)
    max_e = max((m.n_edges for m in law.modes), default=0)
    return f"""/* ntc_protocol.h: the digital protocol exported by ntc-design {__version__}.
   A generated file (ntc export); README.txt says how to build and run it. */
#ifndef NTC_PROTOCOL_H
#define NTC_PROTOCOL_H

#define NTC_N {law.n}            /* agents */
#define NTC_D {law.dim}            /* the state dimension d */
#define NTC_MODES {len(law.modes)}        /* topologies (modes) */
#define NTC_DELAY {law.digital.delay}        /* D: a measurement is D samples old */
#define NTC_MAX_IN {max_in}       /* the most in-edges of one agent, in any mode */
#define NTC_MAX_EDGES {max_e}    /* the most edges of one mode */
#define NTC_AGENTS {law.n if agent is None else 1}       /* agents whose tables are here (1: ntc export --agent) */
#define NTC_SELF {-1 if agent is None else agent}         /* that one agent's index (-1: every agent) */
#define NTC_POLICY {_POLICY_CODE[law.policy]}       /* lost messages: 0 none (lossless), 1 skip, 2 rescale, 3 hold */

/* One in-edge e = (j -> i) of an agent, in its mode's file order. */
typedef struct {{
    int from;                    /* j, the in-neighbour (0-based agent index) */
    int edge;                    /* e, the edge's index in its mode's file order */
    double sign;                 /* sgn(A_ij): +1 or -1 */
    double sigma;                /* sigma_e: the measurement's additive noise (replay) */
    double weight[NTC_D][NTC_D]; /* |A_ij| */
    double keep;                 /* 1 - p_e: the probability that its message arrives */
}} ntc_in_edge;

/* One agent's law in one mode. */
typedef struct {{
    int informed;                /* 1: the agent hears the external signal */
    double delta;                /* delta_i (0 for an uninformed agent) */
    double bd[NTC_D][NTC_D];     /* delta_i |B_i| */
    double u[NTC_D];             /* u_i = delta_i |B_i| x0 */
    int n_in;                    /* its in-edges */
    const ntc_in_edge *in;       /* in file order (NULL when none) */
}} ntc_agent;

typedef struct {{
    const char *name;
    int n_edges;                 /* E: step k of this mode reads 2E normals */
    ntc_agent agents[NTC_AGENTS]; /* agents[i] (with --agent: agents[0], agent NTC_SELF) */
}} ntc_mode;

/* One agent, embedded: its state and its own delay line, in static memory (no malloc).
   line[k mod (D+1)] holds x_i(k); line[(k+1) mod (D+1)] holds x_i(k-D) (x_i(0) before the
   start), which step k reads and then overwrites with x_i(k+1). */
typedef struct {{
    int agent;                         /* i, 0-based */
    int slot;                          /* its index into ntc_mode.agents */
    long k;                            /* the next step */
    double line[NTC_DELAY + 1][NTC_D]; /* the delay line */
    double held[NTC_MAX_IN + 1][NTC_D]; /* hold (NTC_POLICY 3): each in-edge's held measurement */
}} ntc_agent_state;

extern const double ntc_period;                     /* h */
extern const double ntc_sqrt_period;                /* sqrt(h) */
extern const double ntc_noise_f[NTC_D][NTC_D];      /* F of f(x) = F x */
extern const ntc_mode ntc_modes[NTC_MODES];
extern const char *const ntc_labels[NTC_N];

/* t_k = k h */
double ntc_time(long k);
/* the gain c(t) */
double ntc_gain(double t);
/* the mode (index into ntc_modes) of step k */
int ntc_mode_at(long k);
/* the measurement m[0..d-1] of in-edge e from the delayed states xd_i, xd_j and the
   edge's normals z1 (additive), z2 (multiplicative): what a sensor delivers */
void ntc_measure(const ntc_in_edge *e, const double *xd_i, const double *xd_j,
                 double z1, double z2, double *m);
/* the agent's next state from its state x_i, its delayed state xd_i and its
   measurements m (n_in rows of d, in its in-edges' order), with c = c(t_k) */
void ntc_agent_update(const ntc_agent *agent, double c, const double *x_i,
                      const double *xd_i, const double *m, double *x_next);
/* the same on lossy links: arrived[s] is 1 when in-edge s's message arrived at this step,
   0 when it was lost (n_in flags in its in-edges' order; NULL: every one arrived). A lost
   message adds nothing; under rescale (NTC_POLICY 2) a received one counts m / keep.
   Under hold (NTC_POLICY 3) m is the held measurements (ntc_agent_hold) and every row
   counts (arrived is not read). */
void ntc_agent_update_arrived(const ntc_agent *agent, double c, const double *x_i,
                              const double *xd_i, const double *m, const int *arrived,
                              double *x_next);

/* Hold: the held measurements (n_in rows of d) take a copy of m's row s where arrived[s]
   is 1. */
void ntc_agent_hold(const ntc_agent *agent, double *held, const double *m, const int *arrived);

/* Start agent i (0-based) at x_i(0) (d numbers); 0, or -1 for an agent whose tables are
   not here. */
int ntc_agent_init(ntc_agent_state *s, int agent, const double *x0);
/* Hold (NTC_POLICY 3): the held measurements before the first arrival, the noiseless
   measurements of x(0) (n_in rows of d in the in-edges' order: ntc_measure with z1 = z2 =
   0.0 on the agents' initial states); call after ntc_agent_init. */
void ntc_agent_init_held(ntc_agent_state *s, const double *m0);
/* The agent's mode at its next step k (index into ntc_modes) and its in-edges there:
   the measurements step k needs, one per in-edge in this order. */
int ntc_agent_mode(const ntc_agent_state *s);
const ntc_agent *ntc_agent_law(const ntc_agent_state *s);
/* x_i(k), its state now, and x_i(k-D), the delayed state a measurement is formed from. */
const double *ntc_agent_x(const ntc_agent_state *s);
const double *ntc_agent_delayed(const ntc_agent_state *s);
/* Step k -> k+1 from the measurements m (n_in rows of d, in the in-edges' order of
   ntc_agent_law(s); ntc_measure forms one from states and normals, a sensor delivers it
   on hardware). Returns the mode used, or -1 (nothing changed) when c(t_k) is not
   finite. */
int ntc_agent_step(ntc_agent_state *s, const double *m);
/* The same on lossy links with the in-edges' arrival flags (n_in, 1 arrived, 0 lost; NULL:
   every one arrived): a lost message's row of m is not read (under hold the agent steps
   with its held measurements, updated first from the arrived rows of m). */
int ntc_agent_step_arrived(ntc_agent_state *s, const double *m, const int *arrived);

#endif
"""


def _gain(law: AgentLaw) -> str:
    g = law.gain
    prog = g.program
    body = "\n".join(f"    {line}" for line in prog.c_lines())
    tail_name = "ntc_gain_tail" if g.is_schedule else "ntc_gain"
    kind = "static double" if g.is_schedule else "double"
    out = [
        f"/* c(t) = {'the tail ' if g.is_schedule else ''}{_comment(prog.text)} */",
        f"{kind} {tail_name}(double t)\n{{\n"
        + ("    (void)t;\n" if prog.constant else "")
        + (body + "\n" if body else "")
        + f"    return {prog.returned()};\n}}\n",
    ]
    if not g.is_schedule:
        return "\n".join(out)
    n = len(g.t)
    linear = g.interpolation == "linear"
    pick = (
        """    if (j < 0) return ntc_table_c[0];
    if (ntc_table_t[j] == t) return ntc_table_c[j];
    {
        const double s = (ntc_table_c[j + 1] - ntc_table_c[j]) / (ntc_table_t[j + 1] - ntc_table_t[j]);
        double r = s * (t - ntc_table_t[j]) + ntc_table_c[j];
        if (r != r) {
            r = s * (t - ntc_table_t[j + 1]) + ntc_table_c[j + 1];
            if (r != r && ntc_table_c[j] == ntc_table_c[j + 1]) r = ntc_table_c[j];
        }
        return r;
    }"""
        if linear
        else "    return ntc_table_c[j < 0 ? 0 : j];"
    )
    out += [
        f"/* the schedule's table ({n} points, {g.interpolation} between them), then the tail */",
        f"#define NTC_TABLE {n}",
        f"static const double ntc_table_t[NTC_TABLE] = {_vec(g.t)};",
        f"static const double ntc_table_c[NTC_TABLE] = {_vec(g.c)};",
        "",
        f"""double ntc_gain(double t)
{{
    long lo = 0, hi = NTC_TABLE, j;
    if (!(t < ntc_table_t[NTC_TABLE - 1])) return ntc_gain_tail(t);
    while (lo < hi) {{  /* the first index with t_i > t */
        const long mid = lo + (hi - lo) / 2;
        if (t < ntc_table_t[mid]) hi = mid; else lo = mid + 1;
    }}
    j = lo - 1;         /* the last index with t_j <= t */
{pick}
}}
""",
    ]
    return "\n".join(out)


def _comment(text: str) -> str:
    """User text safe inside a C comment (no ``*/``, printable ASCII)."""
    s = "".join(ch if 32 <= ord(ch) < 127 else "?" for ch in text)
    return s.replace("*/", "* /").replace("/*", "/ *")[:200]


#: The C rule computes (k mod P)·step in 64 bits: P below 2^31 ticks keeps it exact.
MAX_TICKS = 2**31


def _mode_rule(law: AgentLaw) -> str:
    if not law.schedule:
        return "int ntc_mode_at(long k)\n{\n    (void)k;\n    return 0;\n}\n"
    tk = law.schedule_ticks
    if tk.period >= MAX_TICKS:
        raise InputError(
            f"h and the durations as decimals need {tk.period:.3g} ticks of 1/{tk.unit} s "
            f"per period (the C rule's limit is 2^31); give h and the durations with fewer "
            "decimals",
            field="schedule",
        )
    s = len(law.schedule)
    return f"""/* the schedule: (mode, duration) {s} entries, decided exactly in integer ticks of
   1/{tk.unit} s: h and every duration are their decimals, t_k = k h and the switching
   instants fall on ticks. Step k runs the entry whose cumulative end first exceeds
   tau = t_k mod P (a switching instant belongs to the next entry), as the toolkit does. */
#define NTC_SCHEDULE {s}
static const long long ntc_ticks_step = {tk.step}LL;   /* h mod P, in ticks */
static const long long ntc_ticks_period = {tk.period}LL; /* P, in ticks */
static const long long ntc_schedule_ends[NTC_SCHEDULE] = {{{", ".join(f"{e}LL" for e in tk.ends)}}};
static const int ntc_schedule_mode[NTC_SCHEDULE] = {{{", ".join(str(m) for m in law.schedule_modes)}}};

int ntc_mode_at(long k)
{{
    const long long tau = ((long long)k % ntc_ticks_period) * ntc_ticks_step % ntc_ticks_period;
    int s = 0;
    while (s < NTC_SCHEDULE - 1 && !(tau < ntc_schedule_ends[s])) s++;
    return ntc_schedule_mode[s];
}}
"""


def protocol(law: AgentLaw, agent: int | None = None) -> str:
    """``ntc_protocol.c``: the tables and the functions.

    Parameters
    ----------
    law : AgentLaw
        The agents' law.
    agent : int, optional
        Only this agent's tables (0-based).

    Returns
    -------
    str
    """
    parts = [
        f"/* ntc_protocol.c: the digital protocol exported by ntc-design {__version__}\n"
        f"   (h = {literal(law.digital.period)}, D = {law.digital.delay}). Generated. */",
        "#include <math.h>",
        "#include <stddef.h>",
        '#include "ntc_protocol.h"',
        "",
        f"const double ntc_period = {literal(law.digital.period)};",
        f"const double ntc_sqrt_period = {literal(law.sqrt_period)};",
        f"const double ntc_noise_f[NTC_D][NTC_D] = {_mat(law.noise_f)};",
        "const char *const ntc_labels[NTC_N] = {"
        + ", ".join(c_string(str(a)) for a in law.labels)
        + "};",
        "",
    ]
    modes = []
    for mi, ml in enumerate(law.modes):
        agents = []
        for i in range(law.n) if agent is None else [agent]:
            arr, name = _in_array(mi, ml, i)
            if arr:
                parts.append(arr)
            inf = i in ml.informed
            agents.append(
                f"        {{{int(inf)}, {literal(ml.delta if inf else 0.0)}, {_mat(ml.bd[i])}, "
                f"{_vec(ml.u[i])}, {len(ml.in_edges(i))}, {name}}}"
            )
        modes.append(
            f"    {{{c_string(ml.name)}, {ml.n_edges}, {{\n" + ",\n".join(agents) + "\n    }}"
        )
    parts.append("const ntc_mode ntc_modes[NTC_MODES] = {\n" + ",\n".join(modes) + "\n};\n")
    helpers = law.gain.program.c_helpers()
    if helpers:
        parts.append(helpers)
    parts.append(_gain(law))
    parts.append("double ntc_time(long k)\n{\n    return (double)k * ntc_period;\n}\n")
    parts.append(_mode_rule(law))
    parts.append(AGENT_API)
    parts.append(
        """void ntc_measure(const ntc_in_edge *e, const double *xd_i, const double *xd_j,
                 double z1, double z2, double *m)
{
    double diff[NTC_D];
    int a, b;
    for (b = 0; b < NTC_D; b++) diff[b] = xd_j[b] - xd_i[b];
    for (a = 0; a < NTC_D; a++) {
        double fd = ntc_noise_f[a][0] * diff[0];
        for (b = 1; b < NTC_D; b++) fd += ntc_noise_f[a][b] * diff[b];
        m[a] = e->sign * xd_j[a] - xd_i[a] + (e->sigma * z1 + fd * z2) / ntc_sqrt_period;
    }
}

void ntc_agent_update_arrived(const ntc_agent *agent, double c, const double *x_i,
                              const double *xd_i, const double *m, const int *arrived,
                              double *x_next)
{
    const double hc = ntc_period * c;
    int a, b, s;
#if NTC_POLICY == 0 || NTC_POLICY == 3
    (void)arrived;  /* lossless, or hold (m is the held measurements): every row counts */
#endif
    for (a = 0; a < NTC_D; a++) {
        double acc = agent->u[a];
        if (agent->informed)
            for (b = 0; b < NTC_D; b++) acc -= agent->bd[a][b] * xd_i[b];
        for (s = 0; s < agent->n_in; s++) {
#if NTC_POLICY == 1 || NTC_POLICY == 2
            if (arrived && !arrived[s]) continue;  /* lost: its term and its noise left out */
#endif
            for (b = 0; b < NTC_D; b++)
#if NTC_POLICY == 2
                acc += agent->in[s].weight[a][b] * (m[s * NTC_D + b] / agent->in[s].keep);
#else
                acc += agent->in[s].weight[a][b] * m[s * NTC_D + b];
#endif
        }
        x_next[a] = x_i[a] + hc * acc;
    }
}

void ntc_agent_hold(const ntc_agent *agent, double *held, const double *m, const int *arrived)
{
    int s, b;
    for (s = 0; s < agent->n_in; s++)
        if (!arrived || arrived[s])
            for (b = 0; b < NTC_D; b++) held[s * NTC_D + b] = m[s * NTC_D + b];
}

void ntc_agent_update(const ntc_agent *agent, double c, const double *x_i,
                      const double *xd_i, const double *m, double *x_next)
{
    ntc_agent_update_arrived(agent, c, x_i, xd_i, m, NULL, x_next);
}
"""
    )
    return "\n".join(parts)


AGENT_API = """int ntc_agent_init(ntc_agent_state *s, int agent, const double *x0)
{
    int r, b;
    if (agent < 0 || agent >= NTC_N || (NTC_SELF >= 0 && agent != NTC_SELF)) return -1;
    s->agent = agent;
    s->slot = NTC_SELF >= 0 ? 0 : agent;
    s->k = 0;
    for (r = 0; r <= NTC_DELAY; r++)
        for (b = 0; b < NTC_D; b++) s->line[r][b] = x0[b];  /* held before the start */
    for (r = 0; r <= NTC_MAX_IN; r++)
        for (b = 0; b < NTC_D; b++) s->held[r][b] = 0.0;
    return 0;
}

void ntc_agent_init_held(ntc_agent_state *s, const double *m0)
{
    const ntc_agent *ag = &ntc_modes[ntc_mode_at(s->k)].agents[s->slot];
    int r, b;
    for (r = 0; r < ag->n_in; r++)
        for (b = 0; b < NTC_D; b++) s->held[r][b] = m0[r * NTC_D + b];
}

int ntc_agent_mode(const ntc_agent_state *s)
{
    return ntc_mode_at(s->k);
}

const ntc_agent *ntc_agent_law(const ntc_agent_state *s)
{
    return &ntc_modes[ntc_mode_at(s->k)].agents[s->slot];
}

const double *ntc_agent_x(const ntc_agent_state *s)
{
    return s->line[s->k % (NTC_DELAY + 1)];
}

const double *ntc_agent_delayed(const ntc_agent_state *s)
{
    return s->line[(s->k + 1) % (NTC_DELAY + 1)];
}

int ntc_agent_step(ntc_agent_state *s, const double *m)
{
    return ntc_agent_step_arrived(s, m, NULL);
}

int ntc_agent_step_arrived(ntc_agent_state *s, const double *m, const int *arrived)
{
    const int mode = ntc_mode_at(s->k);
    const double c = ntc_gain(ntc_time(s->k));
    double *xd = s->line[(s->k + 1) % (NTC_DELAY + 1)];
    double next[NTC_D];
    int b;
    if (!isfinite(c)) return -1;
#if NTC_POLICY == 3
    ntc_agent_hold(&ntc_modes[mode].agents[s->slot], &s->held[0][0], m, arrived);
    m = &s->held[0][0];
#endif
    ntc_agent_update_arrived(&ntc_modes[mode].agents[s->slot], c,
                             s->line[s->k % (NTC_DELAY + 1)], xd, m, arrived, next);
    for (b = 0; b < NTC_D; b++) xd[b] = next[b];  /* x_i(k+1) replaces x_i(k-D) */
    s->k++;
    return mode;
}
"""


REPLAY = """/* ntc_replay.c: replays the exported protocol on given normals. Generated by ntc-design.
   stdin (whitespace-separated): x(0) as N*d numbers agent by agent, the number of
   steps K, then for every step k the 2E normals of the edges of its mode in file order
   (each edge's additive xi1, then its multiplicative xi2) and, on lossy links
   (NTC_POLICY != 0), after them the E arrival flags of the same edges in the same order
   (1 arrived, 0 lost); under hold (NTC_POLICY 3) each edge keeps its held measurement,
   the noiseless one of x(0) first. stdout: x_K, one agent per line, %.17g. Exit 2 on malformed
   input, 1 when c(t_k) is not finite. */
#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "ntc_protocol.h"

static int fail(const char *what, long k)
{
    if (k >= 0)
        fprintf(stderr, "ntc_replay: stdin: %s (step %ld)\\n", what, k);
    else
        fprintf(stderr, "ntc_replay: stdin: %s\\n", what);
    return 2;
}

int main(void)
{
    const long nd = (long)NTC_N * NTC_D;
    const long slots = (long)NTC_DELAY + 1;
    double *ring = malloc(sizeof(double) * (size_t)(slots * nd));
    double *next = malloc(sizeof(double) * (size_t)nd);
    double *z = malloc(sizeof(double) * (size_t)(2 * NTC_MAX_EDGES + 1));
    double *m = malloc(sizeof(double) * (size_t)(NTC_MAX_IN * NTC_D + 1));
    int *chi = malloc(sizeof(int) * (size_t)(NTC_MAX_EDGES + 1));
    int *got = malloc(sizeof(int) * (size_t)(NTC_MAX_IN + 1));
    double *held = malloc(sizeof(double) * (size_t)((NTC_MAX_EDGES + 1) * NTC_D));
    char tok[8];
    long K, k, r, q;
    int i, s, ch;
    if (!ring || !next || !z || !m || !chi || !got || !held) {
        fprintf(stderr, "ntc_replay: out of memory\\n");
        return 2;
    }
    for (q = 0; q < nd; q++)
        if (scanf("%lf", &ring[q]) != 1) return fail("expected N*d numbers of the initial state", -1);
    for (r = 1; r < slots; r++) memcpy(ring + r * nd, ring, sizeof(double) * (size_t)nd);
    if (scanf("%ld", &K) != 1 || K < 0) return fail("expected the number of steps K >= 0", -1);
    if (NTC_POLICY == 3) {  /* hold: the noiseless measurements of x(0), edge by edge */
        const ntc_mode *m0 = &ntc_modes[ntc_mode_at(0)];
        for (i = 0; i < NTC_N; i++)
            for (s = 0; s < m0->agents[i].n_in; s++) {
                const ntc_in_edge *e = &m0->agents[i].in[s];
                ntc_measure(e, ring + (long)i * NTC_D, ring + (long)e->from * NTC_D, 0.0, 0.0,
                            held + (long)e->edge * NTC_D);
            }
    }
    for (k = 0; k < K; k++) {
        const ntc_mode *md = &ntc_modes[ntc_mode_at(k)];
        const double c = ntc_gain(ntc_time(k));
        const double *now = ring + (k % slots) * nd;
        double *xd = ring + ((k + 1) % slots) * nd;
        if (!isfinite(c)) {
            fprintf(stderr, "ntc_replay: c(t) = %g is not finite at step %ld\\n", c, k);
            return 1;
        }
        for (q = 0; q < 2L * md->n_edges; q++)
            if (scanf("%lf", &z[q]) != 1) return fail("expected 2E normals", k);
        for (q = 0; q < (NTC_POLICY != 0 ? (long)md->n_edges : 0L); q++) {
            if (scanf("%7s", tok) != 1) return fail("expected E arrival flags (0 or 1)", k);
            if (strcmp(tok, "0") == 0) chi[q] = 0;
            else if (strcmp(tok, "1") == 0) chi[q] = 1;
            else return fail("an arrival flag is not 0 or 1", k);
        }
        for (i = 0; i < NTC_N; i++) {
            const ntc_agent *ag = &md->agents[i];
            for (s = 0; s < ag->n_in; s++) {
                const ntc_in_edge *e = &ag->in[s];
                ntc_measure(e, xd + (long)i * NTC_D, xd + (long)e->from * NTC_D,
                            z[2 * e->edge], z[2 * e->edge + 1], m + s * NTC_D);
                got[s] = NTC_POLICY != 0 ? chi[e->edge] : 1;
                if (NTC_POLICY == 3) {  /* hold: an arrived one is kept, every slot reads it */
                    if (got[s]) memcpy(held + (long)e->edge * NTC_D, m + s * NTC_D,
                                       sizeof(double) * NTC_D);
                    memcpy(m + s * NTC_D, held + (long)e->edge * NTC_D, sizeof(double) * NTC_D);
                }
            }
            ntc_agent_update_arrived(ag, c, now + (long)i * NTC_D, xd + (long)i * NTC_D, m,
                                     got, next + (long)i * NTC_D);
        }
        memcpy(xd, next, sizeof(double) * (size_t)nd);  /* x_{k+1} replaces x_{k-D} */
    }
    while ((ch = getchar()) != EOF)
        if (!isspace(ch)) return fail("more numbers than the K steps read", -1);
    for (i = 0; i < NTC_N; i++) {
        const double *x = ring + (K % slots) * nd + (long)i * NTC_D;
        for (s = 0; s < NTC_D; s++) {
            if (s) putchar(' ');
            printf("%.17g", x[s]);
        }
        printf("\\n");
    }
    free(ring);
    free(next);
    free(z);
    free(m);
    free(chi);
    free(got);
    free(held);
    return 0;
}
"""


def c_files(law: AgentLaw, agent: int | None = None) -> dict[str, str]:
    """The C files, by name.

    Parameters
    ----------
    law : AgentLaw
        The agents' law.
    agent : int, optional
        Only this agent's tables (0-based): the header and the source, no replay program
        (it runs every agent).

    Returns
    -------
    dict of str to str
        ``ntc_protocol.h``, ``ntc_protocol.c`` and (every agent) ``ntc_replay.c``.
    """
    out = {"ntc_protocol.h": header(law, agent), "ntc_protocol.c": protocol(law, agent)}
    if agent is None:
        out["ntc_replay.c"] = REPLAY
    return out


__all__ = [
    "AGENT_API",
    "COMPILE",
    "FILES",
    "MAX_TICKS",
    "c_files",
    "c_string",
    "header",
    "protocol",
]
