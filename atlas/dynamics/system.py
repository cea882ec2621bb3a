"""The piecewise-linear compliant two-contact system (paper Sec. 4.1, eqs. 1, 6-8).

The gaps ``d = (d1, d2)`` obey ``d'' = B f - a`` (paper eq. 1) with the rescaled Kelvin-Voigt
contact law (paper eq. 6)::

    f_i = 0                               if d_i > 0
    f_i = max(0, -k_i d_i - q_i d_i')     if d_i <= 0

State ``g = (d1, d2, d1', d2')``.  A contact is *active* when ``d_i <= 0`` and the force
``phi_i = -k_i d_i - q_i d_i' > 0``.  For a fixed active set ``S`` the dynamics is linear with a
constant forcing, ``g' = A_S g + c_S`` (paper eqs. 7, 8): with ``z = (g, 1)``, ``z' = E_S z`` for
the augmented matrix ``E_S = [[A_S, c_S], [0, 0]]``, advanced exactly with its matrix exponential
(scaling and squaring of its degree-30 Taylor polynomial, :func:`expm`).

This module holds what the simulators (:mod:`atlas.dynamics.simulator`, the outcome engines
:mod:`atlas.dynamics.fast_engine`, :mod:`atlas.dynamics.jax_engine`) and the classification share: the per-mode matrices
(:func:`build_system`), the outcome and status enumerations, the event kinds and the test for an
impact without collision (:func:`iwc_aligned`).

Time is in the units of the inputs (the paper's Fig. 2 uses ``k = (100, 200)``); with ``k2 = 1``,
``k1 = kappa``, ``|b| = 1`` it is the SPEC's scaled time ``1 / sqrt(k2 |b2|)``.
"""

from __future__ import annotations

import dataclasses
import enum
import math

import numpy as np

from atlas.core import checks
from atlas.dynamics.event_bounds import take, xp_of

__all__ = [
    "Outcome",
    "Status",
    "IMPACT",
    "LIFTOFF",
    "FORCE_ON",
    "FORCE_OFF",
    "MODE_NAMES",
    "TAYLOR_DEGREE",
    "Mode",
    "System",
    "build_system",
    "check_finite",
    "expm",
    "iwc_aligned",
    "iwc_aligned_many",
    "eig_rows",
    "aligned_in_basis",
    "mask_from_signs",
    "mode_name",
    "run_scale",
    "ss_equilibrium",
]


class Outcome(enum.IntEnum):
    """Outcome classes of a trajectory (one enumeration drives CF flags, colours and labels)."""

    UNDETERMINED = 0
    SETTLES_SS = 1
    SETTLES_SF = 2
    SETTLES_FS = 3
    SETTLES_FF = 4
    IWC = 5
    GROWING_BOUNCING = 6
    SUSTAINED_OSCILLATION = 7

    @property
    def label(self) -> str:
        return _OUTCOME_STYLE[self][0]

    @property
    def color(self) -> str:
        return _OUTCOME_STYLE[self][1]


_OUTCOME_STYLE = {
    Outcome.UNDETERMINED: ("undetermined", "#bdbdbd"),
    Outcome.SETTLES_SS: ("settles_SS", "#525252"),
    Outcome.SETTLES_SF: ("settles_SF", "#4292c6"),
    Outcome.SETTLES_FS: ("settles_FS", "#9ecae1"),
    Outcome.SETTLES_FF: ("settles_FF", "#f7f7f7"),
    Outcome.IWC: ("IWC", "#e41a1c"),
    Outcome.GROWING_BOUNCING: ("growing_bouncing", "#ff7f00"),
    Outcome.SUSTAINED_OSCILLATION: ("sustained_oscillation", "#4daf4a"),
}


class Status(str, enum.Enum):
    """Why a simulation stopped."""

    T_END = "t_end"  #: reached ``t_end``
    EVENT_CAP = "event_cap"  #: ``max_events`` switching events (Zeno-like burst or long run)
    DIVERGED = "diverged"  #: a gap left ``[-penetration_limit, amplitude_limit]``
    SETTLED = "settled"  #: a stable contact mode was reached and no event can follow
    STEP_CAP = "step_cap"  #: ``max_steps`` sub-steps without reaching ``t_end``


# event kinds
IMPACT, LIFTOFF, FORCE_ON, FORCE_OFF = "impact", "liftoff", "force_on", "force_off"

#: contact configuration of each mode mask (bit i-1 set: contact i active)
MODE_NAMES = ("FF", "SF", "FS", "SS")

TAYLOR_DEGREE = 30
_I2 = np.eye(2)


def expm(M: np.ndarray) -> np.ndarray:
    """Matrix exponential by scaling and squaring of the degree-30 Taylor polynomial.

    ``M / 2^s`` has 1-norm <= 1/2, where the truncation error is below ``0.5^31 / 31! < 1e-42``
    (relative); ``scipy.linalg.expm`` (1.17) takes ~15 ms on small-norm 5 x 5 matrices, this ~30 us.
    """
    norm = float(np.abs(M).sum(axis=0).max())
    s = max(0, math.ceil(math.log2(norm / 0.5))) if norm > 0.5 else 0
    X = M / 2.0**s
    acc = np.eye(M.shape[0])
    for n in range(TAYLOR_DEGREE, 0, -1):
        acc = np.eye(M.shape[0]) + (X @ acc) / n
    for _ in range(s):
        acc = acc @ acc
    return acc


def mode_name(mask: int) -> str:
    """``'SF'`` etc.: letter i is ``S`` when contact i is active (bit i-1 of ``mask``)."""
    return MODE_NAMES[mask]


def mask_from_signs(s) -> int:
    """Mode mask from the recorded signs of ``(d1, d2, phi1, phi2)``: contact i is active when
    ``d_i <= 0`` (sign -1) and ``phi_i > 0``."""
    a1 = s[0] < 0 and s[2] > 0
    a2 = s[1] < 0 and s[3] > 0
    return int(a1) | (int(a2) << 1)


def check_finite(name, value, *, positive=False, nonneg=False):
    """``value`` as a float array; a one-line ``ValueError`` naming ``name`` if it is not finite
    (or not ``> 0`` / ``>= 0`` when asked)."""
    arr = checks.real(name, value, finite=False)
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be finite, got {value!r}")
    if positive and np.any(arr <= 0):
        raise ValueError(f"{name} must be > 0, got {value!r}")
    if nonneg and np.any(arr < 0):
        raise ValueError(f"{name} must be >= 0, got {value!r}")
    return arr


def _matrix_B(beta1, beta2, b_norm) -> np.ndarray:
    """``B`` with columns ``b_j = |b_j| (cos beta_j, sin beta_j)`` (paper eq. 1)."""
    return np.array(
        [
            [b_norm[0] * math.cos(beta1), b_norm[1] * math.cos(beta2)],
            [b_norm[0] * math.sin(beta1), b_norm[1] * math.sin(beta2)],
        ]
    )


@dataclasses.dataclass(frozen=True)
class Mode:
    """One contact configuration ``S`` (bit mask) of a :class:`System`."""

    mask: int
    E: np.ndarray  # (5, 5) augmented matrix [[A, c], [0, 0]]
    h: float  # sub-step [time]
    Phi: np.ndarray  # expm(E h)
    P: np.ndarray  # (N+1, 5, 5) Taylor terms E^n / n!
    LE: np.ndarray  # (4, 5) derivatives of the event functionals
    eig: np.ndarray  # eigenvalues of the active subsystem
    stable: bool  # all Re(eig) < 0 (vacuously true for FF)
    z_eq: np.ndarray | None  # equilibrium of the active gaps (full 5-vector, NaN for free gaps)


@dataclasses.dataclass(frozen=True)
class System:
    """The four modes of one parameter point, and the event functionals ``L z = (d, phi)``."""

    B: np.ndarray
    a: np.ndarray
    k: np.ndarray
    q: np.ndarray
    L: np.ndarray  # (4, 5) event functionals: d1, d2, phi1, phi2
    modes: tuple
    omega: float  # reference frequency sqrt(max k_i |b_ii|) [1/time]


def _active_equilibrium(B, a, k, A, idx):
    """Eigenvalues of the active subsystem ``idx`` and its equilibrium ``B_SS K_S d_S = -a_S``,
    ``v = 0`` (a 5-vector, NaN for free gaps; None if singular)."""
    sub = idx + [i + 2 for i in idx]
    eig = np.linalg.eigvals(A[np.ix_(sub, sub)])
    BS = B[np.ix_(idx, idx)] * k[idx][None, :]
    z_eq = np.full(5, np.nan)
    try:
        d_eq = np.linalg.solve(BS, -a[idx])
    except np.linalg.LinAlgError:
        return eig, None
    z_eq[idx] = d_eq
    z_eq[[i + 2 for i in idx]] = 0.0
    z_eq[4] = 1.0
    return eig, z_eq


def _build_mode(mask, B, a, k, q, L, omega, theta) -> Mode:
    """Matrices of mode ``mask``: ``E_S`` (paper eqs. 7, 8), sub-step ``h_S = theta / rho_S``
    (floored at ``rho_S >= omega / 4``), ``expm(E_S h_S)`` and the Taylor terms ``E_S^n / n!``."""
    act = np.array([mask & 1, (mask >> 1) & 1], dtype=float)
    E = np.zeros((5, 5))
    E[0:2, 2:4] = _I2
    E[2:4, 0:2] = -B @ np.diag(k * act)
    E[2:4, 2:4] = -B @ np.diag(q * act)
    E[2:4, 4] = -a
    A = E[:4, :4]
    rho = float(np.max(np.abs(np.linalg.eigvals(A))))
    h = theta / max(rho, 0.25 * omega)
    P = np.empty((TAYLOR_DEGREE + 1, 5, 5))
    P[0] = np.eye(5)
    for n in range(1, TAYLOR_DEGREE + 1):
        P[n] = P[n - 1] @ E / n
    idx = [i for i in range(2) if act[i]]
    if idx:
        eig, z_eq = _active_equilibrium(B, a, k, A, idx)
        stable = bool(np.all(eig.real < 0))
    else:
        eig, stable, z_eq = np.zeros(0), True, None
    return Mode(
        mask=mask, E=E, h=h, Phi=expm(E * h), P=P, LE=L @ E, eig=eig, stable=stable, z_eq=z_eq
    )


def build_system(beta1, beta2, alpha, k, q, b_norm, a_norm, theta) -> System:
    """:class:`System` of the angles [rad], stiffnesses ``k``, dampings ``q``, ``|b_j|``, ``|a|``
    and sub-step fraction ``theta`` (see :func:`atlas.dynamics.simulate`); inputs checked."""
    beta1 = float(check_finite("beta1", beta1))
    beta2 = float(check_finite("beta2", beta2))
    alpha = float(check_finite("alpha", alpha))
    k = check_finite("k", checks.pair("k", k), positive=True)
    q = check_finite("q", checks.pair("q", q), nonneg=True)
    b_norm = check_finite("b_norm", checks.pair("b_norm", b_norm), positive=True)
    a_norm = float(check_finite("a_norm", a_norm, nonneg=True))
    theta = float(check_finite("theta", theta, positive=True))
    if theta > 1.0:
        raise ValueError(f"theta must be in (0, 1], got {theta!r}")
    B = _matrix_B(beta1, beta2, b_norm)
    a = a_norm * np.array([math.cos(alpha), math.sin(alpha)])
    L = np.zeros((4, 5))
    L[0, 0] = L[1, 1] = 1.0
    L[2, 0], L[2, 2] = -k[0], -q[0]
    L[3, 1], L[3, 3] = -k[1], -q[1]
    omega = math.sqrt(float(np.max(k * b_norm)))
    modes = tuple(_build_mode(mask, B, a, k, q, L, omega, theta) for mask in range(4))
    return System(B=B, a=a, k=k, q=q, L=L, modes=modes, omega=omega)


def run_scale(sysm: System, g0) -> float:
    """Length scale of a run, ``max(|d(0)|, |a| / min_i(k_i |b_i|))`` (the resting penetration
    scale) [1]."""
    return max(
        float(np.max(np.abs(np.asarray(g0)[:2]))),
        float(np.linalg.norm(sysm.a)) / float(np.min(sysm.k * np.linalg.norm(sysm.B, axis=0))),
        1e-300,
    )


def ss_equilibrium(beta1, beta2, alpha, k=(1.0, 1.0), b_norm=(1.0, 1.0), a_norm=1.0):
    """Equilibrium gaps of the SS mode, ``d* = -K^{-1} B^{-1} a`` (paper eq. 8 with ``g' = 0``).

    Returns
    -------
    d_eq : ndarray, shape (2,) or None
        Gaps [1] (units of the inputs) if the SS mode is consistent (``f* = B^{-1} a > 0``,
        SPEC §1), else None.
    """
    k = check_finite("k", checks.pair("k", k), positive=True)
    b_norm = check_finite("b_norm", checks.pair("b_norm", b_norm), positive=True)
    B = _matrix_B(beta1, beta2, b_norm)
    a = a_norm * np.array([math.cos(alpha), math.sin(alpha)])
    try:
        f = np.linalg.solve(B, a)
    except np.linalg.LinAlgError:
        return None
    if not np.all(f > 0):
        return None
    return -f / k


def iwc_aligned(sysm: System, mask: int, g, tol) -> bool:
    """State in an impact without collision (paper Sec. 4.3) in mode ``mask``.

    The deviation of the active gaps and velocities from the mode's equilibrium is expanded in the
    eigenvectors of the active subsystem; it must lie in the span of the real positive eigenvalues
    (other components below ``tol`` relative), the component along the dominant one must be
    non-zero and send every active gap to ``-inf`` (its force to ``+inf``), the active gaps must be
    negative and decreasing, and every free gap open and opening (:func:`iwc_aligned_many` of
    one state).
    """
    mode = sysm.modes[mask]
    if not mask or mode.z_eq is None:
        return False
    g = np.asarray(g, dtype=float)[None, :4]
    return bool(iwc_aligned_many(mode.E[None], mode.z_eq[None], np.array([mask]), g, tol)[0])


#: share of the dominant eigenvector part below which an active gap's component counts as zero
#: (a decoupled contact, ``B`` diagonal up to rounding: its sign is a rounding residue)
DIRECTION_TOL = 1e-9


def aligned_in_basis(w, V, c, dev, n_active, tol):
    """The test of :func:`iwc_aligned` on the expansion ``dev = V c`` (n, na) of the active
    deviations in the eigenvectors ``V`` (n, na, na) with eigenvalues ``w`` (n, na): a real,
    positive dominant eigenvalue carries the deviation (each other part ``|c_m| |v_m| <= tol
    |dev|``) along a direction in which every active gap (the first ``n_active`` components)
    decreases (by more than ``DIRECTION_TOL`` of that part).  NumPy or JAX arrays
    (:func:`atlas.dynamics.event_bounds.xp_of`); bool (n,)."""
    xp = xp_of(w, V, c, dev)
    real_pos = (xp.abs(w.imag) <= 1e-9 * xp.abs(w).max(axis=1, keepdims=True)) & (w.real > 0)
    norm = xp.linalg.norm(dev, axis=1)[:, None]
    parts = xp.abs(c) * xp.linalg.norm(V, axis=1)
    dom = xp.argmax(xp.where(real_pos, w.real, -np.inf), axis=1)
    direction = (take(c, dom)[:, None] * take(V, dom[:, None])).real
    p_dom = take(parts, dom)
    ok = real_pos.any(axis=1) & xp.isfinite(c).all(axis=1)
    ok &= ~xp.any(~real_pos & (parts > tol * norm), axis=1)
    ok &= p_dom > tol * norm[:, 0]
    # each active gap driven down by more than rounding (DIRECTION_TOL of the dominant part)
    ok &= xp.all(direction[:, :n_active] < -DIRECTION_TOL * p_dom[:, None], axis=1)
    return ok


def iwc_aligned_many(E, z_eq, mask, g, tol, eig=None) -> np.ndarray:
    """:func:`iwc_aligned` of ``n`` states ``g`` (n, 4) in the modes ``mask`` (n,) with augmented
    matrices ``E`` (n, 5, 5) and equilibria ``z_eq`` (n, 5); the same arithmetic per state
    (LAPACK ``geev`` and ``gesv`` per matrix).  ``eig(m, rows)``, if given, returns the
    eigenvalues and eigenvectors (complex) that ``geev`` gives for the active subsystems of
    ``E[rows]`` in mode ``m`` (computed once per configuration, e.g.
    :meth:`atlas.dynamics.modal_form.ModalTables.eig`); the same result.  Returns bool (n,)."""
    mask = np.asarray(mask, dtype=int)
    out = np.zeros(mask.shape[0], dtype=bool)
    for m in (1, 2, 3):
        sel = np.flatnonzero(mask == m)
        if sel.size == 0:
            continue
        idx = [i for i in range(2) if m >> i & 1]
        free = [i for i in range(2) if not m >> i & 1]
        sub = idx + [i + 2 for i in idx]
        gs = g[sel]
        signs = np.all(gs[:, sub] < 0, axis=1)
        for i in free:
            signs &= (gs[:, i] >= 0) & (gs[:, i + 2] >= 0)
        sel, gs = sel[signs], gs[signs]
        if sel.size == 0:
            continue
        w, V = _active_eig(E, sel, sub, m, eig)
        dev = gs[:, sub] - z_eq[sel][:, sub]
        try:
            c = np.linalg.solve(V, dev[:, :, None])[:, :, 0]
        except np.linalg.LinAlgError:  # a singular basis: that state is not aligned
            c = np.full(dev.shape, np.nan, dtype=complex)
            for r in range(sel.size):
                try:
                    c[r] = np.linalg.solve(V[r], dev[r])
                except np.linalg.LinAlgError:
                    pass
        out[sel] = aligned_in_basis(w, V, c, dev, len(idx), tol)
    return out


def _active_eig(E, sel, sub, m, eig):
    """``numpy.linalg.eig`` of the active subsystems ``E[sel]`` (indices ``sub``) of mode ``m``,
    or the same from ``eig(m, sel)`` (its complex output made real where every eigenvalue of the
    batch is, as ``numpy.linalg.eig`` returns a batch)."""
    if eig is None:
        return np.linalg.eig(E[sel][:, sub][:, :, sub])
    w, V = eig(m, sel)
    if np.all(w.imag == 0.0):
        return w.real, V.real
    return w, V


def eig_rows(eig, rows):
    """The ``eig`` argument of :func:`iwc_aligned_many` for the states ``rows`` of a batch
    (``None`` stays ``None``)."""
    if eig is None:
        return None
    return lambda m, sel: eig(m, rows[sel])
