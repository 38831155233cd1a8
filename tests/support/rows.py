"""Text of an HTML fragment without tags and with whitespace squashed."""

import html
import re


def _text(html_text: str) -> str:
    """The visible text of an HTML fragment, entities decoded, whitespace collapsed."""
    return " ".join(html.unescape(re.sub(r"<[^>]+>", " ", html_text)).split())


def _squash(s: str) -> str:
    return " ".join(s.split())
