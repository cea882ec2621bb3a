"""The divergence stop of a run, one rule for both engines (:func:`atlas.dynamics.simulate` and
:mod:`atlas.dynamics.fast_engine`; paper Sec. 4.3 for the impact without collision).

A run stops as ``diverged`` at the first time ``t`` at which its state ``g(t)`` (in the
configuration active from ``t`` on, or the one active up to an event at ``t``) has

* a non-finite component, or a gap ``d_i > amplitude_limit`` (default ``1e4 scale``), or
* a gap ``d_i < -1e3 penetration_limit`` (default ``1e6 scale``), or
* an active gap ``d_i < -penetration_limit`` (default ``1e3 scale``) while the state is aligned
  with an IWC eigenvector (:func:`atlas.dynamics.system.iwc_aligned`, tolerance ``ALIGN_TOL``).

The engines test :func:`stopped` at the ends of their steps and at their events; where it holds at
the end of a step and not at its start, :func:`locate` bisects the step on the closed-form
solution to the first time it holds (to ``xtol``), so both engines stop at the same time (within
``xtol``) for the same reason whatever their steps.  A crossing of the amplitude or the deep
penetration limit that is undone inside one step (a peak) is found by each engine's own bracket
of the shifted gaps ``d_i - amplitude_limit``, ``-d_i - 1e3 penetration_limit``
(:func:`limit_rows`)."""

from __future__ import annotations

import numpy as np

from atlas.dynamics.system import iwc_aligned_many

__all__ = ["AMPLITUDE", "PENETRATION", "DEEP", "ALIGN_TOL", "limits", "limit_rows", "stopped",
           "locate"]  # fmt: skip

#: default limits relative to the run's length scale: amplitude, aligned penetration
AMPLITUDE, PENETRATION = 1e4, 1e3
#: the penetration that stops a run whatever its alignment, times the penetration limit
DEEP = 1e3
#: alignment tolerance of the aligned-penetration stop (the classification uses 1e-2)
ALIGN_TOL = 1e-3
#: bisection halvings of :func:`locate` at most (a step of 2^-80 of its length is below rounding)
MAX_HALVINGS = 80


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


def stopped(g, mask, E, z_eq, amp, pen):
    """The stop rule at the states ``g`` (n, 4) in configurations ``mask`` (n,) (augmented
    matrices ``E`` (n, 5, 5), equilibria ``z_eq`` (n, 5), NaN where none), limits ``amp``, ``pen``
    (n,); bool (n,)."""
    g = np.asarray(g, dtype=float)
    mask = np.asarray(mask, dtype=int)
    amp, pen = np.broadcast_to(amp, mask.shape), np.broadcast_to(pen, mask.shape)
    finite = np.isfinite(g).all(axis=1)
    out = ~finite
    with np.errstate(invalid="ignore"):
        out |= np.max(g[:, :2], axis=1) > amp
        out |= np.min(g[:, :2], axis=1) < -DEEP * pen
        act = np.stack([mask & 1, mask >> 1 & 1], axis=1).astype(bool)
        deep = ~out & (act & (g[:, :2] < -pen[:, None])).any(axis=1)
    r = np.flatnonzero(deep)
    if r.size:
        out[r] = iwc_aligned_many(E[r], z_eq[r], mask[r], g[r], ALIGN_TOL)
    return out


def locate(state_at, holds, a, b, xtol):
    """First time in ``(a, b]`` (n,) at which the stop holds, by bisection: ``holds(tau, g)``
    (bool (n,)) is false at ``a`` and true at ``b``; ``state_at(tau)`` gives the states ``g``
    (n, 4) at ``tau`` (n,).  Returns ``(b, g(b))`` with ``b - a <= xtol`` (the stop holds at
    ``b``)."""
    a, b = np.array(a, dtype=float), np.array(b, dtype=float)
    for _ in range(MAX_HALVINGS):
        open_ = b - a > xtol
        if not open_.any():
            break
        mid = np.where(open_, 0.5 * (a + b), b)
        hit = holds(mid, state_at(mid)) | ~open_
        a, b = np.where(hit, a, mid), np.where(hit, mid, b)
    return b, state_at(b)
