"""``ntc export``: write the agents' code (C99 or Python) of a certified design into a
folder, all or nothing, with a README and an example to check a build against.

Besides the code (:mod:`.c`, :mod:`.python`) the folder holds ``README.txt`` (how to
compile and run, the stdin format, the law) and ``example_input.txt`` /
``example_output.txt``: x(0) (the scenario's, else zero), up to :data:`EXAMPLE_STEPS`
steps of seeded normals, and the state the toolkit's
:func:`~ntc_design.simulate.replay.replay` reaches, printed as the programs print it, so
``./ntc_replay < example_input.txt | diff - example_output.txt`` checks a build.
"""

from __future__ import annotations

import os
import stat
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..choices import Language, choices
from ..errors import InputError, Option, one_line
from ..expr.code import literal
from ..io.outputs import check_output_folder, output_folder
from ..protocol.agents import AgentLaw
from ..protocol.digital import decimal_fraction
from ..simulate.replay import replay
from .c import COMPILE, c_files
from .c import FILES as C_FILES
from .checks import check_emitted_gain
from .python import FILES as PY_FILES
from .python import python_files
from .source import NO_OPTIONS, ExportOptions, ExportSource, load_source

LANGUAGES = choices(Language)
#: Steps of the example input (fewer when the scenario's horizon has fewer).
EXAMPLE_STEPS = 100
#: The seed of the example's normals.
EXAMPLE_SEED = 0
#: Refuse an export whose tables would exceed this many numbers.
MAX_NUMBERS = 20_000_000
EXAMPLES = ("example_input.txt", "example_output.txt")


def stdin_text(x_init, steps: int, normals, law: AgentLaw | None = None, arrivals=None) -> str:
    """The input of an exported program: x(0), K and the normals, each number written so
    that it reads back to the same double; on lossy links each step's E arrival flags
    (``0``/``1``) after its 2E normals.

    Parameters
    ----------
    x_init : array_like
        x(0), N·d numbers.
    steps : int
        K.
    normals : array_like
        The normals in the programs' order.
    law : AgentLaw, optional
        The law (the steps' edge counts; needed with ``arrivals``).
    arrivals : array_like, optional
        The arrival flags (0 or 1), step by step.

    Returns
    -------
    str
    """
    x = " ".join(repr(float(v)) for v in np.asarray(x_init, dtype=float).ravel())
    z = np.asarray(normals, dtype=float).ravel().tolist()
    if arrivals is None or law is None:
        rows = [" ".join(repr(v) for v in z[k : k + 8]) for k in range(0, len(z), 8)]
        return "\n".join([x, str(int(steps)), *rows]) + "\n"
    flags = np.asarray(arrivals).ravel().astype(np.int64).tolist()
    out = [x, str(int(steps))]
    e_z = np.concatenate([[0], np.cumsum(law.normals_per_step(steps))]).tolist()
    e_f = np.concatenate([[0], np.cumsum(law.flags_per_step(steps))]).tolist()
    for k in range(steps):
        zk = z[e_z[k] : e_z[k + 1]]
        out += [" ".join(repr(v) for v in zk[j : j + 8]) for j in range(0, len(zk), 8)]
        out.append(" ".join(str(v) for v in flags[e_f[k] : e_f[k + 1]]))
    return "\n".join(out) + "\n"


def state_text(x, d: int) -> str:
    """A state as the exported programs print it: one agent per line, ``%.17g``.

    Parameters
    ----------
    x : array_like
        N·d numbers.
    d : int
        The state dimension.

    Returns
    -------
    str
    """
    rows = np.asarray(x, dtype=float).reshape(-1, d).tolist()
    return "".join(" ".join("%.17g" % v for v in row) + "\n" for row in rows)  # noqa: UP031


def read_state(text: str, nd: int) -> np.ndarray:
    """The state an exported program printed, as numbers.

    Parameters
    ----------
    text : str
        Its stdout.
    nd : int
        N·d.

    Returns
    -------
    numpy.ndarray

    Raises
    ------
    InputError
        Not N·d numbers.
    """
    try:
        x = np.array([float(w) for w in text.split()])
    except ValueError:
        raise InputError("expected numbers", field="output") from None
    if x.size != nd:
        raise InputError(f"expected {nd} numbers, got {x.size}", field="output")
    return x


def example(src: ExportSource) -> tuple[str, str]:
    """The example input and the output the toolkit's replay gives for it.

    Parameters
    ----------
    src : ExportSource
        What is exported.

    Returns
    -------
    (str, str)
        ``example_input.txt`` and ``example_output.txt``.

    Raises
    ------
    InputError
        c(t) is not finite on the example's steps.
    """
    law = src.law
    steps = EXAMPLE_STEPS
    if src.horizon is not None:
        steps = min(steps, law.digital.steps(src.horizon)[0])
    count = int(law.normals_per_step(steps).sum())
    rng = np.random.default_rng(EXAMPLE_SEED)
    z = rng.standard_normal(count)
    if not law.lossy:
        x = replay(law, src.initial, z, steps)
        return stdin_text(src.initial, steps, z), state_text(x, law.dim)
    keep = np.concatenate(
        [np.zeros(0)]
        + [np.asarray(law.modes[int(m)].keep, dtype=float) for m in law.step_modes(steps)]
    )
    chi = (rng.random(keep.size) < keep).astype(np.int64)  # arrives with probability 1 − p_e
    x = replay(law, src.initial, z, steps, arrivals=chi)
    return stdin_text(src.initial, steps, z, law, chi), state_text(x, law.dim)


def _loss_stdin(law: AgentLaw) -> list[str]:
    if not law.lossy:
        return []
    return [
        "  Lossy links: after the 2E normals of step k, its E arrival flags, one per edge",
        "  in the same file order (below): 1 the message arrived, 0 it was lost (only the",
        "  words 0 and 1; anything else is refused, exit 2).",
    ]


def _loss_law(law: AgentLaw) -> list[str]:
    if not law.lossy:
        return []
    keep = sorted({float(v) for m in law.modes for v in np.asarray(m.keep).tolist()})
    shown = ", ".join(literal(v) for v in keep[:8]) + (", …" if len(keep) > 8 else "")
    rescale = law.policy == "rescale"
    if law.policy == "hold":
        return [
            "",
            f"Lossy links, policy hold (compiled in; keep_e = 1 - p_e: {shown}):",
            "  each in-edge keeps its last received measurement (the agent's state), the",
            "  noiseless measurement of x(0) (z1 = z2 = 0) before the first arrival; every",
            "  in-edge adds |A_ij|[a][b] held_e[b] (hold: the mean converges to 1 (x) theta).",
            "  C: ntc_agent_init_held(&s, m0) after ntc_agent_init, then",
            "  ntc_agent_step_arrived(&s, m, arrived) with arrived[q] = 1 or 0 for in-edge",
            "  ag->in[q]. Python: hold_update(held, m, arrived), then agent_update(..., held).",
        ]
    return [
        "",
        f"Lossy links, policy {law.policy} (compiled in; keep_e = 1 - p_e: {shown}):",
        "  an in-edge whose message is lost at step k (flag 0) adds nothing: its term and",
        "  its noise are left out"
        + (
            "; a received one adds |A_ij|[a][b] (m_e[b] / keep_e) (rescale: the mean"
            " drift unbiased)."
            if rescale
            else " (skip: the mean converges to x*, the certificate's offset)."
        ),
        "  C: ntc_agent_step_arrived(&s, m, arrived) with arrived[q] = 1 or 0 for in-edge",
        "  ag->in[q] (ntc_agent_step: every message arrived). Python: agent_update(..., arrived).",
    ]


def _edges_text(law: AgentLaw, most: int = 40) -> list[str]:
    out = []
    lab = law.labels
    for ml in law.modes:
        names = [
            f"{one_line(str(lab[int(j)]))}->{one_line(str(lab[int(i)]))}"
            for i, j in zip(ml.dst, ml.src, strict=True)
        ]
        shown = ", ".join(names[:most]) + (
            f", … ({len(names)} in all)" if len(names) > most else ""
        )
        out.append(f"  mode {one_line(repr(ml.name))} ({ml.n_edges} edges): {shown or 'none'}")
    return out


#: How an agent on hardware forms its measurements (README.txt, C exports).
EMBEDDING = [
    "Embedding one agent (ntc_protocol.h; static memory, no malloc, the delay line inside):",
    "",
    "  static ntc_agent_state s;",
    "  ntc_agent_init(&s, i, x_i0);              /* i: 0-based index of its label in ntc_labels */",
    "  every h seconds (step k = s.k):",
    "    const ntc_agent *ag = ntc_agent_law(&s); /* its mode's in-edges at step k */",
    "    for q = 0 .. ag->n_in - 1: fill m[q*d .. q*d+d-1] for in-edge ag->in[q] (below)",
    "    ntc_agent_step(&s, m);                   /* -1: c(t_k) not finite, nothing done */",
    "    apply ntc_agent_x(&s), the new state x_i(k+1)",
    "",
    "The measurement of in-edge e = j -> i (j = ag->in[q].from) is in the units of the",
    "state x and theta (metres for positions, say; h in the time unit of c(t), seconds):",
    "  m = sign_e * x_j(t_{k-D}) - x_i(t_{k-D})     (sign_e = ag->in[q].sign = sgn A_ij)",
    "taken D samples late (D = NTC_DELAY). A relative-position sensor on agent i gives",
    "r = x_j - x_i (the neighbour's position relative to its own, same units); with",
    "xd = ntc_agent_delayed(&s), the agent's own state at t_{k-D}:",
    "  cooperative edge (sign +1):   m[a] = r[a]",
    "  antagonistic edge (sign -1):  m[a] = -r[a] - 2 xd[a]",
    "all d components in the state's order. The sensor's own noise is the measurement",
    "noise; ntc_measure (used by the replay) adds the model's (sigma_e z1 + F(x_j - x_i) z2)",
    "/ sqrt(h) from given normals instead.",
]


def readme(src: ExportSource, lang: str, agent: int | None = None) -> str:
    """``README.txt``: what the folder holds, how to build and run it, the stdin format and
    the law; for C, how an agent is embedded and forms its measurements from a
    relative-position sensor. User text (the names, the labels, the file's path) is written by
    :func:`~ntc_design.errors.one_line`: a newline or an escape sequence in it stays on its
    line as an escape, so it cannot add a line or reach a terminal.

    Parameters
    ----------
    src : ExportSource
        What is exported.
    lang : str
        ``c`` or ``python``.
    agent : int, optional
        The one agent whose tables are exported (``--agent``).

    Returns
    -------
    str
    """
    law = src.law
    g = law.gain
    gain = (
        f"a table of {len(g.t)} points ({g.interpolation}) on [0, {g.end:g}], then {g.program.text}"
        if g.is_schedule
        else g.program.text
    )
    run = (
        [
            "Build and check (a C99 compiler; no library but libm):",
            "",
            f"  {COMPILE}",
            "  ./ntc_replay < example_input.txt | diff - example_output.txt && echo same",
            "",
            "-ffp-contract=off keeps the compiler from fusing a multiply and an add (FMA): every",
            "operation then rounds as in the toolkit, and the output is the same to the last bit.",
            "",
            *EMBEDDING,
        ]
        if lang == "c" and agent is None
        else [
            f"The tables of agent {one_line(str(law.labels[agent or 0]))} only (index {agent}, "
            "ntc export --agent): no replay program",
            "and no example, which run every agent. Compile ntc_protocol.c with the agent's",
            "own program (a C99 compiler; no library but libm):",
            "",
            "  cc -std=c99 -O2 -ffp-contract=off -Wall -Wextra -c ntc_protocol.c",
            "",
            *EMBEDDING,
        ]
        if lang == "c"
        else [
            "Run and check (Python 3, no package but the standard library):",
            "",
            "  python ntc_protocol.py < example_input.txt | diff - example_output.txt && echo same",
            "",
            "Import it to drive agents yourself: gain(time_of(k)), mode_at(k), measure(...) and",
            "agent_update(...).",
        ]
    )
    sched = (
        [
            "Schedule (mode, duration), repeated with period P = "
            f"{literal(law.schedule_period)}: "
            + ", ".join(f"{one_line(m)} {d!r}" for m, d in law.schedule),
            "Step k runs the mode of the entry whose cumulative end first exceeds",
            "tau = t_k mod P (a switching instant belongs to the next entry), decided exactly:",
            "h and the durations are the decimals written above (0.1 is 1/10), so the code",
            f"counts integer ticks of 1/{law.schedule_ticks.unit} s (h = "
            f"{decimal_fraction(law.digital.period) * law.schedule_ticks.unit} ticks, "
            f"P = {law.schedule_ticks.period} ticks).",
        ]
        if law.schedule
        else []
    )
    lines = [
        f"Digital protocol of {one_line(law.name)}, exported by ntc export from "
        f"{one_line(src.source)} ({src.kind}).",
        *(one_line(n) for n in src.notes),
        "",
        f"Agents N = {law.n} (labels {', '.join(one_line(str(a)) for a in law.labels[:20])}"
        + (", …" if law.n > 20 else "")
        + f"), state dimension d = {law.dim}, theta = {law.theta.tolist()}.",
        f"Period h = {literal(law.digital.period)}, delay D = {law.digital.delay} samples, "
        f"gain c(t) = {gain}.",
        *sched,
        "",
        *run,
        "",
        "stdin (numbers separated by any whitespace):",
        "  x(0): N*d numbers, agent by agent (agent 1's d numbers, then agent 2's, ...);",
        "  K: the number of steps;",
        "  then for k = 0 .. K-1 the 2E normals of step k: for each edge of the mode of",
        "  step k, in file order (below), its additive xi1, then its multiplicative xi2.",
        *_loss_stdin(law),
        "stdout: x_K, one agent per line, d numbers each, printed with %.17g.",
        "",
        "The model (t_k = k*h, c_k = c(t_k), e = x - 1 (x) theta, the state held before t = 0):",
        "  x_{k+1} = x_k + h c_k (u - L_B x_{k-D})",
        "            + c_k sqrt(h) sum_e (g_e xi_{k,e,1} + G_e x_{k-D} xi_{k,e,2})",
        "",
        "The law each agent i runs (xd = x_{k-D}, sqrth = sqrt(h)), for in-edge e = j -> i:",
        "  diff[b] = xd_j[b] - xd_i[b];  fd[a] = sum_b F[a][b] diff[b] (b in order)",
        "  m[a] = s_e xd_j[a] - xd_i[a] + (sigma_e z1 + fd[a] z2) / sqrth",
        "and with hc = h c_k, for each component a:",
        "  acc = u_i[a];  informed: acc -= (delta |B_i|)[a][b] xd_i[b] for b in order",
        "  for each in-edge in file order, for b in order: acc += |A_ij|[a][b] m_e[b]",
        "  x_next[a] = x_i[a] + hc acc",
        *_loss_law(law),
        "",
        "Edges in file order (the order of the normals"
        + (" and of the arrival flags):" if law.lossy else "):"),
        *_edges_text(law),
        "",
    ]
    return "\n".join(lines)


@dataclass(frozen=True)
class ExportResult:
    """What :func:`export` wrote.

    Attributes
    ----------
    folder : Path
        The folder.
    files : tuple of str
        The files in it.
    source : ExportSource
        What was exported.
    """

    folder: Path
    files: tuple[str, ...]
    source: ExportSource


def _size_check(law: AgentLaw) -> None:
    d = law.dim
    numbers = sum(m.n_edges * (d * d + 2) + law.n * (d * d + d) for m in law.modes)
    if numbers > MAX_NUMBERS:
        raise InputError(
            f"the tables would hold {numbers:.3g} numbers (limit {MAX_NUMBERS:.0e}); "
            "too large to write as source code",
            field="export",
        )


#: The time up to which the emitted gain is checked when the source states no horizon
#: (a certificate): about 32 years of samples, sampled as :func:`.checks.sample_steps` says.
CHECK_HORIZON = 1e9


def gain_steps(src: ExportSource) -> int:
    """The steps of the horizon whose emitted gain is checked
    (:func:`~ntc_design.export.checks.check_emitted_gain`): the K whole steps of a
    scenario's horizon, those up to :data:`CHECK_HORIZON` for a certificate (it states
    no horizon).

    Parameters
    ----------
    src : ExportSource
        What is exported.

    Returns
    -------
    int
    """
    if src.horizon is None:
        return max(1, min(int(CHECK_HORIZON / src.law.digital.period), 10**15))
    return src.law.digital.steps(src.horizon)[0]


def agent_index(law: AgentLaw, label: str | None) -> int | None:
    """The 0-based index of the agent ``--agent`` names (its label as text), or None.

    Parameters
    ----------
    law : AgentLaw
        The agents' law.
    label : str or None
        The label.

    Returns
    -------
    int or None

    Raises
    ------
    InputError
        No agent has that label.
    """
    if label is None:
        return None
    for i, a in enumerate(law.labels):
        if str(a) == str(label):
            return i
    shown = ", ".join(one_line(str(a)) for a in law.labels[:10]) + (", …" if law.n > 10 else "")
    raise InputError(
        f"no agent is labelled {one_line(repr(label))} (labels: {shown})",
        field="agent",
        option=True,
    )


def files_for(src: ExportSource, lang: str, agent: str | None = None) -> dict[str, str]:
    """Every file of the export, by name.

    Parameters
    ----------
    src : ExportSource
        What is exported.
    lang : str
        ``c`` or ``python``.
    agent : str, optional
        One agent's label: its tables only (C; no replay program and no example, which
        run every agent).

    Returns
    -------
    dict of str to str

    Raises
    ------
    InputError
        An unknown language or agent, one agent's tables asked of Python, tables too
        large, or an emitted gain that is not the analysed one.
    """
    if lang not in LANGUAGES:
        raise InputError(
            f"expected one of {', '.join(LANGUAGES)}, got {lang!r}", field="lang", option=True
        )
    if agent is not None and lang != "c":
        raise InputError(
            "one agent's tables are emitted in C only (",
            Option("lang", "c"),
            ")",
            field="agent",
            option=True,
        )
    index = agent_index(src.law, agent)
    _size_check(src.law)
    check_emitted_gain(src.law, gain_steps(src), f"{src.source}: gain")
    if index is not None:
        return {**c_files(src.law, index), "README.txt": readme(src, lang, index)}
    code = c_files(src.law) if lang == "c" else python_files(src.law)
    inp, out = example(src)
    return {**code, "README.txt": readme(src, lang), EXAMPLES[0]: inp, EXAMPLES[1]: out}


def replaceable(lang: str | None = None) -> tuple[str, ...]:
    """The names an export may leave in a folder (which a new one replaces, when its
    manifest lists them): the files it writes and ``ntc_replay``, which the README's
    build command makes.

    Parameters
    ----------
    lang : str, optional
        Only that language's (default: any).

    Returns
    -------
    tuple of str
    """

    code: Sequence[str] = {"c": C_FILES, "python": PY_FILES}.get(lang or "", (*C_FILES, *PY_FILES))
    return (*code, "README.txt", *EXAMPLES, "ntc_replay")


#: The file in an export's folder that lists what the export wrote: a later export
#: replaces only regular files listed there (and the manifest itself).
MANIFEST = ".ntc-export-manifest"
MANIFEST_BYTES = 65_536


def manifest_text(files: Sequence[str]) -> str:
    """The manifest of an export: the names it wrote, one a line, and ``ntc_replay``
    (built from them by the README's command).

    Parameters
    ----------
    files : sequence of str
        The files written.

    Returns
    -------
    str
    """
    names = [*files, *(["ntc_replay"] if "ntc_replay.c" in files else [])]
    head = "# written by ntc export; a later ntc export into this folder replaces only these"
    return "\n".join([head, *names]) + "\n"


def _listed(folder: Path) -> set[str]:
    """The names the folder's manifest lists that an export can write (nothing when there is
    no manifest: then no file is an earlier export's)."""
    path = folder / MANIFEST
    try:
        st = os.lstat(path)
    except FileNotFoundError:
        return set()
    except OSError as exc:
        raise InputError(
            f"cannot read {one_line(str(path))!r} ({exc.strerror})", field="out", option=True
        ) from None
    if not stat.S_ISREG(st.st_mode) or st.st_size > MANIFEST_BYTES:
        raise InputError(
            f"{one_line(str(path))!r} is not an export's manifest (not a regular file, "
            "or too large); choose a new folder",
            field="out",
            option=True,
        )
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError):
        return set()
    lines = {line.strip() for line in text.splitlines() if not line.startswith("#")}
    return lines & set(replaceable())


def check_export_folder(out: str | Path) -> Path:
    """Check, before any work, that ``out`` can take an export without losing user data:
    new, empty, or holding only regular files that an earlier export's manifest lists.

    Parameters
    ----------
    out : str or Path
        The folder.

    Returns
    -------
    Path

    Raises
    ------
    InputError
        Anything else in it (a folder or pipe named like an output, an unlisted file): one
        line naming it; nothing is written.
    """
    p = check_output_folder(out, None)
    shown = repr(one_line(str(p)))
    if p.is_symlink():  # the swap would replace the link itself and leave a stray ".old" one
        raise InputError(
            f"{shown} is a link; give the folder it points to (nothing written)",
            field="out",
            option=True,
        )
    if not p.is_dir():
        return p
    listed = _listed(p)
    try:
        entries = sorted(os.scandir(p), key=lambda e: e.name)
    except OSError as exc:
        raise InputError(
            f"cannot read {shown} ({exc.strerror})", field="out", option=True
        ) from None
    for e in entries:
        if e.name != MANIFEST and e.name not in listed:
            raise InputError(
                f"{shown} holds {one_line(e.name)!r}, which no earlier export wrote "
                f"(its {MANIFEST} does not list it); nothing written, choose a new folder",
                field="out",
                option=True,
            )
        if not e.is_file(follow_symlinks=False):
            raise InputError(
                f"{shown} holds {one_line(e.name)!r}, which is not a regular file (a "
                "folder, pipe or link); nothing written, choose a new folder",
                field="out",
                option=True,
            )
    return p


def export(
    path: str | Path,
    lang: Language,
    out: str | Path,
    options: ExportOptions = NO_OPTIONS,
    agent: str | None = None,
) -> ExportResult:
    """Export a scenario's or a certificate's certified design as code, into ``out`` (all
    or nothing: refused before any work when ``out`` holds other files).

    Parameters
    ----------
    path : str or Path
        A scenario or a certificate.
    lang : {"c", "python"}
        The language.
    out : str or Path
        The folder.
    options : ExportOptions, optional
        h and D (over a scenario's or a subject's digital block), the gain, the noise's σ
        and f, p on every edge and the policy for a lost message.
    agent : str, optional
        One agent's label: its tables only (C).

    Returns
    -------
    ExportResult

    Raises
    ------
    InputError
        A bad language, folder, file or value, or a design that is not certified
        (:func:`~ntc_design.export.source.load_source`).
    """
    if lang not in LANGUAGES:
        raise InputError(
            f"expected one of {', '.join(LANGUAGES)}, got {lang!r}", field="lang", option=True
        )
    if agent is not None and lang != "c":
        raise InputError(
            "one agent's tables are emitted in C only (",
            Option("lang", "c"),
            ")",
            field="agent",
            option=True,
        )
    check_export_folder(out)
    src = load_source(path, options)
    texts = files_for(src, lang, agent)
    check_export_folder(out)  # again: the folder may have changed during the work
    # written into a new folder that then replaces ``out`` whole (all or nothing); what it
    # replaces is only files an earlier export wrote (checked just above)
    with output_folder(out, (*replaceable(), MANIFEST)) as tmp:
        for name, text in texts.items():
            (tmp / name).write_text(text, encoding="utf-8")
        (tmp / MANIFEST).write_text(manifest_text(list(texts)), encoding="utf-8")
    return ExportResult(Path(out), tuple(texts), src)


__all__ = [
    "CHECK_HORIZON",
    "EXAMPLES",
    "MANIFEST",
    "EXAMPLE_SEED",
    "EXAMPLE_STEPS",
    "LANGUAGES",
    "MAX_NUMBERS",
    "ExportResult",
    "check_export_folder",
    "example",
    "export",
    "agent_index",
    "files_for",
    "gain_steps",
    "read_state",
    "manifest_text",
    "readme",
    "replaceable",
    "state_text",
    "stdin_text",
]
