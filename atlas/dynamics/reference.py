"""Independent reference for the exact simulator: ``scipy.integrate.solve_ivp`` restarted at every
switching event (same contact law and event functions as :func:`atlas.dynamics.simulate`; the
linear phases integrated numerically, the events located by ``solve_ivp``'s terminal events)."""

from __future__ import annotations

import time as _time

import numpy as np
import scipy.integrate

from atlas.dynamics.system import (
    FORCE_OFF,
    FORCE_ON,
    IMPACT,
    LIFTOFF,
    build_system,
    mask_from_signs,
)

__all__ = ["simulate_solve_ivp"]


def simulate_solve_ivp(
    beta1,
    beta2,
    alpha,
    k=(1.0, 1.0),
    q=(0.0, 0.0),
    b_norm=(1.0, 1.0),
    a_norm=1.0,
    g0=(0.0, 0.0, 0.0, 0.0),
    t_end=10.0,
    max_events=10_000,
    method="DOP853",
    rtol=1e-12,
    atol=1e-15,
):
    """Independent reference: ``scipy.integrate.solve_ivp`` restarted at every switching event.

    Same contact law and the same event functions (gaps, forces) as :func:`simulate`, but the
    linear phases are integrated numerically (``method``, ``rtol``, ``atol``) and events are
    located by ``solve_ivp``'s terminal events.

    Returns
    -------
    dict with ``t_events`` (n,), ``contacts`` (n,), ``kinds`` (list), ``states`` (n, 4),
    ``g_final`` (4,), ``t_final``, ``nfev``, ``wall_time`` [s].
    """
    t_wall = _time.perf_counter()
    sysm = build_system(beta1, beta2, alpha, k, q, b_norm, a_norm, 0.5)
    L = sysm.L
    g = np.asarray(g0, dtype=float).copy()
    s = np.where(L @ np.append(g, 1.0) > 0, 1.0, -1.0)
    t = 0.0
    out_t, out_c, out_k, out_z = [], [], [], []
    nfev = 0
    while t < t_end and len(out_t) < max_events:
        mask = mask_from_signs(s)
        monitored = [0, 1] + [2 + i for i in range(2) if s[i] < 0]
        sol = _phase(sysm.modes[mask].E, L, s, monitored, g, t, t_end, method, rtol, atol)
        nfev += sol.nfev
        if sol.status != 1:
            g = sol.y[:, -1]
            t = t_end
            break
        t, crossing, g = _first_event(sol, monitored)
        for kind, contact in _switch(sysm.modes[mask].LE, L, s, g, crossing):
            out_t.append(t)
            out_c.append(contact)
            out_k.append(kind)
            out_z.append(g.copy())
    return {
        "t_events": np.array(out_t),
        "contacts": np.array(out_c, dtype=int),
        "kinds": out_k,
        "states": np.array(out_z).reshape(-1, 4),
        "g_final": g,
        "t_final": t,
        "nfev": nfev,
        "wall_time": _time.perf_counter() - t_wall,
    }


def _phase(E, L, s, monitored, g, t, t_end, method, rtol, atol):
    """``solve_ivp`` of ``g' = A g + c`` (one mode) from ``(t, g)``, stopped by the first sign
    change of a monitored event function ``L[j] z``."""
    A, c = E[:4, :4], E[:4, 4]

    def make(j, sj):
        def ev(_t, y):
            return sj * (L[j, :4] @ y + L[j, 4])

        ev.terminal = True
        ev.direction = -1
        return ev

    return scipy.integrate.solve_ivp(
        lambda _t, y: A @ y + c,
        (t, t_end),
        g,
        method=method,
        rtol=rtol,
        atol=atol,
        events=[make(j, s[j]) for j in monitored],
        **({"jac": (lambda _t, y: A)} if method in ("Radau", "BDF", "LSODA") else {}),
    )


def _first_event(sol, monitored):
    """Time, crossing event functions (within 1e-12) and state of the terminal event of ``sol``."""
    hits = [
        (sol.t_events[n][0], monitored[n]) for n in range(len(monitored)) if sol.t_events[n].size
    ]
    t_hit = min(h[0] for h in hits)
    crossing = [j for th, j in hits if th <= t_hit + 1e-12]
    idx = [n for n in range(len(monitored)) if sol.t_events[n].size]
    return t_hit, crossing, sol.y_events[idx[0]][0].copy()


def _switch(LE, L, s, g, crossing) -> list:
    """Flip the signs ``s`` (in place) of the crossing event functions at state ``g``; returns
    the events ``[(kind, contact)]`` (the reference's own rule: absolute threshold 1e-9 on a
    closing gap's force, no force event while the gap is open)."""
    vals = L @ np.append(g, 1.0)
    dvals = LE @ np.append(g, 1.0)
    for j in crossing:
        s[j] = -s[j]
    events = []
    for j in crossing:
        i = j % 2
        if j < 2:
            kind = IMPACT if s[j] < 0 else LIFTOFF
            if s[j] < 0:
                force = vals[2 + i] if abs(vals[2 + i]) > 1e-9 else dvals[2 + i]
                s[2 + i] = 1.0 if force > 0 else -1.0
            else:
                s[2 + i] = -1.0
        else:
            if s[i] > 0:
                continue
            kind = FORCE_ON if s[j] > 0 else FORCE_OFF
        events.append((kind, i + 1))
    return events
