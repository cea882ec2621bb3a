"""Drawn boundaries and their distance: contours of verdict masks and margins, Hausdorff distance.

The work-precision section measures how far the SS and II boundaries drawn from a coarse grid
lie from the same boundaries drawn from a finer reference grid (distances in radians of beta).
"""

from __future__ import annotations

import math

import contourpy
import numpy as np
from scipy.spatial import cKDTree

from atlas.core import kernels

__all__ = ["contour_lines", "hausdorff", "masks", "ss_margin", "torus_hausdorff"]


def contour_lines(beta, field, level):
    """Polylines (list of ``(m, 2)`` arrays, radians) of ``field == level`` on the grid
    ``beta x beta`` (marching squares with linear interpolation: contourpy, matplotlib's engine)."""
    gen = contourpy.contour_generator(beta, beta, np.asarray(field, np.float64).T)
    return [ln for ln in gen.lines(level) if len(ln) >= 2]


def _samples(lines, step, *, per_segment=False):
    """Points every ``<= step`` along the polylines, vertices included.

    ``per_segment=False``: each vertex once, ``(m, 2)``.  ``per_segment=True``: both ends of every
    segment, returned as ``(p, q, samples, seg)`` with the segments ``(p, q)`` and the index of
    each sample's segment.  A one-vertex line is a segment of length 0."""
    lines = [np.concatenate([ln, ln]) if len(ln) == 1 else ln for ln in lines if len(ln)]
    firsts = np.array([ln[0] for ln in lines]).reshape(-1, 2)
    p = np.concatenate([ln[:-1] for ln in lines])
    q = np.concatenate([ln[1:] for ln in lines])
    k = np.maximum(1, np.ceil(np.hypot(*(q - p).T) / step).astype(int))
    lo = 0 if per_segment else 1  # t = lo/k .. k/k on each segment
    m = k + 1 - lo
    seg = np.repeat(np.arange(len(p)), m)
    j = np.arange(int(m.sum())) - np.repeat(np.cumsum(m) - m, m) + lo
    pts = p[seg] + (j / k[seg])[:, None] * (q[seg] - p[seg])
    if per_segment:
        return p, q, pts, seg
    return np.concatenate([firsts, pts])


def _segment_distances(a_pts, p, q):
    """Distances from points ``a_pts`` to the segments ``(p, q)`` (row by row)."""
    d = q - p
    den = np.maximum((d * d).sum(1), 1e-300)
    t = np.clip(((a_pts - p) * d).sum(1) / den, 0, 1)
    return np.hypot(*(a_pts - p - t[:, None] * d).T)


def _directed(a_pts, b_lines, step, reduce=True):
    """max over points ``a`` of the distance to the polylines ``b``, exact: every point of a
    segment of ``b`` lies within ``step / 2`` of one of its samples (every ``<= step``), so a
    segment closer than ``d`` has a sample within ``d + step / 2``.  The segments of the 8
    nearest samples give ``d``; where a 9th sample lies within ``d + step / 2`` (a dense cluster
    of vertices next to a long segment), every sample in that ball is checked.
    ``reduce=False``: the distance of each point."""
    p, q, samples, seg = _samples(b_lines, step, per_segment=True)
    tree = cKDTree(samples)
    k = min(8, len(samples))
    dist, idx = tree.query(a_pts, k=k)
    dist, idx = dist.reshape(len(a_pts), k), idx.reshape(len(a_pts), k)
    best = np.full(len(a_pts), np.inf)
    for j in range(k):
        s = seg[idx[:, j]]
        best = np.minimum(best, _segment_distances(a_pts, p[s], q[s]))
    more = np.flatnonzero(dist[:, -1] <= best + 0.5 * step) if k < len(samples) else []
    if len(more):
        balls = tree.query_ball_point(a_pts[more], best[more] + 0.5 * step)
        i = np.repeat(more, [len(b) for b in balls])
        s = seg[np.concatenate(balls).astype(int)]
        np.minimum.at(best, i, _segment_distances(a_pts[i], p[s], q[s]))
    if not reduce:
        return best
    return float(best.max()) if len(best) else math.nan


def hausdorff(lines_a, lines_b, step):
    """Hausdorff distance [rad] between two sets of polylines (each densified to ``step`` and
    measured point-to-segment against the other); 0 if both are empty, NaN if one is."""
    if not lines_a or not lines_b:
        return math.nan if (lines_a or lines_b) else 0.0
    a, b = _samples(lines_a, step), _samples(lines_b, step)
    return max(_directed(a, lines_b, step), _directed(b, lines_a, step))


def _torus_copies(lines):
    """The polylines and their copies shifted by ``+-2 pi`` in each angle."""
    shifts = [
        np.array([x, y])
        for x in (-2 * math.pi, 0, 2 * math.pi)
        for y in (-2 * math.pi, 0, 2 * math.pi)
    ]
    return [ln + s for s in shifts for ln in lines]


def torus_hausdorff(lines_a, lines_b, step, quantile=1.0):
    """:func:`hausdorff` on the torus of angles (a curve traced on the seam ``beta = 0`` by one
    grid and on ``beta = 2 pi`` by another is the same curve); ``quantile < 1``: that quantile of
    the point-to-curve distances of both directions instead of their maximum.  A tuple of
    quantiles gives a tuple, the distances measured once."""
    many = isinstance(quantile, tuple)
    qs = quantile if many else (quantile,)
    if not lines_a or not lines_b:
        got = tuple(math.nan if (lines_a or lines_b) else 0.0 for _ in qs)
    else:
        a, b = _samples(lines_a, step), _samples(lines_b, step)
        d = np.concatenate(
            [
                _directed(a, _torus_copies(lines_b), step, reduce=False),
                _directed(b, _torus_copies(lines_a), step, reduce=False),
            ]
        )
        got = tuple(float(np.quantile(d, x)) for x in qs)
    return got if many else got[0]


def masks(res: dict, damped: bool) -> dict:
    """0/1 masks drawn as boundaries: SS stable (damped; neutral is measure-zero there) or
    stable-or-neutral (q = 0, drawn stable in Fig. 1), II consistent; undecided -> 0."""
    out = {}
    if "stable_SS" in res:
        ss = np.asarray(res["stable_SS"])
        out["SS"] = ((ss == 1) if damped else ((ss == 1) | (ss == 2))).astype(np.float64)
    if "consistent_II" in res:
        out["II"] = (np.asarray(res["consistent_II"]) == 1).astype(np.float64)
    return out


def ss_margin(args):
    """The smooth SS margin :func:`atlas.core.hurwitz.ss_margin` on the broadcast grid ``args``
    (float64 on the host), by the package's jitted kernel (``ss_margin`` of
    :data:`atlas.core.kernels.KERNELS`: one program, not its operations one by one); its zero
    contour is the SS boundary."""
    kernel = kernels.KERNELS["ss_margin"]
    return np.asarray(kernels.run(kernel, dict(zip(kernel.inputs, args)))["margin_SS"], np.float64)
