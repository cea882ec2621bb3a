"""Every algebraic root on the class lines accounted for: a point where the field's codes next to
the line change (a boundary point, codimension 2), or proven to be none.

A root ``r`` of a field's line-restricted polynomials (:func:`atlas.data.boundary_points.line_roots`)
is compared with the codes arbitrarily close to the line on both sides, proven on the two
neighbouring intervals between breaks (:func:`atlas.data.boundary_germs.near_side_codes`, sampled
a quarter of the way to the nearest other break: a germ root, a line root or a multiple of
``pi/2``):

* ``point``: a proven point is listed at ``r`` (:func:`atlas.data.boundary_points.ss_line_points`:
  a code next to the line changes near it), or a code changes across ``r`` on a side: ``r`` lies
  in the closure of two regions of different codes (proven);
* ``not_boundary``: no code changes across ``r``, ``r`` is no multiple of ``pi/2``, and exactly
  one boundary polynomial's germ ``g_0`` (:mod:`atlas.data.boundary_germs`) vanishes at ``r``,
  simply (its derivative's ball excludes 0).  Then the zero set near ``r`` is the line and one
  smooth branch through it (implicit function theorem), the two sectors on each side of the line
  reach the two neighbouring intervals, and both carry the same code: no code changes near ``r``
  off the line (proven);
* ``not_boundary`` (SS) also where a coefficient of ``p`` (paper eq. 9) is negative at ``r`` (its
  ball excludes 0): then it is negative on a neighbourhood of ``r``, and a polynomial whose roots
  all have ``Re <= 0`` has no negative coefficient (a product of ``l + a`` and ``l^2 + 2 a l + b``
  with ``a, b >= 0``), so every point there is SS unstable: one code, whatever boundary
  polynomials vanish at ``r`` and however often (proven); II also where every coefficient of
  ``p`` is positive at ``r`` or vanishes on the whole slice (``a3``, ``a1`` at ``q1 = q2 = 0``):
  then ``p(l) > 0`` for ``l > 0`` on a neighbourhood of ``r``, no real root ``l > 0``, every
  point there II inconsistent (proven);
* II, where none of the above holds: from the branches of the boundaries through ``r``
  (:func:`atlas.data.boundary_branches.decide`: each vanishing germ's zero set a graph over the
  line, the codes of the sectors between them sampled exactly):
  ``not_boundary`` where each side carries one code, ``point`` (``touches_class_line``) where a
  boundary touches the line there (proven);
* ``class_crossing``: ``r`` is a multiple of ``pi/2``, where class lines cross (a vertex of the
  closed-form class lines; the codes around it are not examined here);
* ``undecided``: anything else (a germ whose derivative across the line vanishes at ``r`` too,
  two branches into one quadrant that the chart cannot tell apart, or a sample without a proven
  offset).
"""

from __future__ import annotations

import math
from dataclasses import replace

import flint
import numpy as np

from atlas.data import (
    boundary_branches,
    boundary_germs,
    boundary_points,
    class_lines,
    root_frames,
)
from atlas.data.boundary_curves import Curve, Point

__all__ = [
    "KINDS",
    "REASONS",
    "account_roots",
    "attach",
    "distinct",
    "ii_root_account",
    "ss_root_account",
    "superseded",
]

#: the verdicts of :func:`account_roots`
KINDS = ("point", "not_boundary", "class_crossing", "undecided")
#: why a root is left undecided: the key is stored as its point's ``reason``
#: (:data:`atlas.data.boundary_branches.REASONS` for II roots the branches do not decide)
REASONS = {
    "no_offset": "the codes next to the line beside the root have no proven offset",
    "ss_multiple": "several boundary polynomials vanish at the root, or one vanishes twice, and"
    " no coefficient of p is proven negative there",
    "unseparated": "another break of the line lies within 1e-12 rad and the root's enclosure"
    " holds other than one exact root",
} | boundary_branches.REASONS
_QUARTER = math.pi / 2


def _simple_single(fld, model, m, ball) -> bool:
    """Whether exactly one boundary polynomial's germ ``g_0`` can vanish at the root ``ball``
    [rad] of line ``m``, and its derivative cannot (256-bit balls)."""
    with flint.ctx.workprec(256):
        t = (ball / 2).tan()
        vanishing = 0
        for rows in boundary_germs.germs(fld, m, model):
            g0 = flint.arb_poly(list(rows[0].coeffs()))
            if g0(t).contains(0):
                vanishing += 1
                if g0.derivative()(t).contains(0):
                    return False
        return vanishing == 1


def _unstable_near(model, m, ball) -> bool:
    """Whether a coefficient of ``p`` can be proven negative at the root ``ball`` [rad] of line
    ``m`` (256-bit balls; module docstring)."""
    with flint.ctx.workprec(256):
        t = (ball / 2).tan()
        polys = boundary_germs.coefficients_on_line(m, model)
        return any(flint.arb_poly(list(a.coeffs()))(t) < 0 for a in polys)


def _inconsistent_near(model, m, ball) -> bool:
    """Whether every coefficient of ``p`` can be proven positive at the root ``ball`` [rad] of
    line ``m``, or vanishes on the whole slice (256-bit balls; module docstring)."""
    undamped = model[1] == 0 and model[2] == 0
    with flint.ctx.workprec(256):
        t = (ball / 2).tan()
        polys = boundary_germs.coefficients_on_line(m, model)
        return all(
            (undamped and k in (0, 2)) or flint.arb_poly(list(a.coeffs()))(t) > 0
            for k, a in enumerate(polys)
        )


def _verdict(fld, model, m, ball, listed, others) -> tuple[str, str | None, flint.arb]:
    """The verdict of one root (module docstring) and, for a ``point`` found here, its kind:
    ``crosses_class_line`` where the codes next to the line change across the root on both
    sides, ``leaves_class_line`` on one, ``touches_class_line`` where they change on neither
    but a boundary touches the line there (:func:`atlas.data.boundary_branches.decide`, II); for
    ``undecided``, the reason (a key of :data:`REASONS`); and the root's enclosure [rad]
    (256 bits where its frame is exact, :mod:`atlas.data.root_frames`)."""
    if listed:
        return "point", None, ball
    fr = root_frames.frame(fld, model, m, ball, others)
    if fr is None:
        return "undecided", "unseparated", ball
    got, why = _decided(fld, model, m, fr)
    return got, why, fr.beta


def _decided(fld, model, m, fr) -> tuple[str, str | None]:
    """:func:`_verdict` in the root's frame ``fr``: the codes next to the line sampled at
    ``beta -+ h`` (:func:`atlas.data.root_frames.sample`), offsets at most ``h``."""
    near = [
        boundary_germs.near_side_codes(
            fld, model, m, float(fr.beta.mid()) + s * fr.h, root_frames.sample(fr, s * fr.h), fr.h
        )
        for s in (-1, 1)
    ]
    if None not in near and near[0][:2] != near[1][:2]:
        both = near[0][0] != near[1][0] and near[0][1] != near[1][1]
        return "point", ("leaves_class_line", "crosses_class_line")[both]
    if fr.crossing:
        return "class_crossing", None
    if None not in near and _simple_single(fld, model, m, fr.beta):
        return "not_boundary", None
    if fld == "SS" and _unstable_near(model, m, fr.beta):
        return "not_boundary", None
    if fld == "II" and _inconsistent_near(model, m, fr.beta):
        return "not_boundary", None
    if None in near:
        return "undecided", "no_offset"
    if fld == "SS":
        return "undecided", "ss_multiple"
    got, reason = boundary_branches.decide(fld, model, m, fr, near)
    if got is None:
        return "undecided", reason
    return ("point", got) if got == "touches_class_line" else (got, None)


def _account(fld, model, roots, germ_roots, listed) -> list[tuple]:
    """:func:`account_roots` with each verdict's side changes and enclosure (:func:`_verdict`)."""
    model = tuple(float(v) for v in model)
    breaks = [*roots, *germ_roots]
    return [
        _verdict(fld, model, m, ball, bool(on), [float(b.mid()) for k, b, _ in breaks if k == m])
        for (m, ball, _), on in zip(roots, listed)
    ]


def account_roots(fld, model, roots, germ_roots, listed) -> list[str]:
    """Per root ``(m, beta ball, multiplicity)`` of ``roots`` (the format of
    :func:`atlas.data.boundary_points.line_roots`), its verdict in :data:`KINDS` (module
    docstring); ``germ_roots``: the field's germ roots
    (:func:`atlas.data.boundary_germs.germ_roots`), breaks of the lines; ``listed``: per root,
    whether a proven point stands at it."""
    return [v for v, _, _ in _account(fld, model, roots, germ_roots, listed)]


def _undecided(fld, model, roots, found) -> list[Point]:
    """The undecided roots as points (kind ``undecided_line_root``, not proven, at the root's
    middle, with the reason of :func:`_verdict`); ``found``: per root, ``(verdict, detail)``."""
    return [
        Point(*_xy(m, float(ball.mid())), "undecided_line_root", math.nan, *model, field=fld,
              reason=why)
        for (m, _, _), (v, why, ball) in zip(roots, found)
        if v == "undecided"
    ]  # fmt: skip


def ss_root_account(model, germ_roots, dtype="float64") -> tuple[dict, list[Point]]:
    """Every root of the SS line restrictions (:func:`atlas.data.boundary_points.line_roots`, the
    algebraic count) with its verdict (:func:`account_roots`; ``listed`` where
    :func:`atlas.data.boundary_points.ss_line_points` puts a proven point): the counts per
    verdict (``line_roots_<verdict>``) and the undecided roots as points (kind
    ``undecided_line_root``, not proven, at the root's middle)."""
    roots = boundary_points.line_roots(model)
    codes = boundary_points.root_codes("SS", roots, model, dtype)
    listed = (codes != codes[:, :, :1]).any(axis=(1, 2))
    found = _account("SS", model, roots, germ_roots, listed)
    verdicts = [v for v, _, _ in found]
    counts = {f"line_roots_{k}": verdicts.count(k) for k in KINDS}
    return counts, _undecided("SS", model, roots, found)


def _xy(m, beta) -> tuple[float, float]:
    """``(beta1, beta2)`` [rad] of the point at free angle ``beta`` of torus line ``m``."""
    fixed = (m % 5) * _QUARTER
    x, y = (
        (fixed, beta) if m < 5 else (beta, fixed) if m < 10 else (beta, beta + (m - 11) * math.pi)
    )
    return x % (2 * math.pi), y % (2 * math.pi)


def distinct(roots) -> list:
    """``roots`` (``(m, beta ball, multiplicity)``) with those whose balls overlap an earlier one
    on the same line left out (a root of several boundary polynomials, counted once)."""
    out = []
    for m, ball, mult in roots:
        if not any(k == m and b.overlaps(ball) for k, b, _ in out):
            out.append((m, ball, mult))
    return out


def ii_root_account(model, germ_roots) -> tuple[dict, list[Point]]:
    """Every distinct germ root of the II boundary polynomials on the class lines
    (:func:`distinct`) with its verdict (:func:`account_roots`): ``line_roots`` (the algebraic
    count) and ``line_roots_<verdict>``; and the points: each ``point`` proven (kind
    ``crosses_class_line`` where the codes next to the line change across it on both sides,
    else ``leaves_class_line``; the uncertainty bounds the distance to the true point as in
    :func:`atlas.data.boundary_points.ss_line_points`), each undecided root not proven
    (:func:`_undecided`)."""
    model = tuple(float(v) for v in model)
    roots = distinct(germ_roots)
    found = _account("II", model, roots, germ_roots, [False] * len(roots))
    verdicts = [v for v, _, _ in found]
    points = [
        Point(*_xy(m, float(ball.mid())), kind, _radius(m, ball), *model, proven=True,
              field="II")
        for (m, _, _), (v, kind, ball) in zip(roots, found)
        if v == "point"
    ]  # fmt: skip
    counts = {"line_roots": len(roots)} | {f"line_roots_{k}": verdicts.count(k) for k in KINDS}
    return counts, points + _undecided("II", model, roots, found)


def _radius(m, ball) -> float:
    """A proven bound [rad] on the distance from the stated point of the root ``ball`` of line
    ``m`` (:func:`_xy`) to the true one: the ball's radius plus the rounding of the
    coordinates, times ``sqrt 2`` on a diagonal (both coordinates move)."""
    return (float(ball.rad()) + 4 * math.ulp(2 * math.pi)) * (math.sqrt(2) if m >= 10 else 1.0)


def superseded(points, proven, reach, breaks, near) -> list[Point]:
    """``points`` without the estimated (not proven) ``leaves_class_line`` and
    ``crosses_class_line`` points that stand for one of ``proven`` (the same point, found from
    the algebra with a proven enclosure): those within ``reach`` [rad] of it, and those on a
    class line it lies on (both within ``near`` [rad]) with no break of the line between them (a
    root of ``breaks``, ``(m, beta ball, multiplicity)``, or a multiple of ``pi/2``).  A
    boundary meets a class line only at a break, so such an estimate is the proven point,
    however far off a coarse chord left it."""
    kinds = ("leaves_class_line", "crosses_class_line")
    good = [p for p in proven if p.proven]
    xy = np.array([[p.beta1, p.beta2] for p in good]).reshape(-1, 2)
    marks = [mark for p in good for mark in _on_lines(p.beta1, p.beta2, near)]
    cuts = {m: [float(b.mid()) for k, b, _ in breaks if k == m] for m, _ in marks}
    cuts = {m: np.array(v + [j * _QUARTER for j in range(4)]) for m, v in cuts.items()}

    def stands_for(p):
        d = np.abs(xy - (p.beta1, p.beta2))
        if (np.hypot(*np.minimum(d, 2 * math.pi - d).T) <= reach).any():
            return True
        return any(
            m == k and _adjacent(e, a, cuts[m])
            for m, e in _on_lines(p.beta1, p.beta2, near)
            for k, a in marks
        )

    return [p for p in points if p.proven or p.kind not in kinds or not stands_for(p)]


def _on_lines(x, y, near) -> list[tuple[int, float]]:
    """The torus class lines (``m`` of :func:`atlas.data.boundary_points.line_roots`) within
    ``near`` [rad] of the point ``(x, y)`` [rad], each with the point's free angle along it."""
    x, y = float(x) % (2 * math.pi), float(y) % (2 * math.pi)
    out = []
    for k in range(4):
        if _around(x - k * _QUARTER) <= near:
            out.append((k, y))
        if _around(y - k * _QUARTER) <= near:
            out.append((5 + k, x))
    for m, c in ((11, 0.0), (12, math.pi)):
        if _around(y - x - c) / math.sqrt(2) <= near:
            out.append((m, x))
    return out


def _around(d) -> float:
    """``|d|`` [rad] around the circle (in ``[0, pi]``)."""
    return abs((d + math.pi) % (2 * math.pi) - math.pi)


def _adjacent(e, a, cuts, same=1e-9) -> bool:
    """Whether one of the two arcs of a line from free angle ``e`` to ``a`` [rad] holds none of
    ``cuts`` [rad] (those within ``same`` [rad] of ``a``, the break at ``a`` itself, aside)."""
    for sign in (1, -1):
        span = (sign * (a - e)) % (2 * math.pi)
        at = (sign * (cuts - e)) % (2 * math.pi)
        if not ((at > 0) & (at < span - same)).any():
            return True
    return False


def attach(curves, points, reach, within, near, tol) -> tuple[list, int]:
    """:func:`atlas.data.boundary_points.attach_points` (same arguments) into every curve of a
    field, SS and II alike, but for a splice that extends a piece on a class line past its end
    over a stretch of the line another piece of the field covers (:func:`_unstretched`: the
    pieces on the lines end at their breaks already; such a splice would cover the stretch
    twice).  Returns the curves (same order) and the number of splices kept."""
    got, n = boundary_points.attach_points(curves, points, reach, within, near, tol)
    out = list(curves)  # the other pieces as they stand: spliced where checked, else as before
    for i, (old, new) in enumerate(zip(curves, got)):
        if new.on_class_line and len(new.vertices) > len(old.vertices):
            new, undone = _unstretched(old, new, out[:i] + out[i + 1 :], tol)
            n -= undone
        out[i] = new
    return out, n


def _unstretched(old, new, others, tol) -> tuple[Curve, int]:
    """``new`` (``old`` with points spliced in) without a new end vertex whose segment to its
    neighbour overlaps, by more than ``tol`` [rad] along the line, a segment of a curve of
    ``others`` on the same class line; and how many were dropped."""
    others = [c for c in others if c.on_class_line and len(c.vertices) > 1]
    dropped = 0
    for end in (0, -1):
        v = new.vertices
        is_new = not np.array_equal(v[end], old.vertices[end])
        if len(v) > 2 and is_new and _covered(v[end], v[1 if end == 0 else -2], others, tol):
            new = _without_end(new, end)
            dropped += 1
    return new, dropped


def _covered(a, b, curves, tol) -> bool:
    """Whether the segment ``a -> b`` on a class line overlaps a segment of ``curves`` on the
    same line (both ends within ``tol`` of it) by more than ``tol`` [rad] along it."""
    mid = 0.5 * (np.asarray(a) + np.asarray(b))
    m = int(class_lines.line_distances(mid[None])[0].argmin())
    axis = 1 if m < 5 else 0  # the line's parameter (beta1 on the diagonals)
    lo, hi = sorted((a[axis], b[axis]))
    for c in curves:
        v = c.vertices
        near = class_lines.line_distances(v)[:, m] <= tol
        on = near[1:] & near[:-1]
        s, e = np.minimum(v[:-1, axis], v[1:, axis])[on], np.maximum(v[:-1, axis], v[1:, axis])[on]
        if (np.minimum(e, hi) - np.maximum(s, lo) > tol).any():
            return True
    return False


def _without_end(c: Curve, end: int) -> Curve:
    """``c`` without its first (``end = 0``) or last (``-1``) vertex, a spliced one."""
    keep = slice(1, None) if end == 0 else slice(None, -1)
    n = len(c.vertices)
    spliced = [i - (end == 0) for i in c.spliced if i != (0 if end == 0 else n - 1)]
    return replace(
        c,
        vertices=c.vertices[keep],
        bracket=c.bracket[keep],
        ends=None if c.ends is None else c.ends[keep],
        spliced=tuple(spliced),
    )
