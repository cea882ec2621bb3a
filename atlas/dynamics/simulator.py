"""Exact event-driven simulator of the compliant two-contact dynamics, NumPy engine (paper
Sec. 4.1, 6.4-6.5; the system itself: :mod:`atlas.dynamics.system`).

Between switching events the state ``z = (d1, d2, d1', d2', 1)`` of the active mode ``S`` obeys
``z' = E_S z`` and is advanced exactly with ``expm(E_S h)``.

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
"""

from __future__ import annotations

import dataclasses
import math
import time as _time
from collections.abc import Sequence

import numpy as np

from atlas.core import checks
from atlas.dynamics import stop_rule
from atlas.dynamics.system import (
    FORCE_OFF,
    FORCE_ON,
    IMPACT,
    LIFTOFF,
    Mode,
    Status,
    System,
    build_system,
    check_finite,
    expm,
    mask_from_signs,
    mode_name,
    run_scale,
)

__all__ = ["SimulationResult", "simulate"]


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
    _system: System = dataclasses.field(repr=False)
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
    import scipy.optimize  # noqa: PLC0415 - the fast engine's worker processes need no scipy

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
    sysm = build_system(beta1, beta2, alpha, k, q, b_norm, a_norm, theta)
    g0, lim = _run_limits(
        sysm, g0, t_end, max_events, max_steps, amplitude_limit, penetration_limit,
        stop_when_settled, settle_rtol,
    )  # fmt: skip
    log, t, z, mask, n_steps, (status, message) = _integrate(sysm, g0, lim)
    return log.result(sysm, t, z, mask, status, message, n_steps, lim.scale, t_wall)


@dataclasses.dataclass(frozen=True)
class _Limits:
    """When a run stops (see :func:`simulate`): its horizon, caps, divergence limits
    (``amp_lim``, ``pen_lim``) relative to its length ``scale``, and the settling test."""

    t_end: float
    max_events: int
    max_steps: int
    scale: float
    amp_lim: float
    pen_lim: float
    stop_when_settled: bool
    settle_rtol: float


def _run_limits(sysm, g0, t_end, max_events, max_steps, amplitude_limit, penetration_limit,
                stop_when_settled, settle_rtol):  # fmt: skip
    """Checked ``g0`` and the run's :class:`_Limits` (length scale, divergence limits)."""
    g0 = check_finite("g0", g0)
    if g0.shape != (4,):
        raise ValueError(f"g0 must have 4 components (d1, d2, d1', d2'), got shape {g0.shape}")
    t_end = float(check_finite("t_end", t_end, positive=True))
    max_events = checks.integer("max_events", max_events, 1)
    max_steps = checks.integer("max_steps", max_steps, 1)
    stop_when_settled = checks.boolean("stop_when_settled", stop_when_settled)
    scale = run_scale(sysm, g0)
    amp_lim = 1e4 * scale if amplitude_limit is None else float(amplitude_limit)
    pen_lim = 1e3 * scale if penetration_limit is None else float(penetration_limit)
    check_finite("amplitude_limit", amp_lim, positive=True)
    check_finite("penetration_limit", pen_lim, positive=True)
    lim = _Limits(t_end, max_events, max_steps, scale, amp_lim, pen_lim, stop_when_settled,
                  settle_rtol)  # fmt: skip
    return g0, lim


def _integrate(sysm: System, g0, lim: _Limits):
    """Sub-step and switch from ``g0`` until a stop; returns ``(log, t, z, mask, n_steps,
    (status, message))`` at the stop."""
    L = sysm.L
    z = np.append(g0, 1.0)
    # recorded signs of the four event functions (d1, d2, phi1, phi2); -1 means "<= 0"
    s = np.where(L @ z > 0, 1.0, -1.0)
    mask = mask_from_signs(s)
    t = 0.0
    log = _Log.start(z, mask)
    n_steps = 0
    # the overflow of a non-finite run is its stop (_stop_in), not a warning; once per run
    with np.errstate(over="ignore", invalid="ignore"):
        while True:
            mode = sysm.modes[mask]
            if t >= lim.t_end:
                return log, t, z, mask, n_steps, (Status.T_END, "reached t_end")
            if n_steps >= lim.max_steps:
                return log, t, z, mask, n_steps, (Status.STEP_CAP, f"{lim.max_steps} sub-steps")
            t, z, mask, stop = _sub_step(sysm, mode, s, t, z, mask, lim, log)
            n_steps += 1
            if stop is not None:
                return log, t, z, mask, n_steps, stop


def _sub_step(sysm: System, mode: Mode, s, t, z, mask, lim: _Limits, log: _Log):
    """Advance one sub-step of ``mode`` from ``(t, z)``, or to the first crossing in it (then
    switch the recorded signs ``s`` in place and log the events).

    Returns ``(t, z, mask, stop)`` with ``stop = (status, message)`` if the run stops there.
    """
    h = min(mode.h, lim.t_end - t)
    z1 = (mode.Phi if h == mode.h else expm(mode.E * h)) @ z
    brackets, W = _brackets(sysm.L, mode.LE, s, z, z1, h, mode)
    if brackets:
        r, crossing, z_end = _first_crossing(sysm.L, mode, s, z, brackets, W)
    else:
        r, z_end = h, z1
    stop = _stop_in(mode, z, r, z_end, lim)
    if stop is not None:
        tau, z = stop
        log.step(t + tau, z)
        return t + tau, z, mask, (Status.DIVERGED, _div_message(z, mask, lim.amp_lim, lim.pen_lim))
    if not brackets:
        t, z = t + h, z1
        log.step(t, z)
        return t, z, mask, _stop_after_step(sysm, mode, z, lim)
    t, z = t + r, z_end
    for kind, contact in _switch(sysm, mode, s, z, crossing, lim.scale):
        log.event(t, kind, contact, z)
    mask = mask_from_signs(s)
    log.segment(t, z, mask)
    return t, z, mask, _stop_after_event(sysm, z, mask, t, len(log.ev_t), lim)


@dataclasses.dataclass
class _Log:
    """What a run records: the events, the segment starts (dense output) and the gaps at every
    sub-step end and event (for :func:`atlas.dynamics.classify`)."""

    ev_t: list
    ev_kind: list
    ev_c: list
    ev_z: list
    ev_mode: list
    seg_t: list
    seg_z: list
    seg_mask: list
    env_t: list
    env_d: list

    @classmethod
    def start(cls, z, mask) -> _Log:
        return cls([], [], [], [], [], [0.0], [z.copy()], [mask], [0.0], [z[:2].copy()])

    def step(self, t, z):
        self.env_t.append(t)
        self.env_d.append(z[:2].copy())

    def event(self, t, kind, contact, z):
        self.ev_t.append(t)
        self.ev_kind.append(kind)
        self.ev_c.append(contact)
        self.ev_z.append(z[:4].copy())

    def segment(self, t, z, mask):
        """A new linear segment from ``(t, z)`` in mode ``mask`` (after the events at ``t``)."""
        self.step(t, z)
        self.ev_mode.extend([mode_name(mask)] * (len(self.ev_t) - len(self.ev_mode)))
        self.seg_t.append(t)
        self.seg_z.append(z.copy())
        self.seg_mask.append(mask)

    def result(self, sysm, t, z, mask, status, message, n_steps, scale, t_wall):
        return SimulationResult(
            t_events=np.array(self.ev_t),
            kinds=self.ev_kind,
            contacts=np.array(self.ev_c, dtype=int),
            states=np.array(self.ev_z).reshape(-1, 4),
            modes=self.ev_mode,
            t_final=t,
            g_final=z[:4].copy(),
            mode_final=mode_name(mask),
            status=status,
            message=message,
            n_steps=n_steps,
            wall_time=_time.perf_counter() - t_wall,
            scale=scale,
            _system=sysm,
            _seg_t=np.array(self.seg_t),
            _seg_z=np.array(self.seg_z),
            _seg_mask=np.array(self.seg_mask, dtype=int),
            _env_t=np.array(self.env_t),
            _env_d=np.array(self.env_d).reshape(-1, 2),
        )


def _brackets(L, LE, s, z, z1, h, mode: Mode, rows=None):
    """Crossings of the monitored event functions ``L z`` (the gaps; the forces of the closed
    gaps; or the ``rows`` given) in the sub-step ``(0, h]`` from ``z`` to ``z1`` (``LE = L E``).

    Returns ``({function index: upper end of its bracket}, W)`` with ``W`` the Taylor
    coefficients ``E^n / n! z`` of ``z(tau)`` if they were needed (else None).
    """
    f1 = L @ z1
    fp0 = LE @ z
    fp1 = LE @ z1
    xtol = 1e-13 * mode.h
    brackets, W = {}, None
    if rows is None:
        rows = (0, 1) + tuple(2 + i for i in range(2) if s[i] < 0)
    for j in rows:
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
    return brackets, W


def _first_crossing(L, mode: Mode, s, z, brackets, W):
    """Time ``r`` after the sub-step start of the first crossing, the event functions crossing
    there (within ``1e3 xtol``) and the state at ``r``."""
    if W is None:
        W = mode.P @ z
    xtol = 1e-13 * mode.h
    roots = {j: _root(W @ L[j], s[j], hi, xtol) for j, hi in brackets.items()}
    r = min(roots.values())
    crossing = sorted(j for j, rj in roots.items() if rj <= r + 1e3 * xtol)
    z_new = _horner_vec(W, r)
    z_new[4] = 1.0
    return r, crossing, z_new


def _switch(sysm: System, mode: Mode, s, z, crossing, scale) -> list:
    """Flip the recorded signs ``s`` (in place) of the event functions ``crossing`` at the event
    state ``z``; returns the events ``[(kind, contact)]``.

    A gap closing makes its force's sign count (its value, or its derivative in the pre-event
    mode when the value is at rounding level); a force sign change while its gap is open and not
    closing at the same time is no event.
    """
    dphi = mode.LE @ z  # derivatives at the event (pre-event mode)
    vals = sysm.L @ z
    for j in crossing:
        s[j] = -s[j]
    closing = [c % 2 for c in crossing if c < 2]
    events = []
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
            if s[i] > 0 and i not in closing:
                continue  # force sign change while the gap is open: no effect
            kind = FORCE_ON if s[j] > 0 else FORCE_OFF
        events.append((kind, i + 1))
    return events


def _stop_after_step(sysm, mode, z, lim: _Limits):
    """``(status, message)`` if the run stops after an event-free sub-step, else None."""
    if lim.stop_when_settled and _settled(sysm, mode, z, lim.settle_rtol):
        return Status.SETTLED, f"settled in mode {mode_name(mode.mask)}"
    return None


def _stop_after_event(sysm, z, mask, t, n_events, lim: _Limits):
    """``(status, message)`` if the run stops after the events at ``t``, else None."""
    if n_events >= lim.max_events:
        return Status.EVENT_CAP, f"{n_events} events by t = {t:.6g}"
    if _diverged(sysm, z, mask, lim.amp_lim, lim.pen_lim):
        return Status.DIVERGED, _div_message(z, mask, lim.amp_lim, lim.pen_lim)
    return None


def _horner_vec(W, tau):
    acc = np.zeros(W.shape[1])
    for n in range(W.shape[0] - 1, -1, -1):
        acc = acc * tau + W[n]
    return acc


def _diverged(sysm, z, mask, amp_lim, pen_lim) -> bool:
    """The stop rule (:func:`atlas.dynamics.stop_rule.stopped`) at ``z`` in mode ``mask``."""
    return _stops(sysm.modes[mask], z[None, :4], amp_lim, pen_lim)[0]


def _stops(mode: Mode, g, amp_lim, pen_lim):
    """:func:`atlas.dynamics.stop_rule.stopped` of states ``g`` (n, 4) in ``mode``."""
    n = g.shape[0]
    z_eq = np.full(5, np.nan) if mode.z_eq is None else mode.z_eq
    return stop_rule.stopped(g, np.full(n, mode.mask), np.broadcast_to(mode.E, (n, 5, 5)),
                             np.broadcast_to(z_eq, (n, 5)), amp_lim, pen_lim)  # fmt: skip


def _may_stop(mode: Mode, z, lim: _Limits) -> bool:
    """A necessary condition of the stop rule at ``z`` (scalar tests): a gap past a limit, an
    active one past the penetration limit, or a non-finite component."""
    d1, d2, v1, v2 = (float(x) for x in z[:4])
    if not (math.isfinite(d1) and math.isfinite(d2) and math.isfinite(v1) and math.isfinite(v2)):
        return True
    if max(d1, d2) > lim.amp_lim or min(d1, d2) < -stop_rule.DEEP * lim.pen_lim:
        return True
    return (mode.mask & 1 and d1 < -lim.pen_lim) or (mode.mask & 2 and d2 < -lim.pen_lim)


def _stop_in(mode: Mode, z, r, z_end, lim: _Limits):
    """The first stop in ``(0, r]`` of the sub-step from ``z`` (ending at ``z_end``, before any
    event there): the stop rule at ``z_end``, or a limit of :func:`stop_rule.limit_rows` passed at
    an interior peak; located by :func:`stop_rule.locate`.  Returns ``(tau, z(tau))`` or None."""
    hi, W = None, None
    near = min(lim.amp_lim, stop_rule.DEEP * lim.pen_lim)
    # |z(tau)| <= exp(|E| tau) |z| (infinity norms): no limit within reach, no peak to bracket
    if np.abs(z).max() * math.exp(np.abs(mode.E).sum(axis=1).max() * r) >= near:
        R = stop_rule.limit_rows(lim.amp_lim, lim.pen_lim)
        peaks, W = _brackets(R, R @ mode.E, -np.ones(4), z, z_end, r, mode, rows=(0, 1, 2, 3))
        hi = min(peaks.values(), default=None)
    if _may_stop(mode, z_end, lim) and _stops(mode, z_end[None, :4], lim.amp_lim, lim.pen_lim)[0]:
        hi = r
    if hi is None:
        return None
    W = mode.P @ z if W is None else W

    powers = np.arange(W.shape[0])

    def state_at(tau, _):
        return (tau[:, None] ** powers @ W)[:, :4]

    def near(g, _):
        out, pen = stop_rule.beyond(g, np.full(g.shape[0], mode.mask), lim.amp_lim, lim.pen_lim)
        return out | pen

    tau, g = stop_rule.locate(state_at, lambda g, _: _stops(mode, g, lim.amp_lim, lim.pen_lim),
                              np.zeros(1), np.full(1, hi), 1e-13 * mode.h, near)  # fmt: skip
    return float(tau[0]), np.append(g[0], 1.0)


def _div_message(z, mask, amp_lim, pen_lim) -> str:
    return (
        f"gaps {z[0]:.3g}, {z[1]:.3g} in mode {mode_name(mask)} left "
        f"[-{pen_lim:.3g} (active), {amp_lim:.3g}]"
    )


def _settled(sysm: System, mode: Mode, z, rtol) -> bool:
    """No event can follow: stable mode, active gaps at equilibrium (``rtol``), free gaps leaving."""
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
