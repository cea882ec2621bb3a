"""The polynomials of atlas.core.expressions against sympy, from their definitions (symbolic)."""

from __future__ import annotations

import operator

import numpy as np
import pytest
import sympy

from atlas.core import expressions as ex

SUB = operator.sub
c1, s1, c2, s2, k1, k2, q1, q2, lam, s = sympy.symbols("c1 s1 c2 s2 k1 k2 q1 q2 lam s")
D = c1 * s2 - s1 * c2
B = sympy.Matrix([[c1, c2], [s1, s2]])
#: p(l) = det(l^2 I + B (K + l Q)), paper eq. 9, from the definition
P = sympy.Poly(
    (lam**2 * sympy.eye(2) + B * (sympy.diag(k1, k2) + lam * sympy.diag(q1, q2))).det(), lam
)
A3, A2, A1, A0 = (P.coeff_monomial(lam**k) for k in (3, 2, 1, 0))
ARGS = (c1, s1, c2, s2, k1, k2, q1, q2, D)


def same(x, y):
    return sympy.expand(x - y) == 0


def test_coefficients_are_those_of_the_characteristic_polynomial():
    assert P.LC() == 1 and P.degree() == 4
    got = ex.coefficients(*ARGS, sub=SUB)
    assert all(same(g, w) for g, w in zip(got, (A3, A2, A1, A0)))
    assert same(ex.a3(c1, s2, q1, q2, sub=SUB), A3)
    assert same(ex.a2_undamped(k1, c1, k2, s2, sub=SUB), A2.subs({q1: 0, q2: 0}))
    assert same(ex.det(c1, s1, c2, s2, sub=SUB), B.det())


def test_h_factors():
    (b1, k1c), (b2, k2s) = ex.h_coefficients(c1, s2, k1, k2, q1, q2, sub=SUB)
    h1, h2 = lam**2 + b1 * lam + k1c, lam**2 + b2 * lam + k2s
    d1, d2 = k1 + q1 * lam, k2 + q2 * lam
    assert same(h1, lam**2 + c1 * d1) and same(h2, lam**2 + s2 * d2)
    assert same(h1 * h2 - c2 * s1 * d1 * d2, P.as_expr())


def test_hurwitz_determinants_and_G():
    H2 = sympy.Matrix([[A3, A1], [1, A2]]).det()
    H3 = sympy.Matrix([[A3, A1, 0], [1, A2, A0], [0, A3, A1]]).det()
    assert same(ex.hurwitz_H2(A3, A2, A1, sub=SUB), H2)
    assert same(ex.hurwitz_H3(A3, A2, A1, A0, sub=SUB), H3)
    assert same(H3, D * ex.G(*ARGS, sub=SUB))  # H3 = D G
    # G_scaled: with q = 2^e r the weights give a positive multiple of G
    e = sympy.Symbol("e")
    r1, r2 = q1 / 2**e, q2 / 2**e
    G_q = ex.G(*ARGS, sub=SUB)
    scaled_args = (c1, s1, c2, s2, k1, k2, r1, r2, D)
    pos = ex.G_scaled(*scaled_args, 2 ** (-2 * e), 1, sub=SUB)
    neg = ex.G_scaled(*scaled_args, 1, 2 ** (2 * e), sub=SUB)
    assert sympy.simplify(G_q - 2 ** (4 * e) * pos) == 0
    assert sympy.simplify(G_q - 2 ** (2 * e) * neg) == 0


def test_undamped_and_singular_discriminants():
    mu = sympy.Symbol("mu")
    undamped = P.as_expr().subs({q1: 0, q2: 0}).subs(lam**2, mu)
    disc_mu = sympy.discriminant(sympy.Poly(sympy.expand(undamped), mu))
    assert same(ex.disc_undamped(k1, c1, k2, s2, s1, c2, sub=SUB), disc_mu)
    assert same(ex.x_undamped(k1, c1, k2, s2, sub=SUB), k1 * c1 - k2 * s2)
    # det B = 0: p = l^2 e(l), e = l^2 + a3 l + (k1 c1 + k2 s2)
    e = sympy.Poly(lam**2 + A3 * lam + k1 * c1 + k2 * s2, lam)
    assert same(
        P.as_expr().subs(c1, s1 * c2 / s2),
        sympy.expand((lam**2 * e.as_expr()).subs(c1, s1 * c2 / s2)),
    )
    assert same(ex.disc_singular(c1, s2, k1, k2, q1, q2, sub=SUB), sympy.discriminant(e))


def test_arc_W_is_h2_at_the_root_of_h1_minus_h2():
    A = ex.arc_A(c1, s2, q1, q2, sub=SUB)
    Bx = ex.x_undamped(k1, c1, k2, s2, sub=SUB)
    h1 = lam**2 + c1 * (k1 + q1 * lam)
    h2 = lam**2 + s2 * (k2 + q2 * lam)
    assert same(h1 - h2, A * lam + Bx)
    t = -Bx / A
    assert sympy.simplify(ex.arc_W(c1, s2, k1, k2, q1, q2, sub=SUB) - A**2 * h2.subs(lam, t)) == 0


def test_quartic_discriminant_shift_and_sturm_leading_terms():
    a, b, c, d = sympy.symbols("a b c d")
    quartic = sympy.Poly(lam**4 + a * lam**3 + b * lam**2 + c * lam + d, lam)
    assert same(ex.quartic_discriminant(a, b, c, d, sub=SUB), sympy.discriminant(quartic))
    shifted = sympy.Poly(quartic.as_expr().subs(lam, lam + s), lam)
    got = ex.shifted(a, b, c, d, s, sub=SUB)
    assert all(same(g, shifted.coeff_monomial(lam**k)) for g, k in zip(got, (3, 2, 1, 0)))
    # the Sturm sequence p, p', -rem(...): its polynomials' signs, up to positive factors
    seq = sympy.sturm(quartic)
    p2, p3 = seq[2], seq[3]
    P2 = ex.sturm_P2(a, b, c, d, sub=SUB)

    def ratio(x, y):  # a number: x and y equal up to a constant factor
        r = sympy.simplify(x / y)
        assert r.is_number
        return r

    # signs at +inf and at 0: (1, 1, P2, -T1, Disc) and (d, c, C2, -T0, Disc)
    assert ratio(p2.LC(), P2) > 0
    assert ratio(p2.coeff_monomial(1), ex.sturm_C2(a, b, c, d, sub=SUB)) > 0
    assert ratio(p3.LC() * P2**2, ex.sturm_T1(a, b, c, d, sub=SUB)) < 0
    assert ratio(p3.coeff_monomial(1) * P2**2, ex.sturm_T0(a, b, c, d, sub=SUB)) < 0


@pytest.mark.parametrize(
    "roots",
    [(-1, -2, -3, -4), (1, -2, -3, -4), (1, 2, -3, -4), (1, 2, 3, -4), (-1, 2 + 1j, 2 - 1j, -5)],
)
def test_routh_signs_count_the_right_half_plane(roots):
    a3, a2, a1, a0 = np.real(np.poly(roots)[1:])
    H2 = ex.hurwitz_H2(a3, a2, a1, sub=SUB)
    H3 = ex.hurwitz_H3(a3, a2, a1, a0, sub=SUB)
    signs = ex.routh_signs(1, *(int(np.sign(v)) for v in (a3, H2, H3, a0)))
    variations = sum(1 for u, v in zip(signs, signs[1:]) if u * v < 0)
    assert variations == sum(1 for r in roots if np.real(r) > 0)


def test_integer_scaling_of_the_exact_tier():
    """With c, s -> N c, N s, q -> N q, k -> N^3 k the coefficient a_k gains N^(8 - 2k)."""
    N = sympy.Symbol("N", positive=True)
    sc = {c1: N * c1, s1: N * s1, c2: N * c2, s2: N * s2, k1: N**3 * k1, k2: N**3 * k2}
    sc.update({q1: N * q1, q2: N * q2})
    got = ex.coefficients(*(v.subs(sc, simultaneous=True) for v in ARGS), sub=SUB)
    for g, w, k in zip(got, (A3, A2, A1, A0), (3, 2, 1, 0)):
        assert same(g, N ** (8 - 2 * k) * w)
    W = ex.arc_W(c1, s2, k1, k2, q1, q2, sub=SUB)
    assert same(W.subs(sc, simultaneous=True), N**8 * W)
