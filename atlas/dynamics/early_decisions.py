"""Early decisions of the outcome engines, written once for NumPy and JAX arrays.

A run may stop before its horizon when a bound proves what the exact simulator's finite-horizon
stop would decide: ``settles_XY`` (a decaying or neutral configuration that no event can leave,
:func:`decisions`) or ``IWC`` (a growing configuration driving every active gap to -inf, aligned
with the dominant eigenvector at the stop, :func:`aligned_at_stop`, and keeping the reference's
sign conditions, :func:`signs_from`).  Pure array functions: :mod:`atlas.dynamics.fast_engine`
calls them on NumPy arrays, :mod:`atlas.dynamics.jax_engine` inside its ``jit`` kernel.
"""

from __future__ import annotations

import numpy as np

from atlas.dynamics import event_bounds as eb

__all__ = ["may_decide", "decisions", "aligned_at_stop", "reach_time", "signs_from", "aligned_from"]


def may_decide(lam, valid, s, p, act, mask, t, T):
    """The conditions of :func:`_decide` other than the certificate: a growing configuration
    with a contact (IWC), or a non-growing one whose free gaps are open and accelerating away
    (settles; a neutral one at most half way through the horizon)."""
    xp = eb.xp_of(lam, s, p)
    lscale = xp.abs(lam).max(axis=1, keepdims=True)
    growing = (valid & (lam.real > eb.NEUTRAL * lscale)).any(axis=1)
    neutral = (valid & (xp.abs(lam.real) <= eb.NEUTRAL * lscale)).any(axis=1)
    free_ok = xp.all(act | ((s[:, :2] > 0) & (p[:, :, 2] > 0)), axis=1)
    return xp.where(growing, mask > 0, free_ok & (~neutral | (t <= 0.5 * T)))


def decisions(t, T, t_max, s, mask, p, UE, lam, valid, k, q, scale, act, H):
    """``(settle, iwc, lam_1)`` (n,): the lanes that settle now, those that are IWC now if also
    :func:`aligned_at_stop` (with the dominant real part ``lam_1``); NumPy or JAX arrays."""
    xp = eb.xp_of(t, p, UE, lam)
    re = lam.real
    lscale = xp.abs(lam).max(axis=1, keepdims=True)
    growing = (valid & (re > eb.NEUTRAL * lscale)).any(axis=1)
    neutral = (valid & (xp.abs(re) <= eb.NEUTRAL * lscale)).any(axis=1)
    horizon = xp.where(neutral, t_max - t, np.inf)
    neutral &= ~growing
    cert, G, Bn, l1 = eb.no_event_certificate(s, p, UE, lam, valid, k, q, horizon)
    free_ok = xp.all(act | ((s[:, :2] > 0) & (p[:, :, 2] > 0)), axis=1)
    settle = cert & ~growing & free_ok & (~neutral | (t <= 0.5 * T))
    settle &= _settles_first(p, UE, lam, valid, act, neutral, t, T, k, scale, H)
    # time by which -d_i >= G exp(lam_1 s) + (-d_eq_i - bounded) passes 1e3 penetration_limit
    X = 1e6 * scale[:, None]
    with np.errstate(all="ignore"):
        sig = xp.log(xp.maximum((X + p[:, :, 0] + Bn[:, :2]) / G[:, :2], 1.0))
        sig = xp.where(act & (G[:, :2] > 0), sig / l1[:, None], np.inf).min(axis=1)
    iwc = cert & growing & (mask > 0) & (t + sig <= T)
    return settle, iwc, l1


def _first_reach(c0, c1, c2, limit):
    """First ``s >= 0`` with ``c0 + c1 s + c2 s^2 >= limit`` (``c1, c2 >= 0``; inf if never)."""
    xp = eb.xp_of(c0, c1, c2, limit)
    c0 = c0 - limit
    with np.errstate(all="ignore"):
        lin = xp.where(c1 > 0, -c0 / c1, np.inf)
        quad = (-c1 + xp.sqrt(c1 * c1 - 4 * c2 * c0)) / (2 * c2)
        out = xp.where(c2 > 0, quad, lin)
    return xp.where(c0 >= 0, 0.0, out)


def _settles_first(p, UE, lam, valid, act, neutral, t, T, k, scale, H):
    """The reference settles before any of its other stops: for a decaying configuration its
    settling test (:func:`atlas.dynamics.simulate`, ``settle_rtol = 1e-6``) provably passes
    within the horizon ``T`` and before a free gap can pass the amplitude limit ``1e4 scale``;
    for a neutral one no free gap can pass that limit within ``T``; in FF no gap is falling."""
    xp = eb.xp_of(p, UE, lam, t)
    aw = xp.abs(UE)
    amp = 1e4 * scale
    # upper bound of each free gap: |p0| + |p1| s + |p2| s^2 + sum |u|
    reach = _first_reach(xp.abs(p[:, :, 0]) + eb.sum4(aw), xp.abs(p[:, :, 1]),
                         xp.abs(p[:, :, 2]), amp[:, None])  # fmt: skip
    t_amp = xp.where(act, np.inf, reach).min(axis=1)
    omega = xp.sqrt(k.max(axis=1))
    decay = xp.where(valid, -lam.real, np.inf).min(axis=1)
    d_eq = xp.where(act, xp.abs(p[:, :, 0]), 0.0).max(axis=1)
    size = (aw * (1 + xp.abs(lam) / omega[:, None])[:, None, :]).sum(axis=(1, 2))
    with np.errstate(all="ignore"):
        t_set = xp.maximum(xp.log(size / (1e-6 * d_eq)), 0.0) / decay + 2 * H
    t_set = xp.where(act.any(axis=1), t_set, 0.0)
    ff_falling = (~act & (p[:, :, 1] < 0)).any(axis=1)
    decaying = ~neutral & (t_set < t_amp) & (t + t_set <= T) & ~ff_falling
    return xp.where(neutral, t_amp > T - t, decaying)


def aligned_at_stop(c, p, UE, lam, valid, l1, rest, scale):
    """The reference classifies the divergence as IWC: from the earliest time any gap can reach
    the reference's divergence limits (``1e4 scale``; bound ``|p0| + |p1| s + |p2| s^2 + sum |u|
    exp(max(Re lam, 0) s)``), the components off the dominant eigenvector stay below 1e-2 of the
    deviation (:func:`atlas.dynamics.classify`'s ``align_tol``): ``sum_other |c_m| exp(Re lam_m
    s) (1 + 1e-2) <= 1e-2 |c_1| exp(lam_1 s)``, a ratio that only decreases when ``lam_1`` is the
    largest real part."""
    return aligned_from(c, lam, valid, l1, reach_time(p, UE, lam, rest, scale))


def reach_time(p, UE, lam, rest, scale):
    """A lower bound (n,) of the time from now at which a gap can first reach ``1e4 scale`` (the
    amplitude limit; the deep penetration lies beyond it), at most ``rest``: bisection on the
    increasing bound ``|p0| + |p1| s + |p2| s^2 + sum |u| exp(max(Re lam, 0) s)``."""
    xp = eb.xp_of(p, UE, lam)
    aw = xp.abs(UE)
    grow = xp.maximum(lam.real, 0.0)
    a0, a1, a2 = (xp.abs(p[:, :, i]) for i in range(3))

    def bound(x):
        e = xp.exp(grow * x[:, None])[:, None, :]
        b = a0 + a1 * x[:, None] + a2 * x[:, None] ** 2 + eb.sum4(aw * e)
        return b.max(axis=1)

    lim = 1e4 * scale
    return eb.last_below(lambda x: bound(x) >= lim, rest)


def signs_from(p, UE, lam, valid, l1, act, s, s0):
    """The sign conditions of :func:`atlas.dynamics.system.iwc_aligned` hold from ``s0`` (n,) on:
    every active gap and its velocity negative, every free gap (recorded sign ``s`` positive)
    opening.  Each is ``poly(s) + e^{l1 s} (D +- sum_other |w_m| e^{(Re lam_m - l1) s})`` for the
    dominant term ``D``; the bracket's product with ``e^{l1 s}`` is monotone once of the right
    sign (the other real parts lie below ``l1``: :func:`aligned_from`'s ``strict``), so with the
    polynomial part monotone the right way (active) or outgrown (free: the velocity's
    derivative bounded below at ``s0``) and the sign right at ``s0`` (beyond ``1e-9`` of the
    terms), it holds for all later times."""
    xp = eb.xp_of(p, UE, lam, s0)
    re = xp.where(valid, lam.real, -np.inf)
    j1 = xp.argmax(re, axis=1)
    others = (valid & (xp.arange(valid.shape[1])[None, :] != j1[:, None]))[:, None, :]
    with np.errstate(all="ignore"):
        rel = xp.where(others, xp.exp((re - l1[:, None]) * s0[:, None])[:, None, :], 0.0)
    lUE = UE * lam[:, None, :]
    D, Dv = eb.take(UE, j1[:, None]).real, eb.take(lUE, j1[:, None]).real
    O, Ov = eb.sum4(xp.abs(UE) * rel), eb.sum4(xp.abs(lUE) * rel)
    s1 = s0[:, None]
    c0 = p[:, :, 0] + s1 * (p[:, :, 1] + s1 * p[:, :, 2])
    c1 = p[:, :, 1] + 2 * s1 * p[:, :, 2]
    e1 = xp.exp(l1[:, None] * s1)
    tol = 1e-9
    neg = (D + O * (1 + tol) < 0) & (Dv + Ov * (1 + tol) < 0) & (p[:, :, 2] <= 0) & (c1 <= 0)
    neg &= c0 + e1 * (D + O) * (1 - tol) < 0
    # a free gap stays open (the certificate); its velocity v = c1(s) + e^{l1 s} (Dv - ...) has
    # v' >= 2 p2 + l1 e^{l1 s0} (Dv - Ov(s0)) for s >= s0 while the bracket is positive
    up = Dv - Ov * (1 + tol)
    pos = (up > 0) & (c1 + e1 * up > 0) & (2 * p[:, :, 2] + l1[:, None] * e1 * up >= 0)
    pos &= s[:, :2] > 0
    return xp.all(xp.where(act, neg, pos), axis=1)


def aligned_from(c, lam, valid, l1, s0):
    """The alignment test of :func:`aligned_at_stop` from the time ``s0`` (n,) on; it only gets
    easier as ``s0`` grows (the off-dominant terms decay relative to the dominant one)."""
    xp = eb.xp_of(c, lam, s0)
    re = xp.where(valid, lam.real, -np.inf)
    j1 = xp.argmax(re, axis=1)
    dom = xp.abs(eb.take(c, j1))
    others = valid & (xp.arange(valid.shape[1])[None, :] != j1[:, None])
    strict = xp.all(~others | (re < l1[:, None]), axis=1)
    with np.errstate(all="ignore"):
        off = xp.where(others, xp.abs(c) * xp.exp((re - l1[:, None]) * s0[:, None]), 0.0).sum(1)
    return strict & (dom > 0) & (off * (1 + 1e-2) <= 1e-2 * dom)
