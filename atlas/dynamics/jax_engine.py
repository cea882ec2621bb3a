"""The event-to-event outcome engine of :mod:`atlas.dynamics.fast_engine` as a JAX kernel (paper
Sec. 4.1, eqs. 1, 6-8), ready for an accelerator.

The algorithm is :mod:`atlas.dynamics.fast_engine`'s, step for step, written with the same
functions: every piece that acts on arrays (segments in closed form, certified brackets
:mod:`atlas.dynamics.event_bounds`, the safeguarded Newton root location, the early-decision
certificates, the stop rule's tests and limit brackets :mod:`atlas.dynamics.stop_rule`, the sign
switch at an event) serves both engines (NumPy or
JAX arrays, :func:`atlas.dynamics.event_bounds.xp_of`).  What differs is only the batching:

* Per lane a :func:`jax.lax.while_loop` from event to event (:func:`_step`), ``vmap``-ped over the
  lanes and ``jit``-compiled once per batch size.  Everything inside is fixed-size: the root
  location takes its ``ROOT_ITER`` evaluations, the bisection of the IWC stop its 64 halvings, the
  closed form of a new segment is evaluated in all four configurations and selected; the step
  window (:func:`window`) and the cancellation test (:func:`cancels`) are the NumPy engine's on
  either kind of array.
* The modal forms (``numpy.linalg.eig`` of each configuration, its inverse, equilibria, step caps;
  :func:`atlas.dynamics.modal_form.modal_tables`) are computed on the host once per trajectory
  and passed in as arrays (``jnp.linalg.eig`` exists only on CPU).  The alignment test of the stop
  rule (an active gap past the penetration limit, aligned with an unstable eigenvector) expands
  the state in these eigenvectors (``W x`` instead of the reference's ``solve(V, x)``: the same
  test on the same basis, rounding aside).
* The stop rule (:mod:`atlas.dynamics.stop_rule`) is tested at every step end and just before
  every event in the kernel, its amplitude and deep-penetration limits bracketed like events
  (:func:`atlas.dynamics.stop_rule.limit_steps`); a lane where it holds leaves the kernel with the
  bracket of its last step, and the host locates the stop in it
  (:func:`atlas.dynamics.stop_location.locate_stops`, :func:`atlas.dynamics.stop_rule.locate`), as
  the NumPy engine does: both stop at the same time for the same reason.
* Lanes that finish leave the batch between kernel calls of at most ``steps`` steps each (the host
  gathers the running lanes into the next call), so the slowest trajectory does not set the cost
  of all.
* Impacts are kept as per-bin statistics (bins of ``t_end / 3``: count, largest speed, contacts),
  which give :func:`atlas.dynamics.classify`'s thirds exactly for runs stopped at their horizon
  (``t_end 2^j``, always a bin boundary).  Runs that reach the event cap stop at an arbitrary time:
  they are run by the exact simulator on the host, as are the fallback lanes of the NumPy engine
  (near-singular modal forms, cancelling segments, a stalled root location) and the degenerate
  directions the NumPy engine serves in closed form (:func:`atlas.dynamics.modal_form.closed_segment`;
  ``ok`` False).

Classification of the stopped runs and the horizon extension are the NumPy engine's
(:func:`atlas.dynamics.fast_engine.run_batch`, on the host; a divergence within rounding,
:func:`atlas.dynamics.stop_rule.within_rounding`, is flagged the same way).

The steps, stops and early decisions are the NumPy engine's; what differs is only who runs a lane
(the event cap and the closed forms above: the exact simulator) and rounding (XLA's ``exp`` and
NumPy's differ in the last bits; the alignment's ``W x``).

Behind ``atlas simulate --engine jax``.  Outcomes and the way each run is decided equal the NumPy
engine's run by run, and its stop times the exact simulator's to ``1e-9`` relative; a verdict
that rounding can still move is one that :func:`atlas.dynamics.stop_rule.within_rounding` flags
(a gap at ``9e-15`` against ``-6e-16`` in the exact simulator when a stop coincides with an
event).  On a 2-core CPU the NumPy engine stays the default (``--engine fast``): after 75-85 s of
compilation (three batch sizes, loaded) the kernel ran 2.8x (64^2) to 6.8x (128^2) slower in the
same run, since every lane of a batch does each step's whole work where NumPy does each piece
only for the lanes that need it; the kernel is for accelerators.  Measured on one call of 64
steps x 512 lanes (CPU, ~23 us per lane and step, before the located stops): the early-decision
tests take ~40 % of it, the closed forms of the next segment in all four configurations ~35 %,
the root location ~4 %.
"""

from __future__ import annotations

import dataclasses
import functools

import jax
import jax.numpy as jnp
import numpy as np

from atlas.dynamics import early_decisions as early
from atlas.dynamics import event_bounds as eb
from atlas.dynamics import fast_engine as fe
from atlas.dynamics import modal_form as mf
from atlas.dynamics import step_windows as sw
from atlas.dynamics import stop_location as sl
from atlas.dynamics import stop_rule
from atlas.dynamics.system import Outcome, aligned_in_basis

__all__ = ["run_batch", "kernel", "STEPS", "CHUNK", "NBINS"]

#: kernel steps per call; lanes that finish leave the batch between calls
STEPS = 64
#: bins of the impact and amplitude statistics in a kernel call (at least; ``horizon_cap <= 10``)
NBINS = 32
#: largest batch of one kernel call (fewer running lanes go in batches of 512 or 64)
CHUNK = 4096

_OUTCOME_OF_MASK = np.array([fe.OUTCOME_OF_MASK[m] for m in range(4)], dtype=np.int8)


def _pick(table, mask):
    """Entry ``mask`` (n,) of a per-configuration ``table`` (n, 4, ...)."""
    return table[jnp.arange(mask.shape[0]), mask]


def _select(values, mask):
    """``values[mask]`` of four per-configuration arrays (n, ...)."""
    return _pick(jnp.stack(values, axis=1), mask)


def _aligned_now(mask, g, prm, tol):
    """:func:`atlas.dynamics.system.iwc_aligned_many` of the states ``g`` (n, 4) on the modal
    tables (n,)."""
    out = []
    for m in (1, 2, 3):
        idx = [i for i in range(2) if m >> i & 1]
        sub = idx + [i + 2 for i in idx]
        signs = jnp.all(g[:, sub] < 0, axis=1)
        for i in (i for i in range(2) if not m >> i & 1):
            signs &= (g[:, i] >= 0) & (g[:, i + 2] >= 0)
        x, c = mf.modal_coords(m, g, prm["d_eq"][:, m], prm[f"W{m}"])
        lam = prm["lam"][:, m, : 2 * len(idx)]
        out.append(signs & aligned_in_basis(lam, prm[f"V{m}"], c, x, len(idx), tol))
    return _select([jnp.zeros_like(out[0])] + out, mask)


def _coords(mask, g, prm):
    """:func:`atlas.dynamics.modal_form.modal_coordinates` (n, 4) on the modal tables."""
    out = [jnp.zeros((g.shape[0], 4), dtype=complex)]
    for m in (1, 2, 3):
        c = mf.modal_coords(m, g, prm["d_eq"][:, m], prm[f"W{m}"])[1]
        out.append(jnp.concatenate([c, jnp.zeros((g.shape[0], 4 - c.shape[1]), complex)], 1))
    return _select(out, mask)


def _segments(g, prm):
    """Closed form ``(P, U)`` of segments from ``g`` (n, 4) in each of the four configurations."""
    out = []
    for m in range(4):
        V, W = (prm[f"V{m}"], prm[f"W{m}"]) if m else (None, None)
        out.append(mf.segment(m, g, prm["d_eq"][:, m], V, W, prm["lam"][:, m], prm["B"],
                               prm["a"], prm["k"], prm["q"]))  # fmt: skip
    return [o[0] for o in out], [o[1] for o in out]


def _bin_max(arr, b, value, on):
    """``arr[:, b] = max(arr[:, b], value)`` where ``on`` (n,)."""
    rows = jnp.arange(arr.shape[0])
    cur = arr[rows, b]
    on = on.reshape(on.shape + (1,) * (cur.ndim - 1))
    return arr.at[rows, b].set(jnp.where(on, jnp.maximum(cur, value), cur))


def _step(c, prm):
    """One step of :func:`atlas.dynamics.fast_engine._run_lanes` for the running lanes of
    ``c`` (the same tests in the same order)."""
    run, t, s, since, T = c["run"], c["t"], c["s"], c["since"], prm["T"]
    t_max, width, nbins = (prm[x] for x in ("t_max", "width", "nbins"))
    k, q, scale = prm["k"], prm["q"], prm["scale"]
    mask = fe.mask_of(s)
    lam, valid, H = _pick(prm["lam"], mask), _pick(prm["valid"], mask), _pick(prm["H"], mask)
    P, U, tseg = c["P"], c["U"], c["tseg"]
    d, v, acc, p, UE = eb.evaluate(P, U, lam, t - tseg)
    g = jnp.concatenate([d, v], axis=1)
    act = jnp.stack([mask & 1, mask >> 1 & 1], axis=1).astype(bool)
    # the stop rule at the step end (located inside the step on the host: _locate), the horizon
    div = run & _stops(mask, g, prm)
    keep = run & ~div
    amp = _bin_max(c["amp"], eb.bins(t, width, nbins), jnp.abs(d), keep)
    status = jnp.where(div, 2, jnp.where(keep & (t >= T), 0, c["status"]))
    keep &= t < T
    sched = ((since & (since - 1)) == 0) & (since > 0)
    lo, hi, mon, M, Hw = _brackets(d, v, acc, p, UE, lam, valid, H, k, q, s, act, scale)
    # early decisions
    tryd = keep & sched & jnp.all(hi > (t_max - t)[:, None], axis=1)
    tryd &= early.may_decide(lam, valid, s, p, act, mask, t, T)
    settle, iwc = _decisions(t, T, t_max, s, mask, g, p, UE, lam, valid, k, q, scale, act, H, prm)
    settle &= tryd
    iwc &= tryd & ~settle
    code = jnp.where(settle, jnp.asarray(_OUTCOME_OF_MASK)[mask], c["code"])
    code = jnp.where(iwc, np.int8(Outcome.IWC), code)
    decided_by = jnp.where(settle, 1, jnp.where(iwc, 2, c["decided_by"])).astype(np.int8)
    keep &= ~(settle | iwc)
    rem = T - t
    xtol = fe.XTOL * H
    ev, h, m, lo, hi = _first_crossing(lo, hi, mon, keep, rem, xtol, P, U, lam, t - tseg, s, k, q)
    # a limit of the stop rule passed before the first crossing: step past it (certified)
    lim_lo, lim_hi = stop_rule.limit_steps(d, v, M, scale, Hw)
    ev &= h <= lim_lo
    past = keep & ~ev & (lim_hi <= jnp.minimum(m, rem))
    step = jnp.where(ev, h, jnp.minimum(jnp.minimum(jnp.minimum(m, Hw), rem), lim_lo))
    step = jnp.where(past, jnp.maximum(lim_hi, xtol), step)
    t_new = jnp.where(keep, t + step, t)
    # stalled root location (a grazing contact): the exact simulator takes over
    stall = jnp.where(step < 1e-9 * H, c["stall"] + 1, 0)
    fallback = c["fallback"] | (keep & (stall > fe.STALL))
    keep &= ~fallback
    ev &= keep
    # the stop rule just before the events (in the configuration up to them)
    d2, v2, acc2, _, _ = eb.evaluate(P, U, lam, t_new - tseg)
    g2 = jnp.concatenate([d2, v2], axis=1)
    div2 = ev & _stops(mask, g2, prm)
    ev &= ~div2
    out = _events(c, prm, ev, lo, hi, h, xtol, t_new, s, d2, v2, acc2, amp, fallback)
    out.update({
        "run": keep & ~div2 & ~out["fallback"], "t": t_new,
        "t0": jnp.where(run & ~div, t, c["t0"]),
        "g": jnp.where(run[:, None], jnp.where(div2[:, None], g2, g), c["g"]),
        "since": jnp.where(ev, 0, since + 1), "stall": stall,
        "status": jnp.where(div2, 2, status), "code": code, "decided_by": decided_by,
    })  # fmt: skip
    return out


def _events(c, prm, ev, lo, hi, h, xtol, t_new, s, d2, v2, acc2, amp, fallback):
    """The lanes ``ev`` switch at their events at ``t_new`` (gaps, velocities, accelerations
    ``d2, v2, acc2`` there, pre-event signs ``s``): impacts binned, new segment; as
    :func:`atlas.dynamics.fast_engine._events`.  Returns the entries of the carry it changes."""
    k, q, scale, width, nbins = (prm[x] for x in ("k", "q", "scale", "width", "nbins"))
    f2, fp2 = eb.event_functions(d2, v2, acc2, k, q)
    tol = (h + 1e3 * xtol)[:, None]
    sn, closing, n_ev = fe.switch(s, (hi <= tol) & (lo <= tol), f2, fp2, k, scale)
    closing &= ev[:, None]
    hit = closing.any(axis=1)
    ib = jnp.clip(jnp.floor(t_new / width).astype(int), 0, nbins - 1)
    rows = jnp.arange(t_new.shape[0])
    n_events = c["n_events"] + jnp.where(ev, n_ev, 0)
    s_new = jnp.where(ev[:, None], sn, s)
    mask_new = fe.mask_of(s_new)
    g2 = jnp.concatenate([d2, v2], axis=1)
    Ps, Us = _segments(g2, prm)
    P_new, U_new = _select(Ps, mask_new), _select(Us, mask_new)
    ok = _pick(prm["ok"], mask_new) & ~cancels(P_new, U_new, g2, scale)
    # event-cap runs stop at an arbitrary time (not a bin boundary): the exact simulator
    fallback = fallback | (ev & ~ok) | (ev & ok & (n_events >= prm["max_events"]))
    return {
        "s": s_new, "P": jnp.where(ev[:, None, None], P_new, c["P"]),
        "U": jnp.where(ev[:, None, None], U_new, c["U"]),
        "tseg": jnp.where(ev, t_new, c["tseg"]), "n_events": n_events,
        "last_event": jnp.where(ev & (n_ev > 0), t_new, c["last_event"]),
        "amp": _bin_max(amp, eb.bins(t_new, width, nbins), jnp.abs(d2), ev),
        "n_imp": c["n_imp"].at[rows, ib].add(closing.sum(axis=1)),
        "v_imp": _bin_max(c["v_imp"], ib, jnp.where(closing, jnp.abs(v2), -np.inf).max(axis=1),
                          hit),
        "c_imp": c["c_imp"].at[rows, ib].set(c["c_imp"][rows, ib] | closing),
        "t_first": jnp.where(hit, jnp.minimum(c["t_first"], t_new), c["t_first"]),
        "t_last": jnp.where(hit, jnp.maximum(c["t_last"], t_new), c["t_last"]),
        "fallback": fallback,
    }  # fmt: skip


def _stops(mask, g, prm):
    """:func:`atlas.dynamics.stop_rule.stopped` of the states ``g`` (n, 4) in the
    configurations ``mask`` (n,), the alignment on the modal tables (:func:`_aligned_now`)."""
    amp, pen = stop_rule.limits(prm["scale"])
    out, deep = stop_rule.beyond(g, mask, amp, pen)
    return out | (deep & _aligned_now(mask, g, prm, stop_rule.ALIGN_TOL))


def window(H, lam, valid, p, aUE, scale):
    """The JAX engine's step window (n): :func:`atlas.dynamics.step_windows.window` of ``WINDOWS
    H_S`` where the gaps stay small over it, else ``H_S`` (this engine samples no long step)."""
    w, small = sw.window(H, lam, valid, p, aUE, scale, sw.WINDOWS)
    return eb.xp_of(H, lam, p, aUE).where(small, w, H)


def cancels(P, U, g, scale):
    """:func:`atlas.dynamics.fast_engine.cancels` (bool (n,)) on NumPy or JAX arrays."""
    xp = eb.xp_of(P, U, g, scale)
    terms = xp.abs(P[:, :, 0]) + eb.sum4(xp.abs(U))
    size = xp.maximum(xp.abs(g[:, :2]).max(axis=1), scale)
    with np.errstate(invalid="ignore"):
        return ~(terms.max(axis=1) <= fe.CANCEL_MAX * size)


def _brackets(d, v, acc, p, UE, lam, valid, H, k, q, s, act, scale):
    """Certified brackets ``(lo, hi)`` (n, 4) of the next crossing of each monitored event
    function within the window ``Hw`` (:func:`window`), the monitored ones ``mon``, the
    curvature bound ``M`` and ``Hw`` (as :func:`atlas.dynamics.step_windows.brackets` within the short window)."""
    f, fp = eb.event_functions(d, v, acc, k, q)
    aUE = jnp.abs(UE)
    Hw = window(H, lam, valid, p, aUE, scale)
    A, Bd = jnp.maximum(s * f, 0.0), s * fp
    mon = jnp.concatenate([jnp.ones_like(act), s[:, :2] < 0], axis=1)
    lo, hi, M = sw.bounded(A, Bd, s, p, UE, lam, k, q, aUE, Hw, mon)
    return lo, hi, mon, M, Hw


def _decisions(t, T, t_max, s, mask, g, p, UE, lam, valid, k, q, scale, act, H, prm):
    """``(settle, iwc)`` (n,) of :func:`atlas.dynamics.early_decisions.decisions`, IWC as
    :func:`atlas.dynamics.fast_engine._decide` has it: aligned from now or from the reference's
    stop on, with the reference's sign conditions there (:func:`early.signs_from`)."""
    settle, iwc, l1 = early.decisions(t, T, t_max, s, mask, p, UE, lam, valid, k, q, scale, act, H)
    c = _coords(mask, g, prm)
    s0 = early.reach_time(p, UE, lam, T - t, scale)
    now = early.aligned_from(c, lam, valid, l1, jnp.zeros_like(t))
    iwc &= now | early.aligned_from(c, lam, valid, l1, s0)
    iwc &= early.signs_from(p, UE, lam, valid, l1, act, s, s0)
    return settle, iwc


def _first_crossing(lo, hi, mon, keep, rem, xtol, P, U, lam, tau, s, k, q):
    """``(ev, h, m, lo, hi)``: the rows with an event in the next step, its time, the smallest
    ``sigma_lo``, and the brackets with the one closed by :func:`locate_root` (and its twin's:
    the force of an undamped contact is ``-k_i`` times its gap) set to the event (as
    :func:`atlas.dynamics.fast_engine._first_crossing`)."""
    # smallest sigma_lo, ties to the tightest bracket
    m = lo.min(axis=1)
    tie_hi = jnp.where(lo <= m[:, None], hi, np.inf)
    first = jnp.where(jnp.isinf(tie_hi.min(axis=1)), jnp.argmin(lo, axis=1),
                      jnp.argmin(tie_hi, axis=1))  # fmt: skip
    col = jnp.arange(4)[None, :]
    one = col == first[:, None]
    twin = (col == ((first + 2) % 4)[:, None]) & (eb.take(q, first % 2) == 0)[:, None] & mon
    h = jnp.where(one, hi, 0.0).sum(axis=1)
    ev = keep & (h - m <= xtol) & (h <= rem)
    other = jnp.where(one | twin, np.inf, lo).min(axis=1)
    r = keep & ~ev & (h <= rem) & (other > h)
    lo_f, s_f = jnp.where(one, lo, 0.0).sum(axis=1), jnp.where(one, s, 0.0).sum(axis=1)
    a_r, b_r = fe.locate_root(P, U, lam, tau, jnp.where(r, lo_f, 0.0), jnp.where(r, h, 1.0),
                              first, s_f, k, q, xtol, fe.ROOT_ITER)  # fmt: skip
    done = r & (b_r - a_r <= xtol)
    h = jnp.where(done, b_r, h)
    m = jnp.where(r & ~done, a_r, m)
    closed = done[:, None] & (one | twin)
    lo = jnp.where(closed, h[:, None], lo)
    hi = jnp.where(closed, h[:, None], hi)
    return ev | done, h, m, lo, hi


def _lane(c, prm, steps):
    """Up to ``steps`` steps of one lane (arrays with a leading axis of 1)."""

    def cond(x):
        return x[0]["run"][0] & (x[1] < steps)

    def body(x):
        return _step(x[0], prm), x[1] + 1

    return jax.lax.while_loop(cond, body, (c, 0))[0]


@functools.partial(jax.jit, static_argnames=("steps",))
def kernel(c, prm, *, steps):
    """``steps`` steps of every lane of the batch ``c`` (dict of (n, 1, ...) arrays) with the
    per-lane parameters and modal tables ``prm`` (horizons, event cap and bins included, so one
    compilation serves every map of a batch size): :func:`_lane` ``vmap``-ped."""
    return jax.vmap(functools.partial(_lane, steps=steps))(c, prm)


@dataclasses.dataclass
class _BinnedState(fe.State):
    """:class:`atlas.dynamics.fast_engine.State` with the impacts per time bin of ``t_end / 3``:
    count ``n_imp``, largest speed ``v_imp`` (N, nbins), contacts ``c_imp`` (N, nbins, 2), first
    and last impact times."""

    n_imp: np.ndarray = None
    v_imp: np.ndarray = None
    c_imp: np.ndarray = None
    t_first: np.ndarray = None
    t_last: np.ndarray = None

    @classmethod
    def start(cls, lanes, g0, t_end, nbins):
        st = super().start(lanes, g0, t_end, nbins)
        n = g0.shape[0]
        st.n_imp, st.v_imp = np.zeros((n, nbins), int), np.full((n, nbins), -np.inf)
        st.c_imp = np.zeros((n, nbins, 2), dtype=bool)
        st.t_first, st.t_last = np.full(n, np.inf), np.full(n, -np.inf)
        st.width = t_end / 3.0
        return st

    def impact_stats(self, n, fr, fc, v_fly):
        """:func:`atlas.dynamics.fast_engine._impact_stats` from the bins: the thirds of ``T``
        are bins ``[j, 2j)`` and ``[2j, 3j]`` with ``j = T / t_end`` (a run stopped at its
        horizon; the other statistics are read only for diverged runs: the count)."""
        T = self.t[n]
        nb = self.n_imp.shape[1]
        j = np.rint(T / (3 * self.width)).astype(int)[:, None]
        col = np.arange(nb)[None, :]
        mid, late = (col >= j) & (col < 2 * j), (col >= 2 * j) & (col <= 3 * j)
        cnt, vmax, con = self.n_imp[n], self.v_imp[n], self.c_imp[n]
        n_mid, n_late = np.where(mid, cnt, 0).sum(1), np.where(late, cnt, 0).sum(1)
        m2 = np.where(mid, vmax, -np.inf).max(1)
        m3 = np.where(late, vmax, -np.inf).max(1)
        bouncing = (con & late[:, :, None]).any(axis=1)
        t_first, t_last, count = self.t_first[n].copy(), self.t_last[n].copy(), cnt.sum(1)
        # a gap in free flight falling back, dated T (in the last third)
        np.add.at(count, fr, 1)
        np.add.at(n_late, fr, 1)
        np.maximum.at(m3, fr, v_fly)
        np.minimum.at(t_first, fr, T[fr])
        np.maximum.at(t_last, fr, T[fr])
        bouncing[fr, fc] = True
        return count, n_mid, n_late, m2, m3, t_first, t_last, bouncing


def _bucket(n):
    """Batch size of the kernel calls for ``n`` running lanes: 64, 512 or :data:`CHUNK` (one
    compilation each, 20-30 s on a loaded 2-core machine); ``n`` is cut into batches of it."""
    return 64 if n <= 64 else 512 if n < CHUNK else CHUNK


def _run_round(lanes, tables, st, ix, t_max, max_events, width, fallback):
    """The stepping of :func:`atlas.dynamics.fast_engine._run_lanes` in :func:`kernel`: the
    lanes ``ix`` step until each is decided, stops or falls back; results written into ``st``
    (one round of :func:`atlas.dynamics.fast_engine.run_lanes`)."""
    nbins = st.amp.shape[1]
    mask = fe.mask_of(st.s[ix])
    P, U, _, _, _, ok = mf.segments(lanes, tables, ix, mask, st.g[ix])
    ok &= ~fe.cancels(P, U, st.g[ix], st.scale[ix])
    fallback[ix[~ok]] = True
    ix, P, U = ix[ok], P[ok], U[ok]
    n = ix.size
    if n == 0:
        return
    c = {
        "run": np.ones(n, bool), "t": st.t[ix], "g": st.g[ix], "s": st.s[ix], "P": P, "U": U,
        "tseg": st.t[ix], "t0": st.t[ix], "since": np.zeros(n, int), "stall": np.zeros(n, int),
        "n_events": st.n_events[ix], "last_event": st.last_event[ix], "amp": st.amp[ix],
        "n_imp": st.n_imp[ix], "v_imp": st.v_imp[ix], "c_imp": st.c_imp[ix],
        "t_first": st.t_first[ix], "t_last": st.t_last[ix], "status": np.full(n, fe.RUNNING),
        "code": st.code[ix], "decided_by": st.decided_by[ix], "fallback": np.zeros(n, bool),
    }  # fmt: skip
    prm = {
        "T": st.horizon[ix], "k": lanes.k[ix], "q": lanes.q[ix], "scale": st.scale[ix],
        "B": lanes.B[ix], "a": lanes.a[ix],
        "lam": np.stack([tab.lam[ix] for tab in tables], 1),
        "valid": np.stack([tab.valid[ix] for tab in tables], 1),
        "H": np.stack([tab.H[ix] for tab in tables], 1),
        "ok": np.stack([tab.ok[ix] for tab in tables], 1),
        "d_eq": np.nan_to_num(np.stack([tab.d_eq[ix] for tab in tables], 1)),
        **{f"{x}{m}": getattr(tables[m], x)[ix] for m in (1, 2, 3) for x in "VW"},
    }  # fmt: skip
    prm.update(t_max=np.full(n, float(t_max)), max_events=np.full(n, int(max_events)),
               width=np.full(n, float(width)), nbins=np.full(n, int(nbins)))  # fmt: skip
    # bin arrays padded to NBINS columns (the kernel clips to nbins): one compiled shape
    nb = max(NBINS, nbins)
    for key in ("amp", "n_imp", "v_imp", "c_imp"):
        x = c[key]
        fill = {"amp": 0.0, "n_imp": 0, "v_imp": -np.inf, "c_imp": False}[key]
        extra = np.full((n, nb - nbins) + x.shape[2:], fill, dtype=x.dtype)
        c[key] = np.concatenate([x, extra], axis=1)
    live = np.arange(n)
    while live.size:
        size = _bucket(live.size)
        for a in range(0, live.size, size):
            sel = live[a : a + size]
            pad = np.concatenate([sel, np.full(size - sel.size, sel[0])])
            ci = {key: x[pad][:, None] for key, x in c.items()}
            ci["run"][sel.size :] = False
            out = kernel(ci, {key: x[pad][:, None] for key, x in prm.items()}, steps=STEPS)
            for key, x in out.items():
                c[key][sel] = np.asarray(x)[: sel.size, 0]
        live = live[c["run"][live]]
    st.t[ix], st.g[ix], st.s[ix], st.status[ix] = c["t"], c["g"], c["s"], c["status"]
    st.code[ix], st.decided_by[ix] = c["code"], c["decided_by"]
    for key in ("n_events", "last_event", "t_first", "t_last"):
        getattr(st, key)[ix] = c[key]
    for key in ("amp", "n_imp", "v_imp", "c_imp"):
        getattr(st, key)[ix] = c[key][:, :nbins]
    fallback[ix[c["fallback"]]] = True
    _locate(st, tables, ix, c, prm, width)


def _locate(st, tables, ix, c, prm, width):
    """The stops of the lanes ``ix`` that diverged in the kernel, located inside their last
    step (from ``max(t0, tseg)`` to ``t`` on the segment from ``tseg``) by the NumPy engine's
    :func:`atlas.dynamics.stop_location.locate_stops` (:func:`atlas.dynamics.stop_rule.locate`):
    their time, state and amplitude into ``st``."""
    r = np.flatnonzero(c["status"] == 2)
    if r.size == 0:
        return
    mk = fe.mask_of(c["s"][r])
    tseg = c["tseg"][r]
    a = np.maximum(c["t0"][r], tseg) - tseg
    rec = (ix[r], mk, c["P"][r], c["U"][r], prm["lam"][r, mk], prm["scale"][r], a,
           c["t"][r] - tseg, fe.XTOL * prm["H"][r, mk], tseg)  # fmt: skip
    sl.locate_stops(st, tables, [rec], width)


def run_batch(beta1, beta2, alpha, k, q, g0, *, t_end=150.0, horizon_cap=8.0, max_events=2000,
              reference=None) -> fe.FastResult:  # fmt: skip
    """:func:`atlas.dynamics.fast_engine.run_batch` with the stepping in :func:`kernel` (the
    same arguments, result and classification)."""
    return fe.run_batch(beta1, beta2, alpha, k, q, g0, t_end=t_end, horizon_cap=horizon_cap,
                        max_events=max_events, reference=reference,
                        rounds=(_BinnedState.start, _run_round))  # fmt: skip
