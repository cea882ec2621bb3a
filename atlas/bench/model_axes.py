"""The 2-D rate against grids over the model axes, and the points each tier receives.

The headline rows time one 2-D beta grid at one model.  The grids ``atlas generate`` writes also
span ``kappa, q1, q2``; here a 2-D grid and a 5-D grid laid out as ``atlas generate`` lays it out,
``(beta1, beta2, kappa, q1, q2)``, run through the certified driver
(:func:`atlas.core.points.spectral_points`, the three flag verdicts, exact settlement), each the
minimum of repeats after compilation, in the same run: the ratios are what count.  Every row
carries the driver's own counts of the points each tier received (``Verdicts.stats``).
"""

from __future__ import annotations

import numpy as np

from atlas.bench.config import FLAGS
from atlas.bench.timing import log, timeit
from atlas.core.contact_modes import direction
from atlas.core.points import spectral_points

__all__ = ["MODELS", "TIER_KEYS", "model_grid_inputs", "measure"]

#: the model axes of the 5-D grid: kappa log 0.1-10 (8 values), q1 {0.05, 0.2}, q2 {0.1, 0.3}
MODELS = (np.geomspace(0.1, 10.0, 8), (0.05, 0.2), (0.1, 0.3))
#: the 2-D grids' one model (that of the headline's damped cases)
MODEL_2D = (0.5, 0.1, 0.1)
#: row key -> the driver's count (``Verdicts.stats``) of the points each tier received
TIER_KEYS = {
    "first_pass": "points",
    "tier2": "tier2_points",
    "enclosures": "roots_points",
    "exact": "undecided_before",
    "left": "undecided_after",
}


def model_grid_inputs(n: int, dtype: str, models=MODEL_2D) -> tuple:
    """Broadcastable inputs of an ``n x n`` beta grid (``linspace(0, 2 pi, n)`` in both angles)
    times the model axes ``models`` = ``(kappa, q1, q2)``: scalars give a 2-D grid, sequences
    the axes ``(beta1, beta2, kappa, q1, q2)`` of a 5-D grid."""
    beta = np.linspace(0.0, 2 * np.pi, n)
    c, s = direction(beta, dtype)
    if all(np.ndim(m) == 0 for m in models):
        return (
            c[:, None],
            s[:, None],
            c[None, :],
            s[None, :],
            *(np.asarray(m, dtype) for m in models),
        )

    def axis(a, d):
        return np.asarray(a, dtype).reshape([-1 if i == d else 1 for i in range(5)])

    return (
        axis(c, 0),
        axis(s, 0),
        axis(c, 1),
        axis(s, 1),
        *(axis(m, 2 + i) for i, m in enumerate(models)),
    )


def _grids(cfg) -> list[tuple[str, int, tuple]]:
    """``(label, n, models)`` of the grids of ``cfg["model_grids"]``: the 2-D sizes, then the 5-D
    beta size."""
    spec = cfg["model_grids"]
    out = [(f"2-D {n}^2 (kappa 0.5, q 0.1)", n, MODEL_2D) for n in spec["two_d"]]
    n5 = spec["five_d"]
    out.append((f"5-D {n5}^2 x 8 kappa x 2 q1 x 2 q2", n5, MODELS))
    return out


def measure(cfg) -> list[dict]:
    """One row per grid and dtype: ns per point (certified + exact settlement), the ratio to the
    first 2-D grid of the same dtype and float32 / float64 of the same grid, and the points
    each tier received (:data:`TIER_KEYS`)."""
    if not cfg.get("model_grids"):
        return []
    rows = []
    for dtype in cfg["dtypes"]:
        for label, n, models in _grids(cfg):
            args = model_grid_inputs(n, dtype, models)
            box = {}

            def call(args=args, dtype=dtype, box=box):
                box["r"] = spectral_points(*args, names=FLAGS, dtype=dtype, resolve=True)

            log(f"model grids: {label} {dtype}")
            seconds = timeit(call, budget=cfg["budget"], min_repeats=3, max_repeats=5)
            stats = box["r"].stats
            row = dict(grid=label, dtype=dtype, points=stats["points"], seconds=seconds)
            row["ns_per_point"] = seconds / stats["points"] * 1e9
            row.update({k: stats[v] for k, v in TIER_KEYS.items()})
            rows.append(row)
    _ratios(rows)
    return rows


def _ratios(rows) -> None:
    """``over_2d``: ns/point over the first 2-D row of the same dtype; ``f32_over_f64``: the
    float32 row over the float64 row of the same grid (in place)."""
    first = {}
    for r in rows:
        first.setdefault(r["dtype"], r["ns_per_point"])
        r["over_2d"] = r["ns_per_point"] / first[r["dtype"]]
    f64 = {r["grid"]: r["ns_per_point"] for r in rows if r["dtype"] == "float64"}
    for r in rows:
        r["f32_over_f64"] = (
            r["ns_per_point"] / f64[r["grid"]]
            if r["dtype"] == "float32" and r["grid"] in f64
            else ""
        )
