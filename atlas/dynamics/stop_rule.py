"""The divergence stop of a run, one rule for both engines (:func:`atlas.dynamics.simulate` and
:mod:`atlas.dynamics.fast_engine`; paper Sec. 4.3 for the impact without collision).

A run stops as ``diverged`` at the first time ``t`` at which its state ``g(t)`` (in the
configuration active from ``t`` on, or the one active up to an event at ``t``) has

* a non-finite component, or a gap ``d_i > amplitude_limit`` (default ``1e4 scale``), or
* a gap ``d_i < -1e3 penetration_limit`` (default ``1e6 scale``), or
* an active gap ``d_i < -penetration_limit`` (default ``1e3 scale``) while the state is aligned
  with an IWC eigenvector (:func:`atlas.dynamics.system.iwc_aligned`, tolerance ``ALIGN_TOL``).

The engines test :func:`stopped` at the ends of their steps and at their events; where it holds at
the end of a step and not at its start, :func:`locate` searches the step on the closed-form
solution to the first time it holds (to ``xtol``), so both engines stop at the same time (within
``xtol``) for the same reason whatever their steps.  A crossing of the amplitude or the deep
penetration limit that is undone inside one step (a peak) is found by each engine's own bracket
of the shifted gaps ``d_i - amplitude_limit``, ``-d_i - 1e3 penetration_limit``
(:func:`limit_rows`)."""

from __future__ import annotations

import numpy as np

from atlas.dynamics.event_bounds import safe_steps, xp_of
from atlas.dynamics.system import MODE_NAMES, Status, eig_rows, iwc_aligned_many

__all__ = ["AMPLITUDE", "PENETRATION", "DEEP", "ALIGN_TOL", "ROUNDING_SHARE", "limits",
           "limit_rows", "limit_steps", "beyond", "stopped", "within_rounding", "run_within_rounding", "locate"]  # fmt: skip

#: default limits relative to the run's length scale: amplitude, aligned penetration
AMPLITUDE, PENETRATION = 1e4, 1e3
#: the penetration that stops a run whatever its alignment, times the penetration limit
DEEP = 1e3
#: alignment tolerance of the aligned-penetration stop (the classification uses 1e-2)
ALIGN_TOL = 1e-3
#: share of a state's largest gap (velocity) within which the sign of a gap (velocity) is a
#: rounding residue of the run (:func:`within_rounding`)
ROUNDING_SHARE = 1e-9
#: search rounds of :func:`locate` at most (each divides the bracket by ``SPLIT``)
MAX_ROUNDS = 40


def limits(scale):
    """``(amplitude_limit, penetration_limit)`` of a run of length scale ``scale`` [1]."""
    return AMPLITUDE * scale, PENETRATION * scale


def limit_rows(amp, pen):
    """Rows ``R`` (4, 5) of the shifted gaps on the augmented state ``z = (d, d', 1)``: ``R z``
    is ``d_i - amp`` (rows 0, 1) and ``-d_i - DEEP pen`` (rows 2, 3), all negative inside the
    limits."""
    R = np.zeros((4, 5))
    R[[0, 1], [0, 1]] = 1.0
    R[[2, 3], [0, 1]] = -1.0
    R[:2, 4] = -amp
    R[2:, 4] = -DEEP * pen
    return R


def limit_steps(d, v, M, scale, Hw):
    """``(sigma_lo, sigma_hi)`` (n,) of the limits of the stop rule on the gaps ``d`` (n, 2)
    with velocities ``v`` and curvature bounds ``M`` (n, >= 2) of the gaps over the window ``Hw``
    (n,) (amplitude, deep penetration; the rows of :func:`limit_rows`, bracketed as events by
    :func:`atlas.dynamics.event_bounds.safe_steps`): no gap passes one before ``sigma_lo``, one
    has passed by ``sigma_hi`` (``inf`` beyond ``Hw``); both ``inf`` where the bound cannot
    reach a limit within ``Hw``.  NumPy or JAX arrays."""
    xp = xp_of(d, v, M, scale, Hw)
    amp, pen = limits(scale)
    w = Hw[:, None]
    reach = xp.abs(d) + w * (xp.abs(v) + 0.5 * w * M[:, :2])
    near = (reach >= xp.minimum(amp, DEEP * pen)[:, None]).any(axis=1)
    A = xp.concatenate([amp[:, None] - d, d + DEEP * pen[:, None]], axis=1)
    Bd = xp.concatenate([-v, v], axis=1)
    lo4, hi4 = safe_steps(xp.maximum(A, 0.0), Bd, xp.concatenate([M[:, :2], M[:, :2]], axis=1))
    hi4 = xp.where(hi4 <= w, hi4, np.inf)
    lo = xp.minimum(xp.minimum(lo4[:, 0], lo4[:, 1]), xp.minimum(lo4[:, 2], lo4[:, 3]))
    hi = xp.minimum(xp.minimum(hi4[:, 0], hi4[:, 1]), xp.minimum(hi4[:, 2], hi4[:, 3]))
    return xp.where(near, lo, np.inf), xp.where(near, hi, np.inf)


def beyond(g, mask, amp, pen):
    """The stop rule without its alignment test (bool (n,)): a non-finite component, a gap past
    the amplitude or the deep-penetration limit, or an active gap past the penetration limit; a
    necessary condition of :func:`stopped`, and ``(stop, penetrated)`` where it is sufficient
    (NumPy or JAX arrays)."""
    xp = xp_of(g, mask, amp, pen)
    g = xp.asarray(g, dtype=float)
    mask = xp.asarray(mask, dtype=int)
    amp, pen = xp.broadcast_to(amp, mask.shape), xp.broadcast_to(pen, mask.shape)
    out = ~xp.isfinite(g).all(axis=1)
    with np.errstate(invalid="ignore"):
        out |= xp.max(g[:, :2], axis=1) > amp
        out |= xp.min(g[:, :2], axis=1) < -DEEP * pen
        act = xp.stack([mask & 1, mask >> 1 & 1], axis=1).astype(bool)
        pen_ = ~out & (act & (g[:, :2] < -pen[:, None])).any(axis=1)
    return out, pen_


def stopped(g, mask, E, z_eq, amp, pen, eig=None, rows=None):
    """The stop rule at the states ``g`` (n, 4) in configurations ``mask`` (n,) (augmented
    matrices ``E`` (n, 5, 5), equilibria ``z_eq`` (n, 5), NaN where none), limits ``amp``, ``pen``
    (n,); ``eig`` as in :func:`atlas.dynamics.system.iwc_aligned_many`; bool (n,).  ``rows``
    (n,), if given: the states' rows of ``E``, ``z_eq`` and ``eig`` (gathered only where the
    alignment is tested)."""
    out, deep = beyond(g, mask, amp, pen)
    r = np.flatnonzero(deep)
    if r.size:
        e = r if rows is None else rows[r]
        out[r] = iwc_aligned_many(E[e], z_eq[e], np.asarray(mask)[r], np.asarray(g)[r], ALIGN_TOL,
                                  eig_rows(eig, e))  # fmt: skip
    return out


def within_rounding(g, mask, E, z_eq, tol=1e-2, eig=None):
    """Divergence stops (bool (n,)) at the states ``g`` (n, 4) in configurations ``mask`` (n,)
    (augmented matrices ``E`` (n, 5, 5), equilibria ``z_eq`` (n, 5)) whose verdict sits within
    rounding: the IWC test of the classification (:func:`atlas.dynamics.system.iwc_aligned`,
    tolerance ``tol``; paper Sec. 4.3) changes when the gaps and velocities within
    ``ROUNDING_SHARE`` of the state's largest gap or velocity take either sign (a digit neither
    engine keeps: e.g. a free gap of ``47`` or ``-3e-4`` beside an active one at ``-7e20``).
    ``eig`` as in :func:`atlas.dynamics.system.iwc_aligned_many`."""
    g = np.asarray(g, dtype=float)
    mask = np.asarray(mask, dtype=int)
    out = np.zeros(mask.shape[0], dtype=bool)
    with np.errstate(invalid="ignore"):
        size = np.repeat(np.abs(g).reshape(-1, 2, 2).max(axis=2), 2, axis=1)  # |d|, |d|, |v|, |v|
        small = np.abs(g) <= ROUNDING_SHARE * size
    r = np.flatnonzero((mask > 0) & small.any(axis=1) & np.isfinite(g).all(axis=1))
    if r.size == 0:
        return out
    g, small, size, mask, E, z_eq = g[r], small[r], size[r], mask[r], E[r], z_eq[r]
    if eig is None:  # one eigen-decomposition per state for the 17 tests below
        eig = _eig_once(E, mask)
    else:
        eig = eig_rows(eig, r)
    base = iwc_aligned_many(E, z_eq, mask, g, tol, eig)
    for combo in range(16):  # every sign of the small components
        sign = np.where((combo >> np.arange(4)) & 1, 1.0, -1.0)
        moved = np.where(small, sign * ROUNDING_SHARE * size, g)
        out[r] |= iwc_aligned_many(E, z_eq, mask, moved, tol, eig) != base
    return out


def _eig_once(E, mask):
    """The ``eig`` of :func:`atlas.dynamics.system.iwc_aligned_many` for the states of
    configurations ``mask`` (n,) with augmented matrices ``E`` (n, 5, 5): ``geev`` once per state
    and configuration, on demand."""
    done = {}

    def eig(m, sel):
        if m not in done:
            rows = np.flatnonzero(mask == m)
            sub = [i for i in range(2) if m >> i & 1]
            sub += [i + 2 for i in sub]
            w, V = np.linalg.eig(E[rows][:, sub][:, :, sub])
            pos = np.full(mask.shape[0], -1)
            pos[rows] = np.arange(rows.size)
            done[m] = (w.astype(complex), V.astype(complex), pos)
        w, V, pos = done[m]
        return w[pos[sel]], V[pos[sel]]

    return eig


def run_within_rounding(res) -> bool:
    """:func:`within_rounding` of a run of the exact simulator (a
    :class:`atlas.dynamics.SimulationResult` that stopped as ``diverged``)."""
    if res.status != Status.DIVERGED:
        return False
    mode = res._system.modes[MODE_NAMES.index(res.mode_final)]
    z_eq = np.full(5, np.nan) if mode.z_eq is None else mode.z_eq
    return bool(within_rounding(np.asarray(res.g_final)[None, :4], [mode.mask], mode.E[None],
                                z_eq[None])[0])  # fmt: skip


def locate(state_at, holds, a, b, xtol, near=None):
    """First time in ``(a, b]`` (n,) at which the stop holds: ``holds(g, rows)`` (bool) of the
    states ``g`` of the lanes ``rows`` is false at ``a`` and true at ``b``; ``state_at(tau,
    rows)`` gives the states (m, 4) of lanes ``rows`` (m,) at ``tau`` (m,).  ``near(g, rows)``, a
    cheaper necessary condition of ``holds`` (:func:`beyond`), if given, is located first (``holds``
    is false before it).  Each is located by a search in ``SPLIT`` equal parts of the bracket (the
    first part where it turns true), to ``xtol``.  Returns ``(b, g(b))`` with ``b - a <= xtol``
    (the stop holds at ``b``)."""
    a, b = np.array(a, dtype=float), np.array(b, dtype=float)
    lanes = np.arange(a.size)
    if near is not None:
        a1, b1 = _search(state_at, near, a, b, xtol)
        hit = holds(state_at(b1, lanes), lanes)
        a, b = np.where(hit, a1, b1), np.where(hit, b1, b)
    a, b = _search(state_at, holds, a, b, xtol)
    return b, state_at(b, lanes)


#: parts of a bracket per evaluation round of :func:`locate` (``SPLIT - 1`` states per lane)
SPLIT = 16


def _search(state_at, holds, a, b, xtol):
    a, b = a.copy(), b.copy()
    frac = np.arange(1, SPLIT) / SPLIT
    for _ in range(MAX_ROUNDS):
        r = np.flatnonzero(b - a > xtol)
        if r.size == 0:
            break
        x = a[r, None] + (b - a)[r, None] * frac
        rows = np.repeat(r, SPLIT - 1)
        hit = holds(state_at(x.ravel(), rows), rows).reshape(r.size, SPLIT - 1)
        grid = np.concatenate([a[r, None], x, b[r, None]], axis=1)
        first = np.where(hit.any(axis=1), hit.argmax(axis=1), SPLIT - 1)
        a[r], b[r] = grid[np.arange(r.size), first], grid[np.arange(r.size), first + 1]
    return a, b
