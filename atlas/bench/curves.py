"""The boundary-curve section: certified curves (:mod:`atlas.data.boundaries`) per slice, their
time, and their distance to the curves of a 4x finer grid, next to the grid contours' distance.

For each case and resolution ``n``: the curves of the ``n x n`` slice and of the ``4n x 4n``
reference slice (both certified: vertices within ``tol`` of the true boundary); the torus
Hausdorff distance [rad] between them, and between the reference and the marching-squares
contours of the ``n x n`` grid's codes (what a plot of the atlas draws).
"""

from __future__ import annotations

import math
import time

import numpy as np

from atlas.bench.boundaries import contour_lines, torus_hausdorff
from atlas.bench.timing import log
from atlas.core import brackets, points
from atlas.data import boundaries as bd

__all__ = ["CURVE_CASES", "curves"]

#: (name, kappa, q1, q2) of the slices measured
CURVE_CASES = (
    ("Fig. 1 (kappa=0.5, q=0)", 0.5, 0.0, 0.0),
    ("damped (kappa=2, q=0.1)", 2.0, 0.1, 0.1),
    ("one q=0 (kappa=0.5, q1=0.35, q2=0)", 0.5, 0.35, 0.0),
)


def _grid_contours(fld, n, model) -> list[np.ndarray]:
    """Marching-squares region boundaries of the ``n x n`` grid's codes (no refinement)."""
    beta = np.arange(n + 1) * (2 * math.pi / n)
    codes = brackets.field_codes(fld, beta[:, None], beta[None, :], *model)
    lines = []
    for a in np.unique(codes)[:-1]:
        lines += contour_lines(beta, (codes == a).astype(float), 0.5)
    return lines


def _slice(n, model, chord):
    """The curves of the ``n x n`` slice, their seconds and their certified work per tier
    (:func:`atlas.core.points.tally`)."""
    beta = np.arange(n) * (2 * math.pi / n)
    t0 = time.perf_counter()
    with points.tally() as work:
        out = bd.slice_boundaries(beta, beta, *model, chord=chord)
    return out, time.perf_counter() - t0, work


def curves(cfg) -> list[dict]:
    """Rows: case, n, field, curves, vertices, points, seconds (both fields), the slice's kernel
    calls and points per later tier (both fields, :func:`atlas.core.points.tally`), Hausdorff of
    the curves and of the grid contours to the 4n reference curves, hidden cells, unrefined,
    tips attached and unreached (of the n grid and of the reference)."""
    rows = []
    chord = cfg["curve_chord"]
    for name, *model in CURVE_CASES[: cfg.get("curve_cases", len(CURVE_CASES))]:
        for n in cfg["curve_res"]:
            log(f"curves {name} n={n} (reference {4 * n})")
            got, seconds, work = _slice(n, model, chord)
            ref, ref_seconds, _ = _slice(4 * n, model, chord)
            for fld in ("SS", "II"):
                mine = [c.vertices for c in got.curves if c.field == fld]
                theirs = [c.vertices for c in ref.curves if c.field == fld]
                step = min(1e-3, 2 * math.pi / (16 * n))
                grid = _grid_contours(fld, n, model)
                h_curves, p99_curves = torus_hausdorff(mine, theirs, step, quantile=(1.0, 0.99))
                h_grid, p99_grid = torus_hausdorff(grid, theirs, step, quantile=(1.0, 0.99))
                rows.append(
                    dict(
                        case=name,
                        n=n,
                        field=fld,
                        curves=len(mine),
                        vertices=sum(len(v) for v in mine),
                        points=len(got.points),
                        seconds=seconds,
                        reference_seconds=ref_seconds,
                        kernel_calls=work["calls"],
                        tier2_points=work["tier2_points"],
                        roots_points=work["roots_points"],
                        exact_points=work["exact_points"],
                        hausdorff_curves=h_curves,
                        hausdorff_grid=h_grid,
                        p99_curves=p99_curves,
                        p99_grid=p99_grid,
                        hidden_cells=got.attrs[f"{fld}_hidden_cells"],
                        tips_attached=got.attrs[f"{fld}_tips_attached"],
                        tips_unreached=got.attrs[f"{fld}_tips_unreached"],
                        reference_tips_unreached=ref.attrs[f"{fld}_tips_unreached"],
                        unrefined=got.attrs[f"{fld}_unrefined_segments"],
                        max_bracket=got.attrs[f"{fld}_max_bracket"],
                    )
                )
    return rows
