"""The modal form of each contact configuration of a trajectory (paper eqs. 1, 6-8), precomputed
once per trajectory and shared by the outcome engines (:mod:`atlas.dynamics.fast_engine` on NumPy,
:mod:`atlas.dynamics.jax_engine` on JAX).

Per configuration ``S`` (mask: bit ``i`` set when contact ``i + 1`` is closed) the active gaps and
velocities obey ``x' = A_S x`` about the equilibrium ``d_eq``; with ``A_S = V diag(lambda) W`` a
segment from the state ``g`` is, for every gap, ``d(t) = p0 + p1 t + p2 t^2 + sum_m U_m
exp(lambda_m t)`` (:func:`segments`, :func:`segment`).  A configuration whose eigenvector matrix
``V`` may have a condition number ``>= 1e4`` (:func:`cond_bound` reaches it; or whose equilibrium is
ill-posed) is marked not ``ok``: its lanes fall back to the exact simulator (see the fast engine's
docstring for why).

Degenerate directions (:func:`closed_configurations`): where ``b_ii`` (a single contact ``i``) or
``det B`` (both) is zero up to the rounding of the angles (``<= ROUNDING`` relative), the
configuration is defective or near-defective (a Jordan block at ``lambda = 0``, split by rounding
into ``|lambda| ~ 1e-8``).  There the flow of ``B`` with that entry (or ``det B``) set to zero, a
change of ``B`` within its rounding, is written in closed form (:func:`closed_segment`): a
single contact with ``b_ii = 0`` has its gap in free flight and the other gap a quartic; both
contacts with ``B = b c^T`` of rank one have the gaps' component across ``b`` in free flight and
the one along ``b`` a damped oscillator driven by a quadratic (a quadratic plus two modes).  The
tables keep, for the classification and the stop rule, the eigenvalues and the equilibrium the
exact simulator computes from the unperturbed ``B`` (``closed`` True, ``ok`` False: the JAX engine
still sends these lanes back).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from atlas.dynamics import event_bounds as eb
from atlas.dynamics.system import Mode, System

__all__ = [
    "Lanes", "ModalTable", "ModalTables", "modal_tables", "light_system", "segments", "segment",
    "stack_table", "stack_tables", "z_eq", "modal_coordinates", "modal_coords", "cond_bound",
    "ROUNDING", "closed_configurations", "closed_segment", "log_norm",
]  # fmt: skip

_COND_MAX = 1e4  # eigenvector condition beyond which a configuration falls back
#: ``|b_ii| / |b_i|`` or ``|det B| / (|b_1| |b_2|)`` at or below which it is zero up to the rounding
#: of the angles (``cos(fl(pi / 2)) = 6.1e-17``, ``sin(fl(pi)) = 1.2e-16``, a few ulps of ``2 pi``)
ROUNDING = 16 * np.finfo(float).eps
#: smallest ``|gamma| / (|c| max k)`` and ``|lambda_+ - lambda_-| / max |lambda_pm|`` of the
#: rank-one SS closed form (its particular solution divides by ``gamma``, its modes by the split)
_RANK_ONE_MIN = 1e-4


@dataclasses.dataclass
class Lanes:
    """Parameters of ``N`` trajectories: ``B`` (N, 2, 2), ``a`` (N, 2), ``k``, ``q`` (N, 2)."""

    B: np.ndarray
    a: np.ndarray
    k: np.ndarray
    q: np.ndarray

    @classmethod
    def of(cls, beta1, beta2, alpha, k, q):
        """Unit ``|b_j|``, ``|a|`` (SPEC §1); inputs broadcast to ``(N,)``."""
        beta1, beta2, alpha = np.broadcast_arrays(
            *(np.atleast_1d(np.asarray(x, dtype=float)) for x in (beta1, beta2, alpha))
        )
        n = beta1.size
        B = np.empty((n, 2, 2))
        B[:, 0, 0], B[:, 1, 0] = np.cos(beta1.ravel()), np.sin(beta1.ravel())
        B[:, 0, 1], B[:, 1, 1] = np.cos(beta2.ravel()), np.sin(beta2.ravel())
        a = np.stack([np.cos(alpha.ravel()), np.sin(alpha.ravel())], axis=1)
        kk = np.broadcast_to(np.asarray(k, dtype=float), (n, 2)).copy()
        qq = np.broadcast_to(np.asarray(q, dtype=float), (n, 2)).copy()
        return cls(B, a, kk, qq)


@dataclasses.dataclass
class ModalTable:
    """Modal form of one configuration for ``N`` lanes: eigenvalues ``lam`` (N, 4; unused
    entries 0 with ``valid`` False), right/left eigenvector blocks ``V``, ``W`` (N, na, na) of
    the active subsystem, equilibrium ``d_eq`` (N, 2; NaN for free gaps), ``H`` step cap,
    ``ok`` (well-conditioned), augmented matrices ``E`` (N, 5, 5), ``closed``
    (:func:`closed_configurations`; its ``lam``, ``valid`` and ``d_eq`` are the exact
    simulator's)."""

    mask: int
    lam: np.ndarray
    valid: np.ndarray
    V: np.ndarray
    W: np.ndarray
    d_eq: np.ndarray
    H: np.ndarray
    ok: np.ndarray
    E: np.ndarray
    closed: np.ndarray
    eig_w: np.ndarray | None = None
    eig_V: np.ndarray | None = None


class ModalTables(list):
    """The four :class:`ModalTable` of the lanes (``tables[mask]``) and their entries ``lam``,
    ``valid``, ``d_eq``, ``H``, ``ok``, ``E``, ``mu`` (:func:`log_norm` in units ``1 / H``)
    stacked by configuration (4, N, ...) as attributes
    (each table's entry is a view of one slice), for one gather ``x[mask, ix]`` over mixed
    configurations (:func:`stack_table`)."""

    def __init__(self, tables, stacked):
        super().__init__(tables)
        self.__dict__.update(stacked)

    def eig(self, m, lanes):
        """Eigenvalues (m, na) and eigenvectors (m, na, na) of the active subsystem of
        configuration ``m`` (1, 2, 3) of the ``lanes`` as LAPACK ``geev`` gives them (complex;
        the ``eig`` of :func:`atlas.dynamics.system.iwc_aligned_many`)."""
        return self[m].eig_w[lanes], self[m].eig_V[lanes]


def modal_tables(lanes: Lanes) -> ModalTables:
    """The four :class:`ModalTable` of every lane (FF, SF, FS, SS).  Each distinct active
    subsystem is solved once (:func:`_distinct`; on a ``(beta1, beta2)`` grid ``SF`` depends on
    ``beta1`` only, ``FS`` on ``beta2``, and the perturbations of a cell share all four)."""
    n = lanes.a.shape[0]
    omega = np.sqrt(np.max(lanes.k, axis=1))
    st = {
        "lam": np.zeros((4, n, 4), dtype=complex), "valid": np.zeros((4, n, 4), dtype=bool),
        "d_eq": np.full((4, n, 2), np.nan), "H": np.empty((4, n)), "ok": np.ones((4, n), bool),
        "E": _augmented(lanes.B, lanes.a, lanes.k, lanes.q, np.arange(4)[:, None]),
        "closed": np.zeros((4, n), bool), "mu": np.empty((4, n)),
    }  # fmt: skip
    out = []
    for mask in range(4):
        idx = [i for i in range(2) if mask >> i & 1]
        na = 2 * len(idx)
        lam, valid, d_eq, ok, E = (st[x][mask] for x in ("lam", "valid", "d_eq", "ok", "E"))
        V = W = raw_V = np.zeros((n, na, na), dtype=complex)
        raw_w = np.zeros((n, na), dtype=complex)
        distinct = False  # every lane's flow distinct (no repeats to spare in log_norm)
        if idx:
            sub = idx + [i + 2 for i in idx]
            A = E[:, sub][:, :, sub]
            BS = lanes.B[:, idx][:, :, idx] * lanes.k[:, None, idx]
            a_S = lanes.a[:, idx]
            first, inv = _distinct(A, BS, a_S)
            distinct = first.size == n and na == 4
            if first.size == n:  # all distinct: no gathers
                w, V, W, d_S, ok[:], raw_V = _active_modes(A, BS, a_S)
            else:
                modes = _active_modes(A[first], BS[first], a_S[first])
                w, V, W, d_S, ok[:], raw_V = (x[inv] for x in modes)
            raw_w[:] = w
            lam[:, :na] = w
            valid[:, :na] = True
            d_eq[:, idx] = d_S
            closed = st["closed"][mask]
            closed[:] = closed_configurations(lanes, mask) & ~ok
            _as_reference(lanes, mask, E, np.flatnonzero(closed), lam, d_eq)
        rho = np.abs(lam).max(axis=1)
        H = st["H"][mask]
        H[:] = 1.0 / np.maximum(rho, 0.25 * omega)
        st["mu"][mask] = _log_norms(E, H, distinct)
        out.append(ModalTable(mask, lam, valid, V, W, d_eq, H, ok, E, st["closed"][mask], raw_w,
                              raw_V))  # fmt: skip
    return ModalTables(out, st)


def _log_norms(E, H, distinct):
    """:func:`log_norm` ``(E, 1 / H)`` (N,), once per distinct ``(E, H)`` (rows 0, 1 of
    ``E[:, :4, :4]`` are the same for every lane) unless ``distinct`` (then every lane's is)."""
    if distinct:
        return log_norm(E, 1.0 / H)
    first, inv = _distinct(E[:, 2:4, :4], H)
    return log_norm(E[first], 1.0 / H[first])[inv]


def log_norm(E, w):
    """Logarithmic 2-norm ``mu`` (N,) of ``D A D^-1`` (``A = E[:, :4, :4]`` the flow of all four
    gaps and velocities, ``D = diag(1, 1, 1 / w, 1 / w)``, velocities in units of the rate ``w``
    (N,)): ``|D z(t)| <= exp(mu t) |D z(0)|`` for ``z' = A z`` (Dahlquist), whatever the
    conditioning of the eigenvectors; the largest eigenvalue of the symmetric part, raised by
    ``1e-12`` of its norm for rounding."""
    d = np.concatenate([np.ones((w.size, 2)), np.repeat(w[:, None], 2, axis=1)], axis=1)
    M = E[:, :4, :4] * (d[:, None, :] / d[:, :, None])
    S = 0.5 * (M + M.transpose(0, 2, 1))
    lam = np.linalg.eigvalsh(S)
    return lam[:, -1] + 1e-12 * np.abs(lam).max(axis=1)


def closed_configurations(lanes: Lanes, mask: int) -> np.ndarray:
    """Lanes (N,) whose configuration ``mask`` has the closed form of :func:`closed_segment`:
    ``|b_ii| <= ROUNDING |b_i|`` (one contact ``i``), or ``|det B| <= ROUNDING |b_1| |b_2|`` with
    the rank-one form well-posed (``gamma`` and the split of its two modes above
    ``_RANK_ONE_MIN`` relative)."""
    B = lanes.B
    norm = np.linalg.norm(B, axis=1)  # column norms (N, 2)
    if mask in (1, 2):
        i = mask - 1
        return np.abs(B[:, i, i]) <= ROUNDING * norm[:, i]
    if mask != 3:
        return np.zeros(B.shape[0], bool)
    det = B[:, 0, 0] * B[:, 1, 1] - B[:, 0, 1] * B[:, 1, 0]
    out = np.abs(det) <= ROUNDING * norm[:, 0] * norm[:, 1]
    b, _, c = _rank_one(B)
    gamma, beta = (np.sum(c * x * b, axis=1) for x in (lanes.k, lanes.q))
    lp, lm = _roots(beta, gamma)
    big = np.maximum(np.abs(lp), np.abs(lm))
    out &= np.abs(gamma) >= _RANK_ONE_MIN * np.linalg.norm(c, axis=1) * lanes.k.max(axis=1)
    return out & (np.abs(lp - lm) >= _RANK_ONE_MIN * big)


def _rank_one(B):
    """``b`` (unit, along the first column), ``w`` (unit, across it) and ``c = b^T B`` (N, 2):
    ``B`` projected on ``b`` is ``b c^T``, off ``B`` by ``|det B| / |b_1|`` in its second column."""
    b = B[:, :, 0] / np.linalg.norm(B[:, :, 0], axis=1)[:, None]
    w = np.stack([-b[:, 1], b[:, 0]], axis=1)
    c = np.einsum("ni,nij->nj", b, B)
    return b, w, c


def _roots(beta, gamma):
    """Roots ``lambda_pm`` of ``lambda^2 + beta lambda + gamma`` (complex)."""
    root = np.sqrt((beta * beta - 4 * gamma).astype(complex))
    return 0.5 * (-beta + root), 0.5 * (-beta - root)


def _as_reference(lanes, mask, E, rows, lam, d_eq):
    """For the lanes ``rows`` of configuration ``mask``: the eigenvalues ``lam`` and equilibria
    ``d_eq`` as the exact simulator computes them (:func:`atlas.dynamics.system.build_system`:
    ``eigvals`` and ``solve`` of each lane alone, NaN where ``B_SS K_S`` is singular), for the
    classification and the stop rule of lanes served by :func:`closed_segment`."""
    idx = [i for i in range(2) if mask >> i & 1]
    sub = idx + [i + 2 for i in idx]
    for r in rows:
        lam[r, : len(sub)] = np.linalg.eigvals(E[r][np.ix_(sub, sub)])
        BS = lanes.B[r][np.ix_(idx, idx)] * lanes.k[r][idx][None, :]
        try:
            d_eq[r, idx] = np.linalg.solve(BS, -lanes.a[r][idx])
        except np.linalg.LinAlgError:
            d_eq[r, idx] = np.nan


def _distinct(*arrays):
    """Rows ``first`` of the distinct lanes (bitwise equal in every array, ``(n, ...)``) and
    ``inv`` (n,) with lane ``r`` equal to lane ``first[inv[r]]``."""
    n = arrays[0].shape[0]
    key = np.ascontiguousarray(np.concatenate([x.reshape(n, -1) for x in arrays], axis=1))
    rows = key.view(np.dtype((np.void, key.dtype.itemsize * key.shape[1]))).ravel()
    _, first, inv = np.unique(rows, return_index=True, return_inverse=True)
    return first, inv.ravel()


def _active_modes(A, BS, a_S):
    """Eigenvalues ``w`` (n, na), eigenvectors ``V`` and inverse ``W`` (n, na, na) of the active
    subsystems ``A`` (n, na, na) (LAPACK ``geev``, ``gesv`` per matrix; the identity where not
    ``ok``), the equilibria ``d_S`` (n, na / 2) of ``BS d_S = -a_S`` (paper eq. 8 with ``g' =
    0``), ``ok`` (n,): the condition of ``V`` below ``1e4`` (:func:`cond_bound`), ``BS``
    not singular, no zero eigenvalue, and ``geev``'s eigenvectors (complex, also where not
    ``ok``)."""
    m, na = A.shape[:2]
    w, V = np.linalg.eig(A)  # real arrays if every eigenvalue of the batch is real
    raw = V = V.astype(complex)  # each lane's ``W`` by complex arithmetic, whatever the batch
    W = _inverse(V)
    ok = cond_bound(V, W) < _COND_MAX
    V = np.where(ok[:, None, None], V, np.eye(na))
    W = np.where(ok[:, None, None], W, np.eye(na))
    det = np.linalg.det(BS)
    ok &= np.abs(det) > 1e-12 * np.abs(BS).reshape(m, -1).max(axis=1) ** (na // 2)
    BS = np.where(ok[:, None, None], BS, np.eye(na // 2))
    d_S = np.linalg.solve(BS, -a_S[:, :, None])[:, :, 0]
    ok &= np.all(np.abs(w) > 0, axis=1)
    return w, V, W, d_S, ok, raw


def _inverse(V):
    """``V^-1`` (n, na, na) by LAPACK ``gesv`` per matrix; an exactly singular matrix gets NaN."""
    try:
        return np.linalg.inv(V)
    except np.linalg.LinAlgError:
        W = np.full_like(V, np.nan)
        for r in range(V.shape[0]):  # only when some matrix is exactly singular
            try:
                W[r] = np.linalg.inv(V[r])
            except np.linalg.LinAlgError:
                pass
        return W


def cond_bound(V, W):
    """Upper bound (n,) of the 2-norm condition number ``cond(V) = |V|_2 |V^-1|_2`` of the
    matrices ``V`` (n, na, na) from a computed inverse ``W`` (any ``W``: its error is bounded
    here); ``inf`` where no bound follows (also for NaN or overflow).

    With ``R = W V - I`` and ``|R|_2 < 1``, ``V^-1 = (I + R)^-1 W`` gives ``|V^-1|_2 <= |W|_2 /
    (1 - |R|_2)``, so ``cond(V) <= |V|_F |W|_F / (1 - |R|_F)``.  Rounding: a complex inner
    product of length ``na`` is computed within ``sqrt(2) gamma_(na + 2) |w|^T |v|`` (``gamma_m =
    m u / (1 - m u)``, ``u = 2^-53``; Higham 2002, Sec. 3.6), so ``|fl(W V) - W V|_F <= sqrt(2)
    gamma_(na + 2) |W|_F |V|_F``; with the subtraction of ``I`` this is below the ``4 na u |W|_F
    |V|_F`` added to the computed ``|R|_F`` (``na`` = 2, 4).  The norms' own rounding (relative
    ``< 1e-14``) is covered by the factor ``1 + 1e-12`` and, in ``1 - r`` (whose relative error
    grows as ``1 / (1 - r)``), by taking ``r (1 + 1e-13)``.  Against an SVD-computed condition
    (relative error ``~ u cond``): ``|M|_F >= |M|_2 sqrt(1 + 1 / cond^2)`` for ``M = V, W``, so
    near ``cond = 1e4`` the bound exceeds ``cond`` by a relative ``>= 1e-8``.  The bound exceeds
    ``cond(V)`` by at most ``na / (1 - r)`` (``|M|_F <= sqrt(na) |M|_2``)."""
    na = V.shape[-1]
    with np.errstate(all="ignore"):
        fv = np.sqrt(np.sum(V.real**2 + V.imag**2, axis=(1, 2)))
        fw = np.sqrt(np.sum(W.real**2 + W.imag**2, axis=(1, 2)))
        R = W @ V
        R[:, np.arange(na), np.arange(na)] -= 1.0
        prod = fv * fw
        r = np.sqrt(np.sum(R.real**2 + R.imag**2, axis=(1, 2))) + 4 * na * 2.0**-53 * prod
        r = r * (1 + 1e-13)
        bound = (1 + 1e-12) * prod / (1 - r)
    return np.where((r < 1) & np.isfinite(bound), bound, np.inf)


def light_system(lanes: Lanes, tables, n: int) -> System:
    """The :class:`atlas.dynamics.system.System` of lane ``n`` with what
    :func:`atlas.dynamics.classify_stats` and :func:`atlas.dynamics.system.iwc_aligned` read
    (``E``, ``eig``, ``stable``, ``z_eq``; no sub-step matrices)."""
    k = lanes.k[n]
    modes = []
    for tab in tables:
        na = int(tab.valid[n].sum())
        eig = tab.lam[n, :na]
        z_eq = None
        if tab.mask:
            z_eq = np.full(5, np.nan)
            idx = [i for i in range(2) if tab.mask >> i & 1]
            z_eq[idx] = tab.d_eq[n, idx]
            z_eq[[i + 2 for i in idx]] = 0.0
            z_eq[4] = 1.0
            if np.isnan(z_eq[idx]).any():  # singular B_SS K_S: no equilibrium, as build_system
                z_eq = None
        stable = bool(np.all(eig.real < 0)) if na else True
        modes.append(Mode(tab.mask, tab.E[n], math.nan, None, None, None, eig, stable, z_eq))
    return System(B=lanes.B[n], a=lanes.a[n], k=k, q=lanes.q[n], L=None, modes=tuple(modes),
                  omega=math.sqrt(k.max()))  # fmt: skip


def _augmented(B, a, k, q, mask):
    """``E_S = [[A_S, c_S], [0, 0]]`` (..., 5, 5) of configuration ``mask`` (an int, or an
    integer array broadcasting against the lanes) (paper eqs. 7, 8; as
    :func:`atlas.dynamics.system.build_system`); ``B`` (..., 2, 2), ``a``, ``k``, ``q`` (..., 2)."""
    m = np.asarray(mask)
    act = np.stack([m & 1, (m >> 1) & 1], axis=-1).astype(float)
    E = np.zeros(np.broadcast_shapes(a.shape[:-1], act.shape[:-1]) + (5, 5))
    E[..., 0, 2] = E[..., 1, 3] = 1.0
    E[..., 2:4, 0:2] = -B * (k * act)[..., None, :]
    E[..., 2:4, 2:4] = -B * (q * act)[..., None, :]
    E[..., 2:4, 4] = -a
    return E


# ----------------------------------------------------------------------------- segments


def segments(lanes: Lanes, tables: ModalTables, ix, mask, g, closed=False):
    """Closed form of the segments starting at the states ``g`` (n, 4) of lanes ``ix`` in the
    configurations ``mask`` (n,): ``P`` (n, 2, 3) polynomial coefficients of the gaps, ``U``
    (n, 2, 4) modal amplitudes, ``lam``, ``valid`` (n, 4), step cap ``H`` and ``ok`` (n,).

    ``closed``: the configurations of :func:`closed_configurations` by :func:`closed_segment`
    (``ok`` there), and ``P`` (n, 2, 5) (degree 4) if any lane of ``tables`` has one."""
    n = ix.size
    lam, valid, H, ok, d_eq = stack_tables(tables, _SEGMENT_ENTRIES, ix, mask)
    present = np.flatnonzero(np.bincount(mask, minlength=4))
    if present.size == 1:
        P, U = _segment_of(lanes, tables, present[0], ix, g, d_eq, lam)
    else:
        P = np.empty((n, 2, 3))
        U = np.empty((n, 2, 4), dtype=complex)
        for m in present:
            sel = np.flatnonzero(mask == m)
            P[sel], U[sel] = _segment_of(lanes, tables, m, ix[sel], g[sel], d_eq[sel], lam[sel])
    if not (closed and tables.closed.any()):
        return P, U, lam, valid, H, ok
    P = np.concatenate([P, np.zeros((n, 2, 2))], axis=2)
    r = np.flatnonzero(stack_table(tables, "closed", ix, mask))
    for m in np.unique(mask[r]):
        sel = r[mask[r] == m]
        lx = ix[sel]
        P[sel], U[sel], lam[sel], valid[sel] = closed_segment(
            m, g[sel], lanes.B[lx], lanes.a[lx], lanes.k[lx], lanes.q[lx]
        )
        ok[sel] = True
    return P, U, lam, valid, H, ok


def closed_segment(m, g, B, a, k, q):
    """``(P (n, 2, 5), U, lam, valid)`` of segments from ``g`` (n, 4) in a configuration ``m`` of
    :func:`closed_configurations`, in closed form for ``B`` with ``b_ii = 0`` (``m = 1, 2``) or
    projected to rank one (``m = 3``); ``B`` (n, 2, 2), ``a``, ``k``, ``q`` (n, 2).

    One contact ``i`` (``b_ii = 0``): ``d_i'' = -a_i`` (free flight), so ``phi_i = f0 + f1 t + f2
    t^2`` and ``d_j'' = b_ji phi_i - a_j`` integrate to a quartic.  Both (``B = b c^T``, ``c =
    b^T B``, ``w`` across ``b``): ``zeta = w . d`` has ``zeta'' = -w . a``; ``xi = b . d`` has
    ``xi'' + beta xi' + gamma xi = -(r0 + r1 t + r2 t^2)`` (``gamma = c^T K b``, ``beta = c^T Q
    b``; the right side from ``zeta``), a quadratic particular solution plus the modes
    ``lambda_pm`` of ``lambda^2 + beta lambda + gamma``; ``d = b xi + w zeta`` (paper eq. 1)."""
    n = g.shape[0]
    P = np.zeros((n, 2, 5))
    U = np.zeros((n, 2, 4), dtype=complex)
    lam = np.zeros((n, 4), dtype=complex)
    valid = np.zeros((n, 4), dtype=bool)
    if m in (1, 2):
        i, j = m - 1, 2 - m
        gi, vi, ai, ki, qi = g[:, i], g[:, i + 2], a[:, i], k[:, i], q[:, i]
        f0, f1, f2 = -ki * gi - qi * vi, -ki * vi + qi * ai, 0.5 * ki * ai
        bji = B[:, j, i]
        P[:, i, :3] = np.stack([gi, vi, -0.5 * ai], axis=1)
        P[:, j] = np.stack([g[:, j], g[:, j + 2], 0.5 * (bji * f0 - a[:, j]), bji * f1 / 6,
                            bji * f2 / 12], axis=1)  # fmt: skip
        return P, U, lam, valid
    b, w, c = _rank_one(B)
    xi0, xiv = np.sum(b * g[:, :2], axis=1), np.sum(b * g[:, 2:], axis=1)
    ze0, zev = np.sum(w * g[:, :2], axis=1), np.sum(w * g[:, 2:], axis=1)
    ab, aw = np.sum(b * a, axis=1), np.sum(w * a, axis=1)
    gamma, beta, kw, qw = (np.sum(c * x * y, axis=1) for x, y in ((k, b), (q, b), (k, w), (q, w)))
    r0, r1, r2 = ab + kw * ze0 + qw * zev, kw * zev - qw * aw, -0.5 * kw * aw
    e2 = -r2 / gamma
    e1 = (-r1 - 2 * beta * e2) / gamma
    e0 = (-r0 - 2 * e2 - beta * e1) / gamma
    lp, lm = _roots(beta, gamma)
    h0, h1 = xi0 - e0, xiv - e1
    amp_p, amp_m = (h1 - lm * h0) / (lp - lm), (lp * h0 - h1) / (lp - lm)
    P[:, :, :3] = b[:, :, None] * np.stack([e0, e1, e2], 1)[:, None, :] + w[:, :, None] * np.stack(
        [ze0, zev, -0.5 * aw], 1)[:, None, :]  # fmt: skip
    U[:, :, 0], U[:, :, 1] = b * amp_p[:, None], b * amp_m[:, None]
    lam[:, 0], lam[:, 1] = lp, lm
    valid[:, :2] = True
    return P, U, lam, valid


_SEGMENT_ENTRIES = ("lam", "valid", "H", "ok", "d_eq")


def _segment_of(lanes, tables, m, lx, g, d_eq, lam):
    """:func:`segment` of the lanes ``lx`` all in configuration ``m`` (NumPy): only the
    parameters that configuration reads are gathered."""
    if m == 0:
        return segment(0, g, d_eq, None, None, lam, None, lanes.a[lx], None, None)
    tab = tables[m]
    V, W = tab.V[lx], tab.W[lx]
    if m == 3:
        return segment(3, g, d_eq, V, W, lam, None, None, None, None)
    return segment(m, g, d_eq, V, W, lam, lanes.B[lx], lanes.a[lx], lanes.k[lx], lanes.q[lx])


def segment(m, g, d_eq, V, W, lam, B, a, k, q):
    """Closed form (``P`` (n, 2, 3), ``U`` (n, 2, 4)) of segments in configuration ``m`` (an
    int) from the states ``g`` (n, 4): equilibria ``d_eq`` (n, 2), eigenvectors ``V`` and their
    inverse ``W`` (n, na, na), eigenvalues ``lam`` (n, 4); NumPy or JAX arrays."""
    xp = eb.xp_of(g, d_eq, lam, B)
    idx = [i for i in range(2) if m >> i & 1]
    n = g.shape[0]
    if not idx:  # FF: d'' = -a
        P = xp.stack([g[:, :2], g[:, 2:], -0.5 * a], axis=2)
        return P, xp.zeros((n, 2, 4), dtype=complex)
    c = modal_coords(m, g, d_eq, W)[1]
    Ua = V[:, : len(idx), :] * c[:, None, :]  # the active gaps' modal terms (n, len(idx), na)
    if len(idx) == 2:
        zero = xp.zeros_like(d_eq)
        return xp.stack([d_eq, zero, zero], axis=2), Ua
    # one active contact i, a free gap j: d_j'' = B_ji phi_i - a_j, integrated twice
    i, j = idx[0], 1 - idx[0]
    w = -(k[:, i, None] * V[:, 0, :] + q[:, i, None] * V[:, 1, :]) * c  # phi_i modal terms
    Bji = B[:, j, i]
    Wm = Bji[:, None] * w
    lm = lam[:, :2]
    Uj = Wm / lm**2
    acc0 = -Bji * k[:, i] * d_eq[:, i] - a[:, j]
    zero = xp.zeros((n,))
    Pi = [d_eq[:, i], zero, zero]
    Pj = [g[:, j] - xp.sum(Uj, axis=1).real, g[:, j + 2] - xp.sum(Wm / lm, axis=1).real, 0.5 * acc0]
    P = xp.stack(Pi + Pj if i == 0 else Pj + Pi, axis=1).reshape(n, 2, 3)
    U = xp.stack([Ua[:, 0], Uj] if i == 0 else [Uj, Ua[:, 0]], axis=1)
    return P, xp.concatenate([U, xp.zeros((n, 2, 2), dtype=U.dtype)], axis=2)


def stack_table(tables: ModalTables, name, ix, mask):
    """Table entry ``name`` (``lam``, ``valid``, ``d_eq``, ``H``, ``ok``, ``E``) of the
    configurations ``mask`` (n,) of lanes ``ix`` (n,)."""
    return stack_tables(tables, (name,), ix, mask)[0]


def stack_tables(tables: ModalTables, names, ix, mask):
    """:func:`stack_table` of several entries (one index computation)."""
    flat = np.asarray(mask, dtype=np.intp) * tables.ok.shape[1] + ix
    out = []
    for name in names:
        x = getattr(tables, name)
        out.append(x.reshape((-1,) + x.shape[2:]).take(flat, axis=0))
    return out


def z_eq(tables, ix, mask):
    """Equilibria ``z_eq`` (n, 5) of :func:`light_system`'s modes: ``d_eq`` of the active gaps,
    zero velocities, NaN for free gaps, 1 last."""
    z = np.full((ix.size, 5), np.nan)
    d_eq = stack_table(tables, "d_eq", ix, mask)
    act = np.stack([mask & 1, mask >> 1 & 1], axis=1).astype(bool)
    z[:, :2] = np.where(act, d_eq, np.nan)
    z[:, 2:4] = np.where(act, 0.0, np.nan)
    z[:, 4] = 1.0
    return z


def modal_coordinates(tables, ix, mask, g):
    """Coordinates ``c`` (n, 4) of the active deviation from equilibrium in the eigenvectors of
    the active subsystem (as :func:`atlas.dynamics.system.iwc_aligned` expands it)."""
    c = np.zeros((ix.size, 4), dtype=complex)
    d_eq = stack_table(tables, "d_eq", ix, mask)
    for m in (1, 2, 3):
        sel = np.flatnonzero(mask == m)
        if sel.size:
            W = tables[m].W[ix[sel]]
            c[sel, : 2 * (1 + (m == 3))] = modal_coords(m, g[sel], d_eq[sel], W)[1]
    return c


def modal_coords(m, g, d_eq, W):
    """Deviation ``x`` of the active gaps and velocities from the equilibrium and its
    coordinates ``c = W x`` (n, na) in configuration ``m`` (1, 2, 3); NumPy or JAX arrays."""
    xp = eb.xp_of(g, d_eq, W)
    lo, hi = (0 if m & 1 else 1), (2 if m & 2 else 1)  # the active gaps lo .. hi - 1
    x = xp.concatenate([g[:, lo:hi] - d_eq[:, lo:hi], g[:, lo + 2 : hi + 2]], axis=1)
    return x, xp.einsum("nij,nj->ni", W, x)
