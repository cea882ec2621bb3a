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
  polynomials vanish at ``r`` and however often (proven);
* ``class_crossing``: ``r`` is a multiple of ``pi/2``, where class lines cross (a vertex of the
  closed-form class lines; the codes around it are not examined here);
* ``undecided``: anything else (a multiple root, roots of two polynomials overlapping, or a
  sample without a proven offset).
"""

from __future__ import annotations

import math

import flint
import numpy as np

from atlas.data import boundary_germs, boundary_points
from atlas.data.boundary_curves import Point

__all__ = ["KINDS", "account_roots", "distinct", "ii_root_account", "ss_root_account"]

#: the verdicts of :func:`account_roots`
KINDS = ("point", "not_boundary", "class_crossing", "undecided")
_QUARTER = math.pi / 2


def _neighbours(beta, others) -> float:
    """Distance [rad] along the line (around the torus) from ``beta`` to the nearest of
    ``others`` and the multiples of ``pi/2`` other than ``beta`` itself."""
    grid = np.arange(5) * _QUARTER
    cand = np.concatenate([np.asarray(others, float), grid])
    d = np.abs(cand - beta)
    d = np.minimum(d, 2 * math.pi - d)
    return float(d[d > 1e-12].min())


def _at_crossing(ball) -> bool:
    """Whether the root ``ball`` [rad] can be a multiple of ``pi/2``."""
    k = float((ball / _QUARTER).mid())
    return any((ball - j * flint.arb.pi() / 2).contains(0) for j in (math.floor(k), math.ceil(k)))


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


def _verdict(fld, model, m, ball, listed, others) -> str:
    """The verdict of one root (module docstring)."""
    if listed:
        return "point"
    beta = float(ball.mid())
    h = 0.25 * _neighbours(beta, others)
    near = [boundary_germs.near_side_codes(fld, model, m, beta + s * h) for s in (-1, 1)]
    if None not in near and near[0][:2] != near[1][:2]:
        return "point"
    if _at_crossing(ball):
        return "class_crossing"
    if None not in near and _simple_single(fld, model, m, ball):
        return "not_boundary"
    if fld == "SS" and _unstable_near(model, m, ball):
        return "not_boundary"
    return "undecided"


def account_roots(fld, model, roots, germ_roots, listed) -> list[str]:
    """Per root ``(m, beta ball, multiplicity)`` of ``roots`` (the format of
    :func:`atlas.data.boundary_points.line_roots`), its verdict in :data:`KINDS` (module
    docstring); ``germ_roots``: the field's germ roots
    (:func:`atlas.data.boundary_germs.germ_roots`), breaks of the lines; ``listed``: per root,
    whether a proven point stands at it."""
    model = tuple(float(v) for v in model)
    breaks = [*roots, *germ_roots]
    return [
        _verdict(fld, model, m, ball, bool(on), [float(b.mid()) for k, b, _ in breaks if k == m])
        for (m, ball, _), on in zip(roots, listed)
    ]


def ss_root_account(model, germ_roots, dtype="float64") -> tuple[dict, list[Point]]:
    """Every root of the SS line restrictions (:func:`atlas.data.boundary_points.line_roots`, the
    algebraic count) with its verdict (:func:`account_roots`; ``listed`` where
    :func:`atlas.data.boundary_points.ss_line_points` puts a proven point): the counts per
    verdict (``line_roots_<verdict>``) and the undecided roots as points (kind
    ``undecided_line_root``, not proven, at the root's middle)."""
    roots = boundary_points.line_roots(model)
    codes = boundary_points.root_codes("SS", roots, model, dtype)
    listed = (codes != codes[:, :, :1]).any(axis=(1, 2))
    verdicts = account_roots("SS", model, roots, germ_roots, listed)
    counts = {f"line_roots_{k}": verdicts.count(k) for k in KINDS}
    undecided = [
        Point(*_xy(m, float(ball.mid())), "undecided_line_root", math.nan, *model, field="SS")
        for (m, ball, _), v in zip(roots, verdicts)
        if v == "undecided"
    ]
    return counts, undecided


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


def ii_root_account(model, germ_roots) -> dict:
    """Every distinct germ root of the II boundary polynomials on the class lines
    (:func:`distinct`) with its verdict (:func:`account_roots`, none listed: the II points are
    not stored): ``line_roots`` (the algebraic count) and ``line_roots_<verdict>``."""
    roots = distinct(germ_roots)
    verdicts = account_roots("II", model, roots, germ_roots, [False] * len(roots))
    return {"line_roots": len(roots)} | {f"line_roots_{k}": verdicts.count(k) for k in KINDS}
