"""A fast reader for the plain subset of YAML that machine-written topology files use.

PyYAML's constructor (Python code run for every node) costs most of the time of reading a
large YAML file. Files written by ``yaml.safe_dump(..., default_flow_style=None)`` (as
:func:`ntc_design.generate.write_topology` writes them) use a small subset of YAML: block
mappings and sequences by indentation, flow lists and mappings of scalars (never nested),
and plain scalars that are identifiers or decimal numbers. Such a text is rewritten as
JSON by a few regular-expression passes and one loop over its lines, and parsed by the
``json`` module's C decoder.

The subset is checked strictly and cheaply first; a text outside it (anchors, aliases,
tags, quotes, comments, nested flow collections, YAML 1.1 words such as ``yes`` or
``null``, numbers in any form but ``-12``/``1.5``/``1.5e-07``, ...) is declined (``None``)
and read by the full reader (:func:`ntc_design.files.read_document`), which then gives the
same document or the same error as before. Within the subset every scalar is resolved as
PyYAML's safe loader resolves it: identifiers are strings, the numbers ints and floats of
the same value. Nothing is evaluated.
"""

from __future__ import annotations

import gc
import json
import re
from typing import Any

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


__all__ = ["load_fast", "node_bound", "quote_words"]
