"""Small inline SVG pictures for notebooks (``_repr_html_``), drawn without matplotlib so
that every layer can show itself: a network on a circle and a curve on a log axis. The
report's journal figures are :mod:`ntc_design.reports`'; these are previews."""

from __future__ import annotations

import html
import math
from collections.abc import Sequence

import numpy as np

BLUE, RED, GREEN, GREY = "#1f5fbf", "#c8322d", "#2a7d4f", "#777777"
MAX_DRAWN = 40  # agents drawn on a circle; above this a table says it all


def network_svg(
    labels: Sequence,
    edges: Sequence[tuple[int, int, int, bool]],
    informed: Sequence[int] = (),
    size: int = 260,
) -> str:
    """Agents on a circle, an arrow j -> i per edge: blue positive, red negative, dashed
    semidefinite; informed agents ringed in green.

    Parameters
    ----------
    labels : sequence
        The agent labels.
    edges : sequence of (i, j, sign, definite)
        Edge j -> i, the sign of A_ij and whether it is definite.
    informed : sequence of int, optional
        Agents ringed in green.
    size : int, optional
        Width and height in pixels.

    Returns
    -------
    str
        An ``<svg>`` element; empty for more than MAX_DRAWN agents.
    """
    n = len(labels)
    if n == 0 or n > MAX_DRAWN:
        return ""
    c, r, rv = size / 2, size / 2 - 22, 10
    ang = [math.pi / 2 - 2 * math.pi * k / n for k in range(n)]
    xy = [(c + r * math.cos(a), c - r * math.sin(a)) for a in ang]
    parts = [
        f'<svg xmlns="http://www.w3.org/2000/svg" width="{size}" height="{size}" '
        f'viewBox="0 0 {size} {size}" font-family="sans-serif" font-size="10">',
        '<defs><marker id="ah" viewBox="0 0 10 10" refX="10" refY="5" markerWidth="6" '
        'markerHeight="6" orient="auto-start-reverse"><path d="M0,0 L10,5 L0,10 z" '
        'fill="context-stroke"/></marker></defs>',
    ]
    for i, j, sign, definite in edges:
        (x1, y1), (x2, y2) = xy[j], xy[i]
        dx, dy = x2 - x1, y2 - y1
        d = math.hypot(dx, dy) or 1.0
        x1, y1 = x1 + dx / d * rv, y1 + dy / d * rv
        x2, y2 = x2 - dx / d * (rv + 1), y2 - dy / d * (rv + 1)
        dash = "" if definite else ' stroke-dasharray="4 3"'
        colour = BLUE if sign > 0 else RED
        parts.append(
            f'<line x1="{x1:.1f}" y1="{y1:.1f}" x2="{x2:.1f}" y2="{y2:.1f}" stroke="{colour}" '
            f'stroke-width="1.2"{dash} marker-end="url(#ah)"/>'
        )
    ring = set(informed)
    for k, (x, y) in enumerate(xy):
        edge = GREEN if k in ring else "black"
        parts.append(
            f'<circle cx="{x:.1f}" cy="{y:.1f}" r="{rv}" fill="white" stroke="{edge}" '
            f'stroke-width="{2 if k in ring else 1}"/>'
            f'<text x="{x:.1f}" y="{y + 3.5:.1f}" text-anchor="middle">'
            f"{html.escape(str(labels[k]))}</text>"
        )
    parts.append("</svg>")
    return "".join(parts)


def curve_svg(
    t: np.ndarray, ys: Sequence[tuple[str, np.ndarray, str]], width: int = 420, height: int = 200
) -> str:
    """Curves against t on a logarithmic y axis (positive values only).

    Parameters
    ----------
    t : numpy.ndarray
        The abscissae.
    ys : sequence of (label, values, colour)
        The curves.
    width, height : int, optional
        Size in pixels.

    Returns
    -------
    str
        An ``<svg>`` element; empty when no curve has a positive finite value.
    """
    t = np.asarray(t, dtype=float)
    vals = [np.asarray(y, dtype=float) for _, y, _ in ys]
    pos = np.concatenate([v[np.isfinite(v) & (v > 0)] for v in vals]) if vals else np.zeros(0)
    if pos.size == 0 or t.size < 2:
        return ""
    lo, hi = math.log10(pos.min()), math.log10(pos.max())
    hi = hi if hi > lo else lo + 1
    left, bottom, top, right = 50, 28, 10, 10

    def px(x: float, y: float) -> tuple[float, float]:
        fx = (x - t[0]) / ((t[-1] - t[0]) or 1.0)
        fy = (math.log10(y) - lo) / (hi - lo)
        return left + fx * (width - left - right), height - bottom - fy * (height - bottom - top)

    parts = [
        f'<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" '
        f'font-family="sans-serif" font-size="10">',
        f'<line x1="{left}" y1="{height - bottom}" x2="{width - right}" y2="{height - bottom}" stroke="black"/>',
        f'<line x1="{left}" y1="{top}" x2="{left}" y2="{height - bottom}" stroke="black"/>',
        f'<text x="{left - 4}" y="{top + 8}" text-anchor="end">{10**hi:.2g}</text>',
        f'<text x="{left - 4}" y="{height - bottom}" text-anchor="end">{10**lo:.2g}</text>',
        f'<text x="{left}" y="{height - 10}">t = {t[0]:g}</text>',
        f'<text x="{width - right}" y="{height - 10}" text-anchor="end">t = {t[-1]:g}</text>',
    ]
    for k, ((label, _, colour), v) in enumerate(zip(ys, vals, strict=True)):
        ok = np.isfinite(v) & (v > 0)
        pts = " ".join(
            f"{a:.1f},{b:.1f}" for a, b in (px(x, y) for x, y in zip(t[ok], v[ok], strict=True))
        )
        parts.append(f'<polyline points="{pts}" fill="none" stroke="{colour}" stroke-width="1.3"/>')
        parts.append(
            f'<text x="{width - right}" y="{top + 10 + 12 * k}" text-anchor="end" fill="{colour}">'
            f"{html.escape(label)}</text>"
        )
    parts.append("</svg>")
    return "".join(parts)


__all__ = ["curve_svg", "network_svg"]
