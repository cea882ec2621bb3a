"""Side labels of boundary pieces: the certified codes found just off a piece on each side, and
on the piece itself where it lies on a class line (step 7 of :mod:`atlas.data.boundaries`).

The traced run knows only the code of the region it bounds and the code at the far end of each
vertex's bracket, which along a class line is the line's own (degenerate) code, not the code
across it.  Here both ends of every segment are stepped :func:`side_step` off it along its normal, to
the left and to the right, and both points are evaluated (certified codes, settled exactly).  A
vertex of a piece on a class line is also projected onto the line and evaluated *on* it, with the
line's exact direction vectors (``(c2, s2) = +-(c1, s1)`` on ``beta2 = beta1 + k pi``, axis
vectors on ``beta = k pi/2``): a class line can carry a third code.  The pieces are then

* cut into runs of segments with the same ``(left, right, on)`` codes at both ends (a segment
  whose ends disagree holds a change of codes, ``<= chord`` long after refinement; a segment with
  the same code on both sides bounds nothing at that scale: both are dropped, and counted);
* oriented so that the higher code is on the left (``side_left > side_right``);
* merged where two pieces of one field lie on the same class line with the same codes and
  overlap (a line traced from the regions on both of its sides).
"""

from __future__ import annotations

import itertools
import math

import numpy as np

from atlas.core import brackets, contact_modes
from atlas.data.boundary_curves import Curve
from atlas.data.class_lines import LINE_GRADS, line_labels

__all__ = ["NO_CODE", "label_pieces", "normals", "on_line_codes", "side_step"]

#: ``side_on`` of a piece that carries no third code (off the class lines, or on a line whose
#: own code is one of its side codes)
NO_CODE = -1
#: the smallest step [rad] off a vertex: 1024 units in the last place of ``2 pi``
MIN_STEP = 2.0**-40


def side_step(tol: float) -> float:
    """Distance [rad] off a vertex at which its side codes are evaluated: ``4 tol`` (the vertex
    lies within ``tol / 2`` of the boundary), at least :data:`MIN_STEP`."""
    return max(4.0 * tol, MIN_STEP)


def normals(xy) -> np.ndarray:
    """Unit left normals ``(m - 1, 2)`` of the segments of a polyline ``(m, 2)``."""
    t = np.diff(np.asarray(xy, float), axis=0)
    t /= np.maximum(np.hypot(*t.T), 1e-300)[:, None]
    return np.stack([-t[:, 1], t[:, 0]], 1)


def _line_directions(xy, m) -> tuple[np.ndarray, ...]:
    """Direction vectors ``(c1, s1, c2, s2)`` of the projections of points ``xy`` onto class
    lines ``m`` (columns of :func:`atlas.data.class_lines.line_distances`), exactly on the line."""
    c1, s1 = contact_modes.direction(xy[:, 0])
    c2, s2 = contact_modes.direction(xy[:, 1])
    k = m % 5
    ca, sa = np.array([1.0, 0.0, -1.0, 0.0, 1.0]), np.array([0.0, 1.0, 0.0, -1.0, 0.0])
    axis1, axis2, diag = m < 5, (m >= 5) & (m < 10), m >= 10
    c1, s1 = np.where(axis1, ca[k], c1), np.where(axis1, sa[k], s1)
    c2, s2 = np.where(axis2, ca[k], c2), np.where(axis2, sa[k], s2)
    # on beta2 = beta1 + j pi (m = 11 + j): (c2, s2) = (-1)^j (c1, s1) at the projection's beta1
    j = np.where(diag, m - 11, 0)
    cd, sd = contact_modes.direction(0.5 * (xy[:, 0] + xy[:, 1] - j * math.pi))
    c1, s1 = np.where(diag, cd, c1), np.where(diag, sd, s1)
    sign = np.where(m == 11, 1.0, -1.0)
    c2, s2 = np.where(diag, sign * c1, c2), np.where(diag, sign * s1, s2)
    return c1, s1, c2, s2


def _codes(fld, xy, model, dtype) -> np.ndarray:
    return brackets.field_codes(fld, xy[:, 0], xy[:, 1], *model, dtype=dtype)


def on_line_codes(fld, xy, m, model, dtype) -> np.ndarray:
    """Certified codes exactly on class lines ``m`` at the projections of ``xy``."""
    out = np.empty(len(xy), np.int8)
    for start in range(0, len(xy), brackets.MAX_BATCH):
        part = slice(start, start + brackets.MAX_BATCH)
        dirs = _line_directions(xy[part], m[part])
        out[part] = brackets.direction_codes(fld, *dirs, *model, dtype=dtype)
    return out


def label_pieces(fld, curves, model, tol, near, dtype="float64") -> tuple[list[Curve], int]:
    """The pieces ``curves`` of one field and slice with evaluated side codes (module docstring):
    cut, oriented and merged; returns them and the number of segments dropped.

    Each segment is stepped :func:`side_step` off both of its end vertices along its normal; it
    keeps its codes if the two ends agree (left, right and, on a class line, on) and the two sides
    differ, else it holds a change of codes (a junction, a point where the boundary leaves the
    line) and is dropped.  Consecutive kept segments with the same codes form a piece."""
    if not curves:
        return [], 0
    step = side_step(tol)
    segs = [c for c in curves if len(c.vertices) >= 2]
    a = np.concatenate([c.vertices[:-1] for c in segs])
    b = np.concatenate([c.vertices[1:] for c in segs])
    n = np.concatenate([normals(c.vertices) for c in segs])
    pts = np.concatenate([a + step * n, b + step * n, a - step * n, b - step * n])
    la, lb, ra, rb = np.split(_codes(fld, pts, model, dtype), 4)
    on_line = np.concatenate([np.full(len(c.vertices) - 1, c.on_class_line) for c in segs])
    ends = np.concatenate([a, b])
    # the line of a vertex from its coordinates on the torus: the grid reaches a nudge past
    # 2 pi, where beta2 = beta1 + 2 pi (beta2 = beta1 on the torus) is no column of the lines
    torus = np.mod(ends, 2 * math.pi)
    m = np.where(np.tile(on_line, 2), line_labels(torus, near), -1)
    on = np.full(len(ends), NO_CODE, np.int8)
    if (m >= 0).any():
        on[m >= 0] = on_line_codes(fld, torus[m >= 0], m[m >= 0], model, dtype)
    on_a, on_b = np.split(on, 2)
    m_a, m_b = np.split(m, 2)
    good = (la == lb) & (ra == rb) & (on_a == on_b) & (m_a == m_b) & (la != ra)
    third = np.where((on_a == la) | (on_a == ra), NO_CODE, on_a)
    key = np.where(good, 0, 1)
    out, start = [], 0
    for c in segs:
        stop = start + len(c.vertices) - 1
        rows = [
            (bool(good[k]), int(la[k]), int(ra[k]), int(third[k]), int(m_a[k]))
            for k in range(start, stop)
        ]
        i = 0
        for (ok, lft, rgt, o, _), grp in itertools.groupby(rows):
            size = len(list(grp))
            if ok:
                out.append(_oriented(c, slice(i, i + size + 1), lft, rgt, o))
            i += size
        start = stop
    return _merged(out, near), int(key.sum())


def _oriented(c: Curve, run, left, right, on) -> Curve:
    """Vertices ``run`` of ``c`` as a piece with codes ``left``/``right``/``on``, reversed if
    needed so that the higher code is on the left."""
    xy, bracket = c.vertices[run], c.bracket[run]
    ends = None if c.ends is None else c.ends[run]
    if left < right:
        xy, bracket = xy[::-1], bracket[::-1]
        ends = None if ends is None else ends[::-1]
        left, right = right, left
    kind = str(brackets.boundary_kind(c.field, left, right)[()])
    return Curve(
        c.field, kind, left, right, xy, bracket, c.on_class_line, c.kappa, c.q1, c.q2, ends, on
    )


def _merged(curves: list[Curve], near) -> list[Curve]:
    """Pieces on one class line with the same codes whose ranges along the line overlap, merged
    into one (vertices sorted along the line, the higher code kept on the left)."""
    groups, rest = {}, []
    for c in curves:
        if not c.on_class_line:
            rest.append(c)
            continue
        lab = line_labels(c.vertices, near)
        if not (lab >= 0).any():
            rest.append(c)
            continue
        m = int(np.bincount(lab[lab >= 0]).argmax())
        groups.setdefault((m, c.side_left, c.side_right, c.side_on), []).append(c)
    for (m, *_), group in groups.items():
        g = LINE_GRADS[m] / math.hypot(*LINE_GRADS[m])
        along = np.array([-g[1], g[0]])  # the line's direction: its left is where g grows
        spans = sorted(
            (
                (float((c.vertices @ along).min()), float((c.vertices @ along).max()), c)
                for c in group
            ),
            key=lambda span: span[:2],
        )
        merged = []
        for lo, hi, c in spans:
            if merged and lo <= merged[-1][1]:
                merged[-1][1] = max(merged[-1][1], hi)
                merged[-1][2].append(c)
            else:
                merged.append([lo, hi, [c]])
        for _, _, parts in merged:
            rest.append(parts[0] if len(parts) == 1 else _union(parts, along))
    return rest


def _union(parts: list[Curve], along) -> Curve:
    """One piece from overlapping pieces on a line: their vertices sorted along it (in the
    direction of the first piece), duplicates dropped."""
    c = parts[0]
    xy = np.concatenate([p.vertices for p in parts])
    bracket = np.concatenate([p.bracket for p in parts])
    ends = None if c.ends is None else np.concatenate([p.ends for p in parts])
    t = xy @ along
    sign = 1.0 if (c.vertices[-1] - c.vertices[0]) @ along >= 0 else -1.0
    order = np.argsort(sign * t, kind="stable")
    keep = np.r_[True, np.diff(sign * t[order]) > 0]
    order = order[keep]
    return Curve(
        c.field,
        c.kind,
        c.side_left,
        c.side_right,
        xy[order],
        bracket[order],
        True,
        c.kappa,
        c.q1,
        c.q2,
        None if ends is None else ends[order],
        c.side_on,
    )
