"""Exact / high-precision reference classifier (SPEC §4 "Accuracy").

Takes the *same floating-point inputs* as the fast kernels (direction components ``c1, s1, c2, s2``,
``kappa``, ``q1``, ``q2``; see :func:`atlas.mechanics.direction`) as exact rationals, and decides every
verdict independently of the fast path:

* the characteristic polynomial is formed from its definition ``det(l^2 I + B (K + l Q))`` with exact
  rational polynomial arithmetic (sympy over QQ), not from the kernels' coefficient formulas;
* roots on the imaginary axis are counted exactly (``gcd`` of the real and imaginary parts of
  ``p(i w)``, real roots by Sturm sequences); the other roots' real-part signs come from roots
  computed with >= 60 significant digits (mpmath ``polyroots``), the precision doubling until every
  sign is separated from the root error estimate by a factor 1e10;
* positive real roots are isolated exactly (rational intervals); the sign of the eigenvector
  condition at such a root is exact (``gcd`` test for a zero, interval refinement otherwise);
* class/subclass codes and Table 1 consistency use exact rational signs (ties exact) and ranks of
  50-digit angles.

It is slow (milliseconds per point) and is used to settle the few points the fast kernels leave
``undecided`` and as the reference in tests and benchmarks.  It returns ``UNDECIDED`` only if a
dominance tie (a complex pair with real part within ``10**-(dps-10)`` of the real dominant root)
survives the largest precision; such points are counted wherever they occur.
"""

from __future__ import annotations

from fractions import Fraction

import mpmath
import numpy as np
import sympy

from .verdicts import Consistency, Verdict

__all__ = [
    "characteristic_poly",
    "point_spectral",
    "ss_hurwitz",
    "resolve",
    "point_codes",
    "resolve_codes",
]

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


def _imag_axis_roots(p: sympy.Poly) -> int:
    """Number of roots of ``p`` on the imaginary axis (with multiplicity), exactly.

    ``p(i w) = R(w) + i I(w)``; the common real roots of ``R`` and ``I`` are the axis roots.  The
    multiplicity of ``i w`` as a root of ``p`` equals its multiplicity in ``gcd(R, I)`` for real ``w``
    (``p`` has real coefficients, so ``R, I`` are the real/imaginary parts on the real line).
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
    coeffs = [mpmath.mpf(int(c.p)) / int(c.q) for c in p.all_coeffs()]
    with mpmath.workdps(dps):
        coeffs = [mpmath.mpf(int(c.p)) / int(c.q) for c in p.all_coeffs()]
        roots, err = mpmath.polyroots(coeffs, maxsteps=400, extraprec=2 * dps, error=True)
    return roots, err


def _sign_at_root(h: sympy.Poly, f: sympy.Poly, a, b) -> int:
    """Exact sign of ``h`` at the unique root of square-free ``f`` in the isolating interval.

    sympy's isolating intervals are open (or a single rational point), so the interval is first
    shrunk until neither endpoint is a root of ``f``; then a common root of ``f`` and ``h`` inside it
    means ``h = 0`` at the root, otherwise it is refined until ``h`` has no root in it.
    """
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
    """Exact verdicts for one point: ``stable_SS``, ``consistent_II``, ``stable_II`` and roots."""
    p = characteristic_poly(c1, s1, c2, s2, kappa, q1, q2)
    n_axis = _imag_axis_roots(p)
    # --- real parts of the other roots, at increasing precision
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

    # --- II: exact positive real roots and the eigenvector sign condition
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

    # --- dominance: II is stable iff the largest positive real root is II-consistent, simple, and
    # strictly right of every other root (compared at the precision reached above)
    stable_ii = Verdict.UNSTABLE
    if consistent == Consistency.CONSISTENT:
        a, b, mult, cons = max(ii_roots, key=lambda r: r[1])
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


_SPECTRAL = ("stable_SS", "consistent_II", "stable_II")


def ss_hurwitz(c1, s1, c2, s2, kappa, q1, q2):
    """Exact SS verdict from the Hurwitz conditions in rational arithmetic, or ``None``.

    Microseconds a point (``fractions.Fraction`` on the float inputs), for settling ``stable_SS``
    where the fast path could not certify a sign.  Coefficients of ``p`` (module docstring of
    :mod:`atlas.spectral`) and, for ``Q != 0``, the Routh-Hurwitz conditions on the Hurwitz
    determinants of the *coefficients* (not the fast path's factor ``G``): stable iff ``a3 > 0``,
    ``H2 = a3 a2 - a1 > 0``, ``H3 = a3 a2 a1 - a1^2 - a3^2 a0 > 0`` and ``a0 > 0``; otherwise, if
    ``a0 H3 != 0`` no root
    lies on the imaginary axis (Orlando) and the verdict is unstable.  ``a0 H3 = 0`` returns
    ``None`` (the caller uses :func:`point_spectral`).  For ``Q = 0``, ``l^2 = mu`` with
    ``mu^2 + a2 mu + a0 = 0``: neutral iff ``a2^2 >= 4 a0``, ``a2 >= 0`` and ``a0 >= 0``, else
    unstable.
    """
    c1, s1, c2, s2, k, q1, q2 = (Fraction(float(v)) for v in (c1, s1, c2, s2, kappa, q1, q2))
    D = c1 * s2 - s1 * c2
    a3 = c1 * q1 + s2 * q2
    a2 = k * c1 + s2 + D * q1 * q2
    a1 = D * (k * q2 + q1)
    a0 = D * k
    if q1 == 0 and q2 == 0:
        neutral = a2 * a2 >= 4 * a0 and a2 >= 0 and a0 >= 0
        return int(Verdict.NEUTRAL if neutral else Verdict.UNSTABLE)
    h3 = a3 * a2 * a1 - a1 * a1 - a3 * a3 * a0
    if a3 > 0 and a3 * a2 - a1 > 0 and h3 > 0 and a0 > 0:
        return int(Verdict.STABLE)
    if a0 != 0 and h3 != 0:
        return int(Verdict.UNSTABLE)
    return None


def resolve(points: dict, names=_SPECTRAL) -> dict:
    """Exact spectral verdicts for 1-D arrays of points (keys ``c1 s1 c2 s2 kappa q1 q2``).

    ``names == ("stable_SS",)`` takes :func:`ss_hurwitz` where it decides (the root-based
    :func:`point_spectral` elsewhere and for every II verdict).
    """
    keys = ("c1", "s1", "c2", "s2", "kappa", "q1", "q2")
    arrs = [np.atleast_1d(np.asarray(points[k])) for k in keys]
    arrs = np.broadcast_arrays(*arrs)
    n = arrs[0].size
    out = {name: np.empty(n, np.int8) for name in names}
    ss_only = tuple(names) == ("stable_SS",)
    for i in range(n):
        args = [float(a.ravel()[i]) for a in arrs]
        v = ss_hurwitz(*args) if ss_only else None
        r = {"stable_SS": v} if v is not None else point_spectral(*args)
        for name in names:
            out[name][i] = r[name]
    return out


# --- class codes and Table 1, exactly ------------------------------------------------------------


def _angle(c, s):
    with mpmath.workdps(50):
        a = mpmath.atan2(mpmath.mpf(float(s)), mpmath.mpf(float(c)))
        return a % (2 * mpmath.pi)


def _same_dir(u, v) -> bool:
    ux, uy = (Fraction(float(t)) for t in u)
    vx, vy = (Fraction(float(t)) for t in v)
    return ux * vy - uy * vx == 0 and ux * vx + uy * vy > 0


def _rank(target, others) -> int:
    """1-based rank of ``target`` among ``others + [target]``; 0 on an exact tie."""
    if any(_same_dir(target, o) for o in others):
        return 0
    t = _angle(*target)
    return 1 + sum(1 for o in others if _angle(*o) < t)


_AXES = [(0.0, 1.0), (-1.0, 0.0), (0.0, -1.0)]


def point_codes(c1, s1, c2, s2, ca=None, sa=None) -> dict:
    """Exact class (and subclass, Table 1) codes of one point (ties -> 0)."""
    b1, b2 = (float(c1), float(s1)), (float(c2), float(s2))
    i = _rank(b1, _AXES)
    j = _rank(b2, [b1, (-b1[0], -b1[1])] + _AXES)
    cls = 0 if i == 0 or j == 0 else 10 * i + j
    out = {"class_code": cls}
    if ca is None:
        return out
    a = (float(ca), float(sa))
    k = _rank(a, [b1, b2] + _AXES)
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
