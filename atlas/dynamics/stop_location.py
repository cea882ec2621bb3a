"""Where the stop rule (:mod:`atlas.dynamics.stop_rule`) holds on the modal segments of the NumPy
engine's lanes: checked at given states (:func:`stops_at`) and located between two times of a
segment (:func:`locate_stops`), the same location for the NumPy and the JAX engines."""

from __future__ import annotations

import numpy as np

from atlas.dynamics import event_bounds as eb
from atlas.dynamics import stop_rule
from atlas.dynamics.modal_form import stack_table, z_eq
from atlas.dynamics.system import eig_rows

__all__ = ["stops_at", "locate_stops"]


def stops_at(tables, ix, mask, act, g, scale):
    """Rows where the stop rule (:func:`stop_rule.stopped`) holds at the states ``g`` (n, 4);
    the alignment is computed only where a penetration passes its limit."""
    amp, pen = stop_rule.limits(scale)
    d = g[:, :2]
    with np.errstate(invalid="ignore"):
        cand = ~eb.all_cols(np.isfinite(g)) | (np.maximum(d[:, 0], d[:, 1]) > amp)
        cand |= ((act | (d < -stop_rule.DEEP * pen[:, None])) & (d < -pen[:, None])).any(axis=1)
    r = eb.rows(cand)
    if r.size:
        lx, mk = ix[r], mask[r]
        r = r[stop_rule.stopped(g[r], mk, stack_table(tables, "E", lx, mk), z_eq(tables, lx, mk),
                                amp[r], pen[r], eig_rows(tables.eig, lx))]  # fmt: skip
    return r


def locate_stops(st, tables, stops, width):
    """Locate the collected stops ``[(lanes, mask, P, U, lam, scale, a, b, xtol, tseg)]`` (each
    between ``a`` and ``b`` on its segment) in one :func:`_locate_stop`; their time, state and
    amplitude into ``st``."""
    if not stops:
        return
    lx, mk, P, U, lam, scale, a, b, xtol, tseg = (np.concatenate(x) for x in zip(*stops))
    stops.clear()
    tau, g = _locate_stop(tables, lx, mk, P, U, lam, scale, a, b, xtol)
    t = tseg + tau
    st.t[lx], st.g[lx] = t, g
    bb = eb.bins(t, width, st.amp.shape[1])
    st.amp[lx, bb] = np.maximum(st.amp[lx, bb], np.abs(g[:, :2]))


def _locate_stop(tables, lx, mk, P, U, lam, scale, a, b, xtol):
    """:func:`stop_rule.locate` on the segments ``P, U, lam`` of lanes ``lx`` in configurations
    ``mk``: the first ``tau`` in ``(a, b]`` at which the stop holds and the state there."""
    E, zq = stack_table(tables, "E", lx, mk), z_eq(tables, lx, mk)
    amp, pen = stop_rule.limits(scale)

    def state_at(tau, rows):
        d, v = eb.gaps_at(P[rows], U[rows], lam[rows], tau)[:2]
        return np.concatenate([d, v], axis=1)

    def holds(g, rows):
        return stop_rule.stopped(g, mk[rows], E, zq, amp[rows], pen[rows],
                                 eig_rows(tables.eig, lx), rows)  # fmt: skip

    def near(g, rows):
        out, penetrated = stop_rule.beyond(g, mk[rows], amp[rows], pen[rows])
        return out | penetrated

    return stop_rule.locate(state_at, holds, a, b, xtol, near)
