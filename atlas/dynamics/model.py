"""Exact event-driven simulator of the compliant two-contact dynamics (paper Sec. 4.1, 6.4-6.5).

The gaps ``d = (d1, d2)`` obey ``d'' = B f - a`` (paper eq. 1) with the rescaled Kelvin-Voigt
contact law (paper eq. 6)::

    f_i = 0                               if d_i > 0
    f_i = max(0, -k_i d_i - q_i d_i')     if d_i <= 0

State ``g = (d1, d2, d1', d2')``.  A contact is *active* when ``d_i <= 0`` and the force
``phi_i = -k_i d_i - q_i d_i' > 0``.  For a fixed active set ``S`` the dynamics is linear with a
constant forcing, ``g' = A_S g + c_S`` (paper eqs. 7, 8), so between switching events the state is
advanced exactly with the matrix exponential of the augmented matrix ``E_S = [[A_S, c_S], [0, 0]]``
(scaling and squaring of its degree-30 Taylor polynomial, :func:`_expm`).

Event detection (no crossing skipped)
-------------------------------------
The monitored event functions are linear functionals of the state: the gaps ``d_i`` (always) and
the forces ``phi_i`` (while ``d_i <= 0``).  Time is cut into sub-steps ``h_S = theta / rho_S``
where ``rho_S`` is the largest eigenvalue modulus of ``A_S`` (``theta = 0.5`` by default, i.e.
about 1/12 of the fastest period), and advanced with ``expm(E_S h_S)``.  On each sub-step a
crossing is detected when the function's value at the end has the opposite sign to the recorded
one *or* when its derivative changes sign and the value at the extremum (found by Brent's method)
has the opposite sign (this catches a double crossing inside one sub-step).  The crossing is
then located by Brent's method on the exact Taylor polynomial of ``expm(E_S tau) z`` (degree 30,
truncation error below 1e-30 for ``rho_S tau <= 0.5``) to an absolute time tolerance
``xtol = 1e-13 h_S``.  A burst of events ends with status ``"event_cap"``, never a hang.

Time is in the units of the inputs (the paper's Fig. 2 uses ``k = (100, 200)``); with ``k2 = 1``,
``k1 = kappa``, ``|b| = 1`` it is the SPEC's scaled time ``1 / sqrt(k2 |b2|)``.
"""

from __future__ import annotations

import dataclasses
import enum
import math
import time as _time
from collections.abc import Sequence

import numpy as np
import scipy.optimize

__all__ = [
    "Outcome",
    "Status",
    "SimulationResult",
    "simulate",
    "classify",
    "simulate_solve_ivp",
    "fig2_cases",
    "ss_equilibrium",
    "TrajectoryStats",
    "trajectory_stats",
    "classify_stats",
    "simulate_outcome",
    "subclass_codes",
    "no_stable_subclass",
    "outcome_grid",
    "perturbed_initial_states",
    "outcome_map",
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

_TAYLOR_DEGREE = 30
_I2 = np.eye(2)


def _expm(M: np.ndarray) -> np.ndarray:
    """Matrix exponential by scaling and squaring of the degree-30 Taylor polynomial.

    ``M / 2^s`` has 1-norm <= 1/2, where the truncation error is below ``0.5^31 / 31! < 1e-42``
    (relative); ``scipy.linalg.expm`` (1.17) takes ~15 ms on small-norm 5 x 5 matrices, this ~30 us.
    """
    norm = float(np.abs(M).sum(axis=0).max())
    s = max(0, math.ceil(math.log2(norm / 0.5))) if norm > 0.5 else 0
    X = M / 2.0**s
    acc = np.eye(M.shape[0])
    for n in range(_TAYLOR_DEGREE, 0, -1):
        acc = np.eye(M.shape[0]) + (X @ acc) / n
    for _ in range(s):
        acc = acc @ acc
    return acc


def _mode_name(mask: int) -> str:
    """``'SF'`` etc.: letter i is ``S`` when contact i is active (bit i-1 of ``mask``)."""
    return ("S" if mask & 1 else "F") + ("S" if mask & 2 else "F")


# ----------------------------------------------------------------------------- system


def _check_finite(name, value, *, positive=False, nonneg=False):
    arr = np.asarray(value, dtype=float)
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be finite, got {value!r}")
    if positive and np.any(arr <= 0):
        raise ValueError(f"{name} must be > 0, got {value!r}")
    if nonneg and np.any(arr < 0):
        raise ValueError(f"{name} must be >= 0, got {value!r}")
    return arr


def _pair(name, value):
    arr = np.broadcast_to(np.asarray(value, dtype=float), (2,)).copy()
    return arr


@dataclasses.dataclass(frozen=True)
class _Mode:
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
class _System:
    B: np.ndarray
    a: np.ndarray
    k: np.ndarray
    q: np.ndarray
    L: np.ndarray  # (4, 5) event functionals: d1, d2, phi1, phi2
    modes: tuple
    omega: float  # reference frequency sqrt(max k_i |b_ii|) [1/time]


def _build_system(beta1, beta2, alpha, k, q, b_norm, a_norm, theta) -> _System:
    beta1 = float(_check_finite("beta1", beta1))
    beta2 = float(_check_finite("beta2", beta2))
    alpha = float(_check_finite("alpha", alpha))
    k = _check_finite("k", _pair("k", k), positive=True)
    q = _check_finite("q", _pair("q", q), nonneg=True)
    b_norm = _check_finite("b_norm", _pair("b_norm", b_norm), positive=True)
    a_norm = float(_check_finite("a_norm", a_norm, nonneg=True))
    theta = float(_check_finite("theta", theta, positive=True))
    if theta > 1.0:
        raise ValueError(f"theta must be in (0, 1], got {theta!r}")
    B = np.array(
        [
            [b_norm[0] * math.cos(beta1), b_norm[1] * math.cos(beta2)],
            [b_norm[0] * math.sin(beta1), b_norm[1] * math.sin(beta2)],
        ]
    )
    a = a_norm * np.array([math.cos(alpha), math.sin(alpha)])
    L = np.zeros((4, 5))
    L[0, 0] = L[1, 1] = 1.0
    L[2, 0], L[2, 2] = -k[0], -q[0]
    L[3, 1], L[3, 3] = -k[1], -q[1]
    omega = math.sqrt(float(np.max(k * b_norm)))
    modes = []
    for mask in range(4):
        act = np.array([mask & 1, (mask >> 1) & 1], dtype=float)
        E = np.zeros((5, 5))
        E[0:2, 2:4] = _I2
        E[2:4, 0:2] = -B @ np.diag(k * act)
        E[2:4, 2:4] = -B @ np.diag(q * act)
        E[2:4, 4] = -a
        A = E[:4, :4]
        rho = float(np.max(np.abs(np.linalg.eigvals(A))))
        h = theta / max(rho, 0.25 * omega)
        Phi = _expm(E * h)
        P = np.empty((_TAYLOR_DEGREE + 1, 5, 5))
        P[0] = np.eye(5)
        for n in range(1, _TAYLOR_DEGREE + 1):
            P[n] = P[n - 1] @ E / n
        idx = [i for i in range(2) if act[i]]
        if idx:
            sub = idx + [i + 2 for i in idx]
            eig = np.linalg.eigvals(A[np.ix_(sub, sub)])
            stable = bool(np.all(eig.real < 0))
            # equilibrium of the active gaps: B_SS K_S d_S = -a_S (v = 0)
            BS = B[np.ix_(idx, idx)] * k[idx][None, :]
            z_eq = np.full(5, np.nan)
            try:
                d_eq = np.linalg.solve(BS, -a[idx])
                z_eq[idx] = d_eq
                z_eq[[i + 2 for i in idx]] = 0.0
                z_eq[4] = 1.0
            except np.linalg.LinAlgError:
                z_eq = None
        else:
            eig = np.zeros(0)
            stable = True
            z_eq = None
        modes.append(
            _Mode(mask=mask, E=E, h=h, Phi=Phi, P=P, LE=L @ E, eig=eig, stable=stable, z_eq=z_eq)
        )
    return _System(B=B, a=a, k=k, q=q, L=L, modes=tuple(modes), omega=omega)


def ss_equilibrium(beta1, beta2, alpha, k=(1.0, 1.0), b_norm=(1.0, 1.0), a_norm=1.0):
    """Equilibrium gaps of the SS mode, ``d* = -K^{-1} B^{-1} a`` (paper eq. 8 with ``g' = 0``).

    Returns
    -------
    d_eq : ndarray, shape (2,) or None
        Gaps [1] (units of the inputs) if the SS mode is consistent (``f* = B^{-1} a > 0``,
        SPEC §1), else None.
    """
    k = _check_finite("k", _pair("k", k), positive=True)
    b_norm = _check_finite("b_norm", _pair("b_norm", b_norm), positive=True)
    B = np.array(
        [
            [b_norm[0] * math.cos(beta1), b_norm[1] * math.cos(beta2)],
            [b_norm[0] * math.sin(beta1), b_norm[1] * math.sin(beta2)],
        ]
    )
    a = a_norm * np.array([math.cos(alpha), math.sin(alpha)])
    try:
        f = np.linalg.solve(B, a)
    except np.linalg.LinAlgError:
        return None
    if not np.all(f > 0):
        return None
    return -f / k


# ----------------------------------------------------------------------------- result


@dataclasses.dataclass
class SimulationResult:
    """Output of :func:`simulate`.

    Attributes
    ----------
    t_events : ndarray (n_events,)
        Event times [time].
    kinds : list of str
        ``"impact"`` (gap d_i becomes <= 0), ``"liftoff"`` (d_i becomes > 0), ``"force_on"``,
        ``"force_off"`` (``-k_i d_i - q_i d_i'`` changes sign while ``d_i <= 0``).
    contacts : ndarray of int (n_events,)
        Contact index (1 or 2) of each event.
    states : ndarray (n_events, 4)
        State ``g = (d1, d2, d1', d2')`` at each event.
    modes : list of str
        Contact configuration (``"SS"``, ``"SF"``, ``"FS"``, ``"FF"``; S = active) after each event.
    t_final, g_final, mode_final
        Time, state and configuration where the run stopped.
    status : Status
    message : str
    n_steps : int
        Sub-steps taken.
    wall_time : float
        [s].
    scale : float
        Length scale of the run, ``max(|d(0)|, |a| / min_i(k_i |b_i|))`` (the resting
        penetration scale) [1]; the amplitude tests of :func:`classify` are relative to it.
    """

    t_events: np.ndarray
    kinds: list
    contacts: np.ndarray
    states: np.ndarray
    modes: list
    t_final: float
    g_final: np.ndarray
    mode_final: str
    status: Status
    message: str
    n_steps: int
    wall_time: float
    scale: float
    _system: _System = dataclasses.field(repr=False)
    _seg_t: np.ndarray = dataclasses.field(repr=False)
    _seg_z: np.ndarray = dataclasses.field(repr=False)
    _seg_mask: np.ndarray = dataclasses.field(repr=False)
    _env_t: np.ndarray = dataclasses.field(repr=False, default=None)
    _env_d: np.ndarray = dataclasses.field(repr=False, default=None)

    @property
    def n_events(self) -> int:
        return len(self.t_events)

    def sample(self, times) -> np.ndarray:
        """Exact state at the requested times (dense output).

        Parameters
        ----------
        times : array_like
            Times in ``[0, t_final]`` [time].

        Returns
        -------
        ndarray (..., 4)
            ``g(t) = expm(E_S (t - t_s)) g(t_s)`` from the segment start ``t_s`` preceding ``t``
            (evaluated as whole sub-steps ``expm(E_S h_S)`` plus the degree-30 Taylor polynomial
            of the remainder, like the simulator itself).
        """
        times = np.asarray(times, dtype=float)
        if np.any(~np.isfinite(times)) or np.any(times < 0) or np.any(times > self.t_final):
            raise ValueError("times must lie in [0, t_final]")
        flat = times.ravel()
        seg = np.searchsorted(self._seg_t, flat, side="right") - 1
        seg = np.clip(seg, 0, len(self._seg_t) - 1)
        out = np.empty((flat.size, 4))
        for s in np.unique(seg):
            sel = seg == s
            mode = self._system.modes[self._seg_mask[s]]
            tau = flat[sel] - self._seg_t[s]
            # the simulator's own arithmetic: sub-steps expm(E h), then the Taylor polynomial
            n = np.floor(tau / mode.h).astype(int)
            grid = np.empty((n.max() + 1, 5))
            grid[0] = self._seg_z[s]
            for m in range(1, n.max() + 1):
                grid[m] = mode.Phi @ grid[m - 1]
            off = tau - n * mode.h
            W = np.einsum("kij,sj->ksi", mode.P, grid[n])
            acc = np.zeros((tau.size, 5))
            for kk in range(W.shape[0] - 1, -1, -1):
                acc = acc * off[:, None] + W[kk]
            out[sel] = acc[:, :4]
        return out.reshape(times.shape + (4,))


# ----------------------------------------------------------------------------- core


def _horner(c, tau):
    acc = 0.0
    for cn in reversed(c):
        acc = acc * tau + cn
    return acc


def _root(coef, s, hi, xtol):
    """First root in (0, hi] of the polynomial ``coef`` (ascending), whose sign at 0 is ``s``."""
    c = coef.tolist()

    def F(tau):
        if tau == 0.0:
            return s * 1e-300
        return _horner(c, tau)

    if s * F(hi) >= 0:
        # the bracket came from expm(E h) z, whose sign at hi differs only by rounding from the
        # Taylor polynomial's: the sign change is at the end of the sub-step
        return hi
    return scipy.optimize.brentq(F, 0.0, hi, xtol=xtol, rtol=4 * np.finfo(float).eps)


def simulate(
    beta1: float,
    beta2: float,
    alpha: float,
    k: Sequence[float] = (1.0, 1.0),
    q: Sequence[float] = (0.0, 0.0),
    b_norm: Sequence[float] = (1.0, 1.0),
    a_norm: float = 1.0,
    g0: Sequence[float] = (0.0, 0.0, 0.0, 0.0),
    t_end: float = 10.0,
    max_events: int = 10_000,
    max_steps: int = 10_000_000,
    amplitude_limit: float | None = None,
    penetration_limit: float | None = None,
    stop_when_settled: bool = True,
    settle_rtol: float = 1e-6,
    theta: float = 0.5,
) -> SimulationResult:
    """Simulate the compliant-contact gap dynamics exactly between events (paper eqs. 1, 6-8).

    Parameters
    ----------
    beta1, beta2 : float
        Directions of the columns ``b_j = |b_j| (cos beta_j, sin beta_j)`` of ``B`` [rad].
    alpha : float
        Direction of ``a = |a| (cos alpha, sin alpha)`` [rad].
    k : (float, float)
        Contact stiffnesses ``k_i > 0`` (paper eq. 6) [1].
    q : (float, float)
        Contact damping ``q_i >= 0`` (paper eq. 6) [1].
    b_norm : (float, float)
        ``|b_1|, |b_2| > 0`` [1].
    a_norm : float
        ``|a| >= 0`` [1].
    g0 : (float, float, float, float)
        Initial state ``(d1, d2, d1', d2')`` [1].
    t_end : float
        Final time [time].
    max_events : int
        Stop with status ``"event_cap"`` after this many events.
    max_steps : int
        Stop with status ``"step_cap"`` after this many sub-steps.
    amplitude_limit, penetration_limit : float, optional
        Stop with status ``"diverged"`` when a gap ``d_i > amplitude_limit``, when an active
        contact has ``d_i < -penetration_limit`` while the state is aligned with an IWC
        eigenvector (impact without collision, paper Sec. 4.3; see :func:`classify`), or when any
        ``d_i < -1e3 penetration_limit``.
        Defaults: ``1e4`` and ``1e3`` times the scale
        ``s = max(|d(0)|, |a| / min_i(k_i |b_i|))``.
    stop_when_settled : bool
        Stop with status ``"settled"`` once a mode is reached from which no event can follow:
        the active subsystem is asymptotically stable, the state is within
        ``settle_rtol * |d_eq|`` of its equilibrium with all equilibrium forces > 0, and every
        free gap is positive, non-decreasing and accelerating away (``d_i'' > 0``).
    settle_rtol : float
        Relative tolerance of the settling test [1].
    theta : float
        Sub-step as a fraction of ``1 / rho_S`` (fastest eigenvalue modulus), ``0 < theta <= 1``.

    Returns
    -------
    SimulationResult
    """
    t_wall = _time.perf_counter()
    sysm = _build_system(beta1, beta2, alpha, k, q, b_norm, a_norm, theta)
    g0 = _check_finite("g0", g0)
    if g0.shape != (4,):
        raise ValueError(f"g0 must have 4 components (d1, d2, d1', d2'), got shape {g0.shape}")
    t_end = float(_check_finite("t_end", t_end, positive=True))
    if int(max_events) < 1:
        raise ValueError(f"max_events must be >= 1, got {max_events!r}")
    if int(max_steps) < 1:
        raise ValueError(f"max_steps must be >= 1, got {max_steps!r}")
    scale = max(
        float(np.max(np.abs(g0[:2]))),
        float(np.linalg.norm(sysm.a)) / float(np.min(sysm.k * np.linalg.norm(sysm.B, axis=0))),
        1e-300,
    )
    amp_lim = 1e4 * scale if amplitude_limit is None else float(amplitude_limit)
    pen_lim = 1e3 * scale if penetration_limit is None else float(penetration_limit)
    _check_finite("amplitude_limit", amp_lim, positive=True)
    _check_finite("penetration_limit", pen_lim, positive=True)

    L = sysm.L
    z = np.append(g0, 1.0)
    vals = L @ z
    # recorded signs of the four event functions (d1, d2, phi1, phi2); -1 means "<= 0"
    s = np.where(vals > 0, 1.0, -1.0)
    mask = _mask_from_signs(s)
    t = 0.0
    ev_t, ev_kind, ev_c, ev_z, ev_mode = [], [], [], [], []
    seg_t, seg_z, seg_mask = [0.0], [z.copy()], [mask]
    env_t, env_d = [0.0], [z[:2].copy()]  # gaps at every sub-step end and event (for classify)
    n_steps = 0
    status, message = Status.T_END, "reached t_end"
    while True:
        mode = sysm.modes[mask]
        if t >= t_end:
            status, message = Status.T_END, "reached t_end"
            break
        if n_steps >= max_steps:
            status, message = Status.STEP_CAP, f"{max_steps} sub-steps"
            break
        h = min(mode.h, t_end - t)
        Phi = mode.Phi if h == mode.h else _expm(mode.E * h)
        z1 = Phi @ z
        f1 = L @ z1
        fp0 = mode.LE @ z
        fp1 = mode.LE @ z1
        monitored = (0, 1) + tuple(2 + i for i in range(2) if s[i] < 0)
        xtol = 1e-13 * mode.h
        brackets = {}
        W = None
        for j in monitored:
            if s[j] * f1[j] < 0:
                brackets[j] = h
            elif s[j] * fp0[j] < 0 and s[j] * fp1[j] > 0:
                # s*f has an interior minimum: does it dip across zero?
                if W is None:
                    W = mode.P @ z
                cj = W @ L[j]
                dcj = cj[1:] * np.arange(1, len(cj))
                tau_e = _root(dcj, np.sign(fp0[j]), h, xtol)
                if s[j] * _horner(cj.tolist(), tau_e) < 0:
                    brackets[j] = tau_e
        n_steps += 1
        if not brackets:
            t += h
            z = z1
            env_t.append(t)
            env_d.append(z[:2].copy())
            if _diverged(sysm, z, mask, amp_lim, pen_lim):
                status, message = Status.DIVERGED, _div_message(z, mask, amp_lim, pen_lim)
                break
            if stop_when_settled and _settled(sysm, mode, z, settle_rtol):
                status, message = Status.SETTLED, f"settled in mode {_mode_name(mask)}"
                break
            continue
        if W is None:
            W = mode.P @ z
        roots = {j: _root(W @ L[j], s[j], hi, xtol) for j, hi in brackets.items()}
        r = min(roots.values())
        crossing = sorted(j for j, rj in roots.items() if rj <= r + 1e3 * xtol)
        z_new = _horner_vec(W, r)
        z_new[4] = 1.0
        t += r
        dphi = mode.LE @ z_new  # derivatives at the event (pre-event mode)
        vals = L @ z_new
        for j in crossing:
            s[j] = -s[j]
        for j in crossing:
            i = j % 2
            if j < 2:
                kind = IMPACT if s[j] < 0 else LIFTOFF
                if s[j] < 0:  # gap closed: force sign now matters
                    if abs(vals[2 + i]) > 1e-9 * abs(sysm.k[i] * scale):
                        s[2 + i] = 1.0 if vals[2 + i] > 0 else -1.0
                    else:
                        s[2 + i] = 1.0 if dphi[2 + i] > 0 else -1.0
                else:
                    s[2 + i] = -1.0
            else:
                if s[i] > 0 and i not in [c % 2 for c in crossing if c < 2]:
                    continue  # force sign change while the gap is open: no effect
                kind = FORCE_ON if s[j] > 0 else FORCE_OFF
            ev_t.append(t)
            ev_kind.append(kind)
            ev_c.append(i + 1)
            ev_z.append(z_new[:4].copy())
        z = z_new
        env_t.append(t)
        env_d.append(z[:2].copy())
        new_mask = _mask_from_signs(s)
        for _ in range(len(ev_t) - len(ev_mode)):
            ev_mode.append(_mode_name(new_mask))
        mask = new_mask
        seg_t.append(t)
        seg_z.append(z.copy())
        seg_mask.append(mask)
        if len(ev_t) >= max_events:
            status, message = Status.EVENT_CAP, f"{len(ev_t)} events by t = {t:.6g}"
            break
        if _diverged(sysm, z, mask, amp_lim, pen_lim):
            status, message = Status.DIVERGED, _div_message(z, mask, amp_lim, pen_lim)
            break
    return SimulationResult(
        t_events=np.array(ev_t),
        kinds=ev_kind,
        contacts=np.array(ev_c, dtype=int),
        states=np.array(ev_z).reshape(-1, 4),
        modes=ev_mode,
        t_final=t,
        g_final=z[:4].copy(),
        mode_final=_mode_name(mask),
        status=status,
        message=message,
        n_steps=n_steps,
        wall_time=_time.perf_counter() - t_wall,
        scale=scale,
        _system=sysm,
        _seg_t=np.array(seg_t),
        _seg_z=np.array(seg_z),
        _seg_mask=np.array(seg_mask, dtype=int),
        _env_t=np.array(env_t),
        _env_d=np.array(env_d).reshape(-1, 2),
    )


def _horner_vec(W, tau):
    acc = np.zeros(W.shape[1])
    for n in range(W.shape[0] - 1, -1, -1):
        acc = acc * tau + W[n]
    return acc


def _mask_from_signs(s) -> int:
    a1 = s[0] < 0 and s[2] > 0
    a2 = s[1] < 0 and s[3] > 0
    return int(a1) | (int(a2) << 1)


def _diverged(sysm, z, mask, amp_lim, pen_lim) -> bool:
    """Gap above ``amp_lim``, or an active gap below ``-pen_lim`` along an IWC eigenvector
    (or any gap below ``-1e3 pen_lim``)."""
    if not np.all(np.isfinite(z)):
        return True
    if np.max(z[:2]) > amp_lim or np.min(z[:2]) < -1e3 * pen_lim:
        return True
    for i in range(2):
        if mask >> i & 1 and z[i] < -pen_lim and _iwc_aligned(sysm, mask, z[:4], 1e-3):
            return True
    return False


def _div_message(z, mask, amp_lim, pen_lim) -> str:
    return (
        f"gaps {z[0]:.3g}, {z[1]:.3g} in mode {_mode_name(mask)} left "
        f"[-{pen_lim:.3g} (active), {amp_lim:.3g}]"
    )


def _settled(sysm: _System, mode: _Mode, z, rtol) -> bool:
    if not mode.stable:
        return False
    acc = sysm.modes[mode.mask].E[2:4] @ z
    for i in range(2):
        if not mode.mask >> i & 1:
            if z[i] <= 0 or z[2 + i] < 0 or acc[i] <= 0:
                return False
    if mode.mask == 0:
        return True
    if mode.z_eq is None:
        return False
    idx = [i for i in range(2) if mode.mask >> i & 1]
    d_eq = mode.z_eq[idx]
    if np.any(d_eq >= 0):
        return False
    dev = np.abs(z[idx] - d_eq).max() + np.abs(z[[i + 2 for i in idx]]).max() / sysm.omega
    if dev > rtol * np.abs(d_eq).max():
        return False
    # the free gap must keep accelerating away once the active gaps sit at equilibrium
    z_star = z.copy()
    z_star[idx] = d_eq
    z_star[[i + 2 for i in idx]] = 0.0
    acc_star = mode.E[2:4] @ z_star
    return all(acc_star[i] > 0 for i in range(2) if not mode.mask >> i & 1)


# ----------------------------------------------------------------------------- classification


@dataclasses.dataclass(frozen=True)
class TrajectoryStats:
    """What :func:`classify` reads from a trajectory (any simulator can fill it in).

    Attributes
    ----------
    t_final : float
        End of the run ``T`` [time].
    status : Status
    mode_final : str
        Contact configuration at ``T``.
    g_final : ndarray (4,)
        State at ``T``.
    scale : float
        Length scale of the run (:attr:`SimulationResult.scale`) [1].
    last_event : float
        Time of the last event (0 if none) [time].
    t_imp, v_imp : ndarray
        Impact times [time] and impact speeds ``|d_i'|`` [1/time], in time order, including the
        return of a gap in free flight (FF, falling back) dated ``T``.
    c_imp : ndarray of int
        Contact (1, 2) of each impact.
    late_amplitude : ndarray (2,)
        ``max |d_i|`` over the sub-step ends and events in ``[2T/3, T]`` [1].
    """

    t_final: float
    status: Status
    mode_final: str
    g_final: np.ndarray
    scale: float
    last_event: float
    t_imp: np.ndarray
    v_imp: np.ndarray
    c_imp: np.ndarray
    late_amplitude: np.ndarray


def trajectory_stats(res: SimulationResult) -> TrajectoryStats:
    """:class:`TrajectoryStats` of a :func:`simulate` result."""
    sysm = res._system
    T = res.t_final
    mask = ["FF", "SF", "FS", "SS"].index(res.mode_final)
    g = res.g_final
    acc = sysm.modes[mask].E[2:4] @ np.append(g, 1.0)
    imp = np.array([k == IMPACT for k in res.kinds], dtype=bool)
    t_imp = res.t_events[imp]
    c_imp = res.contacts[imp]
    v_imp = np.abs(res.states[imp][np.arange(imp.sum()), c_imp + 1])
    # a free gap in flight that will come back: its impact speed, dated at the end of the run
    for i in range(2):
        if mask == 0 and g[i] > 0 and acc[i] < 0:  # FF: constant acceleration -a_i
            t_imp = np.append(t_imp, T)
            c_imp = np.append(c_imp, i + 1)
            v_imp = np.append(v_imp, math.sqrt(g[i + 2] ** 2 + 2 * abs(acc[i]) * g[i]))
    late = res._env_t >= 2 * T / 3
    amp = np.abs(res._env_d[late]).max(axis=0) if late.any() else np.abs(g[:2])
    return TrajectoryStats(
        t_final=T,
        status=res.status,
        mode_final=res.mode_final,
        g_final=g,
        scale=res.scale,
        last_event=float(res.t_events[-1]) if res.n_events else 0.0,
        t_imp=t_imp,
        v_imp=v_imp,
        c_imp=c_imp,
        late_amplitude=amp,
    )


def classify(
    res: SimulationResult,
    *,
    min_impacts: int = 6,
    growth_ratio: float = 1.25,
    small_amplitude: float = 10.0,
    align_tol: float = 1e-2,
) -> Outcome:
    """Outcome class of a simulated trajectory (the label depends on the simulated horizon).

    With ``T = t_final``, the impact speeds ``|d_i'|`` at the impacts (gap ``d_i`` closing),
    ``m2`` / ``m3`` = the largest impact speed with impact time in ``[T/3, 2T/3)`` /
    ``[2T/3, T]``, ``s`` the run's length scale (:attr:`SimulationResult.scale`: the larger of the
    initial gaps and the resting penetration ``|a| / min k_i |b_i|``) and ``A3`` the largest
    ``|d_i|`` in ``[2T/3, T]`` over the contacts with an impact there, the criteria are checked in
    this order:

    * ``settles_XY`` -- either the run stopped with status ``"settled"`` in mode XY (a stable mode
      is reached, the active gaps are within ``settle_rtol`` of their equilibrium and the free gaps
      move away, so no further event can occur; see :func:`simulate`), or it reached ``t_end``
      in mode XY with no event in the second half of the run and no eigenvalue of the active
      subsystem with positive real part (this admits the *neutral* ``q = 0`` SS mode, which
      oscillates forever without leaving the mode, as in the paper's Fig. 2b).
    * ``IWC`` -- impact without collision (paper Sec. 4.3): the run diverged and the state's
      deviation from the current mode's equilibrium is aligned (``1 - |cos| < align_tol``) with the
      eigenvector of a real positive eigenvalue of ``A_S`` along which every active gap goes to
      ``-inf`` (so its force goes to ``+inf``), with every free gap open and opening.
    * ``growing_bouncing`` -- the run diverged (a gap beyond ``1e4 s``) after at least 3 impacts
      with an event in its last 20 % or a gap in flight falling back; otherwise a diverged run is
      ``undetermined``.
    * ``undetermined`` if fewer than ``min_impacts`` impacts (too short a run: see
      :func:`simulate_outcome`, which extends the horizon).
    * ``growing_bouncing`` -- ``m3 > growth_ratio * m2`` (still growing late in the run); or
      ``A3 > small_amplitude * s``: the bouncing amplified the initial excursion more than
      ``small_amplitude`` times and keeps bouncing (this includes bouncing that grew and then
      saturated at a large amplitude, as the paper's Fig. 2c does after t ~ 300).
    * ``sustained_oscillation`` -- small (``A3 <= small_amplitude * s``) non-growing
      (``m2 / growth_ratio <= m3 <= growth_ratio * m2``) bouncing with an impact in the last 10 %
      of the run, status ``"t_end"`` or ``"event_cap"`` with the impacts spread over more than half
      of ``[0, T]``.
    * ``undetermined`` -- anything else (a Zeno-like burst at the event cap, decaying bouncing
      not yet settled, a slowly drifting mode at ``t_end``, ...).
    """
    return classify_stats(
        trajectory_stats(res),
        res._system,
        min_impacts=min_impacts,
        growth_ratio=growth_ratio,
        small_amplitude=small_amplitude,
        align_tol=align_tol,
    )


def classify_stats(
    st: TrajectoryStats,
    sysm: _System,
    *,
    min_impacts: int = 6,
    growth_ratio: float = 1.25,
    small_amplitude: float = 10.0,
    align_tol: float = 1e-2,
) -> Outcome:
    """:func:`classify` from the :class:`TrajectoryStats` of a run of the system ``sysm``."""
    T = st.t_final
    if st.status == Status.SETTLED:
        return Outcome[f"SETTLES_{st.mode_final}"]
    mask = ["FF", "SF", "FS", "SS"].index(st.mode_final)
    mode = sysm.modes[mask]
    g = st.g_final
    if st.status == Status.DIVERGED and mask and _iwc_aligned(sysm, mask, g, align_tol):
        return Outcome.IWC
    acc = mode.E[2:4] @ np.append(g, 1.0)
    if st.status in (Status.T_END, Status.DIVERGED) and st.last_event <= 0.5 * T:
        lam = mode.eig
        neutral_or_stable = lam.size == 0 or np.all(lam.real <= 1e-9 * np.abs(lam).max())
        if neutral_or_stable and _free_gaps_leaving(mode, g):
            return Outcome[f"SETTLES_{st.mode_final}"]
    t_imp, speeds = st.t_imp, st.v_imp
    if st.status == Status.DIVERGED:
        # a gap beyond the amplitude limit (1e4 x scale) after repeated impacts, with an event
        # late or a gap in flight falling back: growing bouncing
        in_flight = any(not mask >> i & 1 and acc[i] < 0 for i in range(2))
        if t_imp.size >= min(3, min_impacts) and (st.last_event >= 0.8 * T or in_flight):
            return Outcome.GROWING_BOUNCING
        return Outcome.UNDETERMINED
    if t_imp.size < min_impacts:
        return Outcome.UNDETERMINED
    mid = speeds[(t_imp >= T / 3) & (t_imp < 2 * T / 3)]
    late_sel = t_imp >= 2 * T / 3
    late = speeds[late_sel]
    if mid.size == 0 or late.size == 0:
        return Outcome.UNDETERMINED
    m2, m3 = mid.max(), late.max()
    if m3 > growth_ratio * m2:
        return Outcome.GROWING_BOUNCING
    bouncing = np.unique(st.c_imp[late_sel]) - 1
    if st.late_amplitude[bouncing].max() > small_amplitude * st.scale:
        return Outcome.GROWING_BOUNCING
    if m3 >= m2 / growth_ratio and t_imp[-1] >= 0.9 * T:
        if st.status == Status.T_END or (
            st.status == Status.EVENT_CAP and t_imp[-1] - t_imp[0] > 0.5 * T
        ):
            return Outcome.SUSTAINED_OSCILLATION
    return Outcome.UNDETERMINED


def simulate_outcome(*args, t_end: float = 150.0, horizon_cap: float = 8.0, **kwargs):
    """:func:`simulate` then :func:`classify`, doubling ``t_end`` (up to ``horizon_cap * t_end``)
    while the outcome is undetermined and the run simply ran out of time (status ``"t_end"``,
    at least one event: e.g. long flights between few impacts).

    Returns
    -------
    (Outcome, SimulationResult)
        The outcome and the last run.
    """
    t_max = horizon_cap * float(t_end)
    T = float(t_end)
    while True:
        res = simulate(*args, t_end=T, **kwargs)
        out = classify(res)
        if (
            out != Outcome.UNDETERMINED
            or res.status != Status.T_END
            or res.n_events == 0
            or 2 * T > t_max * (1 + 1e-12)
        ):
            return out, res
        T *= 2


def _free_gaps_leaving(mode: _Mode, g) -> bool:
    """Every free gap open, opening, and accelerating away once the active gaps sit at their
    equilibrium (the mean acceleration of an oscillating neutral mode)."""
    z = np.append(g, 1.0)
    if mode.mask and mode.z_eq is not None:
        idx = [i for i in range(2) if mode.mask >> i & 1]
        z[idx] = mode.z_eq[idx]
        z[[i + 2 for i in idx]] = 0.0
    elif mode.mask:
        return False
    acc = mode.E[2:4] @ z
    return all(
        g[i] > 0 and g[i + 2] >= 0 and acc[i] > 0 for i in range(2) if not mode.mask >> i & 1
    )


def _iwc_aligned(sysm: _System, mask: int, g, tol) -> bool:
    """State in an impact without collision (paper Sec. 4.3) in mode ``mask``.

    The deviation of the active gaps and velocities from the mode's equilibrium is expanded in the
    eigenvectors of the active subsystem; it must lie in the span of the real positive eigenvalues
    (other components below ``tol`` relative), the component along the dominant one must be
    non-zero and send every active gap to ``-inf`` (its force to ``+inf``), the active gaps must be
    negative and decreasing, and every free gap open and opening.
    """
    mode = sysm.modes[mask]
    idx = [i for i in range(2) if mask >> i & 1]
    if not idx or mode.z_eq is None:
        return False
    sub = idx + [i + 2 for i in idx]
    if any(g[i] >= 0 or g[i + 2] >= 0 for i in idx):
        return False
    if any(g[i] < 0 or g[i + 2] < 0 for i in range(2) if i not in idx):
        return False
    A = mode.E[np.ix_(sub, sub)]
    w, V = np.linalg.eig(A)
    dev = g[sub] - mode.z_eq[sub]
    try:
        c = np.linalg.solve(V, dev)
    except np.linalg.LinAlgError:
        return False
    real_pos = (np.abs(w.imag) <= 1e-9 * np.abs(w).max()) & (w.real > 0)
    if not real_pos.any():
        return False
    norm = np.linalg.norm(dev)
    parts = np.abs(c) * np.linalg.norm(V, axis=0)
    if np.any(parts[~real_pos] > tol * norm):
        return False
    dom = int(np.argmax(np.where(real_pos, w.real, -np.inf)))
    if parts[dom] <= tol * norm:
        return False
    direction = (c[dom] * V[:, dom]).real
    return bool(np.all(direction[: len(idx)] < 0))


# ----------------------------------------------------------------------------- reference


def simulate_solve_ivp(
    beta1,
    beta2,
    alpha,
    k=(1.0, 1.0),
    q=(0.0, 0.0),
    b_norm=(1.0, 1.0),
    a_norm=1.0,
    g0=(0.0, 0.0, 0.0, 0.0),
    t_end=10.0,
    max_events=10_000,
    method="DOP853",
    rtol=1e-12,
    atol=1e-15,
):
    """Independent reference: ``scipy.integrate.solve_ivp`` restarted at every switching event.

    Same contact law and the same event functions (gaps, forces) as :func:`simulate`, but the
    linear phases are integrated numerically (``method``, ``rtol``, ``atol``) and events are
    located by ``solve_ivp``'s terminal events.

    Returns
    -------
    dict with ``t_events`` (n,), ``contacts`` (n,), ``kinds`` (list), ``states`` (n, 4),
    ``g_final`` (4,), ``t_final``, ``nfev``, ``wall_time`` [s].
    """
    import scipy.integrate

    t_wall = _time.perf_counter()
    sysm = _build_system(beta1, beta2, alpha, k, q, b_norm, a_norm, 0.5)
    L = sysm.L
    g = np.asarray(g0, dtype=float).copy()
    s = np.where(L @ np.append(g, 1.0) > 0, 1.0, -1.0)
    t = 0.0
    out_t, out_c, out_k, out_z = [], [], [], []
    nfev = 0
    while t < t_end and len(out_t) < max_events:
        mask = _mask_from_signs(s)
        E = sysm.modes[mask].E
        A, c = E[:4, :4], E[:4, 4]
        monitored = [0, 1] + [2 + i for i in range(2) if s[i] < 0]

        def make(j, sj):
            def ev(_t, y):
                return sj * (L[j, :4] @ y + L[j, 4])

            ev.terminal = True
            ev.direction = -1
            return ev

        events = [make(j, s[j]) for j in monitored]
        sol = scipy.integrate.solve_ivp(
            lambda _t, y, A=A, c=c: A @ y + c,
            (t, t_end),
            g,
            method=method,
            rtol=rtol,
            atol=atol,
            events=events,
            **({"jac": (lambda _t, y, A=A: A)} if method in ("Radau", "BDF", "LSODA") else {}),
        )
        nfev += sol.nfev
        if sol.status != 1:
            g = sol.y[:, -1]
            t = t_end
            break
        hits = [
            (sol.t_events[n][0], monitored[n])
            for n in range(len(monitored))
            if sol.t_events[n].size
        ]
        t_hit = min(h[0] for h in hits)
        crossing = [j for th, j in hits if th <= t_hit + 1e-12]
        idx = [n for n in range(len(monitored)) if sol.t_events[n].size]
        g = sol.y_events[idx[0]][0].copy()
        t = t_hit
        vals = L @ np.append(g, 1.0)
        dvals = sysm.modes[mask].LE @ np.append(g, 1.0)
        for j in crossing:
            s[j] = -s[j]
        for j in crossing:
            i = j % 2
            if j < 2:
                kind = IMPACT if s[j] < 0 else LIFTOFF
                if s[j] < 0:
                    s[2 + i] = (
                        1.0
                        if (vals[2 + i] if abs(vals[2 + i]) > 1e-9 else dvals[2 + i]) > 0
                        else -1.0
                    )
                else:
                    s[2 + i] = -1.0
            else:
                if s[i] > 0:
                    continue
                kind = FORCE_ON if s[j] > 0 else FORCE_OFF
            out_t.append(t)
            out_c.append(i + 1)
            out_k.append(kind)
            out_z.append(g.copy())
    return {
        "t_events": np.array(out_t),
        "contacts": np.array(out_c, dtype=int),
        "kinds": out_k,
        "states": np.array(out_z).reshape(-1, 4),
        "g_final": g,
        "t_final": t,
        "nfev": nfev,
        "wall_time": _time.perf_counter() - t_wall,
    }


# ----------------------------------------------------------------------------- paper cases


def fig2_cases() -> dict:
    """Parameters of the paper's Fig. 2 panels a-e (caption), as keyword arguments of simulate.

    ``|b_1| = |b_2| = 1``, ``|a| = 1``, ``k = (100, 200)``.  ``t_end`` is chosen here (the paper
    does not state its time axis).
    """
    pi = math.pi
    base = {"k": (100.0, 200.0), "b_norm": (1.0, 1.0), "a_norm": 1.0}
    a = dict(
        base,
        beta1=0.2 * pi,
        beta2=0.65 * pi,
        alpha=0.35 * pi,
        q=(0.0, 0.0),
        g0=(-0.008, -0.004, 0.0, 0.0),
        t_end=10.0,
    )
    b = dict(a, beta1=0.05 * pi)
    c = dict(b, g0=(-0.05, -0.05, 0.0, 0.0))
    d = dict(
        base,
        beta1=0.15 * pi,
        beta2=1.07 * pi,
        alpha=0.2 * pi,
        q=(20.0, 20.0),
        g0=(0.0, 0.0, 0.0, 0.0),
        t_end=10.0,
    )
    e = dict(d, beta2=1.1 * pi)
    return {"a": a, "b": b, "c": c, "d": d, "e": e}


# ----------------------------------------------------------------------------- outcome map

#: subclasses (and their duals) where the paper predicts no stable mode or impact (Sec. 6.4-6.5)
NO_STABLE_SUBCLASSES = (132, 133, 142, 143)


def subclass_codes(beta1, beta2, alpha) -> np.ndarray:
    """Subclass codes ``ijk`` (SPEC §1) of angles [rad] via :func:`atlas.core.mechanics.subclass_code`
    (the reference implementation; 0 degenerate, -1 undecided); arrays broadcast."""
    import jax.numpy as jnp

    from atlas.core import mechanics

    vec = [mechanics.direction(np.asarray(x, dtype=float)) for x in (beta1, beta2, alpha)]
    args = [jnp.asarray(v) for cs in vec for v in cs]
    return np.asarray(mechanics.subclass_code(*args)).astype(np.int16)


def no_stable_subclass(beta1, beta2, alpha) -> np.ndarray:
    """True in subclasses 132, 133, 142, 143 or their duals (paper Sec. 6.4-6.5); arrays broadcast.

    The dual (contacts swapped) is :func:`atlas.core.mechanics.dual_vectors` of the direction vectors.
    """
    import jax.numpy as jnp

    from atlas.core import mechanics

    vec = [mechanics.direction(np.asarray(x, dtype=float)) for x in (beta1, beta2, alpha)]
    args = [jnp.asarray(v) for cs in vec for v in cs]
    code = np.asarray(mechanics.subclass_code(*args))
    dual = np.asarray(mechanics.subclass_code(*mechanics.dual_vectors(*args)))
    return np.isin(code, NO_STABLE_SUBCLASSES) | np.isin(dual, NO_STABLE_SUBCLASSES)


def outcome_grid(n: int) -> tuple[np.ndarray, np.ndarray]:
    """``beta1 = (i + 1/3) 2 pi / n``, ``beta2 = (j + 2/3) 2 pi / n`` [rad], ``i, j < n``.

    One sample per cell of the uniform ``n x n`` grid of ``[0, 2 pi)^2`` (the Fig. 1 cells for the
    same ``n``), offset so that no sample is degenerate for any ``n``: no angle is a multiple of
    ``pi / 2`` and ``beta2 - beta1`` is never a multiple of ``pi``.
    """
    n = int(n)
    if n < 1:
        raise ValueError(f"n must be >= 1, got {n!r}")
    step = 2 * math.pi / n
    return (np.arange(n) + 1 / 3) * step, (np.arange(n) + 2 / 3) * step


def perturbed_initial_states(
    beta1_values, beta2_values, alpha, kappa, n_perturb=1, seed=0, perturbation=1e-2
) -> np.ndarray:
    """Initial states of :func:`outcome_map`, shape ``(n1, n2, n_perturb, 4)``.

    Seeded perturbations of the SS equilibrium ``d* = -K^{-1} B^{-1} a`` (paper eq. 8):
    ``d = d* + perturbation * |d*| * xi``, ``d' = perturbation * |d*| * xi'`` with standard normal
    ``xi``; where the SS mode is inconsistent, ``d = -perturbation * |xi| / min(kappa, 1)``
    (both gaps pushed into contact), ``d' = perturbation * xi' / min(kappa, 1)``.
    """
    rng = np.random.default_rng(seed)
    b1 = np.atleast_1d(np.asarray(beta1_values, dtype=float))
    b2 = np.atleast_1d(np.asarray(beta2_values, dtype=float))
    out = np.empty((b1.size, b2.size, int(n_perturb), 4))
    for i, x1 in enumerate(b1):
        for j, x2 in enumerate(b2):
            d_eq = ss_equilibrium(x1, x2, alpha, k=(kappa, 1.0))
            for m in range(int(n_perturb)):
                xi = rng.standard_normal(4)
                if d_eq is not None:
                    s = np.abs(d_eq).max()
                    out[i, j, m, :2] = d_eq + perturbation * s * xi[:2]
                    out[i, j, m, 2:] = perturbation * s * xi[2:]
                else:
                    s = 1.0 / min(kappa, 1.0)
                    out[i, j, m, :2] = -perturbation * s * np.abs(xi[:2])
                    out[i, j, m, 2:] = perturbation * s * xi[2:]
    return out


def outcome_map(
    beta1_values,
    beta2_values,
    kappa: float = 0.5,
    q=0.0,
    alpha: float = 0.35 * math.pi,
    n_perturb: int = 1,
    seed: int = 0,
    perturbation: float = 1e-2,
    t_end: float = 150.0,
    horizon_cap: float = 8.0,
    max_events: int = 2000,
    engine: str = "numpy",
    progress=None,
):
    """Simulated outcome over a ``(beta1, beta2)`` grid (what the dynamics actually do).

    Scaled parameters (SPEC §1): ``|b_1| = |b_2| = |a| = 1``, ``k = (kappa, 1)``,
    ``q = (q1_hat, q2_hat)``; time in units of ``1 / sqrt(k2 |b2|)``.  Initial conditions from
    :func:`perturbed_initial_states`.  Each run is classified by :func:`classify`; undetermined
    runs that ran out of time are extended (``t_end`` doubled, up to ``horizon_cap * t_end``, see
    :func:`simulate_outcome`).

    Parameters
    ----------
    beta1_values, beta2_values : array_like
        Grid of contact directions [rad] (e.g. :func:`outcome_grid`).
    kappa : float
        ``k1 |b1| / (k2 |b2|)`` [1].
    q : float or (float, float)
        Scaled damping ``q_j_hat`` [1].
    alpha : float
        Direction of ``a`` [rad].
    n_perturb : int
        Initial conditions per grid point; ``outcome`` is the most frequent class and
        ``agreement`` the fraction of runs that gave it.
    seed : int
        Seed of ``numpy.random.default_rng``.
    perturbation : float
        Relative size of the perturbation [1].
    t_end, horizon_cap, max_events
        Horizon [scaled time], its extension factor, and event cap per trajectory.
    engine : {"numpy", "jax"}
        ``"numpy"``: :func:`simulate` run by run; ``"jax"``: the batched stepper of
        :mod:`atlas.dynamics.jax_engine` (one ``vmap`` over all runs, extension runs batched too).
    progress : callable, optional
        Called with ``(done, total)`` after each grid point (numpy engine).

    Returns
    -------
    xarray.Dataset
        ``outcome`` (int8, CF flags from :class:`Outcome`) and ``agreement`` (float32) over
        ``(beta1, beta2)``; ``no_stable_subclass`` (bool): subclasses 132, 133, 142, 143 or duals.
        Attributes record the parameters, ``trajectories``, ``seconds`` and
        ``trajectories_per_second``.
    """
    import xarray as xr

    b1 = np.atleast_1d(_check_finite("beta1_values", beta1_values)).astype(float)
    b2 = np.atleast_1d(_check_finite("beta2_values", beta2_values)).astype(float)
    if b1.ndim != 1 or b2.ndim != 1 or b1.size == 0 or b2.size == 0:
        raise ValueError("beta1_values and beta2_values must be non-empty 1-D arrays")
    kappa = float(_check_finite("kappa", kappa, positive=True))
    qq = _check_finite("q", np.broadcast_to(np.asarray(q, dtype=float), (2,)), nonneg=True)
    alpha = float(_check_finite("alpha", alpha))
    if int(n_perturb) < 1:
        raise ValueError(f"n_perturb must be >= 1, got {n_perturb!r}")
    perturbation = float(_check_finite("perturbation", perturbation, positive=True))
    t_end = float(_check_finite("t_end", t_end, positive=True))
    horizon_cap = float(_check_finite("horizon_cap", horizon_cap, positive=True))
    if horizon_cap < 1:
        raise ValueError(f"horizon_cap must be >= 1, got {horizon_cap!r}")
    if engine not in ("numpy", "jax"):
        raise ValueError(f"engine must be 'numpy' or 'jax', got {engine!r}")
    g0 = perturbed_initial_states(b1, b2, alpha, kappa, n_perturb, seed, perturbation)
    k = (kappa, 1.0)
    t0 = _time.perf_counter()
    if engine == "jax":
        from atlas.dynamics import jax_engine as dynamics_jax

        codes = dynamics_jax.outcomes(
            b1, b2, alpha, k, qq, g0, t_end=t_end, horizon_cap=horizon_cap, max_events=max_events
        )
    else:
        codes = np.zeros(g0.shape[:3], dtype=np.int8)
        total = b1.size * b2.size
        for i, x1 in enumerate(b1):
            for j, x2 in enumerate(b2):
                for m in range(g0.shape[2]):
                    out, _ = simulate_outcome(
                        x1,
                        x2,
                        alpha,
                        k=k,
                        q=qq,
                        g0=g0[i, j, m],
                        t_end=t_end,
                        horizon_cap=horizon_cap,
                        max_events=max_events,
                    )
                    codes[i, j, m] = int(out)
                if progress is not None:
                    progress(i * b2.size + j + 1, total)
    wall = _time.perf_counter() - t0
    n_traj = codes.size
    # most frequent class per pixel (ties: the smallest code)
    counts = np.stack([(codes == int(o)).sum(axis=2) for o in Outcome], axis=-1)
    out = np.array([int(o) for o in Outcome], dtype=np.int8)[counts.argmax(axis=-1)]
    agree = (counts.max(axis=-1) / codes.shape[2]).astype(np.float32)
    B1, B2 = np.meshgrid(b1, b2, indexing="ij")
    region = no_stable_subclass(B1, B2, np.full(B1.shape, alpha))
    flags = {
        "long_name": "simulated outcome of perturbed SS equilibrium",
        "flag_values": np.array([int(m) for m in Outcome], dtype=np.int8),
        "flag_meanings": " ".join(m.label for m in Outcome),
    }
    coords = {
        "beta1": ("beta1", b1, {"units": "rad", "long_name": "direction of b1"}),
        "beta2": ("beta2", b2, {"units": "rad", "long_name": "direction of b2"}),
    }
    ds = xr.Dataset(
        {
            "outcome": (("beta1", "beta2"), out, flags),
            "agreement": (
                ("beta1", "beta2"),
                agree,
                {"units": "1", "long_name": "fraction of perturbed runs giving outcome"},
            ),
            "no_stable_subclass": (
                ("beta1", "beta2"),
                region,
                {"long_name": "subclass 132, 133, 142, 143 or dual (paper Sec. 6.4-6.5)"},
            ),
        },
        coords=coords,
        attrs={
            "title": "Outcome map of the compliant two-contact dynamics",
            "references": "Varkonyi, P. L.: Dynamics of mechanical systems with multiple sliding "
            "contacts: new faces of Painleve's paradox (Sec. 4.1, 6.4-6.5, Fig. 2)",
            "method": f"exact event-driven simulation ({engine} engine), atlas.dynamics.classify",
            "kappa": kappa,
            "q1": float(qq[0]),
            "q2": float(qq[1]),
            "alpha": alpha,
            "alpha_units": "rad",
            "n_perturb": int(n_perturb),
            "seed": int(seed),
            "perturbation": perturbation,
            "t_end": t_end,
            "horizon_cap": horizon_cap,
            "max_events": int(max_events),
            "engine": engine,
            "trajectories": int(n_traj),
            "seconds": wall,
            "trajectories_per_second": n_traj / wall if wall > 0 else float("nan"),
        },
    )
    return ds
