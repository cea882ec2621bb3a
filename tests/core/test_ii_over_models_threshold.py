"""The threshold rule of :mod:`atlas.core.ii_over_models` (classes 15 / 32, ``gamma < 0``,
``det B < 0``, ``3 |gamma| <= 2 |c1 s2|``: II stable for every model), certified in exact
rational arithmetic (sympy): the two events through which the stability could change (module
docstring) have no model, by polynomial identities with nonnegative coefficients (the code's
verdicts against numpy eigenvalues: ``test_ii_over_models.py``).

Unit class 15 (the scaling law): ``p = (l^2 + d1)(l^2 - d2) + (1 - e) d1 d2``, ``d1 = kappa + q1 l``,
``d2 = 1 + q2 l``, ``e = |D| / |c1 s2|`` in ``[1/3, 1)``.  An event model is one whose roots are
``L, -rho, L +- i sqrt(b)`` (a tie) or ``L, L, w, -rho`` (a double top root), ``L, b, rho > 0``,
``0 < w <= L``; matching the coefficients of ``l^0, l^3, l^1`` gives ``kappa, q1, q2`` (rational),
and the ``l^2`` one leaves ``H = 0``.  Each region of ``u = L rho`` is either infeasible (a
combination of ``q1 >= 0``, ``q2 >= 0`` with nonnegative multipliers is negative) or has ``-H``
equal to such a combination plus a polynomial with nonnegative coefficients and a positive term."""

import pytest

sp = pytest.importorskip("sympy")

l, L, b, rho, w, e, k, q1, q2 = sp.symbols("l L b rho w e kappa q1 q2", positive=True)
v, f, t, z = sp.symbols("v f t z", nonnegative=True)
THIRD = sp.Rational(1, 3)


def _event(roots):
    """``(q1, q2, H)`` of the unit class-15 models whose polynomial is ``roots`` (monic)."""
    p = sp.expand((l**2 + k + q1 * l) * (l**2 - 1 - q2 * l) + (1 - e) * (k + q1 * l) * (1 + q2 * l))
    eq = [sp.expand(p.coeff(l, i) - sp.expand(roots).coeff(l, i)) for i in range(4)]
    K = sp.solve(eq[0], k)[0]
    sol = sp.solve([eq[3].subs(k, K), eq[1].subs(k, K)], [q1, q2], dict=True)[0]
    return sol[q1], sol[q2], eq[2].subs(k, K).subs(sol)


def _numerator(expr, gens):
    """The numerator of ``expr`` over a denominator with positive coefficients (a Poly)."""
    n, d = sp.fraction(sp.cancel(sp.together(expr)))
    dp = sp.Poly(d, *gens)
    sign = 1 if min(dp.coeffs()) > 0 else -1
    assert all(c * sign > 0 for c in dp.coeffs()), d
    return sp.Poly(sign * n, *gens)


def _nonneg(poly, zero_ok) -> bool:
    """Every coefficient ``>= 0`` and one positive term free of the variables ``zero_ok`` (which
    may vanish): positive on the region."""
    free = [i for i, g in enumerate(poly.gens) if g not in zero_ok]
    terms = list(zip(poly.monoms(), poly.coeffs()))
    return all(c >= 0 for _, c in terms) and any(
        c > 0 and all(m[i] == 0 for i in range(len(m)) if i not in free) for m, c in terms
    )


def _combination(polys, mults, gens):
    mono = lambda m: sp.prod([g**x for g, x in zip(gens, m)])  # noqa: E731
    return sum((c * mono(m) * polys[i].as_expr() for i, m, c in mults), sp.Integer(0))


def _region(ev, subs, gens):
    """``q1``, ``q2`` (constraints ``>= 0``) and ``-H`` on a region (numerators, Poly)."""
    return [_numerator(x.subs(subs, simultaneous=True), gens) for x in (ev[0], ev[1], -ev[2])]


TIE = (l - L) * (l + rho) * ((l - L) ** 2 + b)
DOUBLE = (l - L) ** 2 * (l - w) * (l + rho)


def test_no_tie_with_a_complex_pair():
    """Roots ``L, -rho, L +- i sqrt(b)``: ``u = L rho < 1/3`` (``rho = 1 / (3 L (1 + v))``) has
    ``-H = 6 L^2 b q2 + (nonnegative coefficients)``; ``u >= 1/3`` (``rho = (1/3 + t) / L``)
    has ``(3 f + b + L^2) q1 + 3 t (b + L^2) q2 < 0``: no model, for every ``e >= 1/3``."""
    ev = _event(TIE)
    G = (L, v, b, f)
    Q1, Q2, mH = _region(ev, {rho: 1 / (3 * L * (1 + v)), e: THIRD + f}, G)
    rest = sp.Poly(mH.as_expr() - _combination((Q1, Q2), [(1, (2, 0, 1, 0), 6)], G), *G)
    assert _nonneg(rest, (v, f))
    G = (L, t, b, f)
    Q1, Q2, _ = _region(ev, {rho: (THIRD + t) / L, e: THIRD + f}, G)
    mults = [(0, (0, 0, 0, 1), 3), (0, (0, 0, 1, 0), 1), (0, (2, 0, 0, 0), 1)]
    mults += [(1, (0, 1, 1, 0), 3), (1, (2, 1, 0, 0), 3)]
    assert _nonneg(sp.Poly(-_combination((Q1, Q2), mults, G), *G), (t, f))


def test_no_double_top_root():
    """Roots ``L, L, w, -rho`` (``w = L / (1 + z)``): ``-H`` has nonnegative coefficients for
    ``u < 1/3`` (every ``e >= 1/3``) and for ``1/3 <= u < 1/2``
    (``rho = (1/3 + t / (6 (1 + t))) / L``, ``e = 1/3 + 2 f / (3 (1 + f))`` in ``[1/3, 1)``);
    ``u >= 1/2`` has ``(3 f + L^2) q1 + 6 L t q2 < 0``: no model."""
    ev = _event(DOUBLE)
    G = (L, v, z, f)
    *_, mH = _region(ev, {rho: 1 / (3 * L * (1 + v)), w: L / (1 + z), e: THIRD + f}, G)
    assert _nonneg(mH, (v, z, f))
    G = (L, t, z, f)
    mid = {rho: (THIRD + t / (6 * (1 + t))) / L, w: L / (1 + z), e: THIRD + 2 * f / (3 * (1 + f))}
    assert _nonneg(_region(ev, mid, G)[2], (t, z, f))
    Q1, Q2, _ = _region(ev, {rho: (sp.Rational(1, 2) + t) / L, w: L / (1 + z), e: THIRD + f}, G)
    mults = [(0, (0, 0, 0, 1), 3), (0, (2, 0, 0, 0), 1), (1, (1, 1, 0, 0), 6)]
    assert _nonneg(sp.Poly(-_combination((Q1, Q2), mults, G), *G), (t, z, f))


def test_the_certificates_can_fail():
    """Below ``e = 1/3`` the tie certificate's remainder has a negative coefficient (the far
    witnesses are there): the check is not vacuous."""
    G = (L, v, b, f)
    sub = {rho: 1 / (3 * L * (1 + v)), e: sp.Rational(1, 4) + f}
    Q1, Q2, mH = _region(_event(TIE), sub, G)
    rest = sp.Poly(mH.as_expr() - _combination((Q1, Q2), [(1, (2, 0, 1, 0), 6)], G), *G)
    assert not _nonneg(rest, (v, f))


def test_class_32_is_class_15():
    """Unit class 32, ``p = (l^2 - d1)(l^2 + d2) + (1 - e) d1 d2``, at ``l = K m`` and the model
    ``(K^2, q1, q2)`` is ``K^4`` times unit class 15 at ``m`` and ``(1 / K^2, q2 / K, q1 / K)``."""
    K, m = sp.symbols("K m", positive=True)

    def unit(sign, x, kap, a1, a2):
        d1, d2 = kap + a1 * x, 1 + a2 * x
        return (x**2 + sign * d1) * (x**2 - sign * d2) + (1 - e) * d1 * d2

    lhs = unit(-1, K * m, K**2, q1, q2)
    assert sp.expand(lhs - K**4 * unit(1, m, 1 / K**2, q2 / K, q1 / K)) == 0
