"""The step window of the event-to-event engines and the certified event brackets within it
(paper Sec. 4.1): one definition for the NumPy engine (:mod:`atlas.dynamics.fast_engine`) and the
JAX engine (:mod:`atlas.dynamics.jax_engine`), on NumPy or JAX arrays
(:func:`atlas.dynamics.event_bounds.xp_of`).

A step is at most ``WINDOWS H_S`` long (``WIDE H_S`` in the NumPy engine), or ``LONG H_S`` over
an event-free stretch (the NumPy engine), and never so long that a modal term grows by more than
``GROWTH`` over it; the gaps are tested at most ``H_S`` apart inside a longer step unless they provably stay within ``SMALL`` times
the scale (``small``).  Past the ``GROWTH`` cap a step goes on (:func:`stretch`, the NumPy
engine) where no event and no limit of the stop rule can come before its end: a run growing
to its divergence stop with no event reaches the limit in one step, not one doubling a step.
"""

from __future__ import annotations

import math

import numpy as np

from atlas.dynamics import event_bounds as eb
from atlas.dynamics import stop_rule

__all__ = [
    "CANCELLING",
    "GROWTH",
    "LONG",
    "SHORT",
    "SMALL",
    "WIDE",
    "WINDOWS",
    "bounded",
    "brackets",
    "limit_reach",
    "limit_steps",
    "no_event_within",
    "stretch",
    "window",
]

#: longest step in windows ``H_S`` (``LONG`` where no event can come within ``WINDOWS``), where the
#: growth over it stays within ``GROWTH``; the gaps are sampled at most ``H_S`` apart inside a
#: longer step unless provably within ``SMALL`` times the scale
WINDOWS = 4.0
LONG = 64.0
GROWTH = 2.0
SMALL = 10.0
#: the NumPy engine's window in ``H_S`` (its safe sub-steps cross an oscillation's window in one
#: step, :func:`atlas.dynamics.substeps.safe_substeps`); the JAX engine keeps ``WINDOWS``
WIDE = 8.0
#: a step below ``SHORT`` times its window is bracketed again within a shorter window, where the
#: flow's curvature bound is below ``CANCELLING`` times the modal one
SHORT = 0.125
CANCELLING = 0.5
#: windows of the signed-curvature brackets, in multiples of a step cut by a ``sigma_lo``
TAYLOR = (2.0, 8.0, 32.0)


def window(H, lam, valid, p, aUE, scale, windows=WINDOWS):
    """Step window (n,) and ``small`` (n,): ``windows H_S``, shortened so that no modal term grows
    by more than ``GROWTH`` over it (the curvature bound's factor ``exp(max(Re lambda, 0)
    window)``), but never below ``H_S`` (where the growth over ``H_S`` exceeds ``GROWTH`` the window
    is ``H_S``, and the curvature bound uses that window's own growth factor); ``small`` where both
    gaps provably stay within ``SMALL scale`` over the window (bound ``|p0| + |p1| s + |p2| s^2 +
    GROWTH sum |u|``, and ``|p3| s^3 + |p4| s^4`` of a quartic, ``aUE = |u|`` (n, 2, 4)): elsewhere
    a step longer than ``H_S`` is sampled, so that the tests of the gaps at the step ends
    (divergence, late amplitude ``> 10 scale``) see the gaps at most ``H_S`` apart."""
    xp = eb.xp_of(H, lam, p, aUE)
    grow = xp.where(valid, lam.real, 0.0).max(axis=1)
    with np.errstate(divide="ignore"):
        cap = xp.where(grow > 0, math.log(GROWTH) / grow, np.inf)
    w = xp.maximum(H, xp.minimum(windows * H, cap))
    a = xp.abs(p)
    w2 = w[:, None]
    reach = a[:, :, 0] + w2 * (a[:, :, 1] + w2 * a[:, :, 2]) + GROWTH * eb.sum4(aUE)
    if p.shape[2] > 3:  # a quartic (closed forms of degenerate directions)
        reach = reach + w2**3 * (a[:, :, 3] + w2 * a[:, :, 4])
    return w, xp.maximum(reach[:, 0], reach[:, 1]) <= SMALL * scale


def bounded(A, Bd, s, p, UE, lam, k, q, aUE, Hw, mon, flow=None):
    """``(lo, hi, M)``: certified brackets (n, 4) of the next crossing of each monitored (``mon``)
    event function with value bound ``A`` and slope ``Bd`` (:func:`eb.safe_steps`) within the
    window ``Hw`` (n,), under the curvature bound ``M`` over it (:func:`eb.curvature_bound`);
    ``lo`` at most ``Hw``, ``hi`` ``inf`` beyond it or unmonitored.  ``flow``: ``(C zn (n, 4),
    mu (n,))`` of :func:`eb.flow_curvature_bound`, a second bound (the smaller is used)."""
    xp = eb.xp_of(A, Bd, p, UE, Hw)
    M = eb.curvature_bound(p, UE, lam, Hw, k, q, aUE)
    if flow is not None:
        Czn, mu = flow
        M = xp.minimum(M, Czn * xp.exp(xp.maximum(mu, 0.0) * Hw)[:, None])
    lo, hi = eb.safe_steps(A, Bd, M)
    flat = (A == 0) & (Bd == 0)
    if xp is not np or flat.any():  # a double zero (exactly zero state): the second derivative
        lo = xp.where(flat, eb.flat_step(s, p, UE, lam, Hw, k, q), lo)
    lo = xp.where(mon, xp.minimum(lo, Hw[:, None]), np.inf)
    hi = xp.where(mon & (hi <= Hw[:, None]), hi, np.inf)
    return lo, hi, M


def brackets(d, v, acc, k, q, s, p, UE, lam, valid, H, scale, act, mu):
    """Certified brackets ``(lo, hi)`` (n, 4) of the next crossing of each monitored event
    function (``mon``: every force, the falling gaps), within the step window ``Hw`` and under
    the curvature bound ``M`` (both returned, for the stop rule's limits), and ``small``
    (:func:`window`).  The window is ``WIDE H_S`` at most, or ``LONG H_S`` where no function
    can cross within the shorter one (an event-free stretch: free flight, a settled contact).
    A step cut far below its window is bracketed again within a shorter one under the smaller of
    the modal terms' bound and the flow's (:func:`_shorter`, ``mu`` (n,) the logarithmic norms of
    the configurations).
    NumPy arrays (the JAX engine keeps the short window and the modal bound)."""
    f, fp = eb.event_functions(d, v, acc, k, q)
    aUE = np.abs(UE)
    A, Bd = np.maximum(s * f, 0.0), s * fp
    mon = np.concatenate([np.ones_like(act), s[:, :2] < 0], axis=1)
    Hw, small = window(H, lam, valid, p, aUE, scale, WIDE)
    lo, hi, M = bounded(A, Bd, s, p, UE, lam, k, q, aUE, Hw, mon)
    r = eb.rows(eb.min_cols(lo) >= Hw)
    if r.size:
        w, sm = window(H[r], lam[r], valid[r], p[r], aUE[r], scale[r], LONG)
        r, w, sm = r[w > Hw[r]], w[w > Hw[r]], sm[w > Hw[r]]
        lo_r, hi_r, M_r = bounded(A[r], Bd[r], s[r], p[r], UE[r], lam[r], k[r], q[r], aUE[r], w,
                                  mon[r])  # fmt: skip
        # both brackets hold (each within its window): the larger lower end, the smaller upper
        longer = eb.min_cols(lo_r) > Hw[r]
        r, lo_r, hi_r, M_r, w, sm = (x[longer] for x in (r, lo_r, hi_r, M_r, w, sm))
        lo[r], hi[r] = np.maximum(lo[r], lo_r), np.minimum(hi[r], hi_r)
        M[r], Hw[r], small[r] = M_r, w, sm
    r = eb.rows(eb.min_cols(lo) < Hw)
    if r.size:
        _far(r, lo, hi, M, Hw, small, s, p, UE, lam, valid, k, q, aUE, mon, H, scale)
    r = eb.rows(eb.min_cols(lo) < SHORT * Hw)
    if r.size:
        _shorter(r, lo, hi, M, Hw, A, Bd, s, p, UE, lam, k, q, aUE, mon, acc, H, mu)
    r = eb.rows(eb.min_cols(lo) < Hw)
    if r.size:
        _taylor(r, lo, hi, M, Hw, A, Bd, s, p, UE, lam, k, q, mon)
    return lo, hi, mon, M, Hw, small


def _taylor(r, lo, hi, M, Hw, A, Bd, s, p, UE, lam, k, q, mon):
    """Rows ``r`` whose step is cut by a ``sigma_lo``: the brackets again from the signed
    curvature at the step's start (:func:`eb.taylor_steps`) within windows ``TAYLOR`` times the
    step (at most ``Hw``), each bracket kept where tighter (both hold); ``lo``, ``hi`` in place.
    A row stops widening once its step falls inside the window: a wider window's lower
    quadratic lies below, so its ``sigma_lo`` cannot be longer."""
    m = eb.min_cols(lo[r])
    lo_r, hi_r, mon_r, Hw_r, A_r, Bd_r = lo[r], hi[r], mon[r], Hw[r], A[r], Bd[r]
    f2, terms = eb.taylor_terms(p[r], UE[r], lam[r], k[r], q[r])
    C = s[r] * f2
    err = 1e-13 * M[r]  # the rounding of f2: below 1e-13 of its terms' moduli
    j = np.arange(r.size)  # the rows still widening, into r
    for f in TAYLOR:
        W = np.minimum(Hw_r[j], f * m[j])
        lo_t, hi_t = eb.taylor_steps(A_r[j], Bd_r[j], C[j], eb.third_bound(_rows(terms, j), W),
                                     W, err[j])  # fmt: skip
        mon_j, lo_j = mon_r[j], lo_r[j]
        lo_j = np.where(mon_j, np.maximum(lo_j, lo_t), lo_j)
        lo_r[j], hi_r[j] = lo_j, np.where(mon_j, np.minimum(hi_r[j], hi_t), hi_r[j])
        j = j[(eb.min_cols(lo_j) >= W) & (W < Hw_r[j])]
        if j.size == 0:
            break
    lo[r], hi[r] = lo_r, hi_r


def _rows(terms, j):
    """:func:`eb.taylor_terms`' ``terms`` of the rows ``j``."""
    return tuple(x[j] for x in terms)


def _far(r, lo, hi, M, Hw, small, s, p, UE, lam, valid, k, q, aUE, mon, H, scale):
    """Rows ``r`` whose step is cut by a ``sigma_lo``: where every monitored function keeps its
    sign over the ``LONG`` window by the size of its terms (:func:`eb.keeps_sign_within`: an
    oscillation far from its contacts, growing by at most ``GROWTH``), the step is that window
    (``lo``, ``hi``, ``M``, ``Hw``, ``small`` replaced in place).  Quadratic segments only."""
    if p.shape[2] > 3:  # closed forms: those with cubic or quartic terms left out
        r = r[~(p[r, :, 3:] != 0).any(axis=(1, 2))]
    if r.size == 0:
        return
    w, sm = window(H[r], lam[r], valid[r], p[r], aUE[r], scale[r], LONG)
    wider = w > Hw[r]  # the test only where the long window is longer
    r, w, sm = r[wider], w[wider], sm[wider]
    pr = p[r, :, :3]
    ok = eb.all_cols(eb.keeps_sign_within(s[r], pr, UE[r], lam[r], k[r], q[r], w) | ~mon[r])
    r, w, sm = r[ok], w[ok], sm[ok]
    lo[r] = np.where(mon[r], w[:, None], np.inf)
    hi[r] = np.inf
    M[r] = eb.curvature_bound(p[r], UE[r], lam[r], w, k[r], q[r], aUE[r])
    Hw[r], small[r] = w, sm


def _shorter(r, lo, hi, M, Hw, A, Bd, s, p, UE, lam, k, q, aUE, mon, acc, H, mu):
    """Rows ``r`` whose step is cut far below the window: the brackets again under the smaller of
    the modal bound and the flow's (:func:`eb.flow_curvature_bound`, at the step's start) within
    a shorter window ``W`` (twice the smallest ``sigma_lo`` under the flow's bound at the start,
    so that its growth ``exp(mu W)`` stays near 1), kept where they allow a longer step (``lo``,
    ``hi``, ``M``, ``Hw`` replaced in place); tried where the flow's bound at the start is below
    ``CANCELLING`` times the modal one.  Where large modal terms cancel the step is then set by the size of
    ``f''`` near ``tau``."""
    C, zn = eb.flow_curvature_bound(p[r], UE[r], lam[r], acc[r], H[r], k[r], q[r])
    Czn = C * zn[:, None]
    # only where the flow's bound at the start is well below the modal one (terms cancelling)
    below = eb.rows((mon[r] & (Czn < CANCELLING * M[r])).any(axis=1))
    r, Czn = r[below], Czn[below]
    lo0, _ = eb.safe_steps(A[r], Bd[r], Czn)
    w = np.minimum(Hw[r], 2 * eb.min_cols(np.where(mon[r], lo0, np.inf)))
    lo_r, hi_r, M_r = bounded(A[r], Bd[r], s[r], p[r], UE[r], lam[r], k[r], q[r], aUE[r], w,
                              mon[r], (Czn, mu[r]))  # fmt: skip
    better = eb.min_cols(lo_r) > eb.min_cols(lo[r])
    r, lo_r, hi_r, M_r, w = (x[better] for x in (r, lo_r, hi_r, M_r, w))
    lo[r], hi[r], M[r], Hw[r] = lo_r, hi_r, M_r, w


def limit_steps(d, v, M, scale, Hw):
    """:func:`stop_rule.limit_steps` (``(sigma_lo, sigma_hi)`` (n,)), computed only where the
    curvature bound ``M`` lets a gap reach a limit within ``Hw`` (``inf`` elsewhere)."""
    n = d.shape[0]
    lo, hi = np.full(n, np.inf), np.full(n, np.inf)
    amp, pen = stop_rule.limits(scale)
    near = np.minimum(amp, stop_rule.DEEP * pen)[:, None]
    w = Hw[:, None]
    r = eb.rows((np.abs(d) + w * (np.abs(v) + 0.5 * w * M[:, :2]) >= near).any(axis=1))
    if r.size:
        lo[r], hi[r] = stop_rule.limit_steps(d[r], v[r], M[r], scale[r], Hw[r])
    return lo, hi


def stretch(s, p, UE, lam, valid, k, q, H, scale, rest, step):
    """Steps (n,) past the ``GROWTH`` cap of the rows' windows: up to ``LONG H_S`` and ``rest``
    [time], the time before which no gap can pass a limit of the stop rule
    (:func:`limit_reach`), where every monitored event function keeps its sign over it
    (:func:`no_event_within`, no event); ``step`` (n,) where that is not longer.  Tried where the
    signs are kept over ``step`` (necessary: the certificate over a longer horizon implies it
    over a shorter one).  Quadratic ``p`` (n, 2, 3); NumPy arrays."""
    out = step.copy()
    r = eb.rows(no_event_within(s, p, UE, lam, valid, k, q, step))
    if r.size == 0:
        return out
    reach = limit_reach(p[r], UE[r], lam[r], scale[r], np.minimum(LONG * H[r], rest[r]), step[r])
    r, reach = r[reach > step[r]], reach[reach > step[r]]
    if r.size:
        ok = no_event_within(s[r], p[r], UE[r], lam[r], valid[r], k[r], q[r], reach)
        out[r[ok]] = reach[ok]
    return out


#: bisection rounds of :func:`limit_reach` (its bound to ``2^-REACH_ROUNDS`` of the interval)
REACH_ROUNDS = 12


def limit_reach(p, UE, lam, scale, rest, lo=None):
    """A lower bound (n,) of the time from now at which a gap can first pass the amplitude limit
    (``d_i > amp``) or the deep penetration (``d_i < -DEEP pen``) of the stop rule, in ``[lo,
    rest]`` [time] (``lo`` default 0): bisection (:func:`eb.last_below`) on nondecreasing upper
    bounds of ``+-d_i`` (:func:`_over_limits`); ``rest`` where they stay below by then, 0 where
    they pass by ``lo``.  Quadratic ``p`` (n, 2, 3); NumPy arrays."""
    lo = np.zeros(rest.size) if lo is None else lo
    over = _over_limits(p, UE, lam, scale)
    first = over(lo)
    out = np.where(first, 0.0, rest)
    r = eb.rows(~first & over(rest))
    if r.size:
        sub, a = _over_limits(p[r], UE[r], lam[r], scale[r]), lo[r]
        with np.errstate(over="ignore", invalid="ignore"):
            out[r] = a + eb.last_below(lambda x: sub(a + x), rest[r] - a, REACH_ROUNDS)
    return out


def _over_limits(p, UE, lam, scale):
    """The test ``over(x)`` (bool (n,)) that an upper bound of ``+-d_i`` passes the amplitude
    (``+``) or the deep-penetration limit (``-``) at time ``x`` (n,) from now: ``+-p0 + max(+-p1,
    0) x + max(+-p2, 0) x^2 + sum_m b_m exp(max(Re lam_m, 0) x)``, ``b_m = max(+-Re u_m, 0)`` for
    a real ``lam_m`` (its term is ``Re u_m exp(lam_m x)``), else ``|u_m|``; plus ``1e-12`` of all
    the terms' moduli for the rounding of the gaps.  Nondecreasing in ``x``; NaN counts as over."""
    amp, pen = stop_rule.limits(scale)
    grow = np.maximum(lam.real, 0.0)[:, None, :]
    aw = np.abs(UE)
    real = (lam.imag == 0)[:, None, :]
    sides = []
    for sign, lim in ((1.0, amp), (-1.0, stop_rule.DEEP * pen)):
        b = np.where(real, np.maximum(sign * UE.real, 0.0), aw)
        c = [sign * p[:, :, 0]] + [np.maximum(sign * p[:, :, i], 0.0) for i in (1, 2)]
        sides.append((c, b, lim[:, None]))
    a = [np.abs(p[:, :, i]) for i in range(3)]

    def over(x):
        x2 = x[:, None]
        with np.errstate(over="ignore", invalid="ignore"):
            e = np.exp(grow * x2[:, :, None])
            margin = 1e-12 * (a[0] + x2 * (a[1] + x2 * a[2]) + eb.sum4(aw * e))
            out = np.zeros(x.size, dtype=bool)
            for c, b, lim in sides:
                bound = c[0] + x2 * (c[1] + x2 * c[2]) + eb.sum4(b * e) + margin
                out |= ((bound >= lim) | np.isnan(bound)).any(axis=1)
        return out

    return over


def no_event_within(s, p, UE, lam, valid, k, q, S):
    """Every monitored event function (each gap; the force of a closed contact) keeps its recorded
    sign ``s`` (n, 4) over ``[tau, tau + S]`` (S (n,) [time]): by :func:`eb.keeps_sign` over that
    horizon (a growing real dominant term of its sign) or by :func:`eb.keeps_sign_within` (each
    term grown by its growth over ``S``); bool (n,).  Quadratic ``p`` (n, 2, 3); NumPy arrays."""
    c, w = eb.event_terms(p, UE, lam, k, q)
    sj = s[:, :, None]
    ok = eb.keeps_sign(sj * c, sj * w, lam[:, None, :], valid[:, None, :],
                       np.repeat(S[:, None], 4, axis=1))[0]  # fmt: skip
    ok |= eb.keeps_sign_within(s, p, UE, lam, k, q, S)
    mon = np.concatenate([np.ones((s.shape[0], 2), dtype=bool), s[:, :2] < 0], axis=1)
    return eb.all_cols(ok | ~mon)
