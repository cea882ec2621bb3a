"""Safe sub-steps of the fast engine's steps (:mod:`atlas.dynamics.fast_engine`): a step cut
short by a ``sigma_lo`` continued by further certified safe steps under the same curvature
bound, the crossing they stopped before located in the same step, and the first of one or two
certified brackets located (paper Sec. 4.1)."""

from __future__ import annotations

import numpy as np

from atlas.dynamics import event_bounds as eb

__all__ = ["SUBSTEPS", "SUBSTEP_MIN", "safe_substeps", "event_after", "locate_first", "twins"]

SUBSTEPS = 8  # further certified safe steps within one step's window (:func:`safe_substeps`)
SUBSTEP_MIN = 0.05  # shortest of them, in H_S


def safe_substeps(r, step, cap, P, U, lam, tau, s, k, q, M, mon, H):
    """Steps (of the rows ``r``) continued by up to ``SUBSTEPS`` further certified safe steps
    (:func:`eb.safe_steps` from the event functions at the step's end, under the same curvature
    bound ``M``, valid over the whole window), each at least ``SUBSTEP_MIN H_S``, never past
    ``cap`` (window, horizon, stop-rule limit) nor where a crossing is certified before ``cap``
    (one certified beyond it stops none: a gap drifting slowly towards a contact far away):
    no monitored function changes sign over the longer step.  An oscillating gap far from its contact is
    then crossed in one step of the window rather than several of its curvature's ``sigma_lo``.
    Returns the steps and ``(A, lo, hi, |d|)`` ((r.size, 4), |d| (r.size, 2)) of the last
    evaluation of each row that stopped below ``cap`` (:func:`event_after`; ``A`` 0
    elsewhere)."""
    out, c = step[r].copy(), cap[r]
    x = (P[r], U[r], lam[r], tau[r], s[r], k[r], q[r], M[r], mon[r], SUBSTEP_MIN * H[r])
    live = np.arange(r.size)
    # rows that go on to the end keep A = 0, hi = inf: neither a crossing ahead nor one reached
    last = (np.zeros((r.size, 4)), np.zeros((r.size, 4)), np.full((r.size, 4), np.inf),
            np.zeros((r.size, 2)))  # fmt: skip
    for _ in range(SUBSTEPS):
        Pl, Ul, ll, tl, sl_, kl, ql, Ml, ml, short = x
        dva = eb.gaps_at(Pl, Ul, ll, tl + out[live])
        f, fp = eb.event_functions(*dva, kl, ql)
        A, Bd = sl_ * f, sl_ * fp
        lo, hi = eb.safe_steps(np.maximum(A, 0.0), Bd, Ml)
        inc = eb.min_cols(np.where(ml, lo, np.inf))
        # a crossing certified beyond the cap (past the window its bound holds over) stops none
        ahead = out[live][:, None] + hi <= c[live][:, None]
        ok = ~(ml & ((A <= 0) | ahead)).any(axis=1) & (inc >= short)
        for a, b in zip(last, (A, lo, hi, np.abs(dva[0])), strict=True):
            a[live[~ok]] = b[~ok]
        live = live[ok]
        out[live] = np.minimum(out[live] + inc[ok], c[live])
        ok[ok] = out[live] < c[live]
        live = live[out[live] < c[live]]
        if live.size == 0:
            break
        if not ok.all():
            x = tuple(a[ok] for a in x)
    return out, last


def event_after(r, out, last, cap, lo, hi, mon, P, U, lam, tau, s, k, q, xtol, root_iter):
    """The crossing a step of safe sub-steps (:func:`safe_substeps`) stopped before, located in
    the same step: where every monitored function is positive at the step's end (``last``:
    ``A``, ``lo``, ``hi`` there, under the step's curvature bound, valid over its window) and
    one is certified to cross by its ``hi`` before ``cap`` and before every other's ``lo`` (its
    twin aside; or one other's certified too, :func:`locate_first`), as
    :func:`atlas.dynamics.fast_engine._first_crossing` at the next step would bracket it; or
    where the last sub-step ended on a crossing (:func:`_on_crossing`).  Returns the rows
    with a located event, its time from ``tau`` and ``|d|`` at the sub-steps' end; their ``lo``,
    ``hi`` (in place) are those there (from ``tau``), the located function's (and twin's) set to
    the event."""
    A, lo_e, hi_e, ad = last
    m = mon[r]
    zero = m & (A <= 0)
    at = eb.rows(_on_crossing(zero, hi_e, out, cap))
    rz = r[at]
    lo[rz] = np.where(mon[rz], out[at][:, None] + lo_e[at], lo[rz])
    hi[rz] = np.where(mon[rz], out[at][:, None] + hi_e[at], hi[rz])
    go = ~zero.any(axis=1) & (m & (hi_e < np.inf)).any(axis=1)
    rr, ev_t, ad_t = _located_after(r, eb.rows(go), out, last, cap, lo, hi, mon, P, U, lam, tau, s,
                                    k, q, xtol, root_iter)  # fmt: skip
    return (np.concatenate([rz, rr]), np.concatenate([out[at], ev_t]),
            np.concatenate([ad[at], ad_t]))  # fmt: skip


def _on_crossing(zero, hi_e, out, cap):
    """Rows whose sub-steps ended on a crossing: a monitored function at zero (``zero``) there,
    each such one falling (its ``hi`` there 0: the bracket the next step would start with,
    ``[0, 0]``), before ``cap``.  The last sub-step's ``sigma_lo`` was the root (exact for a gap in
    free flight, a quadratic whose curvature bound is its own)."""
    return zero.any(axis=1) & ~(zero & (hi_e != 0)).any(axis=1) & (out < cap)


def _located_after(r, w, out, last, cap, lo, hi, mon, P, U, lam, tau, s, k, q, xtol, root_iter):
    """:func:`event_after`'s crossings certified ahead of the sub-steps' end (rows ``w`` of
    ``r``), located by :func:`locate_first`."""
    A, lo_e, hi_e, ad = last
    if w.size == 0:
        return w, np.zeros(0), np.zeros((0, 2))
    rr = r[w]
    lo_w, hi_w = np.where(mon[rr], lo_e[w], np.inf), np.where(mon[rr], hi_e[w], np.inf)
    first = np.argmin(hi_w, axis=1)
    done, h, _ = locate_first(lo_w, hi_w, first, mon[rr], cap[w] - out[w], P[rr], U[rr], lam[rr],
                              tau[rr] + out[w], s[rr], k[rr], q[rr], xtol[rr], root_iter)  # fmt: skip
    w, rr = w[done], rr[done]
    lo[rr] = np.where(mon[rr], out[w][:, None] + lo_w[done], lo[rr])
    hi[rr] = np.where(mon[rr], out[w][:, None] + hi_w[done], hi[rr])
    return rr, out[w] + h[done], ad[w]


def locate_first(lo, hi, first, mon, lim, P, U, lam, tau, s, k, q, xtol, root_iter):
    """The first crossing of rows whose function ``first`` (n,) has a certified bracket ``[lo,
    hi]`` (n, 4; from ``tau``) ending within ``lim`` (n,), located by :func:`eb.locate_root`
    where every other function's ``sigma_lo`` lies beyond it (its twin aside, :func:`twins`), or
    where one other function does, with a certified bracket too, and every further one lies
    beyond both: both roots are located in the same step (a gap and its lightly damped force
    crossing ``1e-3 H_S`` apart), the earlier is the event.  Returns ``(done, h, safe)`` (n,):
    the rows with a located event at ``h``; ``safe``, where tried and not done, a step with no
    crossing before it (``nan`` where not tried).  ``lo``, ``hi`` of a located root (and its
    twin's) are set to its bracket, the event's to the event (in place)."""
    n = first.size
    rows, cols = np.arange(n), np.arange(4)[None, :]
    hf = hi[rows, first]
    excl = (cols == first[:, None]) | twins(first, mon, q)
    lo_o = np.where(excl, np.inf, lo)
    second = np.argmin(lo_o, axis=1)
    hs = hi[rows, second]
    single = (lo_o[rows, second] > hf) & (hf <= lim)
    pair = ~single & (hf <= lim) & np.isfinite(hs) & (hs <= lim)
    if pair.any():
        excl |= (cols == second[:, None]) | twins(second, mon, q)
        pair &= eb.min_cols(np.where(excl, np.inf, lo)) > np.minimum(hf, hs)
    t1, t2 = eb.rows(single | pair), eb.rows(pair)
    idx, fn = np.concatenate([t1, t2]), np.concatenate([first[t1], second[t2]])
    a, b = eb.locate_root(P[idx], U[idx], lam[idx], tau[idx], lo[idx, fn], hi[idx, fn], fn,
                          s[idx, fn], k[idx], q[idx], xtol[idx], root_iter)  # fmt: skip
    a_, b_ = np.full((n, 2), np.nan), np.full((n, 2), np.inf)
    n1 = t1.size
    a_[t1, 0], b_[t1, 0], a_[t2, 1], b_[t2, 1] = a[:n1], b[:n1], a[n1:], b[n1:]
    closed = b_ - a_ <= xtol[:, None]
    done = closed[:, 0] & (closed[:, 1] | single)
    h = np.minimum(b_[:, 0], b_[:, 1])
    safe = np.where(single, a_[:, 0], np.minimum(a_[:, 0], a_[:, 1]))
    for j, f in enumerate((first, second)[: 2 if t2.size else 1]):
        r = eb.rows(done if j == 0 else done & pair)
        fr = f[r]
        lo[r, fr] = np.where(b_[r, j] <= h[r], h[r], a_[r, j])
        hi[r, fr] = np.where(b_[r, j] <= h[r], h[r], b_[r, j])
        tw_r, tw_c = np.nonzero(twins(fr, mon[r], q[r]))
        lo[r[tw_r], tw_c], hi[r[tw_r], tw_c] = lo[r[tw_r], fr[tw_r]], hi[r[tw_r], fr[tw_r]]
    return done, h, safe


def twins(first, mon, q):
    """(n, 4): the monitored function that is ``-k_i`` times the function ``first`` (n,): the
    force ``phi_i = -k_i d_i - q_i d_i'`` of a gap ``d_i`` with ``q_i = 0``, and that gap of the
    force (the same roots)."""
    i = first % 2
    undamped = np.where(i == 0, q[:, 0], q[:, 1]) == 0
    partner = (first + 2) % 4
    return (np.arange(4)[None, :] == partner[:, None]) & (undamped[:, None] & mon)
