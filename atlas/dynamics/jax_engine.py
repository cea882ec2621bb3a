"""Batched event-driven simulator in JAX: the stepper of :func:`atlas.dynamics.simulate` as a pure
``lax.while_loop``, ``jit``-compiled and ``vmap``-ped over parameters and initial conditions.

Same arithmetic as the NumPy simulator (paper eqs. 1, 6-8; :mod:`atlas.dynamics`): per contact
configuration ``S`` the state ``z = (d1, d2, d1', d2', 1)`` obeys ``z' = E_S z``; sub-steps
``h_S = theta / rho_S`` advance it exactly with ``expm(E_S h_S)`` (precomputed on the host, one per
mode and trajectory); the last partial step and all event locations use the degree-30 Taylor
polynomial of ``expm(E_S tau) z``.  Event detection per sub-step, for the gaps ``d_i`` and (while
``d_i <= 0``) the forces ``phi_i = -k_i d_i - q_i d_i'``:

* a sign change between the ends of the sub-step, or a sign change of the derivative with the
  function's value at the extremum (located by bisection of the derivative polynomial) of the
  opposite sign -- the double crossing inside one sub-step;
* the crossing is then located by *bisection* on the bracket (64 halvings: the bracket shrinks to
  ``h 2^-64``, below the NumPy simulator's Brent tolerance ``1e-13 h``), so no crossing is skipped
  and the located root is certified to lie in the final bracket.

Differences from :func:`atlas.dynamics.simulate` (documented, tested): the ``"diverged"`` stop uses
the amplitude bounds only (``d_i > amplitude_limit`` or ``d_i < -1e3 penetration_limit``; the
NumPy simulator also stops earlier when an active gap passes ``-penetration_limit`` along an
impact-without-collision eigenvector, which :func:`atlas.dynamics.classify` tests on the final
state either way); the event log is a fixed buffer of ``max_events + 4`` rows.
"""

from __future__ import annotations

import functools

import jax
import jax.numpy as jnp
import numpy as np

from atlas.dynamics.classification import (
    TrajectoryStats,
    classify_stats,
    impacts,
    needs_longer_run,
)
from atlas.dynamics.system import (
    FORCE_OFF,
    FORCE_ON,
    IMPACT,
    LIFTOFF,
    Status,
    build_system,
    mask_from_signs,
    mode_name,
    run_scale,
)

__all__ = ["simulate_batch", "outcomes", "KIND_CODES"]

#: event kind codes in the buffer
KIND_CODES = {IMPACT: 0, LIFTOFF: 1, FORCE_ON: 2, FORCE_OFF: 3}
_RUNNING = -1
_STATUS = [Status.T_END, Status.EVENT_CAP, Status.DIVERGED, Status.SETTLED, Status.STEP_CAP]
_N_BISECT = 64


def _system_arrays(sysm) -> dict:
    """Per-trajectory constant arrays of a :class:`atlas.dynamics.system.System`."""
    modes = sysm.modes
    z_eq = np.stack([np.nan_to_num(m.z_eq, nan=0.0) if m.z_eq is not None else np.zeros(5)
                     for m in modes])  # fmt: skip
    has_eq = np.array([m.z_eq is not None for m in modes])
    return {
        "Phi": np.stack([m.Phi for m in modes]),
        "P": np.stack([m.P for m in modes]),
        "h": np.array([m.h for m in modes]),
        "E": np.stack([m.E for m in modes]),
        "L": sysm.L,
        "stable": np.array([m.stable for m in modes]),
        "z_eq": z_eq,
        "has_eq": has_eq,
        "k": sysm.k,
        "omega": np.float64(sysm.omega),
    }


def _horner(W, tau):
    """``sum_n W[n] tau^n`` for ``W`` of shape (N+1, ...)."""

    acc = W[-1]
    for n in range(W.shape[0] - 2, -1, -1):  # unrolled: one fused kernel
        acc = acc * tau + W[n]
    return acc


def _bisect(coef, sign0, hi):
    """First sign change in (0, hi] of the polynomials ``coef`` (4, N+1) with sign ``sign0`` at 0.

    Bisection keeps ``sign0 * p(lo) > 0 >= sign0 * p(hi)``; returns the upper end.
    """

    def body(_, lohi):
        lo, up = lohi
        mid = 0.5 * (lo + up)
        val = jax.vmap(_horner)(coef, mid)
        left = sign0 * val <= 0
        return jnp.where(left, lo, mid), jnp.where(left, mid, up)

    lo = jnp.zeros_like(hi)
    return jax.lax.fori_loop(0, _N_BISECT, body, (lo, hi), unroll=8)[1]


def _mask_of(s):
    """Mode mask from the recorded signs of ``(d1, d2, phi1, phi2)`` (as ``mask_from_signs``)."""
    a1 = (s[0] < 0) & (s[2] > 0)
    a2 = (s[1] < 0) & (s[3] > 0)
    return a1.astype(jnp.int32) + 2 * a2.astype(jnp.int32)


def _settled(arr, settle_rtol, mask, z):
    """No event can follow (the NumPy simulator's settling test, branch-free)."""
    E = arr["E"][mask]
    act = jnp.array([mask & 1, (mask >> 1) & 1]) > 0
    acc = E[2:4] @ z
    free_ok = jnp.all(act | ((z[:2] > 0) & (z[2:4] >= 0) & (acc > 0)))
    zeq = arr["z_eq"][mask]
    deq = zeq[:2]
    dev = (
        jnp.max(jnp.where(act, jnp.abs(z[:2] - deq), 0.0))
        + jnp.max(jnp.where(act, jnp.abs(z[2:4]), 0.0)) / arr["omega"]
    )
    dmax = jnp.max(jnp.where(act, jnp.abs(deq), 0.0))
    eq_ok = jnp.all(jnp.where(act, deq < 0, True)) & (dev <= settle_rtol * dmax)
    zs = jnp.where(jnp.concatenate([act, act, jnp.array([False])]),
                   jnp.concatenate([deq, jnp.zeros(3)]), z)  # fmt: skip
    acc_s = E[2:4] @ zs
    free_star = jnp.all(act | (acc_s > 0))
    ok_eq = (mask == 0) | (arr["has_eq"][mask] & eq_ok & free_star)
    return arr["stable"][mask] & free_ok & ok_eq


def _diverged(z, amp_lim, pen_lim):
    """The amplitude bounds only (see the module docstring)."""
    return (
        (~jnp.all(jnp.isfinite(z))) | (jnp.max(z[:2]) > amp_lim) | (jnp.min(z[:2]) < -1e3 * pen_lim)
    )


def _locate(arr, s, z, t, t_end, mask):
    """One sub-step from ``(t, z)``: its length ``h``, end state ``z1``, Taylor coefficients ``W``,
    the event-functional derivatives ``LE``, the first crossing time ``r``, whether there is one
    and which event functions cross there."""
    L = arr["L"]
    h_mode = arr["h"][mask]
    full = t_end - t >= h_mode
    h = jnp.where(full, h_mode, t_end - t)
    W = jnp.einsum("nij,j->ni", arr["P"][mask], z)  # Taylor coefficients of z(tau)
    z1 = jnp.where(full, arr["Phi"][mask] @ z, _horner(W, h))
    z1 = z1.at[4].set(1.0)
    LE = L @ arr["E"][mask]
    f1 = L @ z1
    fp0 = LE @ z
    fp1 = LE @ z1
    monitored = jnp.array([True, True, s[0] < 0, s[1] < 0])
    cj = W @ L.T  # (N+1, 4) value polynomials
    cj = cj.T  # (4, N+1)
    dcj = cj[:, 1:] * jnp.arange(1, cj.shape[1])  # derivative polynomials
    dcj = jnp.concatenate([dcj, jnp.zeros((4, 1))], axis=1)
    end_cross = s * f1 < 0
    ext = (s * fp0 < 0) & (s * fp1 > 0) & ~end_cross
    hv = jnp.full(4, h)
    tau_e = _bisect(dcj, jnp.sign(fp0), hv)
    val_e = jax.vmap(_horner)(cj, tau_e)
    dip = ext & (s * val_e < 0)
    bracket = monitored & (end_cross | dip)
    hi = jnp.where(end_cross, h, tau_e)
    roots = _bisect(cj, s, jnp.where(bracket, hi, h))
    roots = jnp.where(bracket, roots, jnp.inf)
    r = jnp.min(roots)
    any_ev = jnp.any(bracket)
    xtol = 1e-13 * h_mode
    crossing = bracket & (roots <= r + 1e3 * xtol)
    return h, z1, W, LE, r, any_ev, crossing


def _switch(arr, LE, z_e, s, crossing, scale):
    """New signs after the crossings at the event state ``z_e`` and the event rows
    ``[(recorded, kind code, contact)]`` (the NumPy simulator's rule)."""
    k = arr["k"]
    dphi = LE @ z_e
    vals = arr["L"] @ z_e
    s_new = jnp.where(crossing, -s, s)
    rows = []
    for j in range(4):
        i = j % 2
        if j < 2:
            imp = s_new[j] < 0
            big = jnp.abs(vals[2 + i]) > 1e-9 * jnp.abs(k[i] * scale)
            fs = jnp.where(big, jnp.sign(vals[2 + i]), jnp.sign(dphi[2 + i]))
            fs = jnp.where(fs > 0, 1.0, -1.0)
            s_new = s_new.at[2 + i].set(
                jnp.where(crossing[j], jnp.where(imp, fs, -1.0), s_new[2 + i])
            )
            kind = jnp.where(imp, 0, 1)
            rec = crossing[j]
        else:
            rec = crossing[j] & ~((s_new[i] > 0) & ~crossing[i])
            kind = jnp.where(s_new[j] > 0, 2, 3)
        rows.append((rec, kind, i + 1))
    return s_new, rows


def _record(buf, n_ev, rows, t_e, z_e, any_ev):
    """Scatter the recorded event rows ``(t, kind, contact, g)`` into the buffer."""
    for rec, kind, cnum in rows:
        row = jnp.concatenate([jnp.array([t_e, kind, cnum], dtype=z_e.dtype), z_e[:4]])
        rec = rec & any_ev
        # scatter one row in place; rows not recorded go out of bounds and are dropped
        idx = jnp.where(rec & (n_ev < buf.shape[0]), n_ev, buf.shape[0])
        buf = buf.at[idx].set(row, mode="drop")
        n_ev = n_ev + rec.astype(jnp.int32)
    return buf, n_ev


def _step_fn(arr, t_end, max_events, max_steps, amp_lim, pen_lim, settle_rtol, scale, nbins):
    """The ``lax.while_loop`` body: one sub-step, or up to the first event in it."""

    def body(c):
        t, z, s, n_ev, n_steps, status, buf, amp = c
        h, z1, W, LE, r, any_ev, crossing = _locate(arr, s, z, t, t_end, _mask_of(s))
        z_e = _horner(W, jnp.where(any_ev, r, 0.0)).at[4].set(1.0)
        s_new, rows = _switch(arr, LE, z_e, s, crossing, scale)
        buf2, n2 = _record(buf, n_ev, rows, t + r, z_e, any_ev)
        t2 = jnp.where(any_ev, t + r, t + h)
        z2 = jnp.where(any_ev, z_e, z1)
        s2 = jnp.where(any_ev, s_new, s)
        b = jnp.clip(jnp.floor(t2 / t_end * nbins).astype(jnp.int32), 0, nbins - 1)
        amp2 = amp.at[b].max(jnp.abs(z2[:2]))
        st = jnp.where(
            any_ev & (n2 >= max_events),
            1,
            jnp.where(
                _diverged(z2, amp_lim, pen_lim),
                2,
                jnp.where(
                    ~any_ev & _settled(arr, settle_rtol, _mask_of(s2), z2),
                    3,
                    jnp.where(t2 >= t_end, 0, jnp.where(n_steps + 1 >= max_steps, 4, _RUNNING)),
                ),
            ),
        )
        return (t2, z2, s2, n2, n_steps + 1, st, buf2, amp2)

    return body


@functools.partial(jax.jit, static_argnames=("max_events", "nbins"))
def _run(arr, g0, t_end, amp_lim, pen_lim, scale, max_events, max_steps, settle_rtol, nbins):
    def one(arr, g0, t_end, amp_lim, pen_lim, scale):
        z0 = jnp.concatenate([g0, jnp.ones(1)])
        s0 = jnp.where(arr["L"] @ z0 > 0, 1.0, -1.0)
        buf = jnp.zeros((max_events + 4, 7))
        amp = jnp.zeros((nbins, 2)).at[0].set(jnp.abs(g0[:2]))
        body = _step_fn(arr, t_end, max_events, max_steps, amp_lim, pen_lim, settle_rtol, scale,
                        nbins)  # fmt: skip
        c0 = (jnp.zeros(()), z0, s0, jnp.zeros((), jnp.int32), jnp.zeros((), jnp.int32),
              jnp.array(_RUNNING), buf, amp)  # fmt: skip
        return jax.lax.while_loop(lambda c: c[5] == _RUNNING, body, c0)

    return jax.vmap(one)(arr, g0, t_end, amp_lim, pen_lim, scale)


def simulate_batch(params, g0, t_end, *, max_events=2000, max_steps=10_000_000, theta=0.5,
                   settle_rtol=1e-6, nbins=48, chunk=256):  # fmt: skip
    """Simulate a batch of trajectories with one compiled, ``vmap``-ped ``lax.while_loop``.

    Parameters
    ----------
    params : list of dict
        Keyword arguments of :func:`atlas.dynamics.simulate` per trajectory (``beta1``, ``beta2``,
        ``alpha``, ``k``, ``q``, optional ``b_norm``, ``a_norm``).
    g0 : array_like (n, 4)
        Initial states [1].
    t_end : float or array_like (n,)
        Horizons [time].
    max_events, max_steps, theta, settle_rtol
        As in :func:`atlas.dynamics.simulate` (status codes in :data:`_STATUS` order).
    nbins : int
        Time bins over ``[0, t_end]`` of the recorded ``max |d_i|`` (for :func:`outcomes`).
    chunk : int
        Trajectories per compiled call (memory: ``chunk * (max_events + 4) * 7`` floats).

    Returns
    -------
    list of dict
        Per trajectory: ``t_final``, ``g_final``, ``status`` (:class:`atlas.dynamics.Status`),
        ``t_events``, ``kinds``, ``contacts``, ``states``, ``n_steps``, ``amp_bins`` (nbins, 2),
        ``system`` (host :class:`atlas.dynamics.system.System`), ``scale``.
    """
    g0 = np.asarray(g0, dtype=float).reshape(-1, 4)
    n = g0.shape[0]
    t_end = np.broadcast_to(np.asarray(t_end, dtype=float), (n,)).copy()
    systems = [
        build_system(p["beta1"], p["beta2"], p["alpha"], p.get("k", (1.0, 1.0)),
                     p.get("q", (0.0, 0.0)), p.get("b_norm", (1.0, 1.0)), p.get("a_norm", 1.0),
                     theta)
        for p in params
    ]  # fmt: skip
    arrs = [_system_arrays(sysm) for sysm in systems]
    scales = np.array([run_scale(systems[m], g0[m]) for m in range(n)])
    out = []
    size = min(chunk, n)
    for a in range(0, n, size):
        sl = slice(a, min(a + size, n))
        pad = size - (sl.stop - sl.start)  # pad with copies of the first run: one compiled shape
        idx = list(range(sl.start, sl.stop)) + [sl.start] * pad
        arr = {key: jnp.asarray(np.stack([arrs[i][key] for i in idx])) for key in arrs[0]}
        res = _run(arr, jnp.asarray(g0[idx]), jnp.asarray(t_end[idx]),
                   jnp.asarray(1e4 * scales[idx]), jnp.asarray(1e3 * scales[idx]),
                   jnp.asarray(scales[idx]), max_events, max_steps, settle_rtol, nbins)  # fmt: skip
        res = [np.asarray(x) for x in res]
        for r, m in enumerate(range(sl.start, sl.stop)):
            out.append(_unpack(res, r, t_end[m] / nbins, systems[m], scales[m]))
    return out


_KIND_OF_CODE = {v: kk for kk, v in KIND_CODES.items()}


def _unpack(res, r, bin_width, sysm, scale) -> dict:
    """Row ``r`` of a :func:`_run` result as the dict of :func:`simulate_batch`."""
    t, z, sg, n_ev, n_steps, status, buf, amp = res
    b = buf[r, : min(int(n_ev[r]), buf.shape[1])]
    return {
        "t_final": float(t[r]),
        "g_final": z[r, :4].copy(),
        "status": _STATUS[int(status[r])],
        "mode_final": mode_name(mask_from_signs(sg[r])),
        "t_events": b[:, 0].copy(),
        "kinds": [_KIND_OF_CODE[int(x)] for x in b[:, 1]],
        "contacts": b[:, 2].astype(int),
        "states": b[:, 3:7].copy(),
        "n_steps": int(n_steps[r]),
        "amp_bins": amp[r].copy(),
        "bin_width": bin_width,
        "system": sysm,
        "scale": float(scale),
    }


def stats_of(r) -> TrajectoryStats:
    """:class:`atlas.dynamics.TrajectoryStats` of one :func:`simulate_batch` result."""
    T = r["t_final"]
    g = r["g_final"]
    t_imp, v_imp, c_imp = impacts(
        r["system"], r["mode_final"], g, T, r["kinds"], r["t_events"], r["contacts"], r["states"]
    )
    w = r["bin_width"]
    nb = r["amp_bins"].shape[0]
    starts = np.arange(nb) * w
    late = (starts + w > 2 * T / 3) & (starts <= T)
    amp = r["amp_bins"][late].max(axis=0) if late.any() else np.abs(g[:2])
    return TrajectoryStats(
        t_final=T, status=r["status"], mode_final=r["mode_final"], g_final=g, scale=r["scale"],
        last_event=float(r["t_events"][-1]) if len(r["t_events"]) else 0.0,
        t_imp=t_imp, v_imp=v_imp, c_imp=c_imp, late_amplitude=amp,
    )  # fmt: skip


def outcomes(b1, b2, alpha, k, q, g0, *, t_end=150.0, horizon_cap=8.0, max_events=2000):
    """Outcome codes ``(n1, n2, n_perturb)`` of :func:`atlas.dynamics.outcome_map` (jax engine):
    one batch, then batched re-runs with doubled horizon for the runs
    :func:`atlas.dynamics.simulate_outcome` would extend."""
    n1, n2, npert = g0.shape[:3]
    where = [(i, j, m) for i in range(n1) for j in range(n2) for m in range(npert)]
    params = [{"beta1": b1[i], "beta2": b2[j], "alpha": alpha, "k": k, "q": q} for i, j, _ in where]
    codes = np.zeros((n1, n2, npert), dtype=np.int8)
    todo = list(range(len(params)))
    T = float(t_end)
    t_max = horizon_cap * T
    while todo:
        res = simulate_batch([params[x] for x in todo], np.array([g0[where[x]] for x in todo]), T,
                             max_events=max_events)  # fmt: skip
        again = []
        for x, r in zip(todo, res, strict=True):
            out = classify_stats(stats_of(r), r["system"])
            codes[where[x]] = int(out)
            if needs_longer_run(out, r["status"], len(r["t_events"]), T, t_max):
                again.append(x)
        todo = again
        T *= 2
    return codes
