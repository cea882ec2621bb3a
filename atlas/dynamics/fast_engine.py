"""Batched event-to-event engine for outcome maps, NumPy (paper Sec. 4.1, eqs. 1, 6-8).

Inside one contact configuration ``S`` the gaps follow a known linear flow.  Per trajectory and
configuration the modal form is computed once (:func:`modal_tables`): the active subsystem
``x' = A_S x`` (``x`` = active gaps and velocities, deviation from the equilibrium
``B_SS K_S d_S = -a_S``) in eigenvectors, the free gaps ``d_F'' = (B f)_F - a_F`` integrated
twice in closed form.  On a segment starting at the state ``g`` every gap is::

    d_i(tau) = p0_i + p1_i tau + p2_i tau^2 + Re sum_m u_im exp(lambda_m tau)

and so is every event function (gaps ``d_i``, forces ``phi_i = -k_i d_i - q_i d_i'``).

Event location (certified bracket)
----------------------------------
From ``tau`` the step ``sigma`` obeys ``|f''| <= M`` on ``[tau, tau + W]`` with ``M`` the sum of
the moduli of the modal terms (each grown by ``exp(max(Re lambda, 0) W)``), so for the recorded
sign ``s`` of ``f``::

    s f(tau + sigma) >= s f + s f' sigma - M sigma^2 / 2     (no crossing before its root sigma_lo)
    s f(tau + sigma) <= s f + s f' sigma + M sigma^2 / 2     (a crossing by its root sigma_hi)

Where large modal terms cancel (near-defective modal forms, e.g. near the ``3 pi / 2`` axis) that
``M`` is orders of magnitude above ``|f''|``; a step cut below ``1/8`` of its window is then
bracketed again under the flow's bound (:func:`eb.flow_curvature_bound`: ``z'' = (d'', d''')``
obeys ``z' = A z``, so ``|D z''|`` grows at most by ``exp(mu s)``, ``mu`` the logarithmic norm of
the configuration, :func:`atlas.dynamics.modal_form.log_norm`) within a shorter window
(:func:`atlas.dynamics.step_windows.brackets`).

Every lane advances by the smallest ``sigma_lo`` of its monitored functions (at most the window
``W``: ``H_S = 1 / max(rho_S, omega / 4)``, up to ``8 H_S`` where no modal term grows by more than
2 over it, and up to ``64 H_S`` where no function can cross within ``8 H_S``: an event-free
stretch such as a free flight or a settled contact is crossed in a few steps, so that no lane
costs many times the median lane; past the growth cap, on the early decisions' schedule from its
second try, where no event and no limit of the stop rule can come before its end,
:func:`sw.stretch`: a run growing to its divergence stop with no event gets there in one step);
a step cut short by a ``sigma_lo`` with no crossing certified in the window goes on with further safe steps from its end under the same bound
(:func:`atlas.dynamics.substeps.safe_substeps`: an oscillation far from its contacts crosses
the window in one step; a crossing certified beyond the window stops none), and a crossing
certified where they stop, or reached by their last ``sigma_lo`` (a gap in free flight, an exact
quadratic), is the step's event (:func:`atlas.dynamics.substeps.event_after`; 1.1 steps per
event on event-heavy lanes, was 2.0);
inside a step longer than ``H_S`` the gaps are sampled at
most ``H_S`` apart (:func:`_sample_step`) for the late-amplitude test and the stop rule, unless
both provably stay within ``10 scale``; the first
crossing is the function whose bracket ``[sigma_lo, sigma_hi]`` is narrower than ``1e-12 H_S`` (functions within ``1e3`` times that of it
cross together, as in :func:`atlas.dynamics.simulate`).  Near a simple root the lower bound is a
safeguarded Newton step from the safe side: the bracket shrinks quadratically.  A certified
bracket of the first function that every other function's ``sigma_lo`` lies beyond (its twin
aside: the force of a contact with ``q_i = 0`` is ``-k_i d_i``, the same roots) is closed by
:func:`locate_root` (safeguarded Newton, at most ``ROOT_ITER`` evaluations per step; an
unfinished bracket resumes from its lower end at the next step); where one other function's
``sigma_lo`` lies inside it and that function has a certified bracket too (a gap and its lightly
damped force crossing ``1e-3 H_S`` apart), both are closed and the earlier root is the event
(:func:`atlas.dynamics.substeps.locate_first`).  The bounds hold in
exact arithmetic on the modal form; its floating-point evaluation is not bounded here (values within
``1e-13`` of the function's scale count as zero).

Early decisions (stated, checked)
---------------------------------
On a schedule (1, 2, 4, ... steps after an event), for the lanes where a decision is possible
(:func:`may_decide`; no crossing certified by ``sigma_hi``; :func:`eb.may_keep_signs`, a
necessary condition of the certificate), each monitored function is tested
for keeping its sign for all later times in the current configuration (:func:`eb.keeps_sign`: the
modal terms bounded below by their moduli, a growing real dominant term by ``exp(x) >= 1 + x +
x^2 / 2``, the remaining quadratic tested for positivity).  If all keep their signs, no event can follow, and:

* ``settles``: every eigenvalue has ``Re lambda < 0`` (or is neutral, ``|Re lambda| <= 1e-9
  |lambda|``, bounded over the rest of the horizon and decided at most half way through it, as
  :func:`atlas.dynamics.classify` does): the outcome is ``settles_S``;
* ``IWC``: the dominant eigenvalue is real and positive and every active gap is driven to ``-inf``
  along it (its force to ``+inf``), every free gap open and driven away: an impact without
  collision (paper Sec. 4.3), decided only if the reference's divergence limit
  (``1e3 penetration_limit``) is provably passed within the current horizon.

A lane entering free flight at an event with both gaps open or opening and accelerating away is
``settles_FF`` there (:func:`_leaves_free`), as the exact simulator stops it at its next sub-step,
before any limit its gaps reach later.

Both are declared only where the reference's finite-horizon stops reach the same verdict
(:func:`_settles_first`, :func:`aligned_at_stop`); otherwise the lane keeps stepping.

Divergence (:mod:`atlas.dynamics.stop_rule`, the exact simulator's rule): tested at every step
end and just before every event, and located inside the step by a search on the segment; the
amplitude and deep-penetration limits are bracketed like events (:func:`atlas.dynamics.step_windows.limit_steps`: no step
passes one before its ``sigma_lo``, and a step to its ``sigma_hi`` where no event comes first),
so a peak past a limit inside a step is not missed.  Early IWC also needs the reference's sign
conditions at its stop (:func:`signs_from`).

Lanes that are decided, diverge, reach the horizon or the event cap leave the batch (compaction).
Every ``8`` steps the lanes that stopped are classified; those the reference would run again with
a longer horizon (:func:`atlas.dynamics.needs_longer_run`) rejoin the running batch from where
they stopped, so the horizon extensions of some lanes overlap the first runs of the others.
Lanes the modal form cannot serve (a proven upper bound of the eigenvector condition ``>= 1e4``,
:func:`atlas.dynamics.modal_form.cond_bound`; singular ``B_SS``, a zero
eigenvalue; a segment whose terms exceed its gaps ``CANCEL_MAX`` times, :func:`cancels`) or
whose root location stalls (a grazing contact) are run by the exact simulator instead
(``fallback``).  The condition bound separates the near-defective configurations of
degenerate directions: a grid through ``b_ii = 0`` (e.g. ``beta2 = pi``, where ``sin beta2`` rounds
to ``1.2e-16``) or ``det B = 0`` (``beta2 = beta1 + pi``) gives a double eigenvalue split by
rounding, ``|lambda| ~ 1e-8``, condition ``~ 1 / |lambda| ~ 1e7-1e9``, an equilibrium ``~ 1 /
|lambda|^2 ~ 1e16`` and modal amplitudes of that size that cancel to the ``O(1)`` gaps: their
evaluation keeps no digit, and root location crawls (minutes for one run).  Elsewhere the condition stays below
``1e2`` (``0:2pi:32`` grids, ``kappa = 0.5``, ``q = 0`` and ``0.3``).  Where the degeneracy is
exact or within the rounding of the angles (``b_ii`` or ``det B`` at most ``ROUNDING``
relative) the configuration is served by its closed form instead
(:func:`atlas.dynamics.modal_form.closed_segment`: a quartic, or a quadratic and two modes; no
early decision there), so axis and ``0:2pi:n`` grids stay on the fast path.
Trajectories that end without an early decision are classified as
:func:`atlas.dynamics.classify_stats` classifies the reference's runs, on arrays
(:func:`_classify_many`; :func:`_stats` and :func:`atlas.dynamics.modal_form.light_system` are the per-run form it is
tested against)."""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from atlas.dynamics import early_decisions as early
from atlas.dynamics import event_bounds as eb
from atlas.dynamics import step_windows as sw
from atlas.dynamics import stop_location as sl
from atlas.dynamics import stop_rule
from atlas.dynamics import substeps as ss
from atlas.dynamics.classification import (
    TrajectoryStats,
    impacts,
)
from atlas.dynamics.event_bounds import locate_root
from atlas.dynamics.modal_form import (
    Lanes,
    modal_coordinates,
    modal_tables,
    segments,
    stack_table,
    z_eq,
)
from atlas.dynamics.system import (
    MODE_NAMES,
    Outcome,
    Status,
    eig_rows,
    iwc_aligned_many,
)

__all__ = ["FastResult", "run_batch", "run_lanes", "outcomes", "locate_root"]

XTOL = 1e-12
STALL = 64  # steps below 1e-9 H_S in a row before a lane is handed to the exact simulator
ROOT_ITER = 8  # evaluations per root location; an unfinished one resumes at the next step

#: how a trajectory of :func:`outcomes` was decided
DECIDED_BY = ("stepped", "early_settle", "early_iwc", "fallback")


OUTCOME_OF_MASK = {m: int(Outcome[f"SETTLES_{MODE_NAMES[m]}"]) for m in range(4)}
RUNNING = -1
_STATUS = (Status.T_END, Status.EVENT_CAP, Status.DIVERGED)
#: why a run of :class:`FastResult` stopped (the engine's own stops first, as in ``_STATUS``)
STOPS = _STATUS + (Status.SETTLED, Status.STEP_CAP)


@dataclasses.dataclass
class State:
    """Per-lane state of a batch (arrays over all ``N`` lanes)."""

    t: np.ndarray
    g: np.ndarray
    s: np.ndarray
    n_events: np.ndarray
    last_event: np.ndarray
    amp: np.ndarray
    status: np.ndarray
    code: np.ndarray
    decided_by: np.ndarray
    scale: np.ndarray
    horizon: np.ndarray
    rounding: np.ndarray
    imp: list
    steps: np.ndarray

    @classmethod
    def start(cls, lanes: Lanes, g0, t_end, nbins):
        n = g0.shape[0]
        f, _ = eb.event_functions(g0[:, :2], g0[:, 2:], g0[:, :2] * 0, lanes.k, lanes.q)
        bnorm = np.linalg.norm(lanes.B, axis=1)
        scale = np.maximum(
            np.abs(g0[:, :2]).max(axis=1),
            np.linalg.norm(lanes.a, axis=1) / np.min(lanes.k * bnorm, axis=1),
        )
        return cls(
            t=np.zeros(n), g=g0.copy(), s=np.where(f > 0, 1.0, -1.0), n_events=np.zeros(n, int),
            last_event=np.zeros(n), amp=np.zeros((n, nbins, 2)), status=np.full(n, RUNNING),
            code=np.full(n, -1, dtype=np.int8), decided_by=np.zeros(n, dtype=np.int8),
            scale=np.maximum(scale, 1e-300), horizon=np.full(n, float(t_end)),
            rounding=np.zeros(n, dtype=bool), imp=[], steps=np.zeros(n, dtype=np.int64),
        )  # fmt: skip

    def impact_stats(self, n, fr, fc, v_fly):
        """:func:`_impact_stats` of the stopped lanes ``n`` from the logged impacts and the
        gaps in free flight falling back (rows ``fr``, contacts ``fc``, speeds ``v_fly``),
        dated at the stop."""
        lane, t_i, v_i, c_i = _impacts_of(self, n)
        pos = np.full(self.t.size, -1)
        pos[n] = np.arange(n.size)
        T = self.t[n]
        row = np.concatenate([pos[lane], fr])
        t_i = np.concatenate([t_i, T[fr]])
        return _impact_stats(
            row, t_i, np.concatenate([v_i, v_fly]), np.concatenate([c_i, fc + 1]), T
        )


def _impact_stats(row, t_i, v_i, c_i, T):
    """Impact statistics of :func:`_classify_many` for ``m = T.size`` lanes from impacts at
    rows ``row`` (times ``t_i``, speeds ``v_i``, contacts ``c_i`` 1 or 2): ``count``, ``n_mid``,
    ``n_late`` (in ``[T/3, 2T/3)``, ``[2T/3, T]``), the largest speeds ``m2``, ``m3`` there,
    ``t_first``, ``t_last`` and ``bouncing`` (m, 2) (a contact with a late impact)."""
    m = T.size
    Tr = T[row]
    mid, late = (t_i >= Tr / 3) & (t_i < 2 * Tr / 3), t_i >= 2 * Tr / 3
    m2, m3, t_last = np.full(m, -np.inf), np.full(m, -np.inf), np.full(m, -np.inf)
    t_first = np.full(m, np.inf)
    np.maximum.at(m2, row[mid], v_i[mid])
    np.maximum.at(m3, row[late], v_i[late])
    np.maximum.at(t_last, row, t_i)
    np.minimum.at(t_first, row, t_i)
    bouncing = np.zeros((m, 2), dtype=bool)
    bouncing[row[late], c_i[late] - 1] = True
    n_mid, n_late = np.bincount(row[mid], minlength=m), np.bincount(row[late], minlength=m)
    return np.bincount(row, minlength=m), n_mid, n_late, m2, m3, t_first, t_last, bouncing


def mask_of(s):
    return ((s[:, 0] < 0) & (s[:, 2] > 0)).astype(int) | (
        ((s[:, 1] < 0) & (s[:, 3] > 0)).astype(int) << 1
    )


def switch(s, cross, f, fp, k, scale):
    """New signs after the crossings ``cross`` (n, 4) at the event values ``f``, derivatives
    ``fp`` (pre-event configuration), as :func:`atlas.dynamics.simulate`; returns
    ``(s_new, closing (n, 2), n_events (n,))``."""
    xp = eb.xp_of(s, cross, f)
    sn = xp.where(cross, -s, s)
    closing = cross[:, :2] & (sn[:, :2] < 0)
    opening = cross[:, :2] & (sn[:, :2] > 0)
    force = xp.where(xp.abs(f[:, 2:]) > 1e-9 * xp.abs(k * scale[:, None]), f[:, 2:], fp[:, 2:])
    sf = xp.where(opening, -1.0, xp.where(closing, xp.where(force > 0, 1.0, -1.0), sn[:, 2:]))
    sn = xp.concatenate([sn[:, :2], sf], axis=1)
    # a force crossing while its gap stays open is no event (as in the reference)
    force_ev = cross[:, 2:] & ~((sn[:, :2] > 0) & ~closing & ~opening)
    n_ev = closing.sum(axis=1) + opening.sum(axis=1) + force_ev.sum(axis=1)
    return sn, closing, n_ev


def _admit(lanes, tables, st: State, ix, fallback):
    """The per-lane arrays of :func:`_run_lanes` for the lanes ``ix`` starting from their state
    in ``st`` (time, state, signs, horizon); lanes the modal form cannot serve fall back."""
    t, g, s = st.t[ix].copy(), st.g[ix].copy(), st.s[ix].copy()
    mask = mask_of(s)
    P, U, lam, valid, H, ok = segments(lanes, tables, ix, mask, g, closed=True)
    ok &= ~cancels(P, U, g, st.scale[ix])
    fallback[ix[~ok]] = True
    cols = (ix, t, g, s, mask, P, U, lam, valid, H, t.copy(), st.horizon[ix].copy(),
            lanes.k[ix], lanes.q[ix], st.scale[ix], np.zeros(ix.size, dtype=int),
            np.zeros(ix.size, dtype=int), t.copy())  # fmt: skip
    return tuple(x[ok] for x in cols)


def _classify_stopped(st: State, tables, n, width, t_max, fallback):
    """Classify the lanes ``n`` that stopped (horizon, event cap, divergence); those that
    :func:`atlas.dynamics.needs_longer_run` would run again get the horizon doubled and are
    returned; a divergence whose verdict sits within rounding (:func:`stop_rule.within_rounding`)
    is flagged (``st.rounding``) and goes to the exact simulator (``fallback``): the signs of its
    residues are the integrator's (e.g. a gap at ``+3e-16`` here and ``-3e-16`` there beside one
    at ``-4e5``), and on a closed configuration the closed form changed ``B`` within rounding
    (:func:`atlas.dynamics.modal_form.closed_segment`); the exact simulator's run then flags it."""
    st.code[n] = _classify_many(st, tables, n, width)
    div = n[st.status[n] == 2]
    if div.size:
        mk = mask_of(st.s[div])
        E, zq = stack_table(tables, "E", div, mk), z_eq(tables, div, mk)
        near = div[stop_rule.within_rounding(st.g[div], mk, E, zq, eig=eig_rows(tables.eig, div))]
        st.rounding[near] = True
        fallback[near] = True
    again = n[(st.code[n] == int(Outcome.UNDETERMINED)) & (st.status[n] == 0)
              & (st.n_events[n] > 0) & (2 * st.horizon[n] <= t_max * (1 + 1e-12))]  # fmt: skip
    st.horizon[again] *= 2
    st.status[again] = RUNNING
    st.code[again] = -1
    return again


#: steps between the classifications of the lanes that stopped (those given a longer horizon
#: rejoin the batch then); at every step in a batch below ``_READMIT_NOW`` lanes, where a step
#: costs little more than the classification
_READMIT = 8
_READMIT_NOW = 256


def _run_lanes(lanes, tables, st: State, t_max, max_events, width, fallback):
    """Step every lane event to event until it is decided, stops (horizon ``st.horizon``, event
    cap, divergence) or falls back; a lane that stops undetermined with events rejoins the batch
    with its horizon doubled (:func:`_classify_stopped`); results written into ``st``."""
    nbins = st.amp.shape[1]
    cols = _admit(lanes, tables, st, np.arange(st.t.size), fallback)
    ix = cols[0]
    keep = np.ones(ix.size, dtype=bool)
    pending, stops = [], []
    it = 0
    while True:
        if not keep.all():
            gone = ix[~keep]
            pending.append(gone[(st.status[gone] != RUNNING) & ~fallback[gone]])
            sel = eb.rows(keep)
            cols = tuple(x.take(sel, axis=0) for x in cols)
            ix = cols[0]
        if pending and (ix.size < _READMIT_NOW or it % _READMIT == 0):
            sl.locate_stops(st, tables, stops, width)
            again = _classify_stopped(st, tables, np.concatenate(pending), width, t_max, fallback)
            pending = []
            if again.size:
                new = _admit(lanes, tables, st, again, fallback)
                cols = tuple(np.concatenate([a, b]) for a, b in zip(cols, new, strict=True))
        it += 1
        ix, t, g, s, mask, P, U, lam, valid, H, tseg, T, k, q, scale, stall, since, t0 = cols
        if ix.size == 0:
            return
        st.steps[ix] += 1
        tau = t - tseg
        d, v, acc, p, UE = eb.evaluate(P, U, lam, tau)
        g = np.concatenate([d, v], axis=1)
        act = (mask[:, None] >> _BITS & 1).astype(bool)
        keep = np.ones(ix.size, dtype=bool)

        # the stop rule (divergence) at the step end, located inside the step; the horizon
        div = sl.stops_at(tables, ix, mask, act, g, scale)
        if div.size:  # located with the others of the next classification (locate_stops)
            stops.append(_stop_of(div, ix, mask, P, U, lam, scale, t0, t, tseg, H))
            _leave(st, ix, t, g, s, keep, div, 2)
        b = eb.bins(t, width, nbins)
        st.amp[ix, b] = np.where(keep[:, None], np.maximum(st.amp[ix, b], np.abs(d)), st.amp[ix, b])
        sched = ((since & (since - 1)) == 0) & (since > 0)  # 1, 2, 4, ... steps after an event
        _leave(st, ix, t, g, s, keep, eb.rows(keep & (t >= T)), 0)
        # next step: certified brackets of the monitored event functions
        mu = stack_table(tables, "mu", ix, mask)
        lo, hi, mon, M, Hw, small = sw.brackets(d, v, acc, k, q, s, p, UE, lam, valid, H, scale,
                                                 act, mu)  # fmt: skip
        # early decisions (on the same schedule): no event can follow; not tried where a crossing
        # is certified (sigma_hi) before t_max, which no certificate can pass
        r = eb.rows(keep & sched & eb.all_cols(hi > (t_max - t)[:, None]))
        if r.size:
            dec = _try_decisions(st, tables, ix, r, t, T, t_max, s, mask, g, p, UE, lam, valid,
                                 k, q, scale, act, H)  # fmt: skip
            _leave(st, ix, t, g, s, keep, dec, RUNNING)
        ev, h, xtol, step, t0 = _step_lengths(st, tables, ix, keep, lo, hi, mon, M, Hw, small, d, v,
                                              t, T, tseg, P, U, lam, s, k, q, H, mask, act,
                                              scale, width, (p, UE, valid), sched & (since > 1))  # fmt: skip
        t = np.where(keep, t + step, t)
        since += 1
        # stalled root location (a grazing contact): the exact simulator takes over
        stall = np.where(step < 1e-9 * H, stall + 1, 0)
        st_lane = keep & (stall > STALL)
        fallback[ix[st_lane]] = True
        keep &= ~st_lane
        ev &= keep
        ev_r, dva = _stops_before_events(st, tables, stops, eb.rows(ev), ix, t, t0, tseg,
                                         s, mask, act, P, U, lam, scale, H, keep)  # fmt: skip
        if ev_r.size:
            _events(lanes, tables, st, ix, ev_r, dva, lo, hi, h, xtol, t, tseg, P, U, lam, valid,
                    H, s, mask, k, q, scale, since, max_events, width, keep, fallback)  # fmt: skip
        cols = (ix, t, g, s, mask, P, U, lam, valid, H, tseg, T, k, q, scale, stall, since, t0)


def _step_lengths(st, tables, ix, keep, lo, hi, mon, M, Hw, small, d, v, t, T, tseg, P, U, lam,
                  s, k, q, H, mask, act, scale, width, now, sched):  # fmt: skip
    """The next step of every lane (:func:`_run_lanes`): ``(ev, h, xtol, step, t0)``, ``ev``
    where it ends at a located event ``h`` away, ``step`` its length (to the first crossing, the
    window, the horizon or a stop-rule limit; past the window where :func:`_stretch` allows, tried
    on the rows ``sched``: the early decisions' schedule from its second try, after them) and ``t0`` its start for a stop located
    inside; ``now`` the segments' ``(p, UE, valid)`` there."""
    rem = T - t
    xtol = XTOL * H
    ev, h, m = _first_crossing(lo, hi, mon, keep, rem, xtol, P, U, lam, t - tseg, s, k, q)
    # a limit of the stop rule passed before the first crossing: step past it (certified)
    # and locate it at the next step; steps never pass it unseen
    lim_lo, lim_hi = sw.limit_steps(d, v, M, scale, Hw)
    ev &= h <= lim_lo
    past = keep & ~ev & (lim_hi <= np.minimum(m, rem))
    step = np.where(ev, h, np.minimum(np.minimum(np.minimum(m, Hw), rem), lim_lo))
    step = np.where(past, np.maximum(lim_hi, xtol), step)  # a gap exactly at a limit
    # a step cut short by a sigma_lo with no crossing certified in the window: more safe steps
    cap = np.minimum(np.minimum(Hw, rem), lim_lo)
    r = eb.rows(keep & ~ev & ~past & (step == m) & (step < cap) & np.isinf(eb.min_cols(hi)))
    split = np.zeros(step.size)  # where the safe sub-steps of a step with an event ended
    if r.size:
        step[r], last = ss.safe_substeps(r, step, cap, P, U, lam, t - tseg, s, k, q, M, mon, H)
        re, h_re, d_re = ss.event_after(r, step[r], last, cap[r], lo, hi, mon, P, U, lam, t - tseg,
                                        s, k, q, xtol, ROOT_ITER)  # fmt: skip
        # the end of the safe sub-steps stays a sample of the late amplitudes
        b = eb.bins(t[re] + step[re], width, st.amp.shape[1])
        st.amp[ix[re], b] = np.maximum(st.amp[ix[re], b], d_re)
        split[re] = step[re]
        ev[re], h[re], step[re] = True, h_re, h_re
    # a whole window with no crossing, cut by the growth cap: longer where no event can come
    sel = keep & sched & ~ev & ~past & (step == Hw) & (Hw < np.minimum(rem, lim_lo))
    _stretch(sel & np.isinf(eb.min_cols(hi)), step, small, *now, lam, s, k, q, H, scale, rem, Hw)
    t0 = t.copy()
    # a step over H_S where the gaps may leave SMALL scale: sampled, cut at a stop (a step
    # with safe sub-steps and an event: before and after the sub-steps' end, as two steps)
    parts = ((0.0, np.where(split > 0, split, step)), (split, step - split))
    for i, (a, n) in enumerate(parts):
        r = eb.rows(keep & ~small & (n > H) & ((split > 0) & ev if i else True))
        if r.size:
            rc, s_cut, s_before = _sample_step(st, tables, ix, r, t - tseg + a, n, H, P, U, lam,
                                               mask, act, scale, tseg, width)  # fmt: skip
            a_c = a[rc] if i else 0.0
            step[rc], t0[rc], ev[rc] = a_c + s_cut, t[rc] + a_c + s_before, False
    return ev, h, xtol, step, t0


def _stretch(sel, step, small, p, UE, valid, lam, s, k, q, H, scale, rem, Hw):
    """Steps of the rows ``sel`` whose window the ``GROWTH`` cap cut (a real dominant growing
    eigenvalue), past it where no event and no limit of the stop rule can come
    (:func:`sw.stretch`; quadratic segments); ``step`` and ``small`` (sampled inside: no longer
    provably small) in place."""
    r = eb.rows(sel)
    re = np.where(valid[r], lam[r].real, -np.inf)
    j1 = np.argmax(re, axis=1)
    grow, real = re[np.arange(r.size), j1], lam[r, j1].imag == 0
    # not tried on a growing oscillation: its certificate rarely holds (half the attempts' cost)
    capped = real & (grow * Hw[r] >= math.log(sw.GROWTH) * (1 - 1e-9)) & (Hw[r] < sw.LONG * H[r])
    if p.shape[2] > 3:  # closed forms: those with cubic or quartic terms left out
        capped &= ~(p[r, :, 3:] != 0).any(axis=(1, 2))
    r = r[capped]
    if r.size:
        step[r] = sw.stretch(s[r], p[r, :, :3], UE[r], lam[r], valid[r], k[r], q[r], H[r],
                             scale[r], rem[r], step[r])  # fmt: skip
        small[r] &= step[r] <= Hw[r]


def _try_decisions(st, tables, ix, r, t, T, t_max, s, mask, g, p, UE, lam, valid, k, q, scale,
                   act, H):  # fmt: skip
    """The early decisions (:func:`_decide`) of the rows ``r`` where they may apply
    (:func:`early.may_decide`, :func:`eb.may_keep_signs`; not on closed forms, whose quartics no
    certificate reads); returns the rows decided."""
    if tables.closed.any():
        r = r[~stack_table(tables, "closed", ix[r], mask[r])]
    q2 = p[:, :, :3]  # quadratic there (the quartics are closed, left out above)
    if r.size:
        r = r[early.may_decide(lam[r], valid[r], s[r], q2[r], act[r], mask[r], t[r], T[r])]
    if r.size:
        r = r[eb.may_keep_signs(s[r], q2[r], UE[r], lam[r], valid[r], k[r], q[r])]
    if r.size == 0:
        return r
    _decide(st, tables, ix[r], t[r], T[r], t_max, s[r], mask[r], g[r], q2[r], UE[r], lam[r],
            valid[r], k[r], q[r], scale[r], act[r], H[r])  # fmt: skip
    return r[st.code[ix[r]] >= 0]


def _first_crossing(lo, hi, mon, keep, rem, xtol, P, U, lam, tau, s, k, q):
    """The first crossing of the next step: ``(ev, h, m)`` (n,), the rows with an event, its
    time (the bracket's upper end, from ``tau``) and the smallest ``sigma_lo`` (or a step with
    no crossing before it); ``lo``, ``hi`` of the brackets closed by
    :func:`atlas.dynamics.substeps.locate_first` set to their roots, the event's to the event
    (in place)."""
    # smallest sigma_lo, ties to the tightest bracket
    m = eb.min_cols(lo)
    tie_hi = np.where(lo <= m[:, None], hi, np.inf)
    first = np.where(np.isinf(eb.min_cols(tie_hi)), np.argmin(lo, axis=1),
                     np.argmin(tie_hi, axis=1))  # fmt: skip
    h = hi[np.arange(first.size), first]
    ev = keep & (h - m <= xtol) & (h <= rem)
    # a bracket of the first function that every other function's sigma_lo lies beyond (or one
    # other's, with a certified bracket too): the first crossing is in it, located
    # (:func:`atlas.dynamics.substeps.locate_first`); not yet: step to where no function crosses
    r = eb.rows(keep & ~ev & (h <= rem))
    if r.size:
        lo_r, hi_r = lo[r], hi[r]
        done, h_r, safe = ss.locate_first(lo_r, hi_r, first[r], mon[r], rem[r], P[r], U[r], lam[r],
                                          tau[r], s[r], k[r], q[r], xtol[r], ROOT_ITER)  # fmt: skip
        lo[r], hi[r] = lo_r, hi_r
        tried = ~np.isnan(safe)
        rd, rs = r[done], r[tried & ~done]
        h[rd], m[rs] = h_r[done], safe[tried & ~done]
        ev[rd] = True
    return ev, h, m


def _stops_before_events(st, tables, stops, ev_r, ix, t, t0, tseg, s, mask, act, P, U, lam,
                         scale, H, keep):  # fmt: skip
    """The stop rule just before the events of rows ``ev_r`` (configuration up to them): those
    where it holds leave (located with the next classification, ``stops``); returns the rows
    that switch and their gaps, velocities and accelerations."""
    if ev_r.size == 0:
        return ev_r, None
    dva = eb.gaps_at(P[ev_r], U[ev_r], lam[ev_r], t[ev_r] - tseg[ev_r])
    ge = np.concatenate(dva[:2], axis=1)
    sr = sl.stops_at(tables, ix[ev_r], mask[ev_r], act[ev_r], ge, scale[ev_r])
    if sr.size:
        rs = ev_r[sr]
        stops.append(_stop_of(rs, ix, mask, P, U, lam, scale, t0, t, tseg, H))
        _leave(st, ix, t, ge, s, keep, sr, 2, rows=rs)
        ok = np.ones(ev_r.size, dtype=bool)
        ok[sr] = False
        ev_r, dva = ev_r[ok], tuple(x[ok] for x in dva)
    return ev_r, dva


def _stop_of(r, ix, mask, P, U, lam, scale, t0, t, tseg, H):
    """The record of rows ``r`` whose stop rule held at the end of their last step (from
    ``max(t0, tseg)`` to ``t``), for :func:`atlas.dynamics.stop_location.locate_stops` to locate inside that step."""
    a = np.maximum(t0[r], tseg[r]) - tseg[r]
    return (ix[r], mask[r], P[r], U[r], lam[r], scale[r], a, t[r] - tseg[r], XTOL * H[r], tseg[r])


def _sample_step(st, tables, ix, r, tau0, step, H, P, U, lam, mask, act, scale, tseg, width):
    """The gaps inside the steps ``step`` (from ``tau0`` on the segment) of the rows ``r``, at
    ``ceil(step / H) - 1`` equally spaced points (at most ``H`` apart, as steps of ``H`` would
    end): their late amplitudes into ``st.amp`` and the stop rule (:func:`atlas.dynamics.stop_location.stops_at`) there.
    Returns the rows whose stop holds at a point, the point (from ``tau0``) and the point before
    it (0 at the first): their steps end there, the stop is located between the two."""
    n_in = np.minimum(np.ceil(step[r] / H[r]) - 1, sw.LONG).astype(int)
    r, n_in = r[n_in > 0], n_in[n_in > 0]
    if r.size == 0:
        return r, r * 0.0, r * 0.0
    rr = np.repeat(np.arange(r.size), n_in)
    j = np.arange(rr.size) - np.repeat(np.cumsum(n_in) - n_in, n_in) + 1
    x = step[r][rr] * j / (n_in[rr] + 1)
    rows = r[rr]
    d, v = eb.gaps_at(P[rows], U[rows], lam[rows], tau0[rows] + x)[:2]
    hit = np.zeros(rr.size, dtype=bool)
    hit[sl.stops_at(tables, ix[rows], mask[rows], act[rows], np.concatenate([d, v], 1),
                  scale[rows])] = True  # fmt: skip
    first = np.full(r.size, np.iinfo(np.int64).max)
    np.minimum.at(first, rr[hit], j[hit])
    upto = j <= first[rr]  # the amplitudes up to a stop
    b = eb.bins(tseg[rows] + tau0[rows] + x, width, st.amp.shape[1])
    for c in range(2):
        np.maximum.at(st.amp[:, :, c], (ix[rows][upto], b[upto]), np.abs(d[upto, c]))
    cut = eb.rows(first < np.iinfo(np.int64).max)
    f, m = first[cut], n_in[cut] + 1
    s_r = step[r[cut]]
    return r[cut], s_r * f / m, s_r * (f - 1) / m


#: largest ratio of a segment's terms to its gaps (or the run's scale, if larger): beyond it the
#: evaluation keeps fewer than 10 of the 16 digits of the gaps and root location crawls
CANCEL_MAX = 1e6


def cancels(P, U, g, scale):
    """Segments (n,) whose terms ``|p0| + sum |u|`` of a gap exceed ``CANCEL_MAX`` times the
    gaps ``g[:, :2]`` (or the length ``scale``): near-defective configurations (an eigenvalue
    ``~1e-4`` of ``lambda`` scale ``1``: equilibrium and modal amplitudes ``~1 / lambda^2``
    cancelling to the gaps), handed to the exact simulator."""
    terms = np.abs(P[:, :, 0]) + eb.sum4(np.abs(U))
    size = np.maximum(np.abs(g[:, :2]).max(axis=1), scale)
    with np.errstate(invalid="ignore"):
        return ~(terms.max(axis=1) <= CANCEL_MAX * size)


_BITS = np.arange(2)


def _leave(st, ix, t, g, s, keep, sel, status, rows=None):
    """Lanes ``sel`` (rows) leave the batch: their time, state, signs and status into ``st``
    (``rows``: their rows when ``g`` holds the states of ``sel`` alone, in order)."""
    if sel.size == 0:
        return
    r = sel if rows is None else rows
    st.t[ix[r]], st.g[ix[r]], st.s[ix[r]] = t[r], g[sel], s[r]
    st.status[ix[r]] = status
    keep[r] = False


def _decide(st, tables, ix, t, T, t_max, s, mask, g, p, UE, lam, valid, k, q, scale, act, H):
    """The early decisions of the module docstring for lanes ``ix`` (written into ``st.code``,
    ``st.decided_by``)."""
    settle, iwc, l1 = early.decisions(t, T, t_max, s, mask, p, UE, lam, valid, k, q, scale, act, H)
    st.code[ix[settle]] = np.array([OUTCOME_OF_MASK[m] for m in range(4)])[mask[settle]]
    st.decided_by[ix[settle]] = 1
    r = eb.rows(iwc)
    if r.size:
        c = modal_coordinates(tables, ix[r], mask[r], g[r])
        s0 = early.reach_time(p[r], UE[r], lam[r], T[r] - t[r], scale[r])
        # aligned from now on: from the stop on too
        now = early.aligned_from(c, lam[r], valid[r], l1[r], np.zeros(r.size))
        iwc[r] = now | early.aligned_from(c, lam[r], valid[r], l1[r], s0)
        iwc[r] &= early.signs_from(p[r], UE[r], lam[r], valid[r], l1[r], act[r], s[r], s0)
    st.code[ix[iwc]] = int(Outcome.IWC)
    st.decided_by[ix[iwc]] = 2


def _events(lanes, tables, st, ix, r, dva, lo, hi, h, xtol, t, tseg, P, U, lam, valid, H, s,
            mask, k, q, scale, since, max_events, width, keep, fallback):  # fmt: skip
    """Switch the lanes ``r`` (rows; gaps, velocities, accelerations ``dva`` there) at their
    events and start new segments where their configuration changes (in place)."""
    d, v, acc = dva
    f, fp = eb.event_functions(d, v, acc, k[r], q[r])
    tol = (h[r] + 1e3 * xtol[r])[:, None]
    cross = (hi[r] <= tol) & (lo[r] <= tol)
    sn, closing, n_ev = switch(s[r], cross, f, fp, k[r], scale[r])
    lanes_r = ix[r]
    ci, cc = np.nonzero(closing)
    if ci.size:
        st.imp.append((lanes_r[ci], t[r][ci], np.abs(v[ci, cc]), cc + 1))
    st.n_events[lanes_r] += n_ev
    has = n_ev > 0
    st.last_event[lanes_r[has]] = t[r][has]
    b = eb.bins(t[r], width, st.amp.shape[1])
    st.amp[lanes_r, b] = np.maximum(st.amp[lanes_r, b], np.abs(d))
    # a new segment where the configuration changes (the same flow goes on where it does not)
    m = eb.rows(mask_of(sn) != mask[r])
    s[r] = sn
    mask[r] = mask_of(sn)
    g = np.concatenate([d, v], axis=1)
    ok = np.ones(r.size, dtype=bool)
    if m.size:
        rm = r[m]
        P[rm], U[rm], lam[rm], valid[rm], H[rm], ok[m] = segments(
            lanes, tables, ix[rm], mask[rm], g[m], closed=True
        )
        ok[m] &= ~cancels(P[rm], U[rm], g[m], scale[rm])
        tseg[rm] = t[rm]
    since[r] = 0
    fallback[lanes_r[~ok]] = True
    keep[r[~ok]] = False
    cap = ok & (st.n_events[lanes_r] >= max_events)
    rc = r[cap]
    st.t[ix[rc]], st.g[ix[rc]], st.s[ix[rc]] = t[rc], g[cap], sn[cap]
    st.status[ix[rc]] = 1
    keep[rc] = False
    # a gap crossing here is at its contact: a residue of the other sign is rounding
    at = np.concatenate([np.where(cross[:, :2], np.maximum(d, 0.0), d), v], axis=1)
    rf = r[
        ok & ~cap & _leaves_free(mask[r], at, lanes.a[lanes_r], t[r] + H[r], st.horizon[lanes_r])
    ]
    st.t[ix[rf]], st.g[ix[rf]], st.s[ix[rf]] = t[rf], g[r.searchsorted(rf)], s[rf]
    st.code[ix[rf]], st.decided_by[ix[rf]] = OUTCOME_OF_MASK[0], 1
    keep[rf] = False


def _leaves_free(mask, g, a, t_next, T):
    """Lanes (n,) that enter free flight (FF, ``d'' = -a``) at an event with both gaps open or
    opening (``d_i >= 0``, ``d_i' >= 0``, not both zero) and accelerating away (``-a_i > 0``):
    no event can follow, and the exact simulator declares them settled at its next sub-step
    (before ``t_next``, within the horizon ``T``), whatever limit the gaps reach later."""
    d, v = g[:, :2], g[:, 2:]
    away = (d >= 0) & (v >= 0) & ((d > 0) | (v > 0)) & (-a > 0)
    return (mask == 0) & away[:, 0] & away[:, 1] & (t_next < T)


# ----------------------------------------------------------------------------- outcomes


def _impact_log(st: State):
    """Impacts per lane: ``{lane: (t, speed, contact)}`` in time order."""
    if not st.imp:
        return {}
    lane, t, v, c = (np.concatenate(x) for x in zip(*st.imp, strict=True))
    order = np.lexsort((t, lane))
    lane, t, v, c = lane[order], t[order], v[order], c[order]
    cuts = eb.rows(np.diff(lane)) + 1
    starts = np.concatenate([[0], cuts])
    return {int(lane[a]): (t[a:b], v[a:b], c[a:b])
            for a, b in zip(starts, np.append(cuts, lane.size), strict=True)}  # fmt: skip


def _stats(st: State, n, sysm, log, width) -> TrajectoryStats:
    """:class:`atlas.dynamics.TrajectoryStats` of lane ``n`` (a run that stopped undecided)."""
    T = float(st.t[n])
    g = st.g[n]
    t_ev, v_ev, c_ev = log.get(n, (np.zeros(0), np.zeros(0), np.zeros(0, int)))
    states = np.zeros((t_ev.size, 4))
    states[np.arange(t_ev.size), c_ev + 1] = v_ev
    mode = MODE_NAMES[int(mask_of(st.s[n : n + 1])[0])]
    t_imp, v_imp, c_imp = impacts(sysm, mode, g, T, ["impact"] * t_ev.size, t_ev, c_ev, states)
    nb = st.amp.shape[1]
    starts = np.arange(nb) * width
    late = (starts + width > 2 * T / 3) & (starts < T)
    amp = st.amp[n, late].max(axis=0) if late.any() else np.abs(g[:2])
    return TrajectoryStats(
        t_final=T, status=_STATUS[int(st.status[n])], mode_final=mode, g_final=g,
        scale=float(st.scale[n]), last_event=float(st.last_event[n]), t_imp=t_imp, v_imp=v_imp,
        c_imp=c_imp, late_amplitude=amp,
    )  # fmt: skip


def _classify_many(st: State, tables, n, width) -> np.ndarray:
    """:func:`atlas.dynamics.classify_stats` (default thresholds) of the stopped lanes ``n``
    (statuses ``t_end``, ``event_cap``, ``diverged``), the same tests in the same order on arrays:
    :func:`_stats` and :func:`atlas.dynamics.modal_form.light_system` give the per-lane form of the same inputs."""
    m = n.size
    out = np.full(m, int(Outcome.UNDETERMINED), dtype=np.int8)
    if m == 0:
        return out
    T, g, status, scale = st.t[n], st.g[n], st.status[n], st.scale[n]
    last = st.last_event[n]
    mask = mask_of(st.s[n])
    E = stack_table(tables, "E", n, mask)
    z1 = np.concatenate([g, np.ones((m, 1))], axis=1)
    acc = np.einsum("nij,nj->ni", E[:, 2:4], z1)
    act = np.stack([mask & 1, mask >> 1 & 1], axis=1).astype(bool)
    done = np.zeros(m, dtype=bool)

    def decide(sel, code):
        sel = sel & ~done
        out[sel] = code[sel] if np.ndim(code) else code
        done[sel] = True

    diverged, t_end, cap = status == 2, status == 0, status == 1
    iwc = diverged & (mask > 0)
    r = eb.rows(iwc)
    iwc[r] = iwc_aligned_many(E[r], z_eq(tables, n[r], mask[r]), mask[r], g[r], 1e-2,
                              eig_rows(tables.eig, n[r]))  # fmt: skip
    decide(iwc, int(Outcome.IWC))
    # settled at t_end (or diverged) with no event in the second half: neutral or stable mode,
    # free gaps leaving (classification._free_gaps_leaving)
    lam = stack_table(tables, "lam", n, mask)
    valid = stack_table(tables, "valid", n, mask)
    lmax = np.where(valid, np.abs(lam), 0.0).max(axis=1)
    neutral_or_stable = np.all(~valid | (lam.real <= 1e-9 * lmax[:, None]), axis=1)
    d_eq = stack_table(tables, "d_eq", n, mask)
    z = z1.copy()
    z[:, :2] = np.where(act, d_eq, z[:, :2])
    z[:, 2:4] = np.where(act, 0.0, z[:, 2:4])
    acc_eq = np.einsum("nij,nj->ni", E[:, 2:4], z)
    leaving = np.all(act | ((g[:, :2] > 0) & (g[:, 2:] >= 0) & (acc_eq > 0)), axis=1)
    leaving &= np.all(~act | np.isfinite(d_eq), axis=1)  # no equilibrium (singular B_SS K_S)
    settle = (t_end | diverged) & (last <= 0.5 * T) & neutral_or_stable & leaving
    decide(settle, np.array([OUTCOME_OF_MASK[x] for x in range(4)], dtype=np.int8)[mask])
    # impacts: the logged ones, and a gap in free flight (FF) falling back, dated T
    fly = (mask == 0)[:, None] & (g[:, :2] > 0) & (acc < 0)
    fr, fc = np.nonzero(fly)
    v_fly = np.sqrt(g[fr, fc + 2] ** 2 + 2 * np.abs(acc[fr, fc]) * g[fr, fc])
    count, n_mid, n_late, m2, m3, t_first, t_last, bouncing = st.impact_stats(n, fr, fc, v_fly)
    in_flight = np.any(~act & (acc < 0), axis=1)
    decide(diverged & (count >= 3) & ((last >= 0.8 * T) | in_flight),
           int(Outcome.GROWING_BOUNCING))  # fmt: skip
    decide(diverged | (count < 6), int(Outcome.UNDETERMINED))
    decide((n_mid == 0) | (n_late == 0), int(Outcome.UNDETERMINED))
    decide(m3 > 1.25 * m2, int(Outcome.GROWING_BOUNCING))
    amp = _late_amplitude(st, n, width)
    big = np.where(bouncing, amp, -np.inf).max(axis=1) > 10.0 * scale
    decide(big, int(Outcome.GROWING_BOUNCING))
    spread = t_end | (cap & (t_last - t_first > 0.5 * T))
    decide((m3 >= m2 / 1.25) & (t_last >= 0.9 * T) & spread, int(Outcome.SUSTAINED_OSCILLATION))
    return out


def _impacts_of(st: State, n):
    """Logged impacts ``(lane, t, speed, contact)`` of the lanes ``n``."""
    if not st.imp:
        return np.zeros(0, int), np.zeros(0), np.zeros(0), np.zeros(0, int)
    lane, t, v, c = (np.concatenate(x) for x in zip(*st.imp, strict=True))
    st.imp[:] = [(lane, t, v, c)]
    sel = np.isin(lane, n)
    return lane[sel], t[sel], v[sel], c[sel]


def _late_amplitude(st: State, n, width):
    """``max |d_i|`` (n, 2) over the bins overlapping ``[2T/3, T]`` (``|d(T)|`` if none)."""
    T = st.t[n][:, None]
    starts = np.arange(st.amp.shape[1])[None, :] * width
    late = (starts + width > 2 * T / 3) & (starts < T)
    amp = np.where(late[:, :, None], st.amp[n], -np.inf).max(axis=1)
    return np.where(late.any(axis=1)[:, None], amp, np.abs(st.g[n, :2]))


@dataclasses.dataclass
class FastResult:
    """Outcome per trajectory of :func:`run_batch`: ``code`` (int8, :class:`Outcome`),
    ``decided_by`` (int8 index into :data:`DECIDED_BY`), ``t_final`` (time reached or decided
    at), ``g_final`` (N, 4) the state there, ``n_events``, ``steps`` (steps of the engine's
    batch the lane took part in; 0 for another stepper) and ``within_rounding`` (a divergence
    whose verdict sits within rounding, :func:`stop_rule.within_rounding`, of the engine that
    decided it: :func:`stop_rule.run_within_rounding` for the exact simulator's runs), ``stop``
    (int8 index into :data:`STOPS`, why the run stopped; -1: decided early, with no stop).  A
    fallback lane has the exact simulator's stop, time, state and events (``steps``: the
    engine's before it handed the lane over)."""

    code: np.ndarray
    decided_by: np.ndarray
    t_final: np.ndarray
    g_final: np.ndarray
    n_events: np.ndarray
    steps: np.ndarray
    within_rounding: np.ndarray
    stop: np.ndarray

    @classmethod
    def gather(cls, parts, n: int) -> FastResult:
        """One result of ``n`` lanes from ``[(lane indices, FastResult), ...]``."""
        fields = [f.name for f in dataclasses.fields(cls)]
        out = {}
        for name in fields:
            first = getattr(parts[0][1], name)
            out[name] = np.empty((n,) + first.shape[1:], dtype=first.dtype)
            for idx, res in parts:
                out[name][idx] = getattr(res, name)
        return cls(**out)


def run_batch(beta1, beta2, alpha, k, q, g0, *, t_end=150.0, horizon_cap=8.0, max_events=2000,
              reference=None, pool=None, rounds=None) -> FastResult:  # fmt: skip
    """Outcomes of ``N`` trajectories (parameters broadcast to ``(N,)``, ``g0`` (N, 4)) with the
    classification and horizon extension of :func:`atlas.dynamics.simulate_outcome`.

    ``reference(beta1, beta2, alpha, k=, q=, g0=)`` runs one trajectory with the exact simulator
    for the fallback lanes: :func:`atlas.dynamics.simulate_outcome` with the same ``t_end``,
    ``horizon_cap`` and ``max_events`` (returns ``(Outcome, result)``).  ``pool``: a
    :class:`atlas.dynamics.lane_pool.LanePool` that runs the lanes on several processes (the same
    result bit for bit; the fallback lanes run here).  ``rounds``: see :func:`run_lanes`.
    """
    g0 = np.asarray(g0, dtype=float).reshape(-1, 4)
    n = g0.shape[0]
    if any(np.size(x) not in (1, n) for x in (beta1, beta2, alpha)):
        raise ValueError(f"g0 must have one row per trajectory, got {n}")
    b1, b2, al = (np.broadcast_to(np.asarray(x, dtype=float).ravel(), (n,)).copy()
                  for x in (beta1, beta2, alpha))  # fmt: skip
    kk = np.broadcast_to(np.asarray(k, dtype=float), (n, 2)).copy()
    qq = np.broadcast_to(np.asarray(q, dtype=float), (n, 2)).copy()
    opts = dict(t_end=t_end, horizon_cap=horizon_cap, max_events=max_events, rounds=rounds)
    arrays = (b1, b2, al, kk, qq, g0)
    if pool is None:
        res = run_lanes(*arrays, **opts)
    else:
        res = FastResult.gather(pool.map(run_lanes, arrays, opts), n)
    for i in eb.rows(res.decided_by == 3):
        out, run = reference(b1[i], b2[i], al[i], k=tuple(kk[i]), q=tuple(qq[i]), g0=g0[i])
        res.code[i] = int(out)
        res.within_rounding[i] = stop_rule.run_within_rounding(run)
        res.stop[i], res.n_events[i] = STOPS.index(run.status), run.n_events
        res.t_final[i], res.g_final[i] = run.t_final, run.g_final
    return res


def run_lanes(beta1, beta2, alpha, k, q, g0, *, t_end=150.0, horizon_cap=8.0, max_events=2000,
              rounds=None) -> FastResult:  # fmt: skip
    """:func:`run_batch` without the exact simulator: the lanes it would run have
    ``decided_by`` ``fallback`` and ``code`` -1 (parameters ``(N,)``, ``k``, ``q`` (N, 2)).

    ``rounds``: ``(start, run_round)``, the state's constructor and a stepper run on the lanes
    ``ix`` until each stops (``run_round(lanes, tables, st, ix, t_max, max_events, width,
    fallback)``), after which the stopped lanes are classified and those given a longer horizon
    run again (:func:`_classify_stopped`); how :mod:`atlas.dynamics.jax_engine` runs its kernel.
    Default: this module's stepping, where those lanes rejoin the running batch
    (:func:`_run_lanes`)."""
    lanes = Lanes.of(beta1, beta2, alpha, k, q)
    if lanes.a.shape[0] != g0.shape[0]:
        raise ValueError(f"g0 must have one row per trajectory, got {g0.shape[0]}")
    tables = modal_tables(lanes)
    width = t_end / 3.0
    nbins = int(math.ceil(3 * horizon_cap)) + 1
    start, run_round = rounds or (State.start, None)
    st = start(lanes, g0, t_end, nbins)
    fallback = np.zeros(g0.shape[0], dtype=bool)
    t_max = horizon_cap * t_end
    with np.errstate(all="ignore"):
        if rounds is None:
            _run_lanes(lanes, tables, st, t_max, max_events, width, fallback)
        else:
            ix = np.arange(g0.shape[0])
            while ix.size:
                run_round(lanes, tables, st, ix, t_max, max_events, width, fallback)
                ix = ix[(st.status[ix] != RUNNING) & ~fallback[ix]]
                ix = _classify_stopped(st, tables, ix, width, t_max, fallback)
    st.code[fallback] = -1
    st.decided_by[fallback] = 3
    stop = np.where(st.status >= 0, st.status, -1).astype(np.int8)
    stop[fallback] = -1  # until the exact simulator has run the lane (run_batch)
    return FastResult(
        st.code, st.decided_by, st.t, st.g, st.n_events, st.steps, st.rounding & ~fallback, stop
    )


def outcomes(b1, b2, alpha, k, q, g0, reference, *, t_end=150.0, horizon_cap=8.0,
             max_events=2000):  # fmt: skip
    """Outcome codes ``(n1, n2, n_perturb)`` of :func:`atlas.dynamics.outcome_map` (fast engine)
    and the :class:`FastResult` of all runs (flattened)."""
    n1, n2, npert = g0.shape[:3]
    B1 = np.broadcast_to(np.asarray(b1, dtype=float)[:, None, None], (n1, n2, npert))
    B2 = np.broadcast_to(np.asarray(b2, dtype=float)[None, :, None], (n1, n2, npert))
    res = run_batch(B1.ravel(), B2.ravel(), alpha, k, q, g0.reshape(-1, 4), t_end=t_end,
                    horizon_cap=horizon_cap, max_events=max_events, reference=reference)  # fmt: skip
    return res.code.reshape(n1, n2, npert), res
