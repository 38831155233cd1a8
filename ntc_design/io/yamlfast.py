"""A fast reader for the plain subset of YAML that machine-written topology files use.

PyYAML's constructor (Python code run for every node) costs most of the time of reading a
large YAML file. Files written by ``yaml.safe_dump(..., default_flow_style=None)`` (as
:func:`ntc_design.model.generate.write_topology` writes them) use a small subset of YAML: block
mappings and sequences by indentation, flow lists and mappings of scalars (never nested),
and plain scalars that are identifiers or decimal numbers. Such a text is rewritten as
JSON by a few regular-expression passes and one loop over its lines, and parsed by the
``json`` module's C decoder.

The subset is checked strictly and cheaply first; a text outside it (anchors, aliases,
tags, quotes, comments, nested flow collections, YAML 1.1 words such as ``yes`` or
``null``, numbers in any form but ``-12``/``1.5``/``1.5e-07``, ...) is declined (``None``)
and read by the full reader (:func:`ntc_design.io.documents.read_document`), which then gives the
same document or the same error as before. Within the subset every scalar is resolved as
PyYAML's safe loader resolves it: identifiers are strings, the numbers ints and floats of
the same value. Nothing is evaluated.
"""

from __future__ import annotations

import gc
import json
import re
from typing import Any

import numpy as np

from ..errors import InputError, one_line

#: Characters a text in the subset may hold (no quotes, comments, anchors, aliases, tags,
#: block scalars, tabs, carriage returns or non-ASCII text).
_ALLOWED = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789_ \n.,:[]{}+-"
#: A colon must end a key (be followed by a space or the end of the line).
_BAD_COLON = re.compile(r":(?![ \n])")
#: JSON reads ``1e5``, ``1.5e5`` and ``1E+5`` as floats, YAML 1.1 as text: an exponent
#: must follow a decimal point and carry a sign. (Every other token that is neither an
#: identifier nor a JSON number fails to parse as JSON, and is declined then.)
#: One pattern per letter: a literal first character is searched for fast.
_EXP_UNSIGNED = [re.compile(c + r"(?<=[0-9]" + c + r")(?![-+][0-9])") for c in "eE"]
#: (searched in the reversed text: an exponent whose digits before it follow no dot)
_EXP_NO_DOT = [re.compile(c + r"[0-9]+(?![0-9.])") for c in "eE"]
#: Words PyYAML's safe loader reads as booleans or null, not as strings.
_WORDS_11 = frozenset(
    "yes Yes YES no No NO true True TRUE false False FALSE on On ON off Off OFF "
    "null Null NULL".split()
)
#: An identifier-like plain scalar, always a string in YAML 1.1 once the words above are
#: excluded; the capturing group makes ``'"'.join(_WORD.split(text))`` quote them all.
_WORD = re.compile(r"([A-Za-z_](?<=[ \n\[{,][A-Za-z_])[A-Za-z0-9_.-]*)")
_SCALAR = re.compile(r'"[^"]*"|-?(?:0|[1-9][0-9]*)(?:\.[0-9]+(?:[eE][-+][0-9]+)?)?')
_FLOW = re.compile(r"\[[^\[\]{}]*\]|\{[^\[\]{}]*\}")


class _Decline(Exception):
    """The text is outside the subset: read it with the full reader."""


def quote_words(text: str) -> str | None:
    """``text`` with its identifiers quoted for JSON, if it passes the subset's checks.

    Parameters
    ----------
    text : str
        A YAML text.

    Returns
    -------
    str or None
        The text (after a newline) with every identifier-like plain scalar in double
        quotes; None when a character, a colon, an exponent or a YAML 1.1 boolean or null
        word is outside the subset.
    """
    if not text.isascii() or text.encode("ascii").translate(None, _ALLOWED):
        return None  # a character outside the subset's
    if _BAD_COLON.search(text):
        return None
    text = "\n" + text
    if any(p.search(text) for p in _EXP_UNSIGNED):
        return None
    if ("e" in text or "E" in text) and any(p.search(text[::-1]) for p in _EXP_NO_DOT):
        return None
    parts = _WORD.split(text)
    if not _WORDS_11.isdisjoint(parts[1::2]):
        return None
    return '"'.join(parts)


def node_bound(text: str) -> int:
    """An upper bound on the nodes of a document in the subset, from character counts.

    Parameters
    ----------
    text : str
        A text in the subset.

    Returns
    -------
    int
        At least the number of scalars and collections the text holds (each scalar ends
        at a comma, a closing bracket, a colon or a line end; each collection starts at an
        opening bracket, a dash or a key).
    """
    if len(text) < 2**20:
        return len(text)  # each node takes at least one character
    c = text.count
    ends = c(",") + c("]") + c("}") + c(":") + c("\n") + 1
    return 2 * ends + c("[") + c("{") + c("-")


def load_fast(text: str, max_depth: int, max_nodes: int) -> Any | None:
    """The document of ``text`` if it is in the fast subset, else ``None``.

    Parameters
    ----------
    text : str
        A YAML text (one document).
    max_depth : int
        Nesting limit: a deeper document is declined (the full reader refuses it).
    max_nodes : int
        Node limit: a document that may hold more nodes is declined.

    Returns
    -------
    Any or None
        The same value PyYAML's safe loader gives, or None when the text is outside the
        subset (or not valid in it): read it with the full reader then.
    """
    if node_bound(text) > max_nodes:
        return None
    quoted = quote_words(text)
    if quoted is None:
        return None
    was_enabled = gc.isenabled()
    try:
        out = _to_json(quoted.split("\n"), max_depth)
        gc.disable()  # JSON makes no cycles; collecting during the parse only costs time
        return json.loads(out)
    except (_Decline, ValueError, RecursionError):
        return None
    finally:
        if was_enabled:
            gc.enable()


def _to_json(lines: list[str], max_depth: int) -> str:
    """The block structure of ``lines`` (identifiers already quoted) as JSON text.

    One pass over the lines with a stack of the open block collections (indent, is a
    sequence); a value (a scalar, or a flow collection of scalars, possibly over several
    lines) is copied as it is. Anything else raises :class:`_Decline`.
    """
    out: list[str] = []
    app = out.append
    stack: list[tuple[int, bool]] = []
    want = -1  # indent of the mapping whose last key waits for a value on the next lines
    k, nlines = 0, len(lines)
    row, flow, scalar = "", _FLOW.fullmatch, _SCALAR.fullmatch
    while k < nlines:
        line = lines[k]
        k += 1
        if row and line.startswith(row) and flow(line, len(row) - 1):
            app(",")  # the commonest line: "  - [1.5, 2.5]" after another such
            app(line[len(row) - 1 :])
            continue
        s = line.lstrip(" ")
        if not s:
            continue
        row = ""
        n = len(line) - len(s)
        dash = s[0] == "-"
        if dash:
            if s[1:2] != " " or s[2:3] in (" ", "") or s[2:4] == "- " or s[2:] == "-":
                raise _Decline  # "-1" or "-x" starting a line, "- - x", "-  x"
            s = s[2:]
        if want >= 0 and (n >= want if dash else n > want):  # the value is a collection
            if len(stack) + 2 > max_depth:  # + 2: room for a flow collection inside
                raise _Decline
            stack.append((n, dash))
            app("[" if dash else "{")
            want = -1
        else:
            if want >= 0:
                app("null")
                want = -1
            while stack and stack[-1][0] > n:
                app("]" if stack.pop()[1] else "}")
            if stack and stack[-1] == (n, True) and not dash:  # a sequence under a key ends
                app("]")
                stack.pop()
            if not stack:
                if out or n:
                    raise _Decline  # a second top-level node, or an indented start
                stack.append((n, dash))
                app("[" if dash else "{")
            elif stack[-1] != (n, dash):
                raise _Decline  # bad indentation or a dash in a mapping: the full reader says where
            else:
                app(",")
        end = s.find('"', 1) + 1 if s[0] == '"' else 0
        key = end > 0 and s[end : end + 1] == ":"
        if dash and key:  # "- key: value": a mapping item, its keys two columns further in
            n += 2
            if len(stack) + 2 > max_depth:
                raise _Decline
            stack.append((n, False))
            app("{")
        if key:
            if len(s) == end + 1:  # "key:", its value on the next lines
                app(s)
                want = n
                continue
            if s[end + 1] != " " or len(s) == end + 2:
                raise _Decline  # "key:x" or "key: " with a trailing space: keep the rules few
            if s[end + 2] not in "[{" and scalar(s, end + 2):
                app(s)  # '"key": 1.5' is JSON as it is
                continue
            app(s[: end + 1])
            s = s[end + 2 :]
        elif not dash:
            raise _Decline  # a bare scalar where a key belongs
        elif s[0] == "[" or s[0] == "{":
            row = line[: n + 3]  # the same prefix on the next line: an item like this one
        k = _value(s, n, lines, k, app)
    if want >= 0:
        app("null")
    while stack:
        app("]" if stack.pop()[1] else "}")
    return "".join(out)


def _value(s: str, n: int, lines: list[str], k: int, app: Any) -> int:
    """Copy the value ``s`` of an entry at indent ``n``; a flow collection may go on over
    the lines from ``k`` on, indented further. Returns the next line's index."""
    first = s[0]
    if first != "[" and first != "{":
        if _SCALAR.fullmatch(s) is None:
            raise _Decline  # several words, a trailing space, a comma in a block scalar
        app(s)
        return k
    if _FLOW.fullmatch(s) is not None:
        app(s)
        return k
    close = "]" if first == "[" else "}"
    parts = [s]
    while close not in s:
        if k >= len(lines):
            raise _Decline
        s = lines[k]
        k += 1
        if s[: n + 1].strip():  # a continuation line must be indented further
            raise _Decline
        parts.append(s)
    text = " ".join(parts).rstrip(" ")
    if _FLOW.fullmatch(text) is None:
        raise _Decline
    app(text)
    return k


# YAML 1.1 (PyYAML) and 1.2's core schema (yaml-rs) read some plain scalars differently:
# leading-zero (octal in 1.1) and 0o integers, exponents without a dot (text in 1.1),
# yes/no/on/off/y/n (booleans in 1.1), sexagesimal 1:20 (a number in 1.1); and tags,
# complex keys and merge keys. The text is screened for the numbers, the parsed values for
# the words (a walk that also bounds the depth).
_WORDS_1_1 = frozenset({"yes", "no", "on", "off", "y", "n"})
_SEXAGESIMAL = re.compile(r"[-+]?[0-9][0-9_]*(?::[0-5]?[0-9])+(?:\.[0-9_]*)?")


_WINDOW = 32  # characters looked back from an exponent for the number's start and dot


def numbers_read_differently(text: str) -> bool:
    """A number in ``text`` that YAML 1.1 and 1.2 read differently (see above): byte masks
    over the text, then a window before each exponent (a regex scan of a 30 MB file takes
    seconds).

    Parameters
    ----------
    text : str
        The YAML text.

    Returns
    -------
    bool
    """
    # anchors and aliases too: the guarded composer bounds their expansion as it goes
    # (yaml-rs replays aliases up to its own limit first, 10⁷ events: seconds)
    if "0o" in text or "!" in text or "<<" in text or "? " in text or "&" in text:
        return True
    b = np.frombuffer(text.encode("utf-8"), dtype=np.uint8)
    n = b.size
    if n < 2:
        return False
    digit = (b >= 48) & (b <= 57)
    low = b | 32
    word = digit | (low >= 97) & (low <= 122) | (b == 95) | (b >= 128)
    sign = (b == 43) | (b == 45)
    # an integer with a leading zero (0 then a digit) at the start of a number: after a
    # character that is no part of a number or word, or after a sign that is not an
    # exponent's (1.0e-05 is a float in both)
    lead = np.flatnonzero((b[:-1] == 48) & digit[1:])
    if lead.size:
        p1 = np.where(lead >= 1, b[np.maximum(lead - 1, 0)], 32)
        p2 = np.where(lead >= 2, b[np.maximum(lead - 2, 0)], 32)
        free1 = ~(word[np.maximum(lead - 1, 0)] | (p1 == 46) | (p1 == 43) | (p1 == 45)) | (
            lead == 0
        )
        signed = ((p1 == 43) | (p1 == 45)) & ((p2 | 32) != 101)
        signed &= ~(word[np.maximum(lead - 2, 0)] | (p2 == 46)) | (lead < 2)
        if np.any(free1 | signed):
            return True
    # an underscore between digits in a number (not in a word such as n1_2): yaml-rs and
    # PyYAML both read 0_05 as 5; the composer refuses it, naming the line
    u_at = np.flatnonzero((b[1:-1] == 95) & digit[:-2] & digit[2:]) + 1
    if u_at.size:
        back = u_at[:, None] - np.arange(1, _WINDOW + 1)[None, :]
        ch = b[np.maximum(back, 0)]
        inside = (back >= 0) & (((ch >= 48) & (ch <= 57)) | (ch == 46) | (ch == 95))
        length = np.cumprod(inside, axis=1).astype(bool).sum(axis=1)
        start = u_at - length - 1  # the character before the number's digits
        led_by_word = (start >= 0) & word[np.maximum(start, 0)]
        if np.any(~led_by_word | (length >= _WINDOW)):
            return True
    # an exponent (d e [+-]? d) whose mantissa has no dot since the number began
    e_at = np.flatnonzero((low[1:-1] == 101) & digit[:-2] & (digit[2:] | sign[2:])) + 1
    if e_at.size:
        back = e_at[:, None] - np.arange(1, _WINDOW + 1)[None, :]  # (k, W): k-1, k-2, …
        ch = b[np.maximum(back, 0)]
        inside = (back >= 0) & (
            ((ch >= 48) & (ch <= 57)) | (ch == 46) | (ch == 95) | (ch == 43) | (ch == 45)
        )
        run = np.cumprod(inside, axis=1).astype(bool)  # still within the number
        dot = np.any(run & (ch == 46), axis=1)
        length = run.sum(axis=1)
        before = np.where(
            length < _WINDOW, ch[np.arange(e_at.size), np.minimum(length, _WINDOW - 1)], 32
        )
        led = (length < back.shape[1]) & (e_at - length - 1 >= 0)
        led_by_word = led & word[np.maximum(e_at - length - 1, 0)]
        if np.any(~dot & ~led_by_word & (length < _WINDOW)):
            return True
        del before
    return False


def values_read_differently(doc: Any, max_depth: int, where: str) -> bool:
    """Bound the depth (``max_depth``) and say whether a parsed value reads differently
    under YAML 1.1: a word of 1.1's booleans, a sexagesimal text, a key that is not text
    or a number.

    Parameters
    ----------
    doc : Any
        The parsed document.
    max_depth : int
        Nesting allowed.
    where : str
        The file, for the message.

    Returns
    -------
    bool

    Raises
    ------
    InputError
        Nested deeper than ``max_depth``.
    """
    stack = [(doc, 1)] if isinstance(doc, (dict, list)) else []
    while stack:
        x, d = stack.pop()
        if d > max_depth:
            raise InputError(f"nested deeper than {max_depth} levels", field=where)
        if isinstance(x, dict):
            for k in x:
                if (
                    not isinstance(k, (str, int, float))
                    or isinstance(k, str)
                    and (k.lower() in _WORDS_1_1 or _SEXAGESIMAL.fullmatch(k))
                ):
                    return True
            items: Any = x.values()
        else:
            items = x
        for v in items:
            if isinstance(v, (dict, list)):
                stack.append((v, d + 1))
            elif isinstance(v, str) and (v.lower() in _WORDS_1_1 or _SEXAGESIMAL.fullmatch(v)):
                return True
    return False


def load_compiled(text: str, where: str, max_nodes: int) -> Any:
    """A large YAML text by yaml-rs (Rust, YAML 1.2 core schema): any style a machine
    writes (flow mappings, block style, JSON text) at 10⁵ agents in about a second, where
    the iterative composer above takes 30-150 s. Its own limits bound the work before any
    object is built: nesting (a few hundred levels; the caller bounds the depth with
    :func:`values_read_differently`), alias replays (``max_nodes`` events) and duplicate
    keys (refused).

    Chosen over ryaml (serde_yaml, unmaintained upstream, 1.5-2x slower on the same files)
    and rapidyaml (a tree API that needs a Python loop per node), side by side in
    ``benchmarks/bench_inputs.py``.

    Parameters
    ----------
    text : str
        The YAML text.
    where : str
        The file, for the message.
    max_nodes : int
        Alias replays allowed.

    Returns
    -------
    Any

    Raises
    ------
    InputError
        Not valid YAML, or past a limit.
    """
    import yaml_rs

    limits = yaml_rs.AliasLimits(max_total_replayed_events=max_nodes)
    try:
        doc = yaml_rs.loads(
            text,
            parse_datetime=False,
            alias_limits=limits,
            duplicate_key_policy=yaml_rs.DuplicateKeyPolicy.Error,
        )
    except (yaml_rs.YAMLDecodeError, ValueError, RecursionError) as exc:
        first = str(exc).strip().splitlines()[0] if str(exc).strip() else "malformed YAML"
        raise InputError(f"not valid YAML ({one_line(first)[:120]})", field=where) from None
    return doc


__all__ = [
    "load_compiled",
    "load_fast",
    "node_bound",
    "numbers_read_differently",
    "quote_words",
    "values_read_differently",
]
