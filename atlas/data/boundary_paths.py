"""Pieces as simple paths on the torus (step 8 of :mod:`atlas.data.boundaries`).

* **Wrapped.** Vertex coordinates are reduced into ``[0, 2 pi)`` (the tracing grid reaches a
  nudge past ``2 pi``); a piece is cut where it crosses a seam (the segment across the seam is
  dropped: each coordinate of every vertex stays a certified bracket midpoint).  A piece on the
  class line ``beta = 0`` itself, whose vertices lie on both sides of the seam, is put exactly on
  the line (moved by at most :data:`SEAM`; its side codes are those of the line).
* **Simple.** A piece that crosses or touches itself (a polyline that doubled back over a stretch,
  e.g. into a needle) is cut in halves until every part is simple (:mod:`shapely`
  ``is_simple``).
* **No stretch twice.** A vertex within ``chord`` of a segment of an earlier piece with the same
  codes running the same way (a stretch traced twice) is dropped, longest pieces first; two
  edges of a thin band run in opposite directions and are both kept.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import shapely

from atlas.data.boundary_curves import Curve

__all__ = ["simple_paths", "wrapped"]

TWO_PI = 2 * math.pi
#: distance [rad] within which a class-line piece running along a seam (``beta = 0``) is put on
#: it: its vertices lie on both sides of the seam within the on-line distance of the tracing
SEAM = 1e-6


def _sub(c: Curve, sl) -> Curve:
    return replace(
        c,
        vertices=c.vertices[sl],
        bracket=c.bracket[sl],
        ends=None if c.ends is None else c.ends[sl],
    )


def wrapped(c: Curve) -> list[Curve]:
    """``c`` with its vertices in ``[0, 2 pi)``, cut where it crosses a seam."""
    xy = np.where(c.vertices >= TWO_PI, c.vertices - TWO_PI, c.vertices)
    xy = np.where(xy < 0, xy + TWO_PI, xy)
    if c.on_class_line:  # a piece along a seam line beta = 0 is put on it, not on both sides
        seam = np.minimum(xy, TWO_PI - xy) <= SEAM
        xy = np.where(seam.all(0), 0.0, xy)
    w = replace(c, vertices=xy)
    jump = np.flatnonzero((np.abs(np.diff(xy, axis=0)) > math.pi).any(1))
    cuts = np.r_[0, jump + 1, len(xy)]
    return [_sub(w, slice(a, b)) for a, b in zip(cuts[:-1], cuts[1:]) if b - a >= 2]


def _simple_parts(c: Curve) -> list[Curve]:
    """``c`` cut in halves (sharing the middle vertex) until every part is simple."""
    if len(c.vertices) < 3 or shapely.is_simple(shapely.LineString(c.vertices)):
        return [c]
    mid = len(c.vertices) // 2
    return _simple_parts(_sub(c, slice(0, mid + 1))) + _simple_parts(_sub(c, slice(mid, None)))


def _codes(c: Curve):
    return (c.field, c.side_left, c.side_right, c.side_on, c.kappa, c.q1, c.q2)


def _unique(curves: list[Curve], chord: float) -> tuple[list[Curve], int]:
    """Drop the vertices that retrace an earlier piece (module docstring); returns the pieces
    and the number of vertices dropped."""
    out, dropped, seen = [], 0, {}
    for c in sorted(curves, key=lambda c: -len(c.vertices)):
        key = _codes(c)
        xy = c.vertices
        t = np.diff(xy, axis=0)
        t_v = np.concatenate([t[:1], t[:-1] + t[1:], t[-1:]])  # a direction at each vertex
        dup = np.zeros(len(xy), bool)
        for segs, dirs in seen.get(key, []):
            tree = shapely.STRtree(segs)
            pi, si = tree.query(shapely.points(xy), predicate="dwithin", distance=chord)
            same_way = np.sum(t_v[pi] * dirs[si], axis=1) > 0
            dup[pi[same_way]] = True
        keep = ~dup
        dropped += int(dup.sum())
        edges = np.flatnonzero(np.diff(np.r_[False, keep, False].astype(int)))
        for a, b in zip(edges[::2], edges[1::2]):
            if b - a >= 2:
                part = _sub(c, slice(a, b))
                out.append(part)
                v = part.vertices
                seen.setdefault(key, []).append(
                    (shapely.linestrings(np.stack([v[:-1], v[1:]], 1)), np.diff(v, axis=0))
                )
            else:
                dropped += int(b - a)
    return out, dropped


def simple_paths(curves: list[Curve], chord: float) -> tuple[list[Curve], int]:
    """The pieces wrapped, cut into simple parts, without stretches traced twice (module
    docstring); returns them and the number of vertices dropped as retraced."""
    parts = [s for c in curves for w in wrapped(c) for s in _simple_parts(w)]
    return _unique(parts, chord)
