"""Lossy links for the digital protocol: at each step the message on edge e arrives with
probability 1 − p_e, independently across edges and steps; the informed agents' own term
δ_i B_i is local and never lost. A lost message is handled by one of three policies:

- ``skip``: the agent leaves that edge's term, and its measurement noise, out of the step;
- ``rescale``: received terms are divided by 1 − p_e (the mean drift is unbiased);
- ``hold``: the agent uses the last measurement it received on that edge (before the
  first arrival, the noiseless A_ij x_j(0) − |A_ij| x_i(0)).

This module holds the checks of the input (p in [0, 1) and finite, a known policy, a
per-edge loss only on an edge of the topology) and the per-edge losses p_e of a topology.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Mapping, Sequence
from typing import cast

import numpy as np

from ..choices import LossPolicy, choices
from ..errors import InputError, real_float

#: The policies for a lost message, in the order the docs list them.
POLICIES = choices(LossPolicy)


def require_loss(name: str, value: object) -> float:
    """A loss probability p: a finite number in [0, 1).

    Parameters
    ----------
    name : str
        The field or flag named in the message.
    value : object
        The value as read.

    Returns
    -------
    float

    Raises
    ------
    InputError
        Not a number, not finite, or outside [0, 1).

    Examples
    --------
    >>> require_loss("digital.loss", 0.1)
    0.1
    """
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise InputError(f"expected a loss probability in [0, 1), got {value!r:.60}", field=name)
    p = real_float(name, value)
    if not math.isfinite(p) or not 0.0 <= p < 1.0:
        raise InputError(f"a loss probability must be finite and in [0, 1), got {p!r}", field=name)
    return p


def require_policy(name: str, value: object) -> LossPolicy:
    """A policy for lost messages: one of :data:`POLICIES`.

    Parameters
    ----------
    name : str
        The field or flag named in the message.
    value : object
        The value as read.

    Returns
    -------
    str

    Raises
    ------
    InputError
        Anything else.
    """
    if not isinstance(value, str) or value not in POLICIES:
        shown = repr(value) if not isinstance(value, str) else repr(value[:40])
        raise InputError(f"unknown policy {shown} (known: {', '.join(POLICIES)})", field=name)
    return cast("LossPolicy", value)


def edge_losses(
    edges: Sequence[tuple[int, int]],
    labels: Sequence[object],
    loss: float,
    per_edge: Mapping[tuple[str, str], float] | None = None,
    name: str = "loss",
) -> np.ndarray:
    """The loss p_e of every edge: the edge's own (keyed by its (from, to) labels) over
    the uniform one.

    Parameters
    ----------
    edges : sequence of (int, int)
        The edges (i, j), j -> i, in the topology's order.
    labels : sequence
        The agents' labels.
    loss : float
        p of an edge without its own.
    per_edge : mapping of (str, str) to float, optional
        Per-edge losses keyed by (from, to) labels.
    name : str, optional
        The field named when a per-edge loss names a missing edge.

    Returns
    -------
    numpy.ndarray
        (E,) p_e.

    Raises
    ------
    InputError
        A per-edge loss on an edge that is not in the topology, or a bad value.

    Examples
    --------
    >>> edge_losses([(1, 0), (0, 1)], ["a", "b"], 0.1, {("b", "a"): 0.5}).tolist()
    [0.1, 0.5]
    """
    p = require_loss(name, loss)
    own = {(str(a), str(b)): v for (a, b), v in (per_edge or {}).items()}
    known = {(str(labels[j]), str(labels[i])) for i, j in edges}
    for key, v in own.items():
        if key not in known:
            raise InputError(f"no edge {key[0]}->{key[1]} in the topology", field=name)
        require_loss(f"{name} of edge {key[0]}->{key[1]}", v)
    return np.array(
        [float(own.get((str(labels[j]), str(labels[i])), p)) for i, j in edges], dtype=float
    )


def loss_width(nd_: int, delay: int, n_edges: int, d: int, policy: str) -> int:
    """W, the length of the augmented state (e_k … e_{k−D}, 1, and the held y_e for hold).

    Parameters
    ----------
    nd_ : int
        N·d.
    delay : int
        D.
    n_edges : int
        E.
    d : int
        The state dimension.
    policy : str
        The policy.

    Returns
    -------
    int

    Examples
    --------
    >>> loss_width(21, 1, 8, 3, "hold")  # G1 at D = 1: two states, the 1, 8 held d-vectors
    67
    """
    return (delay + 1) * nd_ + 1 + (n_edges * d if policy == "hold" else 0)


__all__ = ["POLICIES", "edge_losses", "loss_width", "require_loss", "require_policy"]
