"""Where a boundary of a field can meet a class line, from the algebra in two variables, and a
proof that a code sampled just off the line is the code of the whole side there.

Along class line ``m`` let ``t = tan(beta / 2)`` of its free angle (``beta2`` on ``beta1 = k
pi/2``, else ``beta1``) and ``e = tan(delta / 2)`` of an angle ``delta`` off it (the fixed angle
moved by ``delta`` on the lines ``beta_j = k pi/2``, ``beta2`` moved by ``delta`` on the diagonals
``beta2 = beta1 + k pi``).  The direction components are rational functions of ``(t, e)`` whose
denominators are powers of ``1 + t^2`` and ``1 + e^2`` (positive), so every polynomial of
:mod:`atlas.core.expressions` becomes, up to a positive factor, a polynomial ``F(t, e)`` with
exact rational coefficients (``kappa, q1, q2`` read as exact dyadic rationals; python-flint).

A field's codes change only across the class lines and the zero sets of its *boundary
polynomials*:

* SS (Routh-Hurwitz, paper App. C): ``a3``, ``H2 = a3 a2 - a1``, ``G`` (``H3 = D G``) and ``D``
  damped; ``a2`` and ``disc = a2^2 - 4 a0`` undamped.
* II (SPEC §1: a real root ``l > 0`` of ``p`` whose eigenvector has ``x1 x2 > 0``, strictly
  dominant for stability): a positive root appears or leaves through ``l = 0`` (``a0 = kappa D =
  0``, a class line) or in a pair (``disc_l p = 0``); the eigenvector's sign ``-c2 h1`` changes at
  a root only where ``h1 = 0``, which ``p = h1 h2 - c2 s1 d1 d2`` allows only on ``c2 s1 = 0``
  (class lines); the largest real root changes at ``disc_l p = 0`` and ties with a complex pair
  where ``T(l) = 0`` (``T = p' - p'' p''' / 12``, :func:`atlas.core.exact._tie_poly`), so on
  ``res_l(p, T) = 0``.

Write ``F = e^k G`` with ``G(t, 0)`` not identically zero: a branch of ``F = 0`` off the line can
approach it only at a real root of ``G(t, 0)`` (continuity).  These *germ roots* (and the
multiples of ``pi/2``, where other class lines cross) cut the line into intervals along each of
which the codes just off the line on either side are constant.  At a parameter where
``|G(t, 0)|`` exceeds the rest of ``G`` over ``|e| <= e_max`` (ball arithmetic, :func:`clear`), no
branch lies between the line and a sample that far off it: the sample's code is the code of the
whole side of that interval, a proof.
"""

from __future__ import annotations

import functools
import math
import operator
from fractions import Fraction

import flint

from atlas.core import brackets, exact
from atlas.core import expressions as ex
from atlas.data.boundary_points import TORUS_LINES, angle_from_tan_half, real_roots

__all__ = [
    "boundary_polynomials",
    "clear",
    "coefficients_on_line",
    "exact_codes",
    "exact_codes_at",
    "germ_roots",
    "germs",
    "near_side_codes",
]

#: entries kept by each cache of this module (one per line, field and model): the 10 torus lines
#: and 2 fields make 20 a slice, so the slices of 12 models (a run's, an explorer session's) are
#: each eliminated once (0.1-0.2 s a line for II), in about 3.4 MB a model
CACHED = 256
_CTX = flint.fmpq_mpoly_ctx.get(("t", "e", "l"), "lex")
_T, _E, _L = _CTX.gens()
_WT, _WE = 1 + _T * _T, 1 + _E * _E


class _Rat2:
    """``num / ((1 + t^2)^i (1 + e^2)^j)``, ``num`` a polynomial in ``(t, e, l)``."""

    def __init__(self, num, i=0, j=0):
        self.num, self.i, self.j = num, i, j

    def lift(self, i, j):
        return self.num * _WT ** (i - self.i) * _WE ** (j - self.j)

    def __add__(self, o):
        o = o if isinstance(o, _Rat2) else _Rat2(_CTX.from_dict({(0, 0, 0): o} if o else {}))
        i, j = max(self.i, o.i), max(self.j, o.j)
        return _Rat2(self.lift(i, j) + o.lift(i, j), i, j)

    __radd__ = __add__

    def __neg__(self):
        return _Rat2(-self.num, self.i, self.j)

    def __sub__(self, o):
        return self + (-o)

    def __rsub__(self, o):
        return (-self) + o

    def __mul__(self, o):
        if not isinstance(o, _Rat2):
            return _Rat2(self.num * o, self.i, self.j)
        return _Rat2(self.num * o.num, self.i + o.i, self.j + o.j)

    __rmul__ = __mul__

    def __pow__(self, n: int):
        return _Rat2(self.num**n, self.i * n, self.j * n)


_COS_T, _SIN_T = _Rat2(1 - _T * _T, 1), _Rat2(2 * _T, 1)
_COS_E, _SIN_E = _Rat2(1 - _E * _E, 0, 1), _Rat2(2 * _E, 0, 1)
_AXES = {0: (1, 0), 1: (0, 1), 2: (-1, 0), 3: (0, -1)}


def _turned(c, s):
    """``(cos, sin)`` of an angle with ``(c, s)`` turned by ``delta``."""
    return _COS_E * c - _SIN_E * s, _SIN_E * c + _COS_E * s


def _directions(m):
    """``(c1, s1, c2, s2)`` at ``(t, e)`` near class line ``m`` (module docstring)."""
    if m < 5:
        return (*_turned(*_AXES[m % 4]), _COS_T, _SIN_T)
    if m < 10:
        return (_COS_T, _SIN_T, *_turned(*_AXES[(m - 5) % 4]))
    sign = 1 if m == 11 else -1
    return (_COS_T, _SIN_T, *_turned(sign * _COS_T, sign * _SIN_T))


def _common(values):
    """Numerators of ``values`` (``_Rat2`` or rationals) over one common positive denominator."""
    rats = [v for v in values if isinstance(v, _Rat2)]
    i, j = max((r.i for r in rats), default=0), max((r.j for r in rats), default=0)
    one = _Rat2(_CTX.from_dict({(0, 0, 0): 1}), 0, 0)
    return [(v if isinstance(v, _Rat2) else one * v).lift(i, j) for v in values], _WT**i * _WE**j


def _ss_polynomials(c1, s1, c2, s2, kappa, q1, q2) -> list:
    sub = operator.sub
    if q1 == 0 and q2 == 0:
        return [
            ex.a2_undamped(kappa, c1, 1, s2, sub=sub),
            ex.disc_undamped(kappa, c1, 1, s2, s1, c2, sub=sub),
        ]
    D = ex.det(c1, s1, c2, s2, sub=sub)
    a3, a2, a1, _ = ex.coefficients(c1, s1, c2, s2, kappa, 1, q1, q2, D, sub=sub)
    G = ex.G(c1, s1, c2, s2, kappa, 1, q1, q2, D, sub=sub)
    return [a3, ex.hurwitz_H2(a3, a2, a1, sub=sub), G, D]


def _ii_polynomials(c1, s1, c2, s2, kappa, q1, q2) -> list:
    sub = operator.sub
    D = ex.det(c1, s1, c2, s2, sub=sub)
    a3, a2, a1, a0 = ex.coefficients(c1, s1, c2, s2, kappa, 1, q1, q2, D, sub=sub)
    (A0, A1, A2, A3), W = _common([a0, a1, a2, a3])
    p = A0 + A1 * _L + A2 * _L**2 + A3 * _L**3 + W * _L**4  # W p(l)
    # W^2 T of the monic p / W (T = [a1 - a2 a3, -2 a2 - 3 a3^2, -15 a3, -20]: exact._tie_poly)
    T = (
        (A1 * W - A2 * A3)
        - (2 * A2 * W + 3 * A3 * A3) * _L
        - 15 * A3 * W * _L**2
        - 20 * W * W * _L**3
    )
    return list(_eliminated(p, T))


#: ``disc_l p`` and ``res_l(p, T)`` of the II polynomials already computed, by ``(p, T)`` as text
_ELIMINATED: dict = {}


def _mirrored(F):
    """``F(-t, -e, l)``."""
    return F.compose(-_T, -_E, _L)


def _eliminated(p, T) -> tuple:
    """``(disc_l p, res_l(p, T))``, the costly part of :func:`_ii_polynomials` (0.1-0.2 s a
    line); where ``(p, T)`` is exactly the mirror image ``(t, e) -> (-t, -e)`` of a pair done
    before (on the slices tried: the lines ``beta2 = pi`` and ``beta2 = 0``, the two diagonals),
    the mirror images of its results: both are polynomials in the coefficients of ``p`` and
    ``T``, which the substitution maps term by term."""
    key = (str(p), str(T))
    if key not in _ELIMINATED:
        done = _ELIMINATED.get((str(_mirrored(p)), str(_mirrored(T))))
        if len(_ELIMINATED) >= CACHED:
            _ELIMINATED.clear()
        if done is not None:
            _ELIMINATED[key] = tuple(_mirrored(F) for F in done)
        else:
            _ELIMINATED[key] = _eliminate(p, T)
    return _ELIMINATED[key]


def _eliminate(p, T) -> tuple:
    """``(disc_l p, res_l(p, T))``, computed (flint)."""
    return p.discriminant("l"), p.resultant(T, "l")


@functools.lru_cache(maxsize=CACHED)
def coefficients_on_line(m, model) -> tuple:
    """``(a3, a2, a1, a0)`` of ``p`` (paper eq. 9) on class line ``m``, each as the numerator
    (``flint.fmpq_poly`` in ``t``) of its restriction, over a positive denominator: the signs of
    the coefficients along the line; ``model = (kappa, q1, q2)``."""
    kappa, q1, q2 = (flint.fmpq(*Fraction(float(v)).as_integer_ratio()) for v in model)
    c1, s1, c2, s2 = _directions(m)
    D = ex.det(c1, s1, c2, s2, sub=operator.sub)
    comps = ex.coefficients(c1, s1, c2, s2, kappa, 1, q1, q2, D, sub=operator.sub)
    out = []
    for c in comps:
        F = c.num if isinstance(c, _Rat2) else _CTX.from_dict({(0, 0, 0): c} if c else {})
        row = {a: v for (a, b, _), v in zip(F.monoms(), F.coeffs()) if b == 0}
        out.append(flint.fmpq_poly([row.get(a, 0) for a in range(max(row, default=-1) + 1)]))
    return tuple(out)


def boundary_polynomials(fld, m, model) -> tuple:
    """The numerators ``F(t, e)`` (``flint.fmpq_mpoly``) of the boundary polynomials of ``fld``
    (module docstring) near class line ``m``, squarefree (:func:`_radical`); ``model = (kappa,
    q1, q2)``."""
    exact = [flint.fmpq(*Fraction(float(v)).as_integer_ratio()) for v in model]
    comps = (_ss_polynomials if fld == "SS" else _ii_polynomials)(*_directions(m), *exact)
    out = [c.num if isinstance(c, _Rat2) else c for c in comps]
    return tuple(_radical(f) for f in out if not isinstance(f, flint.fmpq) and not f.is_zero())


def _radical(F):
    """``F`` with each repeated factor once (squarefree factorisation): the same zero set, and a
    root of ``G(t, 0)`` that only a squared factor made multiple becomes simple (at ``q = 0``
    ``disc_l p = 16 a0 (a2^2 - 4 a0)^2``)."""
    _, factors = F.factor_squarefree()
    return functools.reduce(operator.mul, (f for f, _ in factors), _CTX.from_dict({(0, 0, 0): 1}))


def _germ(F):
    """``G(t, e) = F / e^k`` as ``[g_0(t), g_1(t), ...]`` (``flint.fmpq_poly``, ``G = sum g_b
    e^b``), ``k`` the largest power of ``e`` dividing ``F``."""
    rows = {}
    for (a, b, _), c in zip(F.monoms(), F.coeffs()):
        rows.setdefault(b, {})[a] = c
    k = min(rows)
    out = []
    for b in range(k, max(rows) + 1):
        coeffs = rows.get(b, {})
        out.append(flint.fmpq_poly([coeffs.get(a, 0) for a in range(max(coeffs, default=-1) + 1)]))
    return out


@functools.lru_cache(maxsize=CACHED)
def germs(fld, m, model) -> tuple:
    """Per boundary polynomial of ``fld`` near line ``m``: its germ rows (:func:`_germ`)."""
    return tuple(_germ(F) for F in boundary_polynomials(fld, m, model))


def germ_roots(fld, model, lines=TORUS_LINES) -> list[tuple[int, flint.arb, int]]:
    """``(m, beta, multiplicity)``: every real root of ``G(t, 0)`` of every boundary polynomial
    of ``fld`` near every line of ``lines``, ``beta = 2 atan(t)`` a certified ball [rad] (the
    format of :func:`atlas.data.boundary_points.line_roots`).  ``beta = pi`` (``t`` infinite)
    is not among them: it is a multiple of ``pi/2``, a break of every line anyway."""
    model = tuple(float(v) for v in model)
    out = []
    for m in lines:
        for rows in germs(fld, m, model):
            out += [(m, angle_from_tan_half(t), mult) for t, mult in real_roots(rows[0])]
    return out


@functools.lru_cache(maxsize=CACHED)
def _ball_germs(fld, m, model, prec) -> tuple:
    """Per boundary polynomial of :func:`germs`, its rows as ``prec``-bit ball polynomials and
    the derivative of the first (converted once: :func:`near_side_codes` tests hundreds of
    offsets against the same rows)."""
    out = []
    for rows in germs(fld, m, model):
        polys = tuple(flint.arb_poly(list(r.coeffs())) for r in rows)
        out.append((polys, polys[0].derivative()))
    return tuple(out)


def _dominated(fld, model, m, t_mid, t_box, e_max) -> bool:
    """Whether ``|g_0(t)| > sum_{b >= 1} |g_b(t)| e_max^b`` over the ball ``t_box`` (middle
    ``t_mid``) for every boundary polynomial of ``fld`` near line ``m`` (256-bit balls)."""
    for polys, slope in _ball_germs(fld, m, model, flint.ctx.prec):
        # mean-value form: a ball argument in Horner's scheme loses the cancellation
        g0 = polys[0](t_mid) + slope(t_box) * (t_box - t_mid)
        rest = sum((abs(p(t_box)) * e_max**k for k, p in enumerate(polys) if k), flint.arb(0))
        if not abs(g0).lower() > rest.upper():
            return False
    return True


def clear(fld, model, m, beta: float, delta_max: float, slack: float = 1e-14) -> bool:
    """Whether no branch of a boundary of ``fld`` comes within ``delta_max`` [rad] (angle off the
    line, module docstring) of line ``m`` at free angle ``beta`` [rad] (+- ``slack``): ``|g_0(t)|
    > sum_{b >= 1} |g_b(t)| e_max^b`` in ball arithmetic for every boundary polynomial."""
    model = tuple(float(v) for v in model)
    with flint.ctx.workprec(256):  # the germs' coefficients are large: 53 bits lose the sign
        b = flint.arb(beta, slack)
        if not (b - flint.arb.pi()).abs_lower() > 0:  # t infinite at beta = pi
            return False
        t_box, t_mid = (b / 2).tan(), (flint.arb(beta) / 2).tan()
        e_max = flint.arb(math.tan(0.5 * delta_max) * (1 + 1e-6))
        return _dominated(fld, model, m, t_mid, t_box, e_max)


#: the exponents ``k`` of the offsets ``e = tan(delta / 2) = 2^-k`` tried by
#: :func:`near_side_codes`, largest offset first (``2^-43`` is the tip offset, ``2^-160`` below
#: any boundary branch the grid's angles could tell from the line)
NEAR_EXPONENTS = tuple(range(43, 161, 3))


def _value_at(r, t, e) -> Fraction:
    """A direction component ``r`` (``_Rat2`` or a rational) at rationals ``(t, e)``
    (``flint.fmpq``), exactly."""
    if not isinstance(r, _Rat2):
        return Fraction(r)
    v = r.num(t, e, 0) / ((1 + t * t) ** r.i * (1 + e * e) ** r.j)
    return Fraction(int(v.p), int(v.q))


def near_side_codes(
    fld, model, m, beta: float, t: Fraction | None = None, max_offset: float = math.inf
) -> tuple[int, int, float] | None:
    """The codes of ``fld`` arbitrarily close to class line ``m`` at free angle ``beta`` [rad],
    on the side ``delta < 0`` and ``delta > 0`` (module docstring), proven: at ``t`` (given, an
    exact rational, or the float nearest ``tan(beta / 2)``), the largest ``e = 2^-k`` (``k`` in
    :data:`NEAR_EXPONENTS`, ``2 atan(e) <= max_offset`` [rad]: clear of the class lines that
    cross this one that far along it) with no branch of a boundary polynomial for ``|e'| <= e``
    (:func:`_dominated`), and the exact codes (:func:`atlas.core.exact.point_verdicts`) at the
    exactly rational unit directions of ``(t, +-e)``.  Returns ``(code at -e, code at +e, delta
    [rad])`` (``delta = 2 atan(e)``), or ``None`` where no offset is proven."""
    model = tuple(float(v) for v in model)
    t = Fraction(math.tan(0.5 * beta)) if t is None else t
    with flint.ctx.workprec(256):
        t_ball = flint.arb(flint.fmpq(t.numerator, t.denominator))
        k = next(
            (k for k in NEAR_EXPONENTS
             if 2.0 ** (1 - k) <= max_offset
             and _dominated(fld, model, m, t_ball, t_ball, flint.arb(2) ** -k)),
            None,
        )  # fmt: skip
    if k is None:
        return None
    return (*exact_codes(fld, model, m, t, k), 2 * math.atan(2.0**-k))


def exact_codes(fld, model, m, t: Fraction, k: int) -> tuple[int, int]:
    """The exact codes of ``fld`` at ``(t, -2^-k)`` and ``(t, 2^-k)`` near class line ``m``
    (module docstring; ``t`` rational, the directions exactly rational;
    :func:`atlas.core.exact.point_verdicts`)."""
    e = Fraction(1, 2**k)
    return exact_codes_at(fld, model, m, t, -e), exact_codes_at(fld, model, m, t, e)


def exact_codes_at(fld, model, m, t: Fraction, e: Fraction) -> int:
    """The exact code of ``fld`` at the rationals ``(t, e)`` near class line ``m`` (module
    docstring; :func:`atlas.core.exact.point_verdicts` at exactly rational directions)."""
    kappa, q1, q2 = (Fraction(v) for v in model)
    at = tuple(flint.fmpq(v.numerator, v.denominator) for v in (t, e))
    dirs = [_value_at(r, *at) for r in _directions(m)]
    verdicts = exact.point_verdicts(*dirs, kappa, q1, q2)
    return int(brackets.codes_of(fld, {n: [verdicts[n]] for n in brackets.FIELDS[fld]})[0])
