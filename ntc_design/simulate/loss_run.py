"""What a run of the digital protocol on lossy links adds to the driver: the per-edge
losses, the exact moments and the Monte Carlo of :mod:`.loss` and :mod:`.loss_mc`, and
the ``digital.loss`` block of the summary (:class:`LossPlan`)."""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

import numpy as np

from ..errors import InputError
from ..model import Topology
from ..protocol.digital import Digital
from ..protocol.loss import edge_losses
from .digital import DigitalMoments
from .grid import TimeGrid
from .loss import check_loss_moments, loss_moments, loss_note
from .system import ModeSystem


@dataclass(frozen=True, eq=False)
class LossPlan:
    """One topology's lossy links: the mode, p_e per edge, the policy and θ.

    Attributes
    ----------
    system : ModeSystem
        The mode.
    loss : numpy.ndarray
        (E,) p_e.
    policy : str
        ``skip``, ``rescale`` or ``hold``.
    theta : numpy.ndarray
        θ.
    offsets : list of float
        ‖lim E x − 1⊗θ‖, appended when the exact moments ran.
    """

    system: ModeSystem
    loss: np.ndarray
    policy: str
    theta: np.ndarray
    offsets: list = field(default_factory=list)

    def check(self, delay: int) -> None:
        """Refuse exact moments that would not fit (:func:`.loss.check_loss_moments`).

        Parameters
        ----------
        delay : int
            D.

        Raises
        ------
        InputError
            Too large.
        """
        s = self.system
        check_loss_moments(s.nd, delay, s.n_edges, s.dim, self.policy)

    def moments(
        self, grid: TimeGrid, gain: Callable, eps0: np.ndarray, delay: int
    ) -> DigitalMoments:
        """The exact moments (:func:`.loss.loss_moments`), the offset kept.

        Parameters
        ----------
        grid : TimeGrid
            The sampling grid.
        gain : callable
            Vectorised c(t).
        eps0 : numpy.ndarray
            e_0.
        delay : int
            D.

        Returns
        -------
        DigitalMoments
        """
        lm = loss_moments(self.system, grid, gain, eps0, self.theta, delay, self.loss, self.policy)
        self.offsets.append(lm.offset)
        return DigitalMoments(lm.moments, lm.peak, lm.peak_time)

    def block(self) -> dict:
        """The summary's ``digital.loss`` block.

        Returns
        -------
        dict
            ``policy``, ``p`` (the largest p_e), ``offset`` (None without exact moments).
        """
        return {
            "policy": self.policy,
            "p": float(np.max(self.loss, initial=0.0)),
            "offset": self.offsets[-1] if self.offsets else None,
        }

    def note(self, n: int) -> str | None:
        """What the run says about where the mean goes (None without exact moments).

        Parameters
        ----------
        n : int
            N.

        Returns
        -------
        str or None
        """
        if not self.offsets:
            return None
        norm = float(np.linalg.norm(np.tile(self.theta, n)))
        return loss_note(self.policy, self.loss, self.offsets[-1], norm)


def topology_losses(topology: object) -> dict[tuple[str, str], float]:
    """A topology file's per-edge ``loss:`` values keyed by (from, to) labels (none for
    anything but one fixed topology).

    Parameters
    ----------
    topology : object
        The run's network.

    Returns
    -------
    dict of (str, str) to float
    """
    if not isinstance(topology, Topology):
        return {}
    lab = topology.labels
    return {(str(lab[j]), str(lab[i])): float(v) for (i, j), v in topology.loss.items()}


def loss_plan(
    digital: Digital | None,
    systems: list[ModeSystem],
    theta: np.ndarray,
    single: bool,
    per_edge: Mapping[tuple[str, str], float] | None = None,
    device: str = "cpu",
) -> LossPlan | None:
    """The lossy links of a run, or None when no message is lost.

    Parameters
    ----------
    digital : Digital or None
        The sampled protocol.
    systems : list of ModeSystem
        The modes.
    theta : numpy.ndarray
        θ.
    single : bool
        Whether the run is on one fixed topology (lossy links are modelled there only).
    per_edge : mapping of (str, str) to float, optional
        Per-edge losses keyed by (from, to) labels (the topology file's ``loss:``).
    device : str, optional
        Where the Monte Carlo runs (kept for the caller; both devices run lossy links).

    Returns
    -------
    LossPlan or None

    Raises
    ------
    InputError
        Lossy links on a switching set or a sampled A(t), or a per-edge loss on a missing
        edge.
    """
    if digital is None or not (digital.lossy or per_edge):
        return None
    if not single or len(systems) != 1:
        raise InputError(
            "lossy links are modelled on one fixed topology (not a switching "
            "set or a sampled A(t))",
            field="digital.loss",
        )
    s = systems[0]
    edges = list(zip(s.dst.tolist(), s.src.tolist(), strict=True))
    p = edge_losses(edges, s.labels, digital.loss, per_edge, "digital.loss")
    if not np.any(p > 0):
        return None
    return LossPlan(s, p, digital.policy, np.asarray(theta, dtype=float))


__all__ = ["LossPlan", "loss_plan", "topology_losses"]
