"""Randomized comparison of the fast engine (:mod:`atlas.dynamics.fast_engine`) with the exact
simulator (:func:`atlas.dynamics.simulate_outcome`) over the whole parameter space: seeded lanes,
the outcome of each by both, the lanes where they disagree."""

from __future__ import annotations

import dataclasses
import math
import time

import numpy as np

from atlas.dynamics import fast_engine
from atlas.dynamics.outcome import initial_states, simulate_outcome, standard_normals

__all__ = ["RandomLanes", "random_lanes", "grid_lanes", "compare", "lane_costs", "cost_ratios",
           "per_event", "summary"]  # fmt: skip


@dataclasses.dataclass(frozen=True)
class RandomLanes:
    """``n`` lanes: angles ``beta1, beta2, alpha`` [rad], stiffness ratio ``kappa`` and damping
    ``q`` [1] (``k = (kappa, 1)``, ``q = (q, q)``), initial states ``g0`` (n, 4)."""

    beta1: np.ndarray
    beta2: np.ndarray
    alpha: np.ndarray
    kappa: np.ndarray
    q: np.ndarray
    g0: np.ndarray


def random_lanes(seed: int, n: int) -> RandomLanes:
    """``n`` lanes drawn by ``numpy.random.default_rng(seed)``: ``beta1, beta2, alpha`` uniform
    in ``[0, 2 pi)`` (a quarter of the ``beta`` on the axes and diagonals ``j pi / 4``, where the
    modal forms are degenerate), ``kappa`` log-uniform in ``[1e-2, 10]``, ``q`` log-uniform in
    ``[1e-3, 2]`` (a fifth ``q = 0``), ``g0`` perturbed SS equilibria
    (:func:`atlas.dynamics.outcome.initial_states`, perturbation ``1e-2``)."""
    n = int(n)
    if n < 1:
        raise ValueError(f"n must be >= 1, got {n!r}")
    rng = np.random.default_rng(seed)
    b = rng.uniform(0, 2 * math.pi, (2, n))
    axis = rng.random((2, n)) < 0.25
    b = np.where(axis, rng.integers(0, 8, (2, n)) * (math.pi / 4), b)
    alpha = rng.uniform(0, 2 * math.pi, n)
    kappa = 10.0 ** rng.uniform(-2, 1, n)
    q = np.where(rng.random(n) < 0.2, 0.0, 10.0 ** rng.uniform(-3, math.log10(2), n))
    xi = rng.standard_normal((n, 1, 4))
    g0 = initial_states(b[0], b[1], alpha, kappa, xi)[:, 0]
    return RandomLanes(b[0], b[1], alpha, kappa, q, g0)


def grid_lanes(beta1, beta2, kappa, q, alpha, n_perturb=1, seed=0) -> RandomLanes:
    """The runs of an outcome atlas over the grid ``beta1 x beta2 x kappa x q`` [rad, 1] at one
    ``alpha`` [rad] (``q = q1 = q2``): ``n_perturb`` perturbed SS equilibria per cell, from the
    normals :func:`atlas.dynamics.outcome.standard_normals` ``(seed)`` of the ``beta`` cells,
    the same for every model, as ``atlas simulate --map`` draws them; lanes in the order
    ``(beta1, beta2, kappa, q, run)``."""
    b1, b2, ka, qa = (np.atleast_1d(np.asarray(x, dtype=float)) for x in (beta1, beta2, kappa, q))
    xi = standard_normals(seed, range(b1.size), b2.size, n_perturb)[:, :, None, None]
    B1, B2, K, Q = np.meshgrid(b1, b2, ka, qa, indexing="ij")
    g0 = initial_states(B1, B2, alpha, K, xi).reshape(-1, 4)
    cell = [np.repeat(x.ravel(), n_perturb) for x in (B1, B2, K, Q)]
    return RandomLanes(cell[0], cell[1], np.full(g0.shape[0], float(alpha)), cell[2], cell[3], g0)


def compare(lanes: RandomLanes, **opts) -> dict:
    """Outcomes of ``lanes`` by both engines (``opts``: ``t_end``, ``horizon_cap``,
    ``max_events`` of both); returns ``fast`` and ``exact`` codes (n,), ``disagree`` (lane
    indices), ``decided_by`` (n,), the CPU seconds of each engine (``fast_s``, ``exact_s``;
    the fallback lanes counted in the fast engine's) and per lane the fast engine's ``steps``
    and ``n_events``, the exact simulator's CPU seconds ``exact_lane_s``, sub-steps
    ``exact_steps`` and events ``exact_events`` (n,)."""
    kw = dict(t_end=150.0, horizon_cap=8.0, max_events=2000) | opts
    k = np.stack([lanes.kappa, np.ones_like(lanes.kappa)], axis=1)
    q = np.stack([lanes.q, lanes.q], axis=1)

    def exact(b1, b2, al, k, q, g0):
        return simulate_outcome(b1, b2, al, k=k, q=q, g0=g0, **kw)

    t0 = time.process_time()
    res = fast_engine.run_batch(lanes.beta1, lanes.beta2, lanes.alpha, k, q, lanes.g0,
                                reference=exact, **kw)  # fmt: skip
    t1 = time.process_time()
    n = k.shape[0]
    ref, cpu, steps, events = (np.zeros(n, dtype=dt) for dt in (int, float, int, int))
    for i in range(n):
        c0 = time.process_time()
        out, run = exact(lanes.beta1[i], lanes.beta2[i], lanes.alpha[i], tuple(k[i]), tuple(q[i]),
                         lanes.g0[i])  # fmt: skip
        cpu[i] = time.process_time() - c0
        ref[i], steps[i], events[i] = int(out), run.n_steps, run.n_events
    t2 = time.process_time()
    code = res.code.astype(int)
    return {"fast": code, "exact": ref, "disagree": np.flatnonzero(code != ref),
            "decided_by": res.decided_by, "fast_s": t1 - t0, "exact_s": t2 - t1,
            "steps": res.steps, "n_events": res.n_events, "exact_lane_s": cpu,
            "exact_steps": steps, "exact_events": events}  # fmt: skip


def lane_costs(r: dict) -> np.ndarray:
    """Each lane's CPU seconds in the fast engine (n,), from :func:`compare`'s result ``r``: the
    lane's share of the batch's CPU seconds in proportion to the steps it took part in (a step
    costs every lane of the batch alike), plus the exact simulator's run of a fallback lane."""
    fb = r["decided_by"] == fast_engine.DECIDED_BY.index("fallback")
    batch = max(r["fast_s"] - r["exact_lane_s"][fb].sum(), 0.0)
    share = batch * r["steps"] / max(int(r["steps"].sum()), 1)
    return share + np.where(fb, r["exact_lane_s"], 0.0)


def cost_ratios(r: dict) -> np.ndarray:
    """Each lane's cost in the fast engine (:func:`lane_costs`) over the exact simulator's CPU
    seconds of the same lane (n,), from :func:`compare`'s result ``r``."""
    return lane_costs(r) / r["exact_lane_s"]


def per_event(r: dict, over: float = 10.0) -> dict:
    """The stated target of a lane's cost, from :func:`compare`'s result ``r``: no lane costs
    out of proportion to the work its physics needs, read as (a) no lane over ``over`` times
    the median lane in steps per event or in fast CPU seconds per event (:func:`lane_costs`;
    events counted at least 1) and (b) no lane over the exact simulator's CPU seconds for the
    same lane (:func:`cost_ratios` over 1), fallbacks aside: a fallback lane pays the fast
    attempt and the exact run, reported apart (``fallback_worst``, its cost over its exact run;
    0 if none).  Returns ``event_steps_worst``, ``event_cost_worst`` (the worst lane's steps
    and cost per event over the median lane's), ``over_event`` (lanes over ``over`` times the
    median in either), ``over_exact_stepped`` (lanes of (b)) and ``met`` ((a) and (b))."""
    fb = np.asarray(r["decided_by"]) == fast_engine.DECIDED_BY.index("fallback")
    events = np.maximum(np.asarray(r["n_events"]), 1)
    ratio, run = cost_ratios(r), ~fb
    worst, over_med = {}, np.zeros(fb.size, dtype=bool)
    for name, x in (("steps", np.asarray(r["steps"]) / events), ("cost", lane_costs(r) / events)):
        x = x[run]
        med = float(np.median(x)) if x.size else 0.0
        worst[name] = float(x.max() / med) if med > 0 else (math.inf if (x > 0).any() else 0.0)
        over_med[run] |= x > over * med
    over_exact = int((run & (ratio > 1)).sum())
    return dict(
        event_steps_worst=worst["steps"], event_cost_worst=worst["cost"],
        over_event=int(over_med.sum()), over_exact_stepped=over_exact,
        fallback_worst=float(ratio[fb].max()) if fb.any() else 0.0,
        met=bool(not over_med.any() and over_exact == 0),
    )  # fmt: skip


def summary(r: dict, over: float = 10.0) -> dict:
    """The reported numbers of :func:`compare`'s result ``r``: ``lanes``, ``disagreements``,
    ``fallback`` (share of lanes), CPU seconds of each engine (``fast_cpu_s``, ``exact_cpu_s``)
    and their ratio ``speedup``; the per-lane fast/exact cost (:func:`cost_ratios`:
    ``ratio_median``, ``ratio_p99``, ``ratio_worst``, and ``over_exact`` the lanes that cost
    more than in the exact simulator); the median and largest steps of a lane,
    the lanes over ``over`` times the median lane in steps (``over_steps``) and in fast CPU
    seconds (:func:`lane_costs`; ``over_cost``), the worst lane's cost over the median lane's
    (``worst_over_median``) and the most steps per event of a lane over ``over`` times the median
    (``over_steps_per_event``: 1 where each step is an event; 0 if none); the target's columns
    of :func:`per_event`."""
    steps, events = np.asarray(r["steps"]), np.asarray(r["n_events"])
    cost, ratio = lane_costs(r), cost_ratios(r)
    med_steps, med_cost = float(np.median(steps)), float(np.median(cost))
    heavy = steps > over * med_steps
    fb = r["decided_by"] == fast_engine.DECIDED_BY.index("fallback")
    return dict(
        lanes=int(steps.size), disagreements=int(r["disagree"].size), fallback=float(fb.mean()),
        fast_cpu_s=float(r["fast_s"]), exact_cpu_s=float(r["exact_s"]),
        speedup=float(r["exact_s"] / r["fast_s"]), ratio_median=float(np.median(ratio)),
        ratio_p99=float(np.quantile(ratio, 0.99)), ratio_worst=float(ratio.max()),
        over_exact=int((ratio > 1).sum()),
        steps_median=med_steps, steps_max=int(steps.max()), over_steps=int(heavy.sum()),
        over_cost=int((cost > over * med_cost).sum()),
        worst_over_median=float(cost.max() / med_cost) if med_cost > 0 else math.inf,
        over_steps_per_event=float((steps[heavy] / np.maximum(events[heavy], 1)).max())
        if heavy.any() else 0.0,
        **per_event(r, over),
    )  # fmt: skip
