"""The simulation sections: :func:`atlas.dynamics.simulate` (exact event times) against
``solve_ivp`` (DOP853, Radau) on the Fig. 2 cases, event-time error against cost; the fast
outcome-map engine (:mod:`atlas.dynamics.fast_engine`) against the exact simulator.
"""

from __future__ import annotations

import math
import time

import numpy as np

from atlas import dynamics
from atlas.bench.timing import log, timeit
from atlas.dynamics import engine_check
from atlas.dynamics.lane_pool import usable_cores

__all__ = ["engine_lanes", "event_error", "gap_events", "jax_outcome_columns", "outcome_maps",
           "simulation"]  # fmt: skip

#: the degenerate-direction grid of the lane comparison: ``beta1 = beta2 = 0:2pi:8`` [rad],
#: ``kappa``, ``q`` [1], ``alpha`` [rad]
DEGENERATE_GRID = dict(beta1=np.arange(8) * (math.pi / 4), beta2=np.arange(8) * (math.pi / 4),
                       kappa=(0.1, 5.0), q=(0.05, 1.5), alpha=0.3 * math.pi)  # fmt: skip

#: the reference of ``simulate``: ``solve_ivp`` at tight tolerances
_TIGHT = dict(method="DOP853", rtol=1e-13, atol=1e-16)


def gap_events(t, kinds, contacts):
    """Times and ``(contact, kind)`` tags of the impacts and lift-offs (force on/off events are
    the simulator's bookkeeping, not events of the motion)."""
    sel = [i for i, k in enumerate(kinds) if k in ("impact", "liftoff")]
    return np.asarray(t)[sel], [(contacts[i], kinds[i]) for i in sel]


def event_error(t, tags, t_ref, tags_ref) -> tuple[float, int]:
    """``(max |t - t_ref|, matching leading events)``; the error is ``inf`` when the sequences of
    events differ (reported as ``mismatch``)."""
    n = min(len(t), len(t_ref))
    match = 0
    while match < n and tags[match] == tags_ref[match]:
        match += 1
    if len(t) != len(t_ref) or match < n:
        return math.inf, match
    return (float(np.max(np.abs(t - t_ref))) if n else 0.0), match


def _timed(fn, cfg):
    """Minimum time of ``fn`` over ``sim_repeats`` runs after one untimed run, and its result."""
    box = {}

    def call():
        box["r"] = fn()

    t = timeit(call, budget=0.5, max_repeats=cfg["sim_repeats"], min_repeats=1)
    return t, box["r"]


def _exact_row(name, kw, cfg):
    """The ``simulate`` row of a case and its gap events (the reference of ``solve_ivp``)."""
    t_sim, r = _timed(lambda: dynamics.simulate(**kw), cfg)
    te, tags = gap_events(r.t_events, r.kinds, r.contacts)
    log(f"simulation case {name}: {len(te)} gap events")
    tight = dynamics.simulate_solve_ivp(**kw, **_TIGHT)
    err, _ = event_error(
        te, tags, *gap_events(tight["t_events"], tight["kinds"], tight["contacts"])
    )
    row = dict(
        case=name,
        method="simulate (exact)",
        rtol="",
        seconds=t_sim,
        events=len(te),
        error=err,
        reference="solve_ivp DOP853 rtol=1e-13",
        nfev="",
    )
    return row, te, tags


def simulation(cfg) -> list[dict]:
    """Rows of ``simulate`` (against tight DOP853) and of ``solve_ivp`` per method and rtol
    (atol = 1e-3 rtol, against ``simulate``) for the cases ``sim_cases``."""
    rows = []
    cases = dynamics.fig2_cases()
    for name in cfg["sim_cases"]:
        kw = cases[name]
        row, te, tags = _exact_row(name, kw, cfg)
        rows.append(row)
        for method, rtols in cfg["sim_methods"]:
            for rtol in rtols:
                t, d = _timed(
                    lambda kw=kw, m=method, r=rtol: dynamics.simulate_solve_ivp(
                        **kw, method=m, rtol=r, atol=r * 1e-3
                    ),
                    cfg,
                )
                ti, itags = gap_events(d["t_events"], d["kinds"], d["contacts"])
                rows.append(
                    dict(
                        case=name,
                        method=f"solve_ivp {method}",
                        rtol=rtol,
                        seconds=t,
                        events=len(ti),
                        error=event_error(ti, itags, te, tags)[0],
                        reference="simulate",
                        nfev=d["nfev"],
                    )
                )
    return rows


def outcome_maps(cfg) -> list[dict]:
    """Rows of the fast engine against the exact simulator on the outcome maps ``outcome_maps``
    ``(n, kappa, q, alpha, sample)``: the whole ``n x n`` map with the fast engine on the usable
    cores (the default of ``atlas simulate --map``; wall time with the start of the processes,
    trajectories per second) and on one core, whether the two maps are identical, how the runs
    were decided; ``sample`` of its cells (seeded) with :func:`atlas.dynamics.simulate_outcome`
    from the same initial states on one core, the speedup per core (one core each), the agreement
    and every disagreement (``disagreements``: cell, both outcomes, the reference's stop)."""
    rows = []
    workers = usable_cores()
    for n, kappa, q, alpha, sample in cfg.get("outcome_maps", ()):
        b1, b2 = dynamics.outcome_grid(n)
        kw = dict(kappa=kappa, q=q, alpha=alpha, engine="fast")
        one = dynamics.outcome_map(b1, b2, workers=1, **kw)
        ds = dynamics.outcome_map(b1, b2, workers=workers, **kw)
        fast = ds["outcome"].values
        identical = bool(np.array_equal(ds["outcome_count"].values, one["outcome_count"].values))
        g0 = dynamics.perturbed_initial_states(b1, b2, alpha, kappa)
        cells = np.random.default_rng(n).choice(n * n, size=min(sample, n * n), replace=False)
        t0 = time.perf_counter()
        bad = []
        for c in cells:
            i, j = divmod(int(c), n)
            out, res = dynamics.simulate_outcome(
                b1[i], b2[j], alpha, k=(kappa, 1.0), q=(q, q), g0=g0[i, j, 0], max_events=2000
            )
            if int(out) != int(fast[i, j]):
                bad.append(
                    f"({i},{j}): reference {out.label} ({res.status.value} at t = "
                    f"{res.t_final:.4g}, {res.n_events} events), fast "
                    f"{dynamics.Outcome(int(fast[i, j])).label}"
                )
        ref_s = time.perf_counter() - t0
        a = ds.attrs
        used = int(a.get("workers", workers))  # fewer if the processes only took turns
        fast_rate = a["trajectories"] / a["seconds"]
        core_rate = one.attrs["trajectories"] / one.attrs["seconds"]
        ref_rate = cells.size / ref_s
        rows.append(dict(
            map=f"{n}x{n}, kappa={kappa:g}, q={q:g}, alpha={alpha / math.pi:.3g}pi",
            trajectories=a["trajectories"], workers=used, fast_seconds=a["seconds"],
            fast_per_s=fast_rate, core_seconds=one.attrs["seconds"], core_per_s=core_rate,
            identical=identical, ref_cells=int(cells.size), ref_per_s=ref_rate,
            speedup=core_rate / ref_rate,
            early_settle=a["runs_early_settle"] / a["trajectories"],
            early_iwc=a["runs_early_iwc"] / a["trajectories"],
            stepped=a["runs_stepped"] / a["trajectories"],
            fallback=a["runs_fallback"] / a["trajectories"],
            agreement=1 - len(bad) / cells.size, disagreements="; ".join(bad),
        ))  # fmt: skip
        log(
            f"outcome map {rows[-1]['map']}: {fast_rate:.0f}/s on {used} cores, "
            f"{core_rate:.0f}/s on one, {ref_rate:.1f}/s exact"
        )
    return rows


def _engine_codes(engine, n, kappa, q, alpha):
    """Outcome codes (n * n,) of ``engine.run_batch`` on the ``n x n`` outcome map (one initial
    state per cell) and its wall time [s]."""
    b1, b2 = dynamics.outcome_grid(n)
    g0 = dynamics.perturbed_initial_states(b1, b2, alpha, kappa)[:, :, 0].reshape(-1, 4)

    def reference(x1, x2, alpha, k, q, g0):
        return dynamics.simulate_outcome(x1, x2, alpha, k=k, q=q, g0=g0, max_events=2000)

    t0 = time.perf_counter()
    res = engine.run_batch(np.repeat(b1, n), np.tile(b2, n), alpha, (kappa, 1.0), (q, q), g0,
                           reference=reference)  # fmt: skip
    return res.code, time.perf_counter() - t0


def jax_outcome_columns(rows, cfg) -> None:
    """With ``cfg["jax_outcome_n"] = n``: the JAX kernel of the same engine
    (:mod:`atlas.dynamics.jax_engine`) on an ``n x n`` map with the parameters of the first map of
    :func:`outcome_maps`, in the same run, as columns of that map's row: ``jax_map`` (``n x n``),
    ``jax_compile_s`` (the first call's wall time less the second's: compiling the batch sizes the
    map needs, or loading them from the persistent compilation cache), ``jax_per_s`` (the second
    call), ``fast_per_s_again`` (the NumPy engine on the same map, one core) and ``jax_same``
    (fraction of cells with the NumPy engine's outcome)."""
    n = cfg.get("jax_outcome_n")
    if not n or not rows:
        return
    from atlas.dynamics import fast_engine, jax_engine  # noqa: PLC0415 - only with the option

    _, kappa, q, alpha, _ = cfg["outcome_maps"][0]
    _, first_s = _engine_codes(jax_engine, n, kappa, q, alpha)
    jx, jax_s = _engine_codes(jax_engine, n, kappa, q, alpha)
    fast, fast_s = _engine_codes(fast_engine, n, kappa, q, alpha)
    rows[0].update(jax_map=f"{n}x{n}", jax_compile_s=max(first_s - jax_s, 0.0),
                   jax_per_s=n * n / jax_s, fast_per_s_again=n * n / fast_s,
                   jax_same=float(np.mean(jx == fast)))  # fmt: skip
    log(f"outcome map {rows[0]['map']} at {n}x{n}: jax kernel {n * n / jax_s:.0f}/s "
        f"(compiled in {first_s - jax_s:.0f} s), numpy {n * n / fast_s:.0f}/s")  # fmt: skip


def _lane_sets(cfg):
    """``(name, lanes)`` of the lane comparison: ``engine_random = (seed, n)`` random lanes over
    the whole parameter space, ``engine_grid = n_perturb`` runs per cell of
    :data:`DEGENERATE_GRID` (each off where its key is missing or 0)."""
    seed, n = cfg.get("engine_random") or (0, 0)
    if n:
        yield f"{n} random lanes (seed {seed})", engine_check.random_lanes(seed, n)
    runs = cfg.get("engine_grid")
    if runs:
        g = DEGENERATE_GRID
        yield (f"beta 0:2pi:8, kappa 0.1,5, q 0.05,1.5, alpha 0.3pi, {runs} runs a cell",
               engine_check.grid_lanes(**g, n_perturb=runs))  # fmt: skip


def engine_lanes(cfg) -> list[dict]:
    """Rows of the lane-by-lane comparison of the fast engine with the exact simulator
    (:func:`atlas.dynamics.engine_check.compare`, one core each, CPU seconds) on the lane sets of
    :func:`_lane_sets`: :func:`atlas.dynamics.engine_check.summary` (disagreements, fallback
    share, per-lane fast/exact cost, lanes over 10 times the median lane) and ``disagree_lanes``
    (each disagreeing lane: index, both outcome codes)."""
    rows = []
    for name, lanes in _lane_sets(cfg):
        r = engine_check.compare(lanes)
        bad = "; ".join(f"lane {i}: exact {r['exact'][i]}, fast {r['fast'][i]}"
                        for i in r["disagree"])  # fmt: skip
        rows.append(dict(set=name, **engine_check.summary(r), disagree_lanes=bad))
        x = rows[-1]
        log(f"engine lanes {name}: {x['disagreements']} disagreements, fast/exact per lane "
            f"{x['ratio_median']:.2f} median, {x['ratio_worst']:.2f} worst")  # fmt: skip
    return rows
