"""Exact classifier in integer arithmetic (SPEC §4 "Accuracy").

Takes the *same floating-point inputs* as the fast kernels (direction components ``c1, s1, c2, s2``,
``kappa``, ``q1``, ``q2``; see :func:`atlas.core.contact_modes.direction`) as exact dyadic rationals and
decides every verdict without rounding: it never returns ``UNDECIDED`` and raises only on
non-finite input.  It settles the points the fast kernels leave undecided and is the reference
of the tests and benchmarks.

**Scaling.**  With every input ``v = V / N`` (``N`` the common denominator, ``2^E`` for floats; ``V`` integer) and
``x = N^2 l``, the characteristic polynomial (paper eq. 9; conventions of :mod:`atlas.core.spectral`)

    p(l) = det(l^2 I + B (K + l Q)) = h1 h2 - c2 s1 d1 d2,
    h1 = l^2 + c1 d1,  h2 = l^2 + s2 d2,  d1 = kappa + q1 l,  d2 = 1 + q2 l,

becomes the monic integer quartic ``P(x) = N^8 p(x / N^2) = x^4 + A3 x^3 + A2 x^2 + A1 x + A0``
(``A_k = a_k N^(8 - 2k)``); ``h1, h2`` become integer quadratics ``H1, H2`` the same way.  A positive
rescaling of ``l`` keeps every verdict.

**Tier 1 (Python ints and small flint calls, 20-60 us a point on the hard-case suites; physical
inputs ``kappa > 0``, ``q1, q2 >= 0``).**

* SS: Routh-Hurwitz (stable iff ``a3, H2 = a3 a2 - a1, H3 = a1 H2 - a3^2 a0, a0 > 0``); off it,
  ``a0 H3 != 0`` means no root on the imaginary axis (Orlando), hence unstable; the boundary in closed
  form: ``a0 = a1 = 0``: ``p = l^2 (l^2 + a3 l + a2)``; ``a3 = a1 = 0``: ``l^2 = mu``;
  ``H3 = 0``: ``p = (l^2 + a1/a3)(l^2 + a3 l + a0 a3/a1)``.
* II consistency: for ``l > 0``, ``h_j = d_j f_j`` with ``f1 = l^2/d1 + c1``, ``f2 = l^2/d2 + s2``
  strictly increasing from ``(c1, s2)``, and ``p = d1 d2 (f1 f2 - gamma)``, ``gamma = c2 s1``: the
  positive roots are the crossings of the monotone curve ``(f1, f2)`` with the hyperbola
  ``f1 f2 = gamma`` and II roots are those with ``sign f1 = -sign c2``.  Which quadrants the curve
  visits follows from the signs of ``c1, s2, D = c1 s2 - s1 c2`` and of ``h1`` at the positive root
  ``r2`` of ``h2`` (``sign(W)``, :func:`_h1_at_r2`); an even number of crossings on a QII/QIV arc
  is counted by a Sturm sequence.  Triangular and diagonal ``B`` (``gamma = 0``) and ``D = 0`` in closed form.
* II stability: when the largest positive root ``l*`` is the II root and simple, four real roots
  (``disc > 0``) make it dominant; with one complex pair ``z`` (``disc < 0``) the Taylor coefficients
  of ``p(l* + x) = x (x^3 + b3 x^2 + b2 x + b1)`` give ``sign(Re z - l*) = sign T(l*)``,
  ``T = b1 - b2 b3 = p' - p'' p''' / 12`` (:func:`_tie_poly`), and ``T(r)`` has the sign of
  ``Re z - r`` at the other real root ``r``: ``l*`` dominates iff the Tarski query
  ``sum_{p(x) = 0} sign T(x)`` (Sturm-Tarski) is ``<= 0``.  Exact ties are thereby unstable.

**Tier 2 (python-flint, about 0.5 ms a point; any input, by the definitions).**  ``P`` is
factored over Z into irreducibles; certified Arb enclosures of their roots (``complex_roots``,
real roots with exactly zero imaginary part) are computed at doubling precision until every
comparison is decided.  Every exact equality is decided algebraically: an irreducible factor has
a root on the imaginary axis only if it is ``x`` or even (then from the signs of ``G(y) = g(x)``,
``y = x^2``); ``h(l) = 0`` iff the factor divides ``h``; ``l*`` ties with a complex pair iff its
factor divides ``T``.  Tier 2 takes the points tier 1 does not cover: ``disc = 0`` with a possibly
multiple ``l*``, and non-physical inputs.
"""

from __future__ import annotations

import math
import operator
from fractions import Fraction
from typing import NamedTuple

import flint
import numpy as np

from atlas.core import expressions as ex
from atlas.core.invariants import KEYS
from atlas.core.verdicts import Verdict

__all__ = [
    "characteristic_poly",
    "point_spectral",
    "point_verdicts",
    "ss_hurwitz",
    "resolve",
    "point_codes",
    "resolve_codes",
]

_SPECTRAL = ("stable_SS", "consistent_II", "stable_II")
_S, _U, _N = int(Verdict.STABLE), int(Verdict.UNSTABLE), int(Verdict.NEUTRAL)
# consistent_II codes are int(bool): Consistency.INCONSISTENT = 0, Consistency.CONSISTENT = 1


_SUB = operator.sub  # the exact subtraction of the expressions


def _sign(x) -> int:
    return (x > 0) - (x < 0)


# --- Sturm and Sturm-Tarski counts (exact, over Q) ---------------------------------------------


def _remainder_sequence(a: flint.fmpq_poly, b: flint.fmpq_poly) -> list:
    """Signed remainder sequence ``a, b, -rem(a, b), ...`` (exact, over Q)."""
    seq = [a, b]
    while seq[-1].degree() > 0:
        r = seq[-2] % seq[-1]
        if r.is_zero():
            break
        seq.append(-r)
    return seq


def _variations(signs) -> int:
    s = [v for v in signs if v]
    return sum(1 for u, v in zip(s, s[1:]) if (u > 0) != (v > 0))


def _var_at(seq, where) -> int:
    """Sign variations of a sequence at ``0``, ``+inf`` (``where = 1``) or ``-inf`` (``-1``)."""
    if where == 0:
        return _variations([_sign(f[0]) for f in seq])
    return _variations([_sign(f[f.degree()]) * where ** f.degree() for f in seq])


def _count_positive(P) -> int:
    """Distinct roots of ``P`` in ``(0, inf)`` (Sturm; ``P(0) != 0``)."""
    p = flint.fmpq_poly(list(P))
    seq = _remainder_sequence(p, p.derivative())
    return _var_at(seq, 0) - _var_at(seq, 1)


def _tarski(P, Q) -> int:
    """Tarski query ``sum over real roots x of P of sign Q(x)`` (Sturm-Tarski)."""
    p, q = flint.fmpq_poly(list(P)), flint.fmpq_poly(list(Q))
    r = (p.derivative() * q) % p
    if r.is_zero():
        return 0
    seq = _remainder_sequence(p, r)
    return _var_at(seq, -1) - _var_at(seq, 1)


def _tie_poly(P) -> list:
    """``T(u) = b1 - b2 b3`` for the Taylor coefficients of ``P(u + x) = sum b_k x^k`` (``P`` monic):
    ``T = P' - (P''/2)(P'''/6)``.  At a simple largest real root ``l*``,
    ``sign T(l*) = sign(Re z - l*)`` for a complex pair ``z`` of ``P``; ``T(l*) = 0`` iff a complex
    pair has real part exactly ``l*``."""
    A0, A1, A2, A3, _ = P
    return [A1 - A2 * A3, -2 * A2 - 3 * A3 * A3, -15 * A3, -20]


# --- the scaled problem ---------------------------------------------------------------------------


class _Scaled(NamedTuple):
    """Inputs as integers over ``N = 2^E``; ``P``, ``H1``, ``H2`` in ``x = N^2 l`` (low degree first)."""

    C1: int
    S1: int
    C2: int
    S2: int
    K: int
    Q1: int
    Q2: int
    N: int
    P: tuple
    H1: tuple
    H2: tuple


def _scaled(c1, s1, c2, s2, kappa, q1, q2) -> _Scaled:
    try:  # exact: floats are dyadic rationals n / d, d = 2^e; a Fraction is taken as it is
        ratios = [
            v.as_integer_ratio() if isinstance(v, Fraction) else float(v).as_integer_ratio()
            for v in (c1, s1, c2, s2, kappa, q1, q2)
        ]
    except (ValueError, OverflowError):
        args = (c1, s1, c2, s2, kappa, q1, q2)
        raise ValueError(f"exact: inputs must be finite, got {args}") from None
    N = math.lcm(*(d for _, d in ratios))  # the largest d when all are powers of two
    C1, S1, C2, S2, K, Q1, Q2 = [n * (N // d) for n, d in ratios]
    k1, k2 = _stiffness(K, N)
    (h1q, h1k), (h2q, h2k) = ex.h_coefficients(C1, S2, k1, k2, Q1, Q2, sub=_SUB)
    D = ex.det(C1, S1, C2, S2, sub=_SUB)
    A3, A2, A1, A0 = ex.coefficients(C1, S1, C2, S2, k1, k2, Q1, Q2, D, sub=_SUB)
    return _Scaled(C1, S1, C2, S2, K, Q1, Q2, N, (A0, A1, A2, A3, 1), (h1k, h1q, 1), (h2k, h2q, 1))


def _stiffness(K, N) -> tuple[int, int]:
    """``k1, k2`` in the integer scaling of :mod:`atlas.core.expressions` (``c -> N c``,
    ``q -> N q``, ``k -> N^3 k``): ``K N^2`` and ``N^3``."""
    return K * N * N, N * N * N


def characteristic_poly(c1, s1, c2, s2, kappa, q1, q2) -> flint.fmpq_poly:
    """``p(l) = det(l^2 I + B (K + l Q))`` with exact rational coefficients (paper eq. 9)."""
    s = _scaled(c1, s1, c2, s2, kappa, q1, q2)
    return flint.fmpq_poly([flint.fmpq(A, s.N ** (8 - 2 * k)) for k, A in enumerate(s.P)])


# --- tier 1: exact sign logic in Python ints ------------------------------------------------------


def _ss_closed(P) -> int | None:
    """SS verdict of the monic integer quartic ``P`` (module docstring), ``None`` if ``a0 = 0 != a1``."""
    A0, A1, A2, A3, _ = P
    if A0 == 0:
        if A1:
            return None
        return _N if A3 >= 0 and A2 >= 0 else _U  # p = l^2 (l^2 + a3 l + a2)
    if A3 == 0 and A1 == 0:  # l^2 = mu, mu^2 + a2 mu + a0 = 0: never stable
        return _N if A2 >= 0 and A0 > 0 and A2 * A2 >= 4 * A0 else _U
    H2 = ex.hurwitz_H2(A3, A2, A1, sub=_SUB)
    H3 = ex.hurwitz_H3(A3, A2, A1, A0, sub=_SUB)
    if A3 > 0 and H2 > 0 and H3 > 0 and A0 > 0:
        return _S
    if H3:
        return _U
    # H3 = 0 (then a1 a3 != 0): p = (l^2 + a1/a3)(l^2 + a3 l + a0 a3/a1)
    return _N if A3 > 0 and A1 > 0 and A0 > 0 else _U


def _h1_at_r2(s: _Scaled) -> int:
    """``sign h1(r2)`` at the positive root ``r2`` of ``h2`` (``s2 < 0``).

    ``h1 - h2 = A l + B`` (``A = c1 q1 - s2 q2``, ``B = c1 kappa - s2``), so ``h1(r2) = A r2 + B``;
    for opposite signs of ``A, B`` compare ``r2`` with ``t = -B/A > 0`` by the sign of
    ``h2(t) = W / A^2``, ``W = B^2 - s2 q2 A B + s2 A^2``.
    """
    k1, k2 = _stiffness(s.K, s.N)
    A = ex.arc_A(s.C1, s.S2, s.Q1, s.Q2, sub=_SUB)  # N^2 A
    B = ex.x_undamped(k1, s.C1, k2, s.S2, sub=_SUB)  # N^4 B
    sa, sb = _sign(A), _sign(B)
    if sa * sb >= 0:
        return _sign(sa + sb)
    return -sa * _sign(ex.arc_W(s.C1, s.S2, k1, k2, s.Q1, s.Q2, sub=_SUB))  # N^8 W


def _routh_rhp(P) -> int | None:
    """Roots of the monic quartic ``P`` with ``Re > 0`` (Routh), ``None`` if a Hurwitz determinant
    vanishes."""
    A0, A1, A2, A3, _ = P
    H2 = ex.hurwitz_H2(A3, A2, A1, sub=_SUB)
    H3 = ex.hurwitz_H3(A3, A2, A1, A0, sub=_SUB)
    if not (A3 and H2 and H3 and A0):
        return None
    return _variations(ex.routh_signs(1, _sign(A3), _sign(H2), _sign(H3), _sign(A0)))


def _dominance(P, simple) -> int | None:
    """``stable_II`` when the largest positive root ``l*`` of ``P`` is the II root (module docstring);
    ``simple``: ``l*`` is known to be simple.  ``None`` if ``disc = 0`` and ``simple`` is false.

    With two real roots ``r < l*`` and a pair ``z``, ``#{Re > 0} = 1 + [r > 0] + 2 [Re z > 0]`` and
    ``sign r = sign a0``: the Routh count settles ``Re z < 0``; otherwise the Tarski query of ``T``.
    """
    A0, A1, A2, A3, _ = P
    n = _routh_rhp(P)
    left = n == 1 + (A0 > 0)
    if simple and left:
        return _S
    disc = flint.fmpz_poly(list(P)).discriminant()
    if disc > 0:  # four real roots (l* is one)
        return _S
    if disc == 0:  # l* simple: the repeated root is real, so are all roots
        return _S if simple else None
    if left or (A3 == 0 and A1 == 0):  # the pair in the left half-plane or on the axis (p even)
        return _S
    return _S if _tarski(P, _tie_poly(P)) <= 0 else _U


def _ii_closed(s: _Scaled) -> tuple[int, int] | None:
    """``(consistent_II, stable_II)`` by the curve argument (module docstring); ``None`` outside its
    hypotheses (``kappa <= 0``, ``q < 0``) or where ``l*`` may be a multiple root."""
    if s.K <= 0 or s.Q1 < 0 or s.Q2 < 0:
        return None
    c1, s1, c2, s2 = (_sign(v) for v in (s.C1, s.S1, s.C2, s.S2))
    if c2 == 0 and s1 == 0:  # diagonal B, p = h1 h2: II iff r1 = r2, a double root
        return int(c1 < 0 and s2 < 0 and _h1_at_r2(s) == 0), _U
    if c2 == 0:  # p = h1 h2; II root r1 (c1 < 0) with s1 f2(r1) < 0, sign f2(r1) = sign(r1 - r2)
        if c1 >= 0:
            return 0, _U
        f2 = 1 if s2 >= 0 else -_h1_at_r2(s)
        cons = s1 * f2 < 0
        return int(cons), _S if cons and s1 < 0 else _U  # s1 < 0: r1 > r2, largest and simple
    if s1 == 0:  # p = h1 h2; II root r2 (s2 < 0) with c2 h1(r2) < 0
        if s2 >= 0:
            return 0, _U
        f1 = 1 if c1 >= 0 else _h1_at_r2(s)
        cons = c2 * f1 < 0
        return int(cons), _S if cons and c2 < 0 else _U
    P = s.P
    A0, A1, A2, A3, _ = P
    d = _sign(ex.det(s.C1, s.S1, s.C2, s.S2, sub=_SUB))
    if d == 0:  # p = l^2 e(l), e = l^2 + a3 l + a2; at a root of e, h1 = -s2 d2
        dq = ex.disc_singular(s.C1, s.S2, *_stiffness(s.K, s.N), s.Q1, s.Q2, sub=_SUB)
        cons = c2 * s2 > 0 and (A2 < 0 or (A3 < 0 and dq >= 0))
        return int(cons), _S if cons and dq > 0 else _U
    if s1 == c2:  # gamma > 0: crossings in QI (f1 f2 increasing) and QIII (decreasing)
        if c2 > 0:  # II in QIII; the later QI root is larger and not II
            return int(c1 < 0 and s2 < 0 and d > 0), _U
        if c1 >= 0 and s2 >= 0 and d > 0:  # starts in QI above the hyperbola
            return 0, _U
        return 1, _dominance(P, simple=True)  # the QI crossing: largest, simple
    # gamma < 0: every positive root lies on one arc, in QII (f1 < 0) or in QIV (f1 > 0)
    if c1 < 0 and s2 >= 0:
        arc = -1
    elif c1 >= 0 and s2 < 0:
        arc = 1
    elif c1 >= 0:  # starts in QI and stays there
        return 0, _U
    else:  # starts in QIII, leaves through the axis that r1 or r2 reaches first
        arc = _h1_at_r2(s)
        if arc == 0:  # through the origin into QI
            return 0, _U
    if arc * c2 > 0:  # the arc is not the II quadrant (sign f1 = -sign c2)
        return 0, _U
    if d > 0 and ((A3 >= 0 and A2 >= 0) or _count_positive(P) == 0):  # even count: Sturm
        return 0, _U
    stab = _dominance(P, simple=False)
    return None if stab is None else (1, stab)


# --- tier 2: certified enclosures (python-flint) and algebraic tie tests --------------------------


def _axis_roots(g: flint.fmpz_poly) -> int:
    """Number of non-real roots of the irreducible ``g`` with real part exactly 0.

    A root ``i w`` (``w != 0``) makes ``g(x)`` and ``g(-x)`` share a root, so ``g`` is even; its axis
    roots are then ``+-sqrt(y)`` for the negative roots ``y`` of ``G(y) = g(sqrt y)`` (degree <= 2).
    """
    c = g.coeffs()
    if len(c) == 2 or any(c[1::2]):
        return 0
    G = [int(v) for v in c[0::2]]
    if len(G) == 2:
        return 2 * (G[0] * G[1] > 0)
    g0, g1, g2 = G
    if g1 * g1 - 4 * g0 * g2 < 0:
        return 0
    if g0 * g2 < 0:
        return 2
    return 4 if g1 * g2 > 0 else 0  # product > 0: both roots negative iff the sum -g1/g2 < 0


def _general(s: _Scaled) -> tuple[int, int, int]:
    """``(stable_SS, consistent_II, stable_II)`` from the definitions (module docstring, tier 2)."""
    P = flint.fmpz_poly(list(s.P))
    H1, H2 = flint.fmpz_poly(list(s.H1)), flint.fmpz_poly(list(s.H2))
    if s.C2:
        rule = (H1, _sign(s.C2))
    elif s.S1:
        rule = (H2, _sign(s.S1))
    else:
        rule = None
    factors = [(g, m, _axis_roots(g)) for g, m in P.factor()[1]]
    T = flint.fmpz_poly(_tie_poly(s.P))
    prec = 64
    while True:
        with flint.ctx.workprec(prec):
            out = _general_at(factors, rule, H1, H2, T)
        if out is not None:
            return out
        prec *= 2


def _general_at(factors, rule, H1, H2, T):
    """One attempt at the working precision; ``None`` if an enclosure is too wide."""
    roots = []  # (z, factor, multiplicity, sign of Re z, real)
    for g, m, n_axis in factors:
        found = 0
        for z, _ in g.complex_roots():
            real = z.imag.is_zero()
            sgn = 1 if z.real > 0 else (-1 if z.real < 0 else None)
            if sgn is None:
                if real and z.real.is_zero():
                    sgn = 0
                elif not real and n_axis:
                    sgn, found = 0, found + 1
                else:
                    return None
            roots.append((z, g, m, sgn, real))
        if found != n_axis:  # an off-axis root not yet separated from the axis
            return None
    n_right = sum(m for _, _, m, sg, _ in roots if sg > 0)
    n_axis = sum(m for _, _, m, sg, _ in roots if sg == 0)
    ss = _U if n_right else (_N if n_axis else _S)

    def consistent(g, x) -> bool | None:
        if rule is None:  # diagonal B: any eigenvector of a double eigenvalue
            return g.gcd(H1).degree() > 0 and g.gcd(H2).degree() > 0
        h, sg = rule
        if g.gcd(h).degree() > 0:
            return False
        v = h(x)
        return sg < 0 if v > 0 else (sg > 0 if v < 0 else None)

    positive = [(z.real, g, m) for z, g, m, sg, real in roots if real and sg > 0]
    cons = [consistent(g, x) for x, g, _ in positive]
    if None in cons:
        return None
    if not any(cons):
        return ss, 0, _U
    xs = [x for x, _, _ in positive]
    top = [i for i, x in enumerate(xs) if all(x > y for j, y in enumerate(xs) if j != i)]
    if not top:
        return None
    x, g, m = positive[top[0]]
    if not cons[top[0]] or m > 1 or g.gcd(T).degree() > 0:  # not II, multiple, or an exact tie
        return ss, 1, _U
    for z, _, _, sg, real in roots:
        if real or sg == 0 or z.real < x:
            continue
        return (ss, 1, _U) if z.real > x else None
    return ss, 1, _S


# --- public API -----------------------------------------------------------------------------------


def _verdicts(s: _Scaled, names=_SPECTRAL) -> dict:
    ss = _ss_closed(s.P)
    if tuple(names) == ("stable_SS",) and ss is not None:
        return {"stable_SS": ss}
    ii = _ii_closed(s)
    if ss is None or ii is None:
        ss, *ii = _general(s)
    return dict(zip(_SPECTRAL, (ss, *ii)))


def _roots(s: _Scaled) -> list:
    """The four roots of ``p`` (with multiplicity) for display: midpoints of certified enclosures."""
    L = s.N * s.N
    with flint.ctx.workprec(64):
        enclosures = flint.fmpz_poly(list(s.P)).complex_roots()
        return [complex((z / L).mid()) for z, m in enclosures for _ in range(m)]


def point_verdicts(c1, s1, c2, s2, kappa, q1, q2) -> dict:
    """Exact ``stable_SS``, ``consistent_II``, ``stable_II`` of one point: :func:`point_spectral`
    without the roots (their enclosures cost more than the verdicts)."""
    return _verdicts(_scaled(c1, s1, c2, s2, kappa, q1, q2))


def point_spectral(c1, s1, c2, s2, kappa, q1, q2) -> dict:
    """Exact ``stable_SS``, ``consistent_II``, ``stable_II`` of one point, with its roots ``[1/time]``
    (``roots``, ``spectral_abscissa``: floats for display)."""
    s = _scaled(c1, s1, c2, s2, kappa, q1, q2)
    out = _verdicts(s)
    roots = _roots(s)
    out["roots"] = roots
    out["spectral_abscissa"] = max(z.real for z in roots)
    return out


def ss_hurwitz(c1, s1, c2, s2, kappa, q1, q2):
    """Exact SS verdict from the Routh-Hurwitz conditions and their closed-form boundary cases
    (module docstring, tier 1), or ``None`` where ``a0 = 0 != a1`` (``kappa = 0``)."""
    return _ss_closed(_scaled(c1, s1, c2, s2, kappa, q1, q2).P)


def resolve(points: dict, names=_SPECTRAL) -> dict:
    """Exact verdicts (int8 codes) for 1-D arrays of points (keys ``c1 s1 c2 s2 kappa q1 q2``)."""
    arrs = np.broadcast_arrays(*(np.atleast_1d(np.asarray(points[k])) for k in KEYS))
    n = arrs[0].size
    rows = [_verdicts(_scaled(*p), names) for p in zip(*(a.ravel().tolist() for a in arrs))]
    return {name: np.array([r[name] for r in rows], np.int8).reshape(n) for name in names}


# --- class codes and Table 1, exactly ------------------------------------------------------------


def _direction(c, s) -> tuple[int, int]:
    """``(c, s)`` times a power of two, as integers: the same direction, exactly."""
    (nc, dc), (ns, ds) = float(c).as_integer_ratio(), float(s).as_integer_ratio()
    d = max(dc, ds)
    return nc * (d // dc), ns * (d // ds)


def _angle_less(u, v) -> bool:
    """``angle(u) < angle(v)`` with angles ``atan2(s, c)`` in ``[0, 2 pi)`` (``(0, 0)`` at 0), exactly:
    half-plane ``[0, pi)`` first, then the sign of the cross product."""
    if v == (0, 0):
        return False
    if u == (0, 0):
        return not (v[1] == 0 and v[0] > 0)
    upper_u = u[1] > 0 or (u[1] == 0 and u[0] > 0)
    upper_v = v[1] > 0 or (v[1] == 0 and v[0] > 0)
    if upper_u != upper_v:
        return upper_u
    return u[0] * v[1] - u[1] * v[0] > 0


def _same_dir(u, v) -> bool:
    return u[0] * v[1] - u[1] * v[0] == 0 and u[0] * v[0] + u[1] * v[1] > 0


def _rank(target, others) -> int:
    """1-based rank of ``target``'s angle among ``others + [target]``; 0 on an exact tie."""
    if any(_same_dir(target, o) for o in others):
        return 0
    return 1 + sum(1 for o in others if _angle_less(o, target))


_AXES = [(0, 1), (-1, 0), (0, -1)]


def point_codes(c1, s1, c2, s2, ca=None, sa=None) -> dict:
    """Exact class (and subclass, Table 1) codes of one point (ties -> 0)."""
    b1, b2 = _direction(c1, s1), _direction(c2, s2)
    i = _rank(b1, _AXES)
    j = _rank(b2, [b1, (-b1[0], -b1[1])] + _AXES)
    cls = 0 if i == 0 or j == 0 else 10 * i + j
    out = {"class_code": cls}
    if ca is None:
        return out
    k = _rank(_direction(ca, sa), [b1, b2] + _AXES)
    out["subclass_code"] = 0 if cls == 0 or k == 0 else 10 * cls + k
    C1, S1, C2, S2, CA, SA = (Fraction(float(t)) for t in (c1, s1, c2, s2, ca, sa))
    out["consistent_FF"] = int(CA < 0 and SA < 0)
    out["consistent_SF"] = int(C1 * CA > 0 and (S1 * CA - SA * C1) * C1 > 0)  # b21/b11 a1 > a2
    out["consistent_FS"] = int(S2 * SA > 0 and (C2 * SA - S2 * CA) * S2 > 0)  # b12/b22 a2 > a1
    det = C1 * S2 - S1 * C2
    if det == 0:
        out["consistent_SS"] = 0
    else:
        f1 = (CA * S2 - SA * C2) / det
        f2 = (C1 * SA - S1 * CA) / det
        out["consistent_SS"] = int(f1 > 0 and f2 > 0)
    return out


def resolve_codes(c1, s1, c2, s2, ca=None, sa=None) -> dict:
    """Exact codes for 1-D arrays of points (see :func:`point_codes`)."""
    arrs = [np.atleast_1d(np.asarray(a)) for a in (c1, s1, c2, s2)]
    if ca is not None:
        arrs += [np.atleast_1d(np.asarray(ca)), np.atleast_1d(np.asarray(sa))]
    arrs = np.broadcast_arrays(*arrs)
    n = arrs[0].size
    rows = [point_codes(*(a.ravel()[i] for a in arrs)) for i in range(n)]
    return {k: np.array([r[k] for r in rows]) for k in rows[0]} if rows else {}
