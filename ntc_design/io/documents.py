"""Reading a YAML or JSON document from a file, under limits: bytes, nesting depth and
nodes with every alias expanded (each refused with one line naming the file). Large YAML
texts go through the compiled reader (:mod:`ntc_design.io.yamlfast`) when it reads them as
PyYAML does. What the document means is the business of :mod:`ntc_design.io.files`."""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import Any

import yaml

from ..errors import InputError
from .yamlfast import load_compiled, load_fast, numbers_read_differently, values_read_differently


def type_name(x: Any) -> str:
    """What a value is, for a message ("nothing" for None).

    Parameters
    ----------
    x : any
        A value read from a document.

    Returns
    -------
    str
        Its type's name, or "nothing".
    """
    return "nothing" if x is None else type(x).__name__


#: Parsing limits (each refused with one line naming the file): bytes in one file, nesting
#: of mappings and lists, and nodes of a YAML document counted with every alias expanded
#: (a "billion laughs" document of a few hundred bytes expands to 10⁹ nodes).
MAX_FILE_BYTES = 64 * 2**20
MAX_DEPTH = 64
MAX_EXPANDED_NODES = 20_000_000
#: YAML texts from this size on are parsed by yaml-rs, unless a scalar in them reads
#: differently under YAML 1.1 (PyYAML, every smaller file) and 1.2: then by PyYAML's rules
#: too, so a file means the same at every size. A JSON text is read as JSON at any size.
COMPILED_YAML_MIN_CHARS = 1 << 20

_Loader = getattr(yaml, "CSafeLoader", yaml.SafeLoader)  # libyaml's parser where present
_NUMBER_TAGS = ("tag:yaml.org,2002:int", "tag:yaml.org,2002:float")


def read_document(path: str | Path) -> dict[str, Any]:
    """Read a YAML or JSON mapping from ``path`` (JSON by the ``.json`` suffix).

    Parameters
    ----------
    path : str or Path
        The file.

    Returns
    -------
    dict
        The top-level mapping.

    Raises
    ------
    InputError
        One line naming the file: missing or unreadable, larger than
        :data:`MAX_FILE_BYTES`, not valid YAML/JSON, nested deeper than :data:`MAX_DEPTH`,
        a YAML document expanding (through aliases) to more than
        :data:`MAX_EXPANDED_NODES` nodes or with a recursive alias, an integer with more
        than 4300 digits, or a top level that is not a mapping.
    """
    p = Path(path)
    try:
        exists = p.is_file()
        size = p.stat().st_size if exists else 0
    except (OSError, ValueError) as exc:  # a name with a NUL byte, a loop of links
        raise InputError(f"cannot read the file ({exc.__class__.__name__})", field=str(p)) from None
    if not exists:
        if p.is_dir():
            raise InputError(f"is a folder, expected a file (e.g. {p / 'g1.yaml'})", field=str(p))
        kind = "not a regular file (a device, pipe or socket)" if p.exists() else "no such file"
        raise InputError(f"{kind}", field=str(p))
    if size > MAX_FILE_BYTES:
        raise InputError(
            f"file of {size / 2**20:.0f} MB is larger than the {MAX_FILE_BYTES // 2**20} MB limit",
            field=str(p),
        )
    try:
        with p.open("rb") as fh:
            raw = fh.read(MAX_FILE_BYTES + 1)
        text = raw.decode("utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"cannot read the file ({exc.__class__.__name__})", field=str(p)) from None
    if len(raw) > MAX_FILE_BYTES:
        raise InputError(f"larger than the {MAX_FILE_BYTES // 2**20} MB limit", field=str(p))
    if not text.strip():
        raise InputError("the file is empty", field=str(p))
    try:
        if p.suffix.lower() == ".json":
            doc = json.loads(text)
            _check_depth(doc, p)
        else:
            doc = _load_yaml(text, p)
    except InputError:
        raise
    except json.JSONDecodeError as exc:
        raise InputError(f"not valid JSON (line {exc.lineno}: {exc.msg})", field=str(p)) from None
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        line = f"line {mark.line + 1}: " if mark is not None else ""
        problem = getattr(exc, "problem", None) or "malformed YAML"
        raise InputError(f"not valid YAML ({line}{problem})", field=str(p)) from None
    except RecursionError:
        raise InputError(f"nested deeper than {MAX_DEPTH} levels", field=str(p)) from None
    except ValueError as exc:  # int('9' * 5000): Python's 4300-digit limit
        if "digits" in str(exc):
            raise InputError("an integer with too many digits", field=str(p)) from None
        raise InputError(
            f"a value that cannot be read ({_one_line(str(exc))})", field=str(p)
        ) from None
    if not isinstance(doc, dict):
        raise InputError(f"expected a mapping at the top level, got {type_name(doc)}", field=str(p))
    if _SURROGATE_ESCAPE.search(text):
        check_text(doc, str(p))
    return doc


#: An escape that can write a surrogate code point (JSON's \uD800, YAML's \U0000D800 too):
#: only a text holding one is walked for strings that are not Unicode text.
_SURROGATE_ESCAPE = re.compile(r"\\(?:u|U0000)[dD][89a-fA-F]")


def check_text(doc: Any, source: str) -> None:
    """Refuse a document with a string that is not Unicode text (a lone surrogate, which
    JSON's and YAML's escapes can write): it cannot be printed, encoded in UTF-8 or
    written to a file, so every later step would fail on it.

    Parameters
    ----------
    doc : any
        The document as read.
    source : str
        The file (named in the message).

    Raises
    ------
    InputError
        ``SOURCE: FIELD: a string that is not Unicode text (a lone surrogate, \\ud800)``.
    """
    stack: list[tuple[Any, str]] = [(doc, "")]
    while stack:
        x, where = stack.pop()
        items = x.items() if isinstance(x, dict) else enumerate(x) if isinstance(x, list) else ()
        for k, v in items:
            field = f"{where}[{k}]" if isinstance(x, list) else f"{where}.{k}" if where else str(k)
            for s in (k, v):
                if isinstance(s, str) and not s.isascii():
                    bad = next((c for c in s if "\ud800" <= c <= "\udfff"), None)
                    if bad is not None:
                        shown = field.encode("utf-8", "backslashreplace").decode("ascii")
                        raise InputError(
                            f"a string that is not Unicode text (a lone "
                            f"surrogate, \\u{ord(bad):04x})",
                            field=f"{source}: {shown}",
                        )
            if isinstance(v, (dict, list)):
                stack.append((v, field))


def _one_line(msg: str, n: int = 80) -> str:
    msg = " ".join(msg.split())
    return msg if len(msg) <= n else msg[: n - 1] + "…"


def _check_depth(doc: Any, p: Path) -> None:
    """Refuse JSON nested deeper than MAX_DEPTH (walked iteratively)."""
    stack = [(doc, 1)] if isinstance(doc, (dict, list)) else []
    while stack:
        x, d = stack.pop()
        if d > MAX_DEPTH:
            raise InputError(f"nested deeper than {MAX_DEPTH} levels", field=str(p))
        items = x.values() if isinstance(x, dict) else x
        stack.extend((v, d + 1) for v in items if isinstance(v, (dict, list)))


def _load_yaml(text: str, p: Path) -> Any:
    """Compose YAML from libyaml's events iteratively, under the depth and alias-expansion
    limits, then construct it with PyYAML's safe constructor.

    Composing here (rather than in libyaml's composer) bounds the work before any node is
    built: libyaml's recursive composer crashes the interpreter at ~10⁵ levels of nesting,
    and is also slower than this loop on large files. A text in the plain subset that
    machine-written files use is read by :func:`ntc_design.io.yamlfast.load_fast` instead
    (the same document, several times faster).
    """
    if text.lstrip().startswith("{"):  # a JSON text (YAML holds it) is read as JSON, at
        try:  # every size (PyYAML would read 1e-05 as text)
            doc = json.loads(text)
        except (json.JSONDecodeError, RecursionError, ValueError):
            doc = None
        if doc is not None:
            _check_depth(doc, p)
            return doc
    if len(text) >= COMPILED_YAML_MIN_CHARS:
        if not numbers_read_differently(text):
            doc = load_compiled(text, str(p), MAX_EXPANDED_NODES)
            if not values_read_differently(doc, MAX_DEPTH, str(p)):
                return doc
        # a scalar that YAML 1.1 (PyYAML, every smaller file) and 1.2 (yaml-rs) read
        # differently, or a tag: the one set of rules, at the slower pace
    doc = load_fast(text, MAX_DEPTH, MAX_EXPANDED_NODES)
    if doc is not None:
        return doc
    loader = _Loader(text)
    try:
        loader.get_event()  # StreamStart
        if not loader.check_event(yaml.DocumentStartEvent):
            loader.get_event()
            return None
        loader.get_event()
        root = None if loader.check_event(yaml.DocumentEndEvent) else _compose(loader, p)
        loader.get_event()  # DocumentEnd
        if not loader.check_event(yaml.StreamEndEvent):
            ev = loader.get_event()
            raise InputError(
                f"not valid YAML (line {ev.start_mark.line + 1}: expected a single document)",
                field=str(p),
            )
        return loader.construct_document(root)
    finally:
        loader.dispose()


def _compose(loader: Any, p: Path) -> Any:
    scalar, seq, mapping = yaml.ScalarNode, yaml.SequenceNode, yaml.MappingNode
    anchors: dict[str, Any] = {}
    sizes: dict[int, int] = {}  # id(node) -> nodes it stands for, aliases expanded
    open_anchors: set[str] = set()
    # stack of [node, expanded size so far, anchor, pending mapping key]
    stack: list[list[Any]] = []
    root = None

    def attach(node: Any, size: int) -> None:
        nonlocal root
        if not stack:
            root = node
            return
        top = stack[-1]
        top[1] += size
        if top[1] > MAX_EXPANDED_NODES:
            raise InputError(
                f"the document expands to more than {MAX_EXPANDED_NODES} nodes through aliases",
                field=str(p),
            )
        if top[0].__class__ is seq:
            top[0].value.append(node)
        elif top[3] is None:
            top[3] = node
        else:
            top[0].value.append((top[3], node))
            top[3] = None

    resolved: dict[tuple[str, Any], str] = {}  # the resolver's regexes are slow; values repeat
    get_event = loader.get_event
    while True:
        ev = get_event()
        cls = ev.__class__
        if cls is yaml.ScalarEvent:
            tag = ev.tag
            if tag is None or tag == "!":
                key = (ev.value, ev.implicit)
                tag = resolved.get(key)
                if tag is None:
                    tag = resolved[key] = loader.resolve(scalar, ev.value, ev.implicit)
                    if "_" in ev.value and tag in _NUMBER_TAGS:  # YAML 1.1: 0_05 is 5
                        raise InputError(
                            f"line {ev.start_mark.line + 1}: {ev.value[:40]!r} is a number "
                            "with underscores (YAML 1.1 reads 0_05 as 5, 1_0 as 10); write it "
                            "without them",
                            field=str(p),
                        )
            node = scalar(tag, ev.value, ev.start_mark, ev.end_mark, style=ev.style)
            if ev.anchor is not None:
                anchors[ev.anchor] = node
                sizes[id(node)] = 1
            attach(node, 1)
        elif cls is yaml.AliasEvent:
            if ev.anchor not in anchors:
                raise InputError(
                    f"not valid YAML (line {ev.start_mark.line + 1}: undefined alias "
                    f"{ev.anchor!r})",
                    field=str(p),
                )
            if ev.anchor in open_anchors:
                raise InputError(
                    f"recursive alias {ev.anchor!r} (line {ev.start_mark.line + 1})", field=str(p)
                )
            node = anchors[ev.anchor]
            attach(node, sizes[id(node)])
        elif cls is yaml.SequenceStartEvent or cls is yaml.MappingStartEvent:
            if len(stack) >= MAX_DEPTH:
                raise InputError(f"nested deeper than {MAX_DEPTH} levels", field=str(p))
            kind = seq if cls is yaml.SequenceStartEvent else mapping
            tag = ev.tag
            if tag is None or tag == "!":
                tag = loader.resolve(kind, None, ev.implicit)
            node = kind(tag, [], ev.start_mark, None, flow_style=ev.flow_style)
            if ev.anchor is not None:
                anchors[ev.anchor] = node
                open_anchors.add(ev.anchor)
            stack.append([node, 1, ev.anchor, None])
        elif cls is yaml.SequenceEndEvent or cls is yaml.MappingEndEvent:
            node, size, anchor, _ = stack.pop()
            node.end_mark = ev.end_mark
            if anchor is not None:
                open_anchors.discard(anchor)
                if anchors.get(anchor) is node:
                    sizes[id(node)] = size
            attach(node, size)
            if not stack:
                return root
        else:  # pragma: no cover - the parser emits nothing else inside a document
            raise InputError(f"not valid YAML (unexpected {cls.__name__})", field=str(p))
        if root is not None and not stack:
            return root


__all__ = [
    "MAX_DEPTH",
    "MAX_EXPANDED_NODES",
    "MAX_FILE_BYTES",
    "check_text",
    "read_document",
    "type_name",
]
