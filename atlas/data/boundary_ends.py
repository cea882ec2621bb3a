"""Curve ends: a drawn curve that stops short of the proven codimension-2 point it runs into is
extended to it, where the stretch between is proven a boundary; and every end with no curve and
no point near it is found (a stretch of boundary no curve covers).

A true boundary curve ends only at a codimension-2 point (where it meets others, or a class line)
or at the edge of the box.  A traced curve can stop short of one: its last segment's side labels
could not be proven (:func:`atlas.data.boundary_sides.label_pieces` drops it), as where a branch
arrives at a class line tangentially and the line's own codes come within the side step of it.
The stretch from such an end to the point is a boundary where, at samples along the segment
between them no farther than ``chord / 2`` [rad] apart, the certified codes (the same
:func:`atlas.core.brackets.field_codes` as every vertex's labels) a small offset ``e <= chord /
4`` to its left and right are the curve's two side codes: a boundary point lies within ``e`` of
each sample, so every point of the segment lies within ``e + chord / 4 < chord`` of the true
boundary (proven), and the curve's labels hold beside it.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import shapely

from atlas.core import brackets
from atlas.data.boundary_points import curve_segments, pairs_near

__all__ = [
    "CHORD_FRACTIONS",
    "MAX_SAMPLES",
    "SMALL_OFFSETS",
    "bridge",
    "dangling",
    "extend_to_points",
    "longest_segment",
    "proven_segment",
]

TWO_PI = 2 * math.pi
#: most samples along one extension (longer stretches are left, and reported by :func:`dangling`)
MAX_SAMPLES = 16384


def longest_segment(chord) -> float:
    """The longest segment [rad] :func:`proven_segment` samples (:data:`MAX_SAMPLES` samples
    ``chord / 2`` apart)."""
    return MAX_SAMPLES * chord / 2


def _torus_delta(a, b) -> np.ndarray:
    """``b - a`` [rad] taken the shorter way round the torus in each coordinate."""
    return (np.asarray(b, float) - np.asarray(a, float) + math.pi) % TWO_PI - math.pi


def _ends_near(curves, reach) -> np.ndarray:
    """Per curve, whether its first and last vertex lie within ``reach`` [rad] of a segment (or
    the lone vertex) of another curve of ``curves`` on the torus ``(n, 2)``
    (:func:`atlas.data.boundary_points.pairs_near`)."""
    a, d, owner, _ = curve_segments(curves)
    lone = [i for i, c in enumerate(curves) if len(c.vertices) == 1]
    a = np.concatenate([a] + [curves[i].vertices for i in lone])
    d = np.concatenate([d, np.zeros((len(lone), 2))])
    owner = np.concatenate([owner, np.asarray(lone, int)])
    ends = np.array([(c.vertices[0], c.vertices[-1]) for c in curves]).reshape(-1, 2)
    i, j = pairs_near(ends, a, d, reach)
    out = np.zeros(len(ends), bool)
    out[i[owner[j] != i // 2]] = True
    return out.reshape(-1, 2)


def _free_ends(curves, reach) -> set[tuple[int, int]]:
    """``(curve, end)`` (end 0 or -1) of the ends of ``curves`` that are no spliced point, not
    where their curve closes, and farther than ``reach`` [rad] from every other curve."""
    near = _ends_near(curves, reach)
    out = set()
    for i, c in enumerate(curves):
        v = c.vertices
        if len(v) < 2 or np.hypot(*_torus_delta(v[0], v[-1])) <= reach:
            continue
        for k, (end, at) in enumerate(((0, 0), (-1, len(v) - 1))):
            if at not in c.spliced and not near[i, k]:
                out.add((i, end))
    return out


def _nearest_point(xy, points) -> tuple[float, object]:
    """The distance [rad] on the torus from ``xy`` to the nearest of ``points``, and that point
    (``inf, None`` where there is none)."""
    best = (math.inf, None)
    for p in points:
        d = float(np.hypot(*_torus_delta(xy, (p.beta1, p.beta2))))
        if d < best[0]:
            best = (d, p)
    return best


#: offsets [rad] tried off each sample of a segment, largest first, as fractions of ``chord``:
#: ``1/4`` down to ``4^-9``; then ``2^-43 .. 2^-47`` rad (each above eight times the rounding of
#: a coordinate near ``2 pi``, as :data:`atlas.data.boundary_cover.NEEDLE_OFFSETS`)
CHORD_FRACTIONS = 4.0 ** -np.arange(1, 10)
SMALL_OFFSETS = 2.0 ** -np.arange(43, 48)


def proven_segment(c, a, b, chord, tol, dtype="float64") -> bool:
    """Whether the segment ``a -> b`` (the direction of travel of curve ``c``) is proven within
    ``chord`` [rad] of the boundary with ``c``'s side codes beside it (module docstring): at the
    middles of its ``ceil(2 |b - a| / chord)`` equal parts (not at its ends: a point, where three
    codes meet) the certified codes ``e`` to the left and right are ``c.side_left`` and
    ``c.side_right``, each sample for one ``e <= chord / 4`` of :data:`CHORD_FRACTIONS` times
    ``chord`` and :data:`SMALL_OFFSETS` (a needle: another boundary closer to it), tried in turn
    on the samples left while each proves some."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    d = b - a
    length = float(np.hypot(*d))
    n = max(2, math.ceil(2 * length / chord))
    if length == 0.0 or n > MAX_SAMPLES:
        return False
    at = a + ((np.arange(n) + 0.5) / n)[:, None] * d
    normal = np.array([-d[1], d[0]]) / length
    model = (c.kappa, c.q1, c.q2)
    for e in [*(chord * CHORD_FRACTIONS), *SMALL_OFFSETS]:
        xy = np.concatenate([at + e * normal, at - e * normal]) % TWO_PI
        codes = brackets.field_codes(c.field, xy[:, 0], xy[:, 1], *model, dtype=dtype)
        left, right = np.split(np.asarray(codes, int), 2)
        bad = (left != c.side_left) | (right != c.side_right)
        if not bad.any():
            return True
        if bad.all():  # no progress: a smaller offset proves no more here (a curve off it)
            return False
        at = at[bad]
    return False


def _extended(c, end, p, chord, tol, dtype):
    """Curve ``c`` with proven point ``p`` appended at ``end`` (0: before its first vertex) where
    the segment to it is proven (:func:`proven_segment`) and the curve stays simple; else
    ``None``.  The vertex is ``p``'s image nearest the end, taken into ``[0, 2 pi)`` (the shift
    added to its radius, which must stay within ``tol / 2``)."""
    v = c.vertices[end]
    img = v + _torus_delta(v, (p.beta1, p.beta2))
    xy = np.clip(img, 0.0, np.nextafter(TWO_PI, 0.0))
    radius = p.uncertainty + float(np.hypot(*(xy - img)))
    if not 2 * radius <= tol:
        return None
    a, b = (xy, v) if end == 0 else (v, xy)
    if not proven_segment(c, a, b, chord, tol, dtype):
        return None
    at = 0 if end == 0 else len(c.vertices)
    out = replace(
        c,
        vertices=np.insert(c.vertices, at, xy, axis=0),
        bracket=np.insert(c.bracket, at, 2 * radius),
        ends=None if c.ends is None else np.insert(c.ends, at, np.nan, axis=0),
        spliced=tuple(sorted([k + (end == 0) for k in c.spliced] + [at])),
    )
    return out if shapely.is_simple(shapely.LineString(out.vertices)) else None


def extend_to_points(curves, points, reach, within, chord, tol, dtype="float64"):
    """Each free end of ``curves`` (one field's: no other curve within ``reach`` [rad]) whose
    nearest proven point of ``points`` lies within ``within`` [rad] but farther than ``tol``,
    extended to that point where the segment is proven (:func:`_extended`).  Returns the curves
    (same order) and the number of extensions."""
    proven = [p for p in points if p.proven]
    out, n = list(curves), 0
    for i, end in sorted(_free_ends(out, reach)):
        d, p = _nearest_point(out[i].vertices[end], proven)
        got = _extended(out[i], end, p, chord, tol, dtype) if tol < d <= within else None
        if got is not None:
            out[i], n = got, n + 1
    return out, n


def _alike(a, b) -> bool:
    """Whether curves ``a`` and ``b`` carry the same labels (so ``a``'s last vertex may join
    ``b``'s first: both run with the higher code on the left)."""
    keys = ("field", "kind", "side_left", "side_right", "side_on", "on_class_line")
    same = all(getattr(a, k) == getattr(b, k) for k in keys)
    return same and math.isnan(a.side_offset) and math.isnan(b.side_offset)


def bridge(curves, reach, within, chord, tol, dtype="float64") -> list:
    """New two-vertex curves joining a free end of ``curves`` (one field's: no other curve within
    ``reach`` [rad]; a curve's last vertex) to the nearest free first vertex of another curve
    with the same labels (:func:`_alike`) within ``within`` [rad], where the segment between is
    proven (:func:`proven_segment`) and crosses no seam of the torus: a segment whose labels
    could not be proven at the side step dropped from a traced curve, its stretch proven
    now at samples ``chord / 2`` apart.  Each end is joined once."""
    free = _free_ends(curves, reach)
    out = []
    for i, c in enumerate(curves):
        if (i, -1) not in free:
            continue
        a = c.vertices[-1]
        cand = [
            (float(np.hypot(*_torus_delta(a, o.vertices[0]))), j)
            for j, o in enumerate(curves)
            if j != i and (j, 0) in free and _alike(c, o)
        ]
        cand = sorted(x for x in cand if x[0] <= within)
        if not cand:
            continue
        o = curves[cand[0][1]]
        b = o.vertices[0]
        if np.abs(a + _torus_delta(a, b) - b).max() > math.pi:  # across a seam
            continue
        if proven_segment(c, a, b, chord, tol, dtype):
            free -= {(i, -1), (cand[0][1], 0)}
            ends = None if c.ends is None or o.ends is None else np.stack([c.ends[-1], o.ends[0]])
            out.append(
                replace(c, vertices=np.stack([a, b]), ends=ends, spliced=(),
                        bracket=np.array([c.bracket[-1], o.bracket[0]]))
            )  # fmt: skip
    return out


def dangling(curves, points, reach) -> list[tuple[list[float], float]]:
    """The free ends of ``curves`` (one field's: no other curve within ``reach`` [rad]) with no
    point of ``points`` (proven or not) within ``reach`` either: where a drawn curve stops and the
    boundary goes on uncovered.  Per end ``([beta1, beta2], distance [rad] to the nearest proven
    point)``."""
    proven = [p for p in points if p.proven]
    ends = [curves[i].vertices[end] for i, end in sorted(_free_ends(curves, reach))]
    return [
        (xy.tolist(), _nearest_point(xy, proven)[0])
        for xy in ends
        if _nearest_point(xy, points)[0] > reach
    ]
