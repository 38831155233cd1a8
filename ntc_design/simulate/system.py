"""The semi-autonomous network with compound noise (Niu & Wu, eq. (5)) as sparse matrices
and edge arrays.

For one mode with design (L_B, x0, B_i) and noise (σ_ji, f_ji), on the stacked state
x ∈ R^{Nd}:

    dx = c(t) [ (u − L_B x) dt + Σ_e g_e dw_1e + Σ_e |A_ij| f(x_j − x_i) dw_2e ]

with one edge e = (j -> i) per nonzero A_ij, ``u = (Δ⊗I_d) B x0`` and
``g_e = e_i ⊗ (σ_ji |A_ij| 1_d)``. The drift is Lemma 1's SAN drift: Σ|A_ij|(sgn x_j − x_i)
+ δ_i|B_i|(x0 − x_i) = −(L_B x)_i + u_i.

Everything is stored per edge (``src`` = j, ``dst`` = i, d×d blocks) and L_B as a
``scipy.sparse`` matrix, so memory and the cost of a step grow with the number of edges,
not with (Nd)². The Monte Carlo kernel (:mod:`.kernels`) reads L_B in CSR form and the
edge arrays; the matrices ``g`` (Nd×E), ``dmat`` (Ed×Nd, the edge
differences) and ``wmat`` (Nd×Ed, |A_ij| into agent i) are built on request, sparse.

The step-size guard (:func:`check_step_size`) uses every eigenvalue of L_B up to
``DENSE_EIG_MAX_ND``; above it, every eigenvalue of each strongly connected component
of at most that many rows (L_B is block triangular in them: a directed chain or tree
costs O(E)) and ARPACK's largest- and smallest-modulus eigenvalues of the larger ones
(a Gershgorin bound if ARPACK does not converge).
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from dataclasses import dataclass
from functools import cached_property

import numpy as np
import scipy.sparse as sp

from ..choices import Scheme, choices
from ..errors import InputError
from ..numerics.linalg import comparison_solve
from ..protocol import ProtocolDesign
from .implicit import diagonal_blocks
from .noise import NoiseModel

DENSE_EIG_MAX_ND = 600  # every eigenvalue of L_B (dense) up to this Nd; ARPACK above
DENSE_LB_MAX_ND = 2000  # below this the design's own dense L_B is used (same numbers)
N_EIGS = 6  # eigenvalues ARPACK computes at each end of the spectrum
FLOOR_RTOL = 1e-12  # a dominance floor must exceed this times max_i |μ_i| to count


@dataclass(frozen=True)
class Spectrum:
    """What the step-size guard uses of L_B's eigenvalues."""

    rho: float  # spectral radius
    bound: float  # min over eigenvalues of 2·Re λ/|λ|²
    min_real: float  # min Re λ
    method: str  # how they were obtained


def _dominance_floor(s: ModeSystem) -> float:
    """min_i (M v)_i / v_i for the comparison matrix of L_B (see
    :attr:`ModeSystem.implicit_floor`), or −inf when dominance fails."""
    n = s.n_agents
    mu = s.block_eigenvalues[:, 0]
    nu = np.linalg.norm(s.abs_w, ord=2, axis=(1, 2)) if s.n_edges else np.zeros(0)
    m = (sp.diags(mu) - sp.csr_matrix((nu, (s.dst, s.src)), shape=(n, n))).tocsr()
    v = comparison_solve(m)
    if not np.all(v > 0):
        return -np.inf
    lo = float(np.min((m @ v) / v))
    # a floor within rounding of zero says nothing: the eigenvalues decide then
    return lo if lo > FLOOR_RTOL * float(np.max(np.abs(mu), initial=0.0)) else -np.inf


@dataclass(frozen=True, eq=False)
class ModeSystem:
    """Matrices of one mode; see the module docstring."""

    name: str
    n_agents: int
    dim: int
    labels: tuple
    lap_b: sp.csr_matrix  # Nd×Nd
    u: np.ndarray  # Nd
    dst: np.ndarray  # (E,) agent i of edge j -> i
    src: np.ndarray  # (E,) agent j
    abs_w: np.ndarray  # (E, d, d) |A_ij|
    g_edge: np.ndarray  # (E, d) σ_ji |A_ij| 1_d
    fmat: np.ndarray  # d×d F (identity when f is a callable: f is applied separately)
    f: Callable[[np.ndarray], np.ndarray] | None  # None when f is linear
    agent_noise: np.ndarray  # (N,) μ_i² = Σ_{e -> i} ‖K_e‖² (K_e = |A_ij| F)

    @cached_property
    def block_eigenvalues(self) -> np.ndarray:
        """(N, d) eigenvalues, ascending, of the symmetric parts of L_B's diagonal blocks:
        λ_max per agent for the explicit guard, λ_min (μ_i) for the implicit one."""
        blocks = diagonal_blocks(self.lap_b, self.dim)
        return np.linalg.eigvalsh(0.5 * (blocks + blocks.transpose(0, 2, 1)))

    @property
    def agent_rate(self) -> np.ndarray:
        """(N,) λ_i = λ_max of the symmetric part of the block L_B,ii."""
        return self.block_eigenvalues[:, -1]

    @cached_property
    def spectrum(self) -> Spectrum:
        """ρ(L_B), the explicit step bound and min Re λ, computed on first use (ARPACK
        with a shift-invert LU above ``DENSE_EIG_MAX_ND``: 25 s at Nd = 3·10⁵, which the
        implicit scheme does not need; see :attr:`implicit_floor`)."""
        return _eig_bounds(self.lap_b)

    @property
    def spectral_radius(self) -> float:
        """ρ(L_B)."""
        return self.spectrum.rho

    @property
    def stability_bound(self) -> float:
        """Explicit Euler on ε' = −c L_B ε is stable for c·h below this."""
        return self.spectrum.bound

    @property
    def min_real(self) -> float:
        """The smallest real part of an eigenvalue of L_B (computed or estimated)."""
        return self.spectrum.min_real

    @property
    def eig_method(self) -> str:
        """How the eigenvalues were obtained."""
        return self.spectrum.method

    @cached_property
    def implicit_floor(self) -> tuple[float, str]:
        """(a floor on min Re λ(L_B), how it was found), what the implicit scheme's guard
        needs. Above ``DENSE_EIG_MAX_ND``, first by block diagonal dominance in time linear
        in the edges (Feingold & Varga, 1962; see :mod:`ntc_design.certify.scale`): with
        μ_i = λ_min(sym L_B,ii), ν_ij = ‖A_ij‖₂ and a comparison vector v > 0 (Jacobi),
        every eigenvalue has Re λ >= min_i (M v)_i / v_i. An estimate in floating point
        (``ntc certify`` proves it); the eigenvalues are used when it is not positive."""
        if self.nd > DENSE_EIG_MAX_ND:
            lo = _dominance_floor(self)
            if lo > 0:
                return lo, "block diagonal dominance with a Jacobi comparison vector"
        return self.min_real, self.eig_method

    @property
    def n_edges(self) -> int:
        """The number of edges E (nonzero A_ij)."""
        return int(self.dst.size)

    @property
    def nd(self) -> int:
        """N·d, the size of the stacked state."""
        return self.n_agents * self.dim

    @cached_property
    def k_blocks(self) -> np.ndarray:
        """(E, d, d) ``K_e = |A_ij| F``: the multiplicative noise of edge e acts as
        ``K_e (x_j − x_i)``."""
        return np.ascontiguousarray(self.abs_w @ self.fmat)

    @property
    def h_blocks(self) -> tuple:
        """(i, j, K_e) per edge (for the exact moments)."""
        return tuple(
            (int(i), int(j), k) for i, j, k in zip(self.dst, self.src, self.k_blocks, strict=True)
        )

    def _block_matrix(self, rows, cols, blocks, shape) -> sp.csr_matrix:
        d = self.dim
        a = np.arange(d)
        r = (rows[:, None, None] * d + a[None, :, None]) * np.ones((1, 1, d), dtype=np.int64)
        c = (cols[:, None, None] * d + a[None, None, :]) * np.ones((1, d, 1), dtype=np.int64)
        return sp.csr_matrix((blocks.ravel(), (r.ravel(), c.ravel())), shape=shape)

    @cached_property
    def g(self) -> sp.csr_matrix:
        """Nd×E additive noise directions (column e = g_e)."""
        d = self.dim
        rows = (self.dst[:, None] * d + np.arange(d)).ravel()
        cols = np.repeat(np.arange(self.n_edges), d)
        return sp.csr_matrix(
            (self.g_edge.ravel(), (rows, cols)), shape=(self.nd, max(self.n_edges, 0))
        )

    @cached_property
    def dmat(self) -> sp.csr_matrix:
        """Ed×Nd edge differences ``F (x_j − x_i)`` (F = I when f is a callable)."""
        e = np.arange(self.n_edges)
        f = np.broadcast_to(self.fmat, (self.n_edges, self.dim, self.dim))
        shape = (self.n_edges * self.dim, self.nd)
        return self._block_matrix(e, self.src, f, shape) - self._block_matrix(e, self.dst, f, shape)

    @cached_property
    def wmat(self) -> sp.csr_matrix:
        """Nd×Ed: ``|A_ij|`` in block (i, e)."""
        e = np.arange(self.n_edges)
        return self._block_matrix(self.dst, e, self.abs_w, (self.nd, self.n_edges * self.dim))

    def lap_b_dense(self) -> np.ndarray:
        """L_B as a dense matrix.

        Returns
        -------
        numpy.ndarray
            L_B, Nd×Nd.
        """
        return self.lap_b.toarray()


def grounded_laplacian_sparse(des: ProtocolDesign) -> sp.csr_matrix:
    """``L_B = L + (Δ⊗I_d) blockdiag(|B_i|)`` assembled from the edge list (time and memory
    linear in the edges): blocks ``−A_ij`` at (i, j), ``Σ_j |A_ij| + δ|B_i|`` at (i, i)
    (Niu & Wu, eq. (8)).

    Parameters
    ----------
    des : ProtocolDesign
        The design.

    Returns
    -------
    scipy.sparse.csr_matrix
        L_B, Nd×Nd (the design's own dense matrix, made sparse, at small Nd).
    """
    top = des.topology
    d, n = top.dim, top.n
    if top.nd <= DENSE_LB_MAX_ND:  # the design's own matrix: the same numbers as before
        return sp.csr_matrix(des.grounded_laplacian())
    keys = list(top.weights)
    w = np.array([top.weights[k] for k in keys]).reshape(-1, d, d)
    ii = np.array([i for i, _ in keys], dtype=np.int64)
    jj = np.array([j for _, j in keys], dtype=np.int64)
    sgn = np.array([top.sign(i, j) for i, j in keys], dtype=float)
    diag = np.zeros((n, d, d))
    np.add.at(diag, ii, sgn[:, None, None] * w)
    for i, bi in des.B.items():
        diag[i] += des.delta * bi
    rows = np.concatenate([ii, np.arange(n)])
    cols = np.concatenate([jj, np.arange(n)])
    blocks = np.concatenate([-w, diag])
    a = np.arange(d)
    r = (rows[:, None, None] * d + a[None, :, None]) + np.zeros((1, 1, d), dtype=np.int64)
    c = (cols[:, None, None] * d + a[None, None, :]) + np.zeros((1, d, 1), dtype=np.int64)
    out = sp.csr_matrix((blocks.ravel(), (r.ravel(), c.ravel())), shape=(top.nd, top.nd))
    out.eliminate_zeros()
    return out


def component_eigenvalues(lap_b: sp.csr_matrix) -> tuple[np.ndarray, sp.csr_matrix | None]:
    """Every eigenvalue of the diagonal blocks of ``lap_b``'s strongly connected components
    of at most ``DENSE_EIG_MAX_ND`` rows, and the largest component left (None when none
    is larger).

    A matrix permuted to block triangular form (its components in topological order) has
    the eigenvalues of its diagonal blocks; a directed chain or tree is all 1×1 or d×d
    blocks, whose eigenvalues cost O(E) in all. ARPACK on such a non-normal matrix (one
    Jordan-like block) needed thousands of restarts: 400 s did not finish at N = 10⁵.

    Parameters
    ----------
    lap_b : scipy.sparse.csr_matrix
        L_B, Nd×Nd.

    Returns
    -------
    (numpy.ndarray, scipy.sparse.csr_matrix or None)
        The eigenvalues (complex) of the small components' blocks, and the submatrix of
        the components above ``DENSE_EIG_MAX_ND`` rows, block diagonal (for ARPACK).
    """
    from scipy.sparse.csgraph import connected_components

    nd_ = lap_b.shape[0]
    _, label = connected_components(lap_b, directed=True, connection="strong")
    size = np.bincount(label)
    order = np.argsort(label, kind="stable")
    start = np.concatenate([[0], np.cumsum(size)])
    pos = np.empty(nd_, dtype=np.int64)  # a row's place within its component
    pos[order] = np.arange(nd_) - start[label[order]]
    coo = lap_b.tocoo()
    inside = label[coo.row] == label[coo.col]
    rows, cols, vals = coo.row[inside], coo.col[inside], coo.data[inside]
    parts: list[np.ndarray] = []
    for s in np.unique(size):
        if s > DENSE_EIG_MAX_ND:
            continue
        comps = np.flatnonzero(size == s)
        slot = np.full(size.size, -1, dtype=np.int64)
        slot[comps] = np.arange(comps.size)
        per_chunk = max(1, DENSE_EIG_MAX_ND**2 // int(s) ** 2)  # the dense memory of before
        on = slot[label[rows]] >= 0
        r, c, v = rows[on], cols[on], vals[on]
        k = slot[label[r]]
        for lo in range(0, comps.size, per_chunk):
            hi = min(comps.size, lo + per_chunk)
            blocks = np.zeros((hi - lo, int(s), int(s)))
            sel = (k >= lo) & (k < hi)
            blocks[k[sel] - lo, pos[r[sel]], pos[c[sel]]] = v[sel]
            parts.append(np.linalg.eigvals(blocks).ravel() if s > 1 else blocks.ravel())
    big = np.flatnonzero(size[label] > DENSE_EIG_MAX_ND)
    rest = lap_b[big][:, big].tocsr() if big.size else None
    lam = np.concatenate(parts) if parts else np.zeros(0)
    return lam.astype(complex), rest


def _eig_bounds(lap_b: sp.csr_matrix) -> Spectrum:
    """ρ(L_B), min over eigenvalues of 2·Re λ/|λ|², min Re λ, and the method."""
    nd_ = lap_b.shape[0]
    if nd_ == 0:
        return Spectrum(0.0, np.inf, np.inf, "empty")
    if nd_ <= DENSE_EIG_MAX_ND:
        return _bounds(np.linalg.eigvals(lap_b.toarray()), "all eigenvalues")
    small, rest = component_eigenvalues(lap_b)
    if rest is None:
        return _bounds(small, "all eigenvalues, block by strongly connected component")
    found, method = _arpack(rest)
    if found is None:
        return _gershgorin(lap_b)
    if small.size:
        method += f" of the components above {DENSE_EIG_MAX_ND} rows, all of the others'"
    return _bounds(np.concatenate([small, found]), method)


def _arpack(lap_b: sp.csr_matrix) -> tuple[np.ndarray | None, str]:
    """ARPACK's ``N_EIGS`` largest- and smallest-modulus eigenvalues (None when it does
    not converge)."""
    from scipy.sparse.linalg import ArpackError, ArpackNoConvergence, eigs

    nd_ = lap_b.shape[0]
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            big = eigs(lap_b, k=N_EIGS, which="LM", return_eigenvectors=False, tol=1e-6)
            # shift-invert at 0; the smallest eigenvalues of a large network cluster
            # (many naive agents at one value), which a default Krylov space of 2k+1
            # resolves only after ~10⁴ iterations (400 s at N = 10⁴): 40 vectors
            small = eigs(
                lap_b,
                k=N_EIGS,
                sigma=0.0,
                which="LM",
                return_eigenvectors=False,
                tol=1e-3,  # a guard's estimate: 61 s at 1e-6, 1 s at 1e-3 (N = 10⁴)
                ncv=min(nd_ - 1, max(2 * N_EIGS + 1, 40)),
                maxiter=2000,
            )
    except (ArpackNoConvergence, ArpackError, RuntimeError):
        return None, ""
    lam = np.concatenate([big, small])
    return lam, f"ARPACK: {N_EIGS} largest- and {N_EIGS} smallest-modulus eigenvalues"


def _gershgorin(lap_b: sp.csr_matrix) -> Spectrum:
    """ρ <= max row sum; every Re λ >= min_i (a_ii − Σ_{j≠i}|a_ij|)."""
    absl = abs(lap_b)
    rho = float(absl.sum(axis=1).max())
    dg = lap_b.diagonal()
    lo = float(np.min(2 * dg - np.asarray(absl.sum(axis=1)).ravel()))
    bound = 2 * lo / rho**2 if lo > 0 else 0.0
    return Spectrum(rho, bound, lo, "Gershgorin discs (ARPACK did not converge)")


def _bounds(lam: np.ndarray, method: str) -> Spectrum:
    rho = float(np.max(np.abs(lam)))
    # |1 − c h λ| < 1 for every eigenvalue λ of L_B  <=>  c h < 2 Re λ / |λ|²
    with np.errstate(divide="ignore", invalid="ignore"):
        bounds = np.where(lam.real > 0, 2 * lam.real / np.abs(lam) ** 2, 0.0)
    return Spectrum(rho, float(np.min(bounds)), float(np.min(lam.real)), method)


def mode_system(des: ProtocolDesign, noise: NoiseModel, name: str = "") -> ModeSystem:
    """Edge arrays, sparse L_B and the eigenvalue bounds of one mode.

    Parameters
    ----------
    des : ProtocolDesign
        Lemma 1 design of the mode.
    noise : NoiseModel
        σ_ji and f_ji.
    name : str
        Mode name (for messages).

    Returns
    -------
    ModeSystem

    Raises
    ------
    InputError
        A per-edge σ names an edge that is not in the topology, or F has the wrong shape.
    """
    top = des.topology
    d = top.dim
    edges = top.edges  # (i, j): j -> i
    e_n = len(edges)
    term = noise.term
    fmat = term.matrix(d)
    lab = top.labels
    sig_by = {(str(a), str(b)): float(s) for (a, b), s in noise.sigma_edges.items()}
    known = {(str(lab[j]), str(lab[i])) for i, j in edges}
    for key in sig_by:
        if key not in known:
            raise InputError(
                f"no edge {key[0]}->{key[1]} in {name or 'the topology'}", field="noise.sigma_edges"
            )
    dst = np.array([i for i, _ in edges], dtype=np.int64)
    src = np.array([j for _, j in edges], dtype=np.int64)
    abs_w = np.array([top.abs_weight(i, j) for i, j in edges], dtype=float).reshape(e_n, d, d)
    sig = np.array(
        [sig_by.get((str(lab[j]), str(lab[i])), noise.sigma) for i, j in edges], dtype=float
    )
    # (σ|A|) 1_d, summed in the order of the earlier dense code (same rounding)
    g_edge = (sig[:, None, None] * abs_w).sum(axis=2)
    k_blocks = abs_w @ fmat
    knorm2 = np.linalg.norm(k_blocks, ord=2, axis=(1, 2)) ** 2 if e_n else np.zeros(0)
    mu2 = np.zeros(top.n)
    if term.linear:  # a callable f has no matrix: no mean-square estimate for it
        np.add.at(mu2, dst, knorm2)
    lap_b = grounded_laplacian_sparse(des)
    return ModeSystem(
        name=name,
        n_agents=top.n,
        dim=d,
        labels=tuple(top.labels),
        lap_b=lap_b,
        u=des.input_vector(),
        dst=dst,
        src=src,
        abs_w=np.ascontiguousarray(abs_w),
        g_edge=np.ascontiguousarray(g_edge),
        fmat=fmat,
        f=term.function,
        agent_noise=mu2,
    )


SCHEMES = choices(Scheme)


def _ms_limit(lam: np.ndarray, mu2: np.ndarray, c: np.ndarray) -> np.ndarray:
    """(2λ − cμ²)/λ², +inf where 2λ <= cμ² or λ <= 0."""
    num = 2 * lam - c * mu2
    return np.where((num > 0) & (lam > 0), num / lam**2, np.inf)


def sysw_label(s: ModeSystem, i: int) -> str:
    """An agent's label for messages.

    Parameters
    ----------
    s : ModeSystem
        The system.
    i : int
        0-based agent index.

    Returns
    -------
    str
        Its label (the index when the system has none).
    """
    return str(s.labels[i]) if s.labels else str(i)


@dataclass(frozen=True)
class StepCheck:
    """Outcome of :func:`check_step_size`: the worst ratio of c·h to its limit and a
    warning text when the step is within a factor 2 of the limit (None otherwise)."""

    ratio: float
    warning: str | None


def check_step_size(systems, grid, c_grid: np.ndarray, scheme: str = "explicit") -> StepCheck:
    """Refuse a step that makes Euler–Maruyama unstable, before anything runs.

    Explicit scheme: the drift ε' = −c L_B ε needs ``c·h < 2·Re λ/|λ|²`` for every
    eigenvalue λ of L_B (all eigenvalues up to ``DENSE_EIG_MAX_ND``; ARPACK's extreme ones
    above). The multiplicative noise tightens this in mean square. On the scalar test
    equation dX = −λX dt + μX dw, Euler–Maruyama's E X² contracts iff
    ``(1 − cλh)² + c²hμ² < 1``, i.e. ``c·h < (2λ − cμ²)/λ²``; it is applied to each
    agent alone, with λ_i = λ_max of the symmetric part of its diagonal block of L_B and
    μ_i² = Σ_{e→i}‖K_e‖² (the part of its noise that multiplies its own state), where
    2λ_i > cμ_i² (otherwise the agent alone is unstable in continuous time too: that is
    the model, not the step). Not applied for a callable f (no matrix). An estimate: on G1 it gives 0.0573 where the spectral radius
    of the exact second-moment recursion crosses 1 at h = 0.0569 (c = 1; tests).
    The implicit scheme (x_{k+1} = (I + c h L_B)^{-1}(x_k + …)) is stable in the drift for
    any step when every Re λ > 0; it is refused only when some eigenvalue has Re λ <= 0.

    Parameters
    ----------
    systems : sequence of ModeSystem
        One system per mode.
    grid : TimeGrid
        The grid (its step sizes and modes).
    c_grid : ndarray
        c(t_k) on the grid's steps.
    scheme : {"explicit", "implicit"}
        The Euler–Maruyama scheme.

    Returns
    -------
    StepCheck
        The worst ratio and a warning when it is close.

    Raises
    ------
    InputError
        The step is unstable: the message names the time, the mode, the largest stable
        step and the implicit option.
    """
    if scheme not in SCHEMES:
        raise InputError(f"must be explicit or implicit, got {scheme!r}", field="scheme")
    if grid.n_steps == 0:
        return StepCheck(0.0, None)
    if scheme == "implicit":
        for s in systems:
            floor, how = s.implicit_floor
            if not floor > 0:
                raise InputError(
                    f"implicit needs every eigenvalue of L_B with Re λ > 0; mode {s.name or 0} has "
                    f"Re λ = {floor:.4g} ({how})",
                    field="scheme",
                )
        return StepCheck(0.0, None)
    modes = grid.mode
    drift = np.array([s.stability_bound for s in systems])[modes]
    ms = np.full(grid.n_steps, np.inf)
    who = np.zeros(grid.n_steps, dtype=np.int64)
    for m, s in enumerate(systems):
        on = np.flatnonzero(modes == m)
        if on.size == 0 or s.n_agents == 0:
            continue
        c = c_grid[on]
        lam, mu2 = s.agent_rate, s.agent_noise
        # the min over agents of (2λ − cμ²)/λ² is attained on a lower envelope of lines
        # in c: keep the agents that are lowest at a few c, then evaluate them per step
        probe = np.linspace(0.0, float(c.max()), 17)
        with np.errstate(divide="ignore", invalid="ignore"):
            lim = _ms_limit(lam[:, None], mu2[:, None], probe[None, :])
            cand = np.unique(np.argmin(lim, axis=0))
            lim = _ms_limit(lam[cand, None], mu2[cand, None], c[None, :])
        ms[on] = lim.min(axis=0)
        who[on] = cand[np.argmin(lim, axis=0)]
    limit = np.minimum(drift, ms)
    ch = c_grid * grid.h
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.where(limit > 0, ch / limit, np.where(ch > 0, np.inf, 0.0))
    worst = int(np.argmax(ratio))
    r = float(ratio[worst])
    sysw = systems[modes[worst]]
    if r >= 1.0 and not limit[worst] > 0:
        raise InputError(
            f"L_B of mode {sysw.name} has an eigenvalue with Re λ <= 0 ({sysw.eig_method}): "
            "the drift is not stable and Euler–Maruyama has no stable step",
            field="dt",
        )
    if r >= 1.0:
        which = (
            f"2·Re λ/|λ|² = {drift[worst]:.4g}"
            if drift[worst] <= ms[worst]
            else f"the mean-square limit (2λ − cμ²)/λ² = {ms[worst]:.4g} of agent {sysw_label(sysw, who[worst])}"
        )
        h_ok = grid.h[worst] / r
        raise InputError(
            f"Euler–Maruyama is unstable: at t = {grid.t[worst]:.4g}, c·h = {ch[worst]:.4g} "
            f"exceeds {which} for L_B of mode {sysw.name} (ρ(L_B) = {sysw.spectral_radius:.4g}, {sysw.eig_method}); "
            f"use dt < {h_ok:.3g}, or the drift-implicit scheme (stepping: intrinsic, scheme: implicit)",
            field="dt",
        )
    if r > 0.5:
        return StepCheck(
            r,
            f"Euler–Maruyama step within a factor {1 / r:.2f} of instability at t = {grid.t[worst]:.4g}; expect a step-size bias",
        )
    return StepCheck(r, None)
