"""Where a root of a class line stands among its neighbours: its enclosure, a quarter of the
distance to the nearest other break of the line, and exact rational points beside it.

The breaks of class line ``m`` for a field are the real roots of its line polynomials (the
germs' ``g_0``, :mod:`atlas.data.boundary_germs`; for SS also the restrictions of
:func:`atlas.data.boundary_points.line_polynomials`) and the multiples of ``pi/2`` (free angle
``beta`` [rad], ``t = tan(beta / 2)``).  The codes next to the line are sampled at ``beta +- h``
and a root's box reaches ``beta +- h`` (:mod:`atlas.data.boundary_roots`,
:mod:`atlas.data.boundary_branches`), ``h`` a quarter of the distance to the nearest other break.

* Where every other break is farther than :data:`SEPARATION` (the float frame), ``beta`` and
  ``h`` are float64 and a point beside the root is the float nearest ``tan(beta' / 2)``.
* Otherwise (the exact frame: damping splits a multiple root into roots 1e-15 rad apart, or moves
  one 1e-13 rad off a multiple of ``pi/2``; float64 angles cannot order them) every distinct real
  root of the line polynomials is isolated exactly (distinct irreducible factors share no root;
  each factor's roots at 256 bits, flint), the root is the one exact root in its enclosure,
  ``h`` a quarter of its proven distance to every other one and to the multiples of ``pi/2``, and
  a point beside it the exact middle of the 256-bit ball of ``tan(beta' / 2)``: strictly between
  the root and its neighbours however close they are.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from fractions import Fraction

import flint
import numpy as np

from atlas.data import boundary_germs, boundary_points

__all__ = ["SEPARATION", "Frame", "frame", "sample"]

#: the distance [rad] to another break below which the float frame is not used
SEPARATION = 1e-12
_PREC = 256
_QUARTER = math.pi / 2


@dataclass(frozen=True)
class Frame:
    """A root's frame: ``beta`` [rad] its enclosure (an arb ball), ``h`` [rad] a quarter of the
    distance to the nearest other break (a float, at most the true quarter), ``crossing``
    whether it is a multiple of ``pi/2``, ``exact`` whether this is the exact frame."""

    beta: flint.arb
    h: float
    crossing: bool
    exact: bool


def _float_distance(beta: float, others) -> float:
    """Distance [rad] along the line (around the torus) from ``beta`` to the nearest of
    ``others`` and the multiples of ``pi/2``, the root itself (distance 0) left out."""
    cand = np.concatenate([np.asarray(others, float), np.arange(5) * _QUARTER])
    d = np.abs(cand - beta)
    d = np.minimum(d, 2 * math.pi - d)
    return float(d[d > 0].min())


def _at_crossing(ball) -> bool:
    """Whether the root ``ball`` [rad] can be a multiple of ``pi/2``."""
    k = float((ball / _QUARTER).mid())
    return any((ball - j * flint.arb.pi() / 2).contains(0) for j in (math.floor(k), math.ceil(k)))


def frame(fld, model, m, ball, others) -> Frame | None:
    """The frame of the root ``ball`` [rad] of line ``m`` (module docstring); ``others``: the
    free angles [rad] of the field's roots on the line (the root itself among them, once or
    more).  Another float equal to the root's may be another root within a float step: then the
    float frame needs the exact breaks to show one root within :data:`SEPARATION` of the ball.
    ``None`` where the exact frame is needed and the enclosure holds other than one exact
    break."""
    model = tuple(float(v) for v in model)
    beta = float(ball.mid())
    h = 0.25 * _float_distance(beta, [b for b in others if b != beta])
    if 4 * h > SEPARATION and (list(others).count(beta) <= 1 or _alone(fld, model, m, ball)):
        return Frame(ball, h, _at_crossing(ball), False)
    return _exact_frame(fld, model, m, ball)


def _alone(fld, model, m, ball) -> bool:
    """Whether exactly one exact break of line ``m`` (:func:`_exact_breaks`) lies within
    :data:`SEPARATION` [rad] of the root ``ball`` [rad]."""
    with flint.ctx.workprec(_PREC):
        wide = ball + flint.arb(0, SEPARATION)
        return sum(b.overlaps(wide) for b, _ in _exact_breaks(fld, m, model)) == 1


def _exact_breaks(fld, m, model) -> list[tuple[flint.arb, bool]]:
    """Every break of line ``m`` as ``(beta ball [rad], crossing)`` at 256 bits: the distinct
    real roots of the line polynomials (:func:`_breaks`) and the multiples of ``pi/2`` (one
    that is a root counted once)."""
    with flint.ctx.workprec(_PREC):
        roots = [(b, c) for _, b, c in _breaks(fld, m, model)]
        grid = [(j * flint.arb.pi() / 2, True) for j in range(4)]
        grid = [g for g in grid if not any(c and b.overlaps(g[0]) for b, c in roots)]
        return roots + grid


def _exact_frame(fld, model, m, ball) -> Frame | None:
    """The exact frame (module docstring) of the root ``ball`` [rad] of line ``m``."""
    with flint.ctx.workprec(_PREC):
        breaks = _exact_breaks(fld, m, model)
        inside = [k for k, (b, _) in enumerate(breaks) if b.overlaps(ball)]
        if len(inside) != 1:
            return None
        beta, crossing = breaks[inside[0]]
        two_pi = 2 * flint.arb.pi()
        gaps = [abs(b - beta) for k, (b, _) in enumerate(breaks) if k != inside[0]]
        lower = min(min(float(g.lower()), float((two_pi - g).lower())) for g in gaps)
        return Frame(beta, 0.25 * lower * (1 - 2.0**-50), crossing, True)


@functools.lru_cache(maxsize=32)
def _breaks(fld, m, model) -> tuple:
    """Every distinct real root of the line polynomials of ``fld`` on line ``m`` (module
    docstring): ``(t, beta, crossing)`` as 256-bit balls, ``crossing`` where the root is
    exactly ``t = 0`` or ``+-1`` (``beta`` a multiple of ``pi/2``)."""
    polys = [rows[0] for rows in boundary_germs.germs(fld, m, model)]
    if fld == "SS":
        polys += list(boundary_points.line_polynomials(m, *model).values())
    factors = {}
    for p in polys:
        for f, _ in p.factor()[1]:
            z = flint.fmpz_poly([int(c * f.denom()) for c in f.coeffs()])
            z = z // z.content() if z.content() != 1 else z
            factors[str(-z if z[z.degree()] < 0 else z)] = z
    out = []
    with flint.ctx.workprec(_PREC):
        for z in factors.values():
            crossing = z.degree() == 1 and any(z(v) == 0 for v in (0, 1, -1))
            for root, _ in z.complex_roots():
                if root.imag == 0:
                    out.append(
                        (root.real, boundary_points.angle_from_tan_half(root.real), crossing)
                    )
    return tuple(out)


def sample(fr: Frame, offset: float) -> Fraction:
    """An exact rational ``t`` at the free angle ``beta + offset`` [rad] of the frame's root
    (to within 2^-250 of it in the exact frame, within float64 rounding in the float frame)."""
    if not fr.exact:
        return Fraction(math.tan(0.5 * (float(fr.beta.mid()) + offset)))
    with flint.ctx.workprec(_PREC):
        t = ((fr.beta + flint.arb(offset)) / 2).tan()
        man, exp = (int(v) for v in t.mid().man_exp())
    return Fraction(man * 2**exp) if exp >= 0 else Fraction(man, 2**-exp)
