"""One beta grid, every method: time per point and errors against the exact reference.

A grid is ``(n+1) x (n+1)`` values of (beta1, beta2) on ``[0, 2 pi]`` at fixed (kappa, q1, q2).
Errors are checked by :mod:`atlas.core.exact` on a seeded sample, every undecided point (capped)
and the points where a method disagrees with the certified driver (capped).
"""

from __future__ import annotations

import time

import jax
import jax.numpy as jnp
import numpy as np

from atlas.bench.boundaries import contour_lines, masks, ss_margin
from atlas.bench.config import FLAGS, KEYS, UNDECIDED
from atlas.bench.timing import timeit
from atlas.core import exact, spectral
from atlas.core.contact_modes import direction
from atlas.core.points import spectral_points

__all__ = [
    "ExactCache",
    "grid_inputs",
    "measure_grid",
    "misclassified",
    "reference",
    "run_method",
]


def grid_inputs(n: int, kappa: float, q1: float, q2: float, dtype: str):
    """``beta`` and the broadcast inputs (:data:`~atlas.bench.config.KEYS`) of an ``(n+1) x (n+1)``
    beta grid on ``[0, 2 pi]`` (spacing ``2 pi / n``)."""
    beta = np.linspace(0.0, 2 * np.pi, n + 1)
    c1, s1 = direction(beta, dtype)
    c2, s2 = direction(beta, dtype)
    dt = np.dtype(dtype)
    return beta, (
        c1[:, None],
        s1[:, None],
        c2[None, :],
        s2[None, :],
        np.asarray(kappa, dt),
        np.asarray(q1, dt),
        np.asarray(q2, dt),
    )


def flat_points(args, shape, idx) -> dict:
    """The float64 inputs at flat indices ``idx`` of the broadcast grid, keyed by name."""
    return {
        k: np.broadcast_to(a, shape).ravel()[idx].astype(np.float64) for k, a in zip(KEYS, args)
    }


class ExactCache:
    """Exact verdicts (:func:`atlas.core.exact.point_spectral`) keyed by the float64 inputs; a
    point whose exact evaluation fails counts as undecided (``failures``)."""

    def __init__(self):
        self.store: dict = {}
        self.seconds = 0.0
        self.failures = 0

    def _point(self, key) -> tuple:
        r = self.store.get(key)
        if r is None:
            try:
                p = exact.point_spectral(*key)
                r = tuple(int(p[k]) for k in FLAGS)
            except ArithmeticError:
                self.failures += 1
                r = (UNDECIDED,) * len(FLAGS)
            self.store[key] = r
        return r

    def get(self, pts: dict, names=FLAGS) -> dict:
        """Verdicts ``names`` (int8 arrays) of the points ``pts`` (dict of float64 arrays)."""
        n = len(pts["c1"])
        out = {k: np.empty(n, np.int8) for k in names}
        t0 = time.perf_counter()
        for i in range(n):
            r = self._point(tuple(float(pts[k][i]) for k in KEYS))
            for j, k in enumerate(FLAGS):
                if k in names:
                    out[k][i] = r[j]
        self.seconds += time.perf_counter() - t0
        return out


def misclassified(fast: dict, ref: dict, names=FLAGS) -> tuple[int, int]:
    """``(misclassified, undecided)`` points: a point is misclassified if any *decided* verdict
    (code != 3) differs from the reference; undecided if any verdict is 3."""
    bad = np.zeros(len(ref[names[0]]), bool)
    und = np.zeros_like(bad)
    for k in names:
        f = np.asarray(fast[k]).ravel()
        decided = f != UNDECIDED
        bad |= decided & (f != np.asarray(ref[k]).ravel())
        und |= ~decided
    return int(bad.sum()), int(und.sum())


def _any_undecided(res: dict, names) -> np.ndarray:
    und = np.zeros(np.shape(res[names[0]]), bool)
    for k in names:
        und |= np.asarray(res[k]) == UNDECIDED
    return und


@jax.jit
def _floor(c1, s1, c2, s2, kappa, q1, q2):
    """The memory-bound floor: reads the same coordinates, writes 4 int8 outputs of the grid."""
    z = c1 * 0 + s1 * 0 + c2 * 0 + s2 * 0 + kappa * 0 + q1 * 0 + q2 * 0
    z = z.astype(jnp.int8)
    return z, z + 1, z + 2, z + 3


def run_method(method, args, names, dtype, damped) -> dict:
    """One evaluation by ``method`` (``certified``, ``eig`` or ``verdicts_jit``); the verdicts
    ``names`` as numpy arrays on the host (synchronised; the certified driver's counts in
    ``.stats``)."""
    if method == "certified":
        return spectral_points(*args, names=names, dtype=dtype, resolve=False)
    if method == "eig":
        return spectral_points(*args, names=names, dtype=dtype, method="eig")
    if method == "verdicts_jit":
        dev = [jnp.asarray(a) for a in args]
        if names == ("stable_SS",):
            res = spectral.verdicts_jit(*dev, ii=False)
        else:
            res = spectral.verdicts_jit(*dev, damped=None if damped else False)
        res = jax.block_until_ready(res)
        return {k: np.asarray(res[k]) for k in names}
    raise ValueError(f"method: must be certified, eig or verdicts_jit, got {method!r}")


def _time_methods(args, shape, names, methods, dtype, damped, cfg):
    """Seconds per grid and verdicts of every timed method, the driver's counts of the certified
    run, and the seconds of the floor kernel."""
    dev = [jnp.asarray(a) for a in args]
    t_floor = timeit(lambda: jax.block_until_ready(_floor(*dev)), budget=cfg["budget"] / 2)
    times, res, counts = {}, {}, {}
    for m in methods:
        if m == "certified+exact":
            continue
        box = {}

        def call(m=m, box=box):
            box["r"] = run_method(m, args, names, dtype, damped)
            box["c"] = getattr(box["r"], "stats", {})

        budget = cfg["budget"] / (2 if m == "eig" else 1)
        # up to 25 repeats where they fit the budget: a shared machine needs many for a stable minimum
        reps = dict(max_repeats=25, min_repeats=cfg.get("min_repeats", 2))
        times[m] = timeit(call, budget=budget, **reps)
        res[m] = {k: np.asarray(v).reshape(shape) for k, v in box["r"].items()}
        counts[m] = box.get("c", {})
    return times, res, counts.get("certified", {}), t_floor


def _capped(rng, idx, cap):
    return np.sort(rng.choice(idx, cap, replace=False)) if idx.size > cap else idx


def _points_to_check(res, shape, names, methods, cfg, rng, sample):
    """Flat indices of the checked points (sample, undecided, disagreements), of the sample
    and of the undecided points to settle; whether the undecided were capped."""
    und_idx = np.flatnonzero(_any_undecided(res["certified"], names))
    capped = und_idx.size > cfg["undecided_cap"]
    und_idx = _capped(rng, und_idx, cfg["undecided_cap"])
    npts = shape[0] * shape[1]
    samp = rng.choice(npts, min(sample, npts), replace=False)
    dis = []
    for m in methods:
        if m in ("certified", "certified+exact"):
            continue
        d = np.zeros(shape, bool)
        for k in names:
            c, o = res["certified"][k], res[m][k]
            d |= (c != UNDECIDED) & (o != UNDECIDED) & (c != o)
        di = np.flatnonzero(d)
        if di.size > cfg["disagree_cap"]:
            di = rng.choice(di, cfg["disagree_cap"], replace=False)
        dis.append(di)
    check = np.unique(np.concatenate([samp, und_idx, *dis]).astype(np.int64))
    return check, samp, und_idx, capped


def _settle(res, times, args, shape, names, und_idx, cache):
    """Add ``certified+exact``: the certified verdicts with ``und_idx`` settled exactly, timed
    as the certified time plus one exact run over those points (what ``resolve=True`` adds)."""
    t0 = time.perf_counter()
    settle = cache.get(flat_points(args, shape, und_idx), names) if und_idx.size else {}
    t_settle = time.perf_counter() - t0
    ce = {k: v.copy() for k, v in res["certified"].items()}
    for k in names:
        if und_idx.size:
            ce[k].ravel()[und_idx] = settle[k]
    res["certified+exact"] = ce
    times["certified+exact"] = times["certified"] + t_settle


def measure_grid(case, dtype, n, names, methods, cfg, cache, rng, *, sample):
    """Time and check every method on one grid.

    Returns ``(rows, verdicts per method, beta, args)``: one row per method with ns per point,
    the floor kernel's ns per point, misclassified points (all checked / the sample alone) and
    undecided points (whole grid).
    """
    name, kappa, q1, q2 = case
    beta, args = grid_inputs(n, kappa, q1, q2, dtype)
    shape = (n + 1, n + 1)
    npts = shape[0] * shape[1]
    damped = (q1 != 0) or (q2 != 0)
    times, res, counts, t_floor = _time_methods(args, shape, names, methods, dtype, damped, cfg)
    check, samp, und_idx, capped = _points_to_check(res, shape, names, methods, cfg, rng, sample)
    # the settlement is timed before the reference fills the cache with the checked points
    if "certified+exact" in methods:
        _settle(res, times, args, shape, names, und_idx, cache)
    ref = cache.get(flat_points(args, shape, check), names)
    insamp = np.isin(check, samp)
    undecided_before = int(_any_undecided(res["certified"], names).sum())
    rows = []
    for m in methods:
        fast = {k: res[m][k].ravel()[check] for k in names}
        bad, _ = misclassified(fast, ref, names)
        sub = ({k: v[insamp] for k, v in fast.items()}, {k: v[insamp] for k, v in ref.items()})
        rows.append(
            dict(
                case=name,
                dtype=dtype,
                n=n,
                h=2 * np.pi / n,
                points=npts,
                outputs="SS" if names == ("stable_SS",) else "all",
                method=m,
                seconds=times[m],
                ns_per_point=times[m] / npts * 1e9,
                floor_ns=t_floor / npts * 1e9,
                checked=int(check.size),
                misclassified=bad,
                sample=int(insamp.sum()),
                misclassified_sample=misclassified(*sub, names)[0],
                undecided=int(_any_undecided(res[m], names).sum()),
                undecided_before=undecided_before,
                settle_capped=bool(capped),
                roots_points=counts.get("roots_points", ""),
            )
        )
    return rows, res, beta, args


def reference(case, cfg, cache):
    """Reference boundaries of ``case``: float64 certified verdicts on a grid ``ref_factor`` times
    finer than the finest measured, every undecided point settled exactly, and the float64 SS
    margin on the same grid; their contours, and how many points were settled / left."""
    n = cfg["res"][-1] * cfg["ref_factor"]
    _, kappa, q1, q2 = case
    beta, args = grid_inputs(n, kappa, q1, q2, "float64")
    shape = (n + 1, n + 1)
    res = spectral_points(*args, names=FLAGS, dtype="float64", resolve=False)
    idx = np.flatnonzero(_any_undecided(res, FLAGS))
    if idx.size:
        ex = cache.get(flat_points(args, shape, idx))
        for k in FLAGS:
            res[k].ravel()[idx] = ex[k]
    left = sum(int((res[k] == UNDECIDED).sum()) for k in FLAGS)
    lines = {b: contour_lines(beta, m, 0.5) for b, m in masks(res, q1 != 0 or q2 != 0).items()}
    lines["SS_margin"] = contour_lines(beta, ss_margin(args), 0.0)
    return dict(n=n, beta=beta, lines=lines, settled=int(idx.size), left=left)
