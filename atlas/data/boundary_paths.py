"""Pieces as simple paths on the torus (step 8 of :mod:`atlas.data.boundaries`).

* **Wrapped.** Vertex coordinates are reduced into ``[0, 2 pi)`` (the tracing grid reaches a
  nudge past ``2 pi``); a piece is cut where it crosses a seam, both parts ending at the point
  where the segment crosses it (interpolated on the segment, like any point of a chord: its
  ``bracket`` is NaN, it has no certified bracket; on the far side of the seam the coordinate
  is written ``nextafter(2 pi, 0)``).
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


def _sub(c: Curve, sl) -> Curve:
    return replace(
        c,
        vertices=c.vertices[sl],
        bracket=c.bracket[sl],
        ends=None if c.ends is None else c.ends[sl],
    )


def wrapped(c: Curve) -> list[Curve]:
    """``c`` with its vertices in ``[0, 2 pi)``, cut where it crosses a seam; the two parts end
    at the crossing point, interpolated on the segment (``bracket`` and ``ends`` NaN)."""
    raw = c.vertices
    turns = np.floor(raw / TWO_PI)
    cross = np.flatnonzero((turns[1:] != turns[:-1]).any(1))
    if not len(cross) and not turns.any():
        return [c]
    xy, bracket = [], []
    ends = [] if c.ends is not None else None
    nan_ends = np.full((2, 2), np.nan)
    pieces, start = [], 0
    for k in list(cross) + [len(raw) - 1]:
        part = slice(start, k + 1)
        xy = list(raw[part] - TWO_PI * turns[part])
        bracket = list(c.bracket[part])
        if ends is not None:
            ends = list(c.ends[part] - TWO_PI * turns[part][:, None, :])
        if start > 0:  # begins at the previous crossing point
            xy.insert(0, pieces[-1][3])
            bracket.insert(0, np.nan)
            if ends is not None:
                ends.insert(0, nan_ends)
        nxt = None
        if k < len(raw) - 1:  # ends at the crossing point of segment k
            a, b = raw[k], raw[k + 1]
            j = int(np.flatnonzero(turns[k] != turns[k + 1])[0])
            seam = TWO_PI * max(turns[k, j], turns[k + 1, j])
            t = (seam - a[j]) / (b[j] - a[j])
            point = a + t * (b - a)
            point[j] = seam
            here = point - TWO_PI * turns[k]
            here[j] = math.nextafter(TWO_PI, 0.0) if turns[k, j] < turns[k + 1, j] else 0.0
            nxt = point - TWO_PI * turns[k + 1]
            nxt[j] = 0.0 if turns[k, j] < turns[k + 1, j] else math.nextafter(TWO_PI, 0.0)
            xy.append(here)
            bracket.append(np.nan)
            if ends is not None:
                ends.append(nan_ends)
        pieces.append((np.array(xy), np.array(bracket), ends, nxt))
        start = k + 1
    out = []
    for v, w, e, _ in pieces:
        v = np.mod(v, TWO_PI)  # the other coordinate of a crossing point near a corner
        v = np.where(v >= TWO_PI, math.nextafter(TWO_PI, 0.0), v)
        keep = np.r_[True, (np.diff(v, axis=0) != 0).any(1)]
        e = None if e is None else np.array(e)[keep]
        part = replace(c, vertices=v[keep], bracket=w[keep], ends=e)
        # a segment that still jumps across the box (through a corner of the torus) is cut
        jump = np.flatnonzero((np.abs(np.diff(part.vertices, axis=0)) > math.pi).any(1))
        cuts = np.r_[0, jump + 1, len(part.vertices)]
        out += [_sub(part, slice(a, b)) for a, b in zip(cuts[:-1], cuts[1:]) if b - a >= 2]
    return out


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
        for segs, dirs, tips in seen.get(key, []):
            tree = shapely.STRtree(segs)
            pi, si = tree.query(shapely.points(xy), predicate="dwithin", distance=chord)
            same_way = np.sum(t_v[pi] * dirs[si], axis=1) > 0
            # where two pieces meet end to start, the shared vertex is no retrace
            at_tip = np.hypot(*(xy[pi, None, :] - tips[None, :, :]).transpose(2, 0, 1)).min(-1)
            dup[pi[same_way & (at_tip > chord)]] = True
        keep = ~dup
        dropped += int(dup.sum())
        edges = np.flatnonzero(np.diff(np.r_[False, keep, False].astype(int)))
        for a, b in zip(edges[::2], edges[1::2]):
            if b - a >= 2:
                part = _sub(c, slice(a, b))
                out.append(part)
                v = part.vertices
                seen.setdefault(key, []).append(
                    (
                        shapely.linestrings(np.stack([v[:-1], v[1:]], 1)),
                        np.diff(v, axis=0),
                        v[[0, -1]],
                    )
                )
            else:
                dropped += int(b - a)
    return out, dropped


def simple_paths(curves: list[Curve], chord: float) -> tuple[list[Curve], int]:
    """The pieces wrapped, cut into simple parts, without stretches traced twice (module
    docstring); returns them and the number of vertices dropped as retraced."""
    parts = [s for c in curves for w in wrapped(c) for s in _simple_parts(w)]
    return _unique(parts, chord)
