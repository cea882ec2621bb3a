"""Independent sympy/mpmath reference for the exact tier (tests only).

The package's previous exact classifier, kept verbatim as a cross-check of :mod:`atlas.core.exact`:

* ``p(l) = det(l^2 I + B (K + l Q))`` is formed from its definition with sympy polynomials over QQ
  (``B = [[c1, c2], [s1, s2]]``, ``K = diag(kappa, 1)``, ``Q = diag(q1, q2)``);
* roots on the imaginary axis are counted exactly (``gcd`` of the real and imaginary parts of
  ``p(i w)``, real roots by Sturm sequences); the other roots' real-part signs come from roots
  computed with >= 60 significant digits (mpmath ``polyroots``), the precision doubling until every
  sign is separated from the root error estimate by a factor 1e10;
* positive real roots are isolated exactly (rational intervals); the sign of the eigenvector
  condition at such a root is exact (``gcd`` test for a zero, interval refinement otherwise).

One fix against the original: the largest positive root is the one with the largest isolating
interval ``(upper, lower)``, not ``upper`` alone (sympy isolates ``1/2`` and ``1`` as ``(0, 1)`` and
``(1, 1)``, e.g. at ``c1, s1, c2, s2, kappa, q1, q2 = -1/2, 0, -1, -1/2, 1/2, 0, 1``).

Slow (9-28 ms a point).  mpmath ``polyroots`` raises ``NoConvergence`` on exact multiple roots
(e.g. ``b1 = (-1, 0)``, ``b2 = (0, -1)``, ``kappa = 1``, ``q1 = q2``); callers skip those points.
"""

from __future__ import annotations

from fractions import Fraction

import mpmath
import sympy

from atlas.core.verdicts import Consistency, Verdict

__all__ = ["characteristic_poly", "point_spectral"]

_lam = sympy.Symbol("lam")
_w = sympy.Symbol("w")
_DPS = (60, 120, 240, 480)


def _q(x) -> sympy.Rational:
    f = Fraction(float(x))
    return sympy.Rational(f.numerator, f.denominator)


def characteristic_poly(c1, s1, c2, s2, kappa, q1, q2) -> sympy.Poly:
    """``det(l^2 I + B (K + l Q))`` over QQ with ``B = [[c1, c2], [s1, s2]]``, ``K = diag(kappa, 1)``."""
    c1, s1, c2, s2, kappa, q1, q2 = (_q(v) for v in (c1, s1, c2, s2, kappa, q1, q2))
    lam = _lam
    d1 = sympy.Poly(kappa + q1 * lam, lam, domain="QQ")
    d2 = sympy.Poly(1 + q2 * lam, lam, domain="QQ")
    l2 = sympy.Poly(lam**2, lam, domain="QQ")
    a11, a12 = l2 + d1 * c1, d2 * c2
    a21, a22 = d1 * s1, l2 + d2 * s2
    return a11 * a22 - a12 * a21


def characteristic_coeffs_mp(c1, s1, c2, s2, kappa, q1, q2) -> list:
    """The coefficients ``[1, a3, a2, a1, a0]`` (highest power first) of
    ``p(l) = (l^2 + c1 d1)(l^2 + s2 d2) - c2 s1 d1 d2`` (``d1 = kappa + q1 l``, ``d2 = 1 + q2 l``,
    paper eq. 9) in mpmath at its current precision, from mpmath numbers given by the caller."""
    cross = [q1 * q2, kappa * q2 + q1, kappa]
    return [
        mpmath.mpf(1),
        c1 * q1 + s2 * q2,
        c1 * kappa + s2 + c1 * s2 * q1 * q2 - c2 * s1 * cross[0],
        c1 * s2 * (kappa * q2 + q1) - c2 * s1 * cross[1],
        c1 * s2 * kappa - c2 * s1 * cross[2],
    ]


def _imag_axis_roots(p: sympy.Poly) -> int:
    """Number of roots of ``p`` on the imaginary axis (with multiplicity), exactly.

    ``p(i w) = R(w) + i I(w)``; the common real roots of ``R`` and ``I`` are the axis roots.
    """
    coeffs = p.all_coeffs()[::-1]  # a0, a1, ...
    re = sum(a * _w**k * (1, 0, -1, 0)[k % 4] for k, a in enumerate(coeffs))
    im = sum(a * _w**k * (0, 1, 0, -1)[k % 4] for k, a in enumerate(coeffs))
    R = sympy.Poly(re, _w, domain="QQ")
    Im = sympy.Poly(im, _w, domain="QQ")
    g = R if Im.is_zero else (Im if R.is_zero else sympy.gcd(R, Im))
    return 0 if g.degree() <= 0 else _count_real(g)


def _count_real(g: sympy.Poly) -> int:
    return sum(m * f.count_roots() for f, m in _sqf(g))


def _sqf(p: sympy.Poly):
    _, factors = p.sqf_list()
    return factors


def _numeric_roots(p: sympy.Poly, dps: int):
    with mpmath.workdps(dps):
        coeffs = [mpmath.mpf(int(c.p)) / int(c.q) for c in p.all_coeffs()]
        roots, err = mpmath.polyroots(coeffs, maxsteps=400, extraprec=2 * dps, error=True)
    return roots, err


def _sign_at_root(h: sympy.Poly, f: sympy.Poly, a, b) -> int:
    """Exact sign of ``h`` at the unique root of square-free ``f`` in the isolating interval."""
    a, b = sympy.Rational(a), sympy.Rational(b)
    if a == b:
        return int(sympy.sign(h.eval(a)))
    while f.eval(a) == 0 or f.eval(b) == 0 or f.count_roots(a, b) != 1:
        a, b = (sympy.Rational(t) for t in f.refine_root(a, b, eps=(b - a) / 4))
        if a == b:
            return int(sympy.sign(h.eval(a)))
    g = sympy.gcd(f, h)
    if g.degree() > 0 and g.count_roots(a, b) > 0:
        return 0
    while h.count_roots(a, b) > 0:
        a, b = (sympy.Rational(t) for t in f.refine_root(a, b, eps=(b - a) / 16))
        if a == b:
            break
    return int(sympy.sign(h.eval((a + b) / 2)))


def point_spectral(c1, s1, c2, s2, kappa, q1, q2) -> dict:
    """``stable_SS``, ``consistent_II``, ``stable_II`` and roots of one point (may raise, see above)."""
    p = characteristic_poly(c1, s1, c2, s2, kappa, q1, q2)
    n_axis = _imag_axis_roots(p)
    for dps in _DPS:
        roots, err = _numeric_roots(p, dps)
        order = sorted(roots, key=lambda z: abs(mpmath.re(z)))
        scale = max(mpmath.mpf(1), *(abs(z) for z in roots))
        tol = (abs(err) + mpmath.mpf(10) ** (-dps + 5)) * scale * mpmath.mpf(10) ** 10
        rest = order[n_axis:]
        if all(abs(mpmath.re(z)) > tol for z in rest):
            break
    else:
        raise ArithmeticError("real-part signs not separated at 480 digits")
    n_rhp = sum(1 for z in rest if mpmath.re(z) > 0)
    ss = Verdict.UNSTABLE if n_rhp else (Verdict.NEUTRAL if n_axis else Verdict.STABLE)

    C1, S1, C2, S2, K, Q1, Q2 = (_q(v) for v in (c1, s1, c2, s2, kappa, q1, q2))
    lam = _lam
    h1 = sympy.Poly(lam**2 + C1 * (K + Q1 * lam), lam, domain="QQ")
    h2 = sympy.Poly(lam**2 + S2 * (1 + Q2 * lam), lam, domain="QQ")
    ii_roots = []  # (lower, upper, multiplicity, consistent) for each root l > 0
    for f, m in _sqf(p):
        if f.eval(0) == 0:
            f = f.quo(sympy.Poly(lam, lam, domain="QQ"))  # square-free: a simple zero root
        if f.degree() <= 0:
            continue
        for (a, b), _k in f.intervals(inf=0):
            a, b = sympy.Rational(a), sympy.Rational(b)
            if C2 != 0:
                cons = int(sympy.sign(C2)) * _sign_at_root(h1, f, a, b) < 0
            elif S1 != 0:
                cons = int(sympy.sign(S1)) * _sign_at_root(h2, f, a, b) < 0
            else:
                cons = _sign_at_root(h1, f, a, b) == 0 and _sign_at_root(h2, f, a, b) == 0
            ii_roots.append((a, b, m, cons))
    consistent = Consistency.CONSISTENT if any(r[3] for r in ii_roots) else Consistency.INCONSISTENT

    stable_ii = Verdict.UNSTABLE
    if consistent == Consistency.CONSISTENT:
        a, b, mult, cons = max(ii_roots, key=lambda r: (r[1], r[0]))
        if cons and mult == 1:
            mid = (mpmath.mpf(int(a.p)) / int(a.q) + mpmath.mpf(int(b.p)) / int(b.q)) / 2
            k = min(range(len(roots)), key=lambda i: abs(roots[i] - mid))
            margin = min(mpmath.re(roots[k]) - mpmath.re(z) for i, z in enumerate(roots) if i != k)
            if margin > tol:
                stable_ii = Verdict.STABLE
            elif not margin < -tol:
                stable_ii = Verdict.UNDECIDED
    roots_c = [complex(z) for z in roots]
    return {
        "stable_SS": int(ss),
        "consistent_II": int(consistent),
        "stable_II": int(stable_ii),
        "spectral_abscissa": max(z.real for z in roots_c),
        "roots": roots_c,
    }
