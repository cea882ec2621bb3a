"""Completeness on the class lines: every stretch of a class line that is itself a boundary (the
codes just off it differ on its two sides) is covered by a curve, or added as one (step 9 of
:mod:`atlas.data.boundaries`).

Each class line is cut at *breaks*: the multiples of ``pi/2`` (where it crosses other class lines)
and every germ root of the field's boundary polynomials
(:func:`atlas.data.boundary_germs.germ_roots`; for SS the roots of
:func:`atlas.data.boundary_points.line_roots`, for II those of the discriminant of ``p`` and of
its resultant with the tie polynomial).  A boundary of the field meets a class line only at such
a root, so along each interval between breaks the codes beside the line are constant: one
certified evaluation on each side, at the interval's middle, decides whether the whole interval is
a boundary stretch.  Each sample is taken :data:`TIP_OFFSET` off the line (along ``beta2`` on a
diagonal) where :func:`atlas.data.boundary_germs.clear` proves that no boundary passes between
it and the line: then the classification of the interval is proven.  Where that fails (a boundary
runs closer to the line, as at vanishing damping) the samples are taken closer, in exact
arithmetic (:func:`atlas.data.boundary_germs.near_side_codes`); an interval where that fails too
is listed (``unproven``), unless it is shorter than ``2 tol`` (below the vertices' resolution,
as the gaps left in :func:`cover_lines`).

A stretch is covered where a curve segment of the field has both ends within ``distance`` of the
line (every point of the line between their projections is then within ``distance`` of it); the
uncovered parts are measured and added as curves on the line, exactly on it (bracket 0), with
their certified side codes: ``4 tol`` off the line where they hold there, else (a needle: another
boundary runs closer to the line, as near a tangency) at the offset :func:`proven_offset` proves
at each vertex, the curve's ``side_offset``, its ends at breaks spliced proven points.
"""

from __future__ import annotations

import math

import numpy as np

from atlas.core import brackets
from atlas.data import boundary_germs, boundary_sides
from atlas.data.boundary_curves import Curve, Point
from atlas.data.boundary_tips import TIP_OFFSET
from atlas.data.class_lines import line_frames, line_values

__all__ = ["cover_lines", "line_stretches", "uncovered"]

TWO_PI = 2 * math.pi
#: the torus line (index of :func:`atlas.data.boundary_points.line_roots`) of each frame index
#: (``beta = 2 pi`` is ``beta = 0``; ``beta2 = beta1 - pi`` is ``beta2 = beta1 + pi``)
_TORUS_LINE = {4: 0, 9: 5, 10: 12}


def _breaks(m, t0, t1, roots) -> np.ndarray:
    """Sorted breaks of frame ``m`` within ``[t0, t1]`` (module docstring): ``t0``, ``t1``, the
    multiples of ``pi/2`` and the root angles of its torus line."""
    quarter = np.arange(math.floor(t0 / (math.pi / 2)), math.ceil(t1 / (math.pi / 2)) + 1)
    line = _TORUS_LINE.get(m, m)
    own = [float(b.mid()) for k, b, _ in roots if k == line]
    t = np.unique(np.concatenate([[t0, t1], quarter * (math.pi / 2), own]))
    return t[(t >= t0) & (t <= t1)]


def _param(m, xy) -> np.ndarray:
    """The parameter along frame ``m`` of the projections of points ``xy`` (torus-wrapped)."""
    if m < 5:
        return xy[:, 1]
    if m < 10:
        return xy[:, 0]
    return xy[:, 0] + 0.5 * _wrapped_value(m, xy)


def _wrapped_value(m, xy) -> np.ndarray:
    """Line ``m``'s function (:func:`atlas.data.class_lines.line_values`) wrapped to
    ``[-pi, pi)``: the signed offset from the line on the torus (times ``sqrt 2`` on a diagonal)."""
    g = line_values(xy)[:, m]
    return (g + math.pi) % TWO_PI - math.pi


def _frames(box):
    """The frames of :func:`atlas.data.class_lines.line_frames`, without ``beta = 2 pi`` where
    ``beta = 0`` is in the box (the torus: the same line)."""
    frames = line_frames(box)
    have = {f[0] for f in frames}
    return [f for f in frames if not (f[0] in (4, 9) and f[0] - 4 in have)]


def line_stretches(fld, box, model, roots, tol, dtype="float64") -> tuple[list[tuple], list]:
    """The intervals of the class lines in ``box`` where the codes arbitrarily close to the line
    differ on its two sides: ``(m, base, direction, lo, hi, left, right)``, points ``base + t
    direction`` for ``lo <= t <= hi``, ``left``/``right`` the codes to the left and the right of
    ``direction`` (``beta2`` moved on a diagonal); and the intervals whose codes are not proven
    (module docstring), as ``[beta1, beta2]`` of their two ends [rad].  The codes are those
    :data:`TIP_OFFSET` off the line where :func:`atlas.data.boundary_germs.clear` proves them the
    side's, else the exact ones closer to it (:func:`atlas.data.boundary_germs.near_side_codes`:
    a boundary running closer to the line than the tip offset)."""
    rows, lefts, rights, fixed, unproven = [], [], [], {}, []
    for m, base, direction, _, t0, t1 in _frames(box):
        t = _breaks(m, t0, t1, roots)
        mid = 0.5 * (t[:-1] + t[1:])
        d = np.asarray(direction, float)
        off = np.array([-1.0, 0.0]) if m < 5 else np.array([0.0, 1.0])  # to the left of d
        on = np.asarray(base) + mid[:, None] * d
        lefts.append(on + TIP_OFFSET * off)
        rights.append(on - TIP_OFFSET * off)
        line = _TORUS_LINE.get(m, m)
        for lo, hi, u in zip(t[:-1], t[1:], mid):
            if hi - lo <= 2 * tol or boundary_germs.clear(fld, model, line, u, 2 * TIP_OFFSET):
                pass
            elif (near := boundary_germs.near_side_codes(fld, model, line, float(u))) is not None:
                fixed[len(rows)] = near[:2] if m < 5 else near[1::-1]  # delta < 0: left of d
            else:
                ends = _on_torus(m, np.asarray(base, float) + np.array([[lo], [hi]]) * d)
                unproven.append(ends.tolist())
            rows.append((m, base, direction, lo, hi))
    if not rows:
        return [], unproven
    xy = np.concatenate(lefts + rights)
    codes = brackets.field_codes(fld, xy[:, 0], xy[:, 1], *model, dtype=dtype)
    lft, rgt = (c.astype(int) for c in np.split(codes, 2))
    for k, (a, b) in fixed.items():
        lft[k], rgt[k] = a, b
    return [(*r, int(a), int(b)) for r, a, b in zip(rows, lft, rgt) if a != b], unproven


def uncovered(m, lo, hi, curves, distance) -> list[tuple[float, float]]:
    """The parts of ``[lo, hi]`` of frame ``m`` not within ``distance`` [rad] of a segment of
    ``curves`` whose two ends lie within ``distance`` of the line."""
    spans = []
    for c in curves:
        v = c.vertices
        if len(v) < 2:
            continue
        near = np.abs(_wrapped_value(m, v)) / math.hypot(*_grad(m)) <= distance
        seg = near[:-1] & near[1:]
        if seg.any():
            t = _param(m, v)
            spans.append(np.stack([np.minimum(t[:-1], t[1:]), np.maximum(t[:-1], t[1:])], 1)[seg])
    gaps, at = [], lo
    for a, b in sorted(map(tuple, np.concatenate(spans))) if spans else ():
        if b <= at:
            continue
        if a > at:
            gaps.append((at, min(a, hi)))
        at = b
        if at >= hi:
            break
    if at < hi:
        gaps.append((at, hi))
    return gaps


def _grad(m) -> tuple[float, float]:
    return (1.0, 0.0) if m < 5 else (0.0, 1.0) if m < 10 else (-1.0, 1.0)


def cover_lines(fld, box, model, curves, roots, distance, tol, dtype="float64"):
    """The class-line stretches of ``fld`` (:func:`line_stretches`) not covered by ``curves``
    within ``distance`` [rad] (:func:`uncovered`), as new curves exactly on the line: where the
    codes :func:`atlas.data.boundary_sides.side_step` off the line are the stretch's, one curve
    between :func:`_pulled` ends; the rest of each gap (a needle of another boundary closer to
    the line than the side step) as :func:`_needle` curves.  Returns them, the pieces still
    uncovered and the line intervals whose codes are not proven as points (kinds
    ``uncovered_class_line`` and ``unproven_class_line`` at their middle, not proven), and the
    stats ``(stretches, uncovered length [rad], length still uncovered [rad], unproven intervals,
    pieces)``, intervals and pieces as ``[beta1, beta2]`` of their two ends [rad].  A gap no
    longer than ``distance`` next to a covered part is left (each of its points is within ``2
    distance`` of a curve).  ``roots``: the germ roots of ``fld``
    (:func:`atlas.data.boundary_germs.germ_roots`)."""
    stretches, unproven = line_stretches(fld, box, model, roots, tol, dtype)
    marks = [_mark(fld, ends, "unproven_class_line", model) for ends in unproven]
    gaps, length = [], 0.0
    for m, base, direction, lo, hi, left, right in stretches:
        d = np.asarray(direction, float)
        t_max = _torus_end(base, d)
        for a, b in uncovered(m, lo, hi, curves, distance):
            a, b = min(a, t_max), min(b, t_max)  # beyond 2 pi: the torus's other end
            size = (b - a) * math.hypot(*d)
            if size <= 2 * tol or (size <= distance and (a > lo or b < hi)):
                continue  # below the vertices' resolution, or within 2 distance of a curve
            length += size
            gaps.append((m, np.asarray(base, float), d, a, b, left, right))
    if not gaps:
        return [], marks, (len(stretches), length, 0.0, unproven, [])
    ends, ok = _pulled(fld, gaps, model, tol, dtype)
    added, left, left_over, pieces = [], marks, 0.0, []
    for gap, (a, b), good in zip(gaps, ends, ok):
        m, base, d, a0, b0, lft, rgt = gap
        if good and b > a:
            xy = _on_torus(m, base + np.array([[a], [b]]) * d)
            added.append(_line_curve(fld, xy, m, lft, rgt, model, dtype))
        rest = [(a0, a), (b, b0)] if good and b > a else [(a0, b0)]
        for u, v in rest:
            if (v - u) * math.hypot(*d) <= 2 * tol:
                continue
            needle = _needle(fld, gap, u, v, model, roots, tol, dtype)
            if needle is not None:
                added.append(needle)
                continue
            left_over += (v - u) * math.hypot(*d)
            pieces.append(_on_torus(m, base[None] + np.array([[u], [v]]) * d[None]).tolist())
            left.append(_mark(fld, pieces[-1], "uncovered_class_line", model))
    return added, left, (len(stretches), length, left_over, unproven, pieces)


def _mark(fld, ends, kind, model) -> Point:
    """A point (not proven) of ``kind`` at the middle of a class-line piece with ``ends``
    ``[[beta1, beta2], [beta1, beta2]]`` [rad] (the shorter way round the torus)."""
    a, b = np.asarray(ends, float)
    mid = a + 0.5 * ((b - a + math.pi) % TWO_PI - math.pi)
    return Point(*(mid % TWO_PI), kind, math.nan, *model, field=fld)


#: offsets [rad] off a class line tried for the side labels of a :func:`_needle` piece, largest
#: first: 2^-43 (:data:`TIP_OFFSET`) to 2^-47, each above eight times the rounding of a
#: coordinate near ``2 pi`` (8.9e-16), so that a sample there lies on its side
NEEDLE_OFFSETS = 2.0 ** -np.arange(43, 48)


def proven_offset(fld, model, m, beta) -> float:
    """The largest of :data:`NEEDLE_OFFSETS` within half of which
    :func:`atlas.data.boundary_germs.clear` proves that no boundary of ``fld`` comes near frame
    ``m`` at parameter ``beta`` [rad] (so the codes at that offset are those arbitrarily close
    to the line there), else the largest ``2 atan(2^-k)`` (``k`` in
    :data:`atlas.data.boundary_germs.NEAR_EXPONENTS`, below ``2^-47``: a sample there is exact
    rational directions, not float coordinates) within which it proves it; 0 where none is."""
    line = _TORUS_LINE.get(m, m)
    smaller = [2 * math.atan(2.0**-k) for k in boundary_germs.NEAR_EXPONENTS if k > 47]
    for e in [*NEEDLE_OFFSETS, *smaller]:
        if boundary_germs.clear(fld, model, line, float(beta), 2 * float(e)):
            return float(e)
    return 0.0


def _break_radius(m, t, roots):
    """The proven distance [rad] from the vertex at parameter ``t`` of frame ``m`` (as
    :func:`_on_torus` places it) to the break it stands for: a germ root whose ball's middle is
    ``t`` (the ball's radius), or a multiple of ``pi/2``; plus the rounding of the parameter and
    of the coordinates (two units in the last place of ``2 pi`` along the line, times ``sqrt 2``
    on a diagonal, and one for the clipping below ``2 pi``).  ``None`` where ``t`` is no break."""
    line, ulp = _TORUS_LINE.get(m, m), math.ulp(TWO_PI)
    speed = math.sqrt(2.0) if m >= 10 else 1.0
    for k, b, _ in roots:
        if k == line and abs(float(b.mid()) - t) <= ulp:
            return speed * (float(b.rad()) + 2 * ulp) + ulp
    if abs(t - round(t / (math.pi / 2)) * (math.pi / 2)) <= ulp:
        return speed * 2 * ulp + ulp
    return None


def _needle(fld, gap, u, v, model, roots, tol, dtype) -> Curve | None:
    """A piece of the class-line stretch of ``gap`` from parameter ``u`` to ``v`` where the codes
    a side step off the line are not the stretch's (another boundary runs closer to the line),
    as a curve whose labels hold at its ``side_offset``: an end at a break (a germ root or a
    multiple of ``pi/2``: a proven codimension-2 point, :func:`_break_radius` within ``tol / 2``)
    is a spliced vertex; every other vertex
    (the other ends, and the middle where both ends are breaks) has its labels proven
    :func:`proven_offset` off the line, the smallest of those is the curve's ``side_offset``.
    The stretch's codes are those arbitrarily close to the line along the whole interval between
    its breaks (:mod:`atlas.data.boundary_germs`).  ``None`` where a vertex has no proven
    offset."""
    m, base, d, _, _, lft, rgt = gap
    radius = [_break_radius(m, t, roots) for t in (u, v)]
    radius = [r if r is not None and 2 * r <= tol else None for r in radius]
    ts = [u, v] if None in radius else [u, 0.5 * (u + v), v]
    radius = radius if None in radius else [radius[0], None, radius[1]]
    offsets = [proven_offset(fld, model, m, t) for t, r in zip(ts, radius) if r is None]
    if min(offsets) <= 0.0:
        return None
    xy = _on_torus(m, base + np.array(ts)[:, None] * d)
    bracket = np.array([0.0 if r is None else 2 * r for r in radius])
    spliced = tuple(k for k, r in enumerate(radius) if r is not None)
    return _line_curve(fld, xy, m, lft, rgt, model, dtype, bracket, spliced, min(offsets))


def _codes_at(fld, gaps, u, step, model, dtype):
    """Per gap (rows) and parameter ``u`` ``(n, k)`` along its line: whether the codes ``step``
    [rad] off the line to its left and right are the gap's ``left`` and ``right``, and the code
    on the line (:func:`atlas.data.boundary_sides.on_line_codes`)."""
    m = np.array([g[0] for g in gaps])
    base = np.array([g[1] for g in gaps])[:, None, :]
    d = np.array([g[2] for g in gaps])[:, None, :]
    n = np.concatenate([-d[..., 1:], d[..., :1]], -1) / np.hypot(d[..., :1], d[..., 1:])
    at = base + u[..., None] * d
    pts = np.concatenate([(at + step * n).reshape(-1, 2), (at - step * n).reshape(-1, 2)])
    lft, rgt = np.split(brackets.field_codes(fld, pts[:, 0], pts[:, 1], *model, dtype=dtype), 2)
    on = boundary_sides.on_line_codes(fld, at.reshape(-1, 2), np.repeat(m, u.shape[1]), model,
                                      dtype)  # fmt: skip
    sides = (lft.reshape(u.shape) == np.array([g[5] for g in gaps])[:, None]) & (
        rgt.reshape(u.shape) == np.array([g[6] for g in gaps])[:, None]
    )
    return sides, on.reshape(u.shape)


#: the most steps of :func:`_pulled`'s bisection per kernel call (``2^k - 1`` probes an end,
#: two side samples each), fewer where the probes would overflow one padded batch
#: (:data:`atlas.core.brackets.MIN_BATCH`)
PULL_STEPS = 6


def _bisection_tree(bad, ok, depth: int) -> np.ndarray:
    """Every parameter the next ``depth`` steps of a bisection between ``bad`` and ``ok`` (arrays
    of any shape) can probe, in heap order along a new last axis (``2^depth - 1``: node ``h``'s
    children are ``2 h`` where the probe has the labels, the new ``ok``, and ``2 h + 1`` where
    not), each computed as the bisection computes it, ``0.5 * (bad + ok)`` of its own interval."""
    lo, hi, nodes = bad[..., None], ok[..., None], []
    for _ in range(depth):
        u = 0.5 * (lo + hi)
        nodes.append(u)
        lo = np.stack([lo, u], -1).reshape(*u.shape[:-1], -1)  # children 2h: ok = u; 2h+1: bad = u
        hi = np.stack([u, hi], -1).reshape(*u.shape[:-1], -1)
    return np.concatenate(nodes, -1)


def _pulled(fld, gaps, model, tol, dtype):
    """The gaps' ends ``(a, b)`` moved towards their middle, by bisection to ``tol``, until the
    codes :func:`atlas.data.boundary_sides.side_step` off the line on both sides and on it are
    those of the middle (at a root the boundary that meets the line changes them within a needle
    along it): every vertex of the added curve carries its labels.  Returns the ends and, per
    gap, whether its middle carries them (else the gap is not added).

    The bisection runs several steps per kernel call: every parameter the next steps can probe
    (:func:`_bisection_tree`) is evaluated at once, then the steps are taken on those codes, the
    same steps (and the same floats) as one call a step."""
    step = boundary_sides.side_step(tol)
    a, b = np.array([g[3] for g in gaps]), np.array([g[4] for g in gaps])
    mid = 0.5 * (a + b)
    speed = np.array([math.hypot(*g[2]) for g in gaps])
    sides, on = _codes_at(fld, gaps, np.stack([mid, a, b], 1), step, model, dtype)
    good = sides & (on == on[:, :1])
    bad = np.stack([a, b], 1)  # per end: a parameter without the labels (or the end itself)
    ok = np.stack([mid, mid], 1)  # ... and one with them
    steps = 0
    while steps < 64:
        live = ~good[:, 1:] & (np.abs(ok - bad) * speed[:, None] > tol)
        if not live.any():
            break
        rows = np.flatnonzero(live.any(1))
        fit = int(math.log2(brackets.MIN_BATCH // (4 * rows.size) + 1))
        depth = max(1, min(PULL_STEPS, fit, 64 - steps))
        u = _bisection_tree(bad[rows], ok[rows], depth)  # (rows, 2, 2^depth - 1)
        s, o = _codes_at(fld, [gaps[r] for r in rows], u.reshape(rows.size, -1), step, model,
                         dtype)  # fmt: skip
        g = np.zeros((len(gaps), 2, u.shape[-1]), bool)
        g[rows] = (s & (o == on[rows, :1])).reshape(u.shape)
        h = np.ones((len(gaps), 2), int)  # the heap node each end's next step probes
        for _ in range(depth):
            live = ~good[:, 1:] & (np.abs(ok - bad) * speed[:, None] > tol)
            if not live.any():
                break
            at = np.take_along_axis(g, (h - 1)[..., None], -1)[..., 0]
            u = 0.5 * (bad + ok)
            ok, bad = np.where(live & at, u, ok), np.where(live & ~at, u, bad)
            h = 2 * h + ~at
            steps += 1
    ends = np.where(good[:, 1:], np.stack([a, b], 1), ok)
    return ends, good[:, 0]


def _torus_end(base, d) -> float:
    """The largest parameter of the line ``base + t d`` whose points are short of ``2 pi`` in
    both coordinates (a line at ``beta = 2 pi`` counts as ``beta = 0``)."""
    t = [(TWO_PI - b) / v for b, v in zip(base, d) if v > 0]
    return math.nextafter(min(t), 0.0) if t else math.inf


def _on_torus(m, xy) -> np.ndarray:
    """Points of frame ``m`` with a line at ``beta = 2 pi`` moved to ``beta = 0``, and a
    coordinate rounded up to ``2 pi`` a float short of it."""
    xy = np.minimum(xy, math.nextafter(TWO_PI, 0.0))
    if m in (4, 9):
        xy[:, m // 5] = 0.0
    return xy


def _line_curve(fld, xy, m, left, right, model, dtype, bracket=None, spliced=(), offset=math.nan):
    """A curve on class line ``m`` through ``xy`` with codes ``left``/``right`` (of the direction
    of travel), reversed if needed so that the higher code is on the left; ``side_on`` the code
    on the line where it differs from both (:mod:`boundary_sides`); ``bracket`` per vertex (0:
    exactly on the line), ``spliced`` the vertices that are proven points, ``offset`` the
    curve's ``side_offset``."""
    mid = 0.5 * (xy[:1] + xy[-1:])
    on = int(boundary_sides.on_line_codes(fld, mid, np.array([m]), model, dtype)[0])
    bracket = np.zeros(len(xy)) if bracket is None else bracket
    if left < right:
        xy, bracket, left, right = xy[::-1], bracket[::-1], right, left
        spliced = tuple(sorted(len(xy) - 1 - k for k in spliced))
    third = boundary_sides.NO_CODE if on in (left, right) else on
    kind = str(brackets.boundary_kind(fld, left, right)[()])
    return Curve(fld, kind, left, right, xy, bracket, True, *model, None, third, spliced, offset)
