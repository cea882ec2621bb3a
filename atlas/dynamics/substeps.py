"""Safe sub-steps of the fast engine's steps (:mod:`atlas.dynamics.fast_engine`): a step cut
short by a ``sigma_lo`` continued by further certified safe steps under the same curvature
bound, and the crossing they stopped before located in the same step (paper Sec. 4.1)."""

from __future__ import annotations

import numpy as np

from atlas.dynamics import event_bounds as eb

__all__ = ["SUBSTEPS", "SUBSTEP_MIN", "safe_substeps", "event_after", "twins"]

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
    last = (np.zeros((r.size, 4)), np.zeros((r.size, 4)), np.zeros((r.size, 4)),
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
    twin aside), as :func:`atlas.dynamics.fast_engine._first_crossing` at the next step would bracket it.  Returns the rows
    with a located event, its time from ``tau`` and ``|d|`` at the sub-steps' end; their ``lo``,
    ``hi`` (in place) are those there (from ``tau``), the located function's (and twin's) set to
    the event."""
    A, lo_e, hi_e, ad = last
    m = mon[r]
    go = ~(m & (A <= 0)).any(axis=1) & (m & (hi_e < np.inf)).any(axis=1)
    w = eb.rows(go)
    if w.size == 0:
        return w, np.zeros(0), np.zeros((0, 2))
    lo_w, hi_w = np.where(m[w], lo_e[w], np.inf), np.where(m[w], hi_e[w], np.inf)
    first = np.argmin(hi_w, axis=1)
    rw = np.arange(w.size)
    twin = twins(first, m[w], q[r[w]])
    other = eb.min_cols(np.where((np.arange(4)[None, :] == first[:, None]) | twin, np.inf, lo_w))
    hf = hi_w[rw, first]
    sel = (other > hf) & (out[w] + hf <= cap[w])
    w, first, twin, lo_w, hi_w = w[sel], first[sel], twin[sel], lo_w[sel], hi_w[sel]
    rr = r[w]
    a, b = eb.locate_root(P[rr], U[rr], lam[rr], tau[rr] + out[w], lo_w[np.arange(w.size), first],
                          hi_w[np.arange(w.size), first], first, s[rr, first], k[rr], q[rr],
                          xtol[rr], root_iter)  # fmt: skip
    done = b - a <= xtol[rr]
    w, first, twin, rr, ev_t = w[done], first[done], twin[done], rr[done], out[w[done]] + b[done]
    ad = ad[w]
    lo[rr] = np.where(mon[rr], out[w][:, None] + lo_w[done], lo[rr])
    hi[rr] = np.where(mon[rr], out[w][:, None] + hi_w[done], hi[rr])
    lo[rr, first] = hi[rr, first] = ev_t
    tw_r, tw_c = np.nonzero(twin)
    lo[rr[tw_r], tw_c] = hi[rr[tw_r], tw_c] = ev_t[tw_r]
    return rr, ev_t, ad


def twins(first, mon, q):
    """(n, 4): the monitored function that is ``-k_i`` times the function ``first`` (n,): the
    force ``phi_i = -k_i d_i - q_i d_i'`` of a gap ``d_i`` with ``q_i = 0``, and that gap of the
    force (the same roots)."""
    i = first % 2
    undamped = np.where(i == 0, q[:, 0], q[:, 1]) == 0
    partner = (first + 2) % 4
    return (np.arange(4)[None, :] == partner[:, None]) & (undamped[:, None] & mon)
