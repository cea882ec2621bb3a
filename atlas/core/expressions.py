"""The polynomials of the spectral problem, each written once (paper eqs. 8-9, Appendix C).

Every expression is a function of its inputs and a keyword ``sub`` and uses only ``+``, ``*``,
integer constants and ``sub``, so one definition serves every number type and every use:

* float arrays: ``sub=jnp.subtract`` gives the value, and with absolute values and ``sub=jnp.add``
  the bound of :func:`atlas.core.signs.evaluate_certified`, whose error model is derived from the
  expression as written (so the order of the operations below is part of each certificate);
* Python integers over a common power-of-two denominator (:mod:`atlas.core.exact`,
  ``sub=operator.sub``): exact values;
* mpmath numbers (:mod:`atlas.core.hardcases`): 50-digit references.

Inputs (SPEC §1): direction components ``c1, s1, c2, s2`` of ``b1, b2``, stiffnesses ``k1, k2``
(``K = diag(k1, k2)``, ``k1 / k2 = kappa``), damping ``q1, q2`` and ``D = det B = c1 s2 - s1 c2``.
Characteristic polynomial (eq. 9)::

    p(l) = det(l^2 I + B (K + l Q)) = l^4 + a3 l^3 + a2 l^2 + a1 l + a0 = h1 h2 - c2 s1 d1 d2
    h1 = l^2 + c1 d1,  h2 = l^2 + s2 d2,  d_j = k_j + q_j l

The expressions are weighted homogeneous: with ``c, s -> N c, N s``, ``k -> N^3 k``,
``q -> N q`` (``l -> N^2 l``) each is multiplied by a power of ``N`` and keeps its sign; the exact
tier evaluates them on integers this way.

The exact power-of-two scalings of the float kernels (:func:`normalize`, :func:`damping_scale`,
:func:`balance`) are here too: they keep every sign and every verdict.
"""

from __future__ import annotations

import functools

import jax.numpy as jnp

from atlas.core.signs import det2, nonzero, subnormal

__all__ = [
    "det",
    "a3",
    "a2_undamped",
    "coefficients",
    "h_coefficients",
    "x_undamped",
    "disc_undamped",
    "disc_singular",
    "hurwitz_m",
    "G",
    "G_scaled",
    "hurwitz_H2",
    "hurwitz_H3",
    "routh_signs",
    "shifted",
    "arc_A",
    "arc_W",
    "quartic_discriminant",
    "sturm_P2",
    "sturm_C2",
    "sturm_T1",
    "sturm_T0",
    "with_det",
    "normalize",
    "damping_scale",
    "balance",
    "any_subnormal",
    "lost_to_underflow",
]


# --- coefficients -------------------------------------------------------------------------------


def det(c1, s1, c2, s2, *, sub):
    """``D = det B = c1 s2 - s1 c2``."""
    return det2(c1, s1, c2, s2, sub=sub)


def a3(c1, s2, q1, q2, *, sub):
    """``a3 = c1 q1 + s2 q2`` (the trace of ``B Q``)."""
    return c1 * q1 + s2 * q2


def a2_undamped(k1, c1, k2, s2, *, sub):
    """``a2`` at ``Q = 0``: ``k1 c1 + k2 s2`` (the trace of ``B K``)."""
    return k1 * c1 + k2 * s2


def coefficients(c1, s1, c2, s2, k1, k2, q1, q2, D, *, sub):
    """``(a3, a2, a1, a0)`` of ``p``: ``a2 = k1 c1 + k2 s2 + D q1 q2``, ``a1 = D (k1 q2 + k2 q1)``,
    ``a0 = D k1 k2``."""
    return (
        a3(c1, s2, q1, q2, sub=sub),
        a2_undamped(k1, c1, k2, s2, sub=sub) + D * q1 * q2,
        D * hurwitz_m(k1, k2, q1, q2, sub=sub),
        D * k1 * k2,
    )


def h_coefficients(c1, s2, k1, k2, q1, q2, *, sub):
    """``((c1 q1, c1 k1), (s2 q2, s2 k2))``: the monic quadratics ``h1 = l^2 + c1 q1 l + c1 k1``
    and ``h2 = l^2 + s2 q2 l + s2 k2`` (rows of the gap-eigenvector equation)."""
    return (c1 * q1, c1 * k1), (s2 * q2, s2 * k2)


# --- undamped and singular closed forms ----------------------------------------------------------


def x_undamped(k1, c1, k2, s2, *, sub):
    """``X = k1 c1 - k2 s2`` (``h1 - h2`` at ``Q = 0``; ``B`` of the arc test)."""
    return sub(k1 * c1, k2 * s2)


def disc_undamped(k1, c1, k2, s2, s1, c2, *, sub):
    """Discriminant of ``mu^2 + a2 mu + a0`` (``Q = 0``, ``l^2 = mu``): ``X^2 + 4 k1 k2 s1 c2``."""
    return x_undamped(k1, c1, k2, s2, sub=sub) ** 2 + 4 * k1 * k2 * s1 * c2


def disc_singular(c1, s2, k1, k2, q1, q2, *, sub):
    """Discriminant ``a3^2 - 4 a2`` of ``l^2 + a3 l + a2``, the factor of ``p = l^2 (...)`` where
    ``det B = 0``."""
    t = a3(c1, s2, q1, q2, sub=sub)
    return sub(t * t, 4 * a2_undamped(k1, c1, k2, s2, sub=sub))


# --- Hurwitz and Routh ----------------------------------------------------------------------------


def hurwitz_m(k1, k2, q1, q2, *, sub):
    """``m = k1 q2 + k2 q1`` (``a1 = D m``)."""
    return k1 * q2 + k2 * q1


def G(c1, s1, c2, s2, k1, k2, q1, q2, D, *, sub):
    """``G`` of ``H3 = D G`` (SS stability with damping, README "Derivations")::

    G = s1 c2 m^2 + q1 q2 [X^2 + D a3 m]
    """
    m = hurwitz_m(k1, k2, q1, q2, sub=sub)
    t = a3(c1, s2, q1, q2, sub=sub)
    return s1 * c2 * m * m + q1 * q2 * (x_undamped(k1, c1, k2, s2, sub=sub) ** 2 + D * t * m)


def G_scaled(c1, s1, c2, s2, k1, k2, q1, q2, D, w2, w4, *, sub):
    """``w2 (s1 c2 m^2 + q1 q2 X^2) + w4 q1 q2 D a3 m``: ``G`` split into its parts of degree 2 and
    4 in ``q``.  With ``q = 2^e r`` (:func:`damping_scale`) and the weights ``(w2, w4) =
    (2^-2e, 1)`` (``e > 0``) or ``(1, 2^2e)``, ``G(q) = 2^(4e) G_scaled(r)`` or ``2^(2e) G_scaled(r)``;
    ``(1, 0)`` and ``(0, 1)`` give the two parts."""
    m = hurwitz_m(k1, k2, q1, q2, sub=sub)
    t = a3(c1, s2, q1, q2, sub=sub)
    part2 = s1 * c2 * m * m + q1 * q2 * x_undamped(k1, c1, k2, s2, sub=sub) ** 2
    return w2 * part2 + w4 * q1 * q2 * D * t * m


def hurwitz_H2(a3, a2, a1, *, sub):
    """Second Hurwitz determinant of the monic quartic: ``a3 a2 - a1``."""
    return sub(a3 * a2, a1)


def hurwitz_H3(a3, a2, a1, a0, *, sub):
    """Third Hurwitz determinant of the monic quartic: ``a1 H2 - a3^2 a0``."""
    return sub(a1 * hurwitz_H2(a3, a2, a1, sub=sub), a3 * a3 * a0)


def routh_signs(one, s_a3, s_H2, s_H3, s_a0):
    """The signs of the first Routh column ``(1, a3, H2/a3, H3/H2, a0)`` of a monic quartic from
    the signs of ``a3, H2, H3, a0``: its sign variations count the roots with ``Re > 0`` (where
    every sign is nonzero).  ``one`` is the sign 1 in the caller's number type."""
    return one, s_a3, s_a3 * s_H2, s_H2 * s_H3, s_a0


def shifted(a3, a2, a1, a0, s, *, sub):
    """Taylor coefficients ``(b3, b2, b1, b0)`` of ``p(l + s)``."""
    b3 = a3 + 4 * s
    b2 = a2 + 3 * a3 * s + 6 * s * s
    b1 = a1 + 2 * a2 * s + 3 * a3 * s * s + 4 * s * s * s
    b0 = (((s + a3) * s + a2) * s + a1) * s + a0
    return b3, b2, b1, b0


# --- the arc test: sign of h1 at the positive root of h2 -----------------------------------------


def arc_A(c1, s2, q1, q2, *, sub):
    """``A = c1 q1 - s2 q2`` of ``h1 - h2 = A l + B`` (``B``: :func:`x_undamped`)."""
    return sub(c1 * q1, s2 * q2)


def arc_W(c1, s2, k1, k2, q1, q2, *, sub):
    """``W = A^2 h2(-B/A) = B^2 - s2 q2 A B + s2 k2 A^2``: where ``A, B`` have opposite signs,
    ``sign h1(r2) = -sign(A) sign(W)`` at the positive root ``r2`` of ``h2``."""
    A = arc_A(c1, s2, q1, q2, sub=sub)
    B = x_undamped(k1, c1, k2, s2, sub=sub)
    return sub(B * B + s2 * k2 * A * A, s2 * q2 * A * B)


# --- discriminant and Sturm sequence of the monic quartic l^4 + a l^3 + b l^2 + c l + d -----------


def quartic_discriminant(a, b, c, d, *, sub):
    """Discriminant of ``l^4 + a l^3 + b l^2 + c l + d`` (its positive and negative monomials)."""
    aa, bb, cc, dd = a * a, b * b, c * c, d * d
    pos = (
        18 * aa * a * b * c * d
        + 144 * aa * b * dd
        + 18 * a * b * cc * c
        + 16 * bb * bb * d
        + 256 * dd * d
        + aa * bb * cc
        + 144 * b * cc * d
    )
    neg = (
        27 * aa * aa * dd
        + 4 * aa * a * cc * c
        + 4 * aa * bb * b * d
        + 6 * aa * cc * d
        + 80 * a * bb * c * d
        + 192 * a * c * dd
        + 4 * bb * b * cc
        + 128 * bb * dd
        + 27 * cc * cc
    )
    return sub(pos, neg)


def sturm_P2(a, b, c, d, *, sub):
    """``P2 = 3 a^2 - 8 b`` (leading coefficients of the Sturm sequence, up to positive factors)."""
    return sub(3 * a * a, 8 * b)


def sturm_C2(a, b, c, d, *, sub):
    """``C2 = a c - 16 d`` (constant term of the third Sturm polynomial, up to a positive factor)."""
    return sub(a * c, 16 * d)


def sturm_T1(a, b, c, d, *, sub):
    """``T1``: leading coefficient of the fourth Sturm polynomial, up to a positive factor."""
    aa, bb = a * a, b * b
    return sub(
        3 * aa * a * c + 6 * aa * d + 4 * bb * b + 18 * c * c, aa * bb + 14 * a * b * c + 16 * b * d
    )


def sturm_T0(a, b, c, d, *, sub):
    """``T0``: constant term of the fourth Sturm polynomial, up to a positive factor."""
    aa = a * a
    return sub(
        9 * aa * a * d + 4 * b * b * c + 48 * c * d, aa * b * c + 32 * a * b * d + 3 * a * c * c
    )


@functools.cache
def with_det(fn):
    """``fn(c1, s1, c2, s2, k1, k2, q1, q2, D, *rest)`` as a function of the 8 inputs and ``rest``,
    ``D = c1 s2 - s1 c2`` computed inside (an error model then covers the cancellation in ``D``,
    relative to ``|c1 s2| + |s1 c2|``)."""

    def inside(c1, s1, c2, s2, k1, k2, q1, q2, *rest, sub):
        return fn(c1, s1, c2, s2, k1, k2, q1, q2, det(c1, s1, c2, s2, sub=sub), *rest, sub=sub)

    return inside


# --- exact power-of-two scalings (float kernels) --------------------------------------------------


def normalize(kappa, q1, q2):
    """Exact power-of-two rescaling: returns ``k1, k2, q1s, q2s, n`` with ``max(k1, k2) <= 1``.

    Eigenvalues of the rescaled problem are those of the original divided by ``2**n``.
    """
    big = jnp.maximum(kappa, jnp.ones_like(kappa))
    n = jnp.ceil(jnp.log2(big) / 2).astype(jnp.int32)
    k1 = jnp.ldexp(kappa, -2 * n)
    k2 = jnp.ldexp(jnp.ones_like(kappa), -2 * n)
    return k1, k2, jnp.ldexp(q1, -n), jnp.ldexp(q2, -n), n


def damping_scale(q1s, q2s):
    """Power-of-two scale of the damping: ``r = q / 2**e`` and the weights ``(w2, w4)`` of
    :func:`G_scaled`."""
    qm = jnp.maximum(q1s, q2s)
    safe = jnp.where(qm > 0, qm, jnp.ones_like(qm))
    e = jnp.round(jnp.log2(safe)).astype(jnp.int32)
    r1, r2 = jnp.ldexp(q1s, -e), jnp.ldexp(q2s, -e)
    one = jnp.ones_like(qm)
    w2 = jnp.where(e > 0, jnp.ldexp(one, -2 * e), one)
    w4 = jnp.where(e > 0, one, jnp.ldexp(one, 2 * e))
    return r1, r2, w2, w4


def balance(kappa, q1, q2):
    """Exact power-of-two scaling to ``k1, k2, q1, q2 <= 1`` (:func:`normalize`, then time
    ``l -> 2^e l``)."""
    k1, k2, q1s, q2s, _ = normalize(kappa, q1, q2)
    qm = jnp.maximum(q1s, q2s)
    _, eq = jnp.frexp(qm)
    _, ek = jnp.frexp(jnp.maximum(k1, k2))
    e = jnp.maximum(jnp.where(qm > 0, eq, -100000), (ek + 1) // 2)
    f = jnp.ldexp(jnp.ones_like(k1), -e)
    return k1 * f * f, k2 * f * f, q1s * f, q2s * f


def any_subnormal(*xs):
    """``True`` where any of ``xs`` is subnormal (from the bits): XLA on CPU reads it as zero, so
    no comparison or sign of it in a kernel is its own (:func:`atlas.core.signs.nonzero`)."""
    out = False
    for x in xs:
        out = out | subnormal(x)
    return out


def lost_to_underflow(originals, scaled):
    """``True`` where a nonzero input is subnormal, or became zero or subnormal by an exact
    power-of-two scaling.

    The error models of :mod:`atlas.core.signs` take their inputs as exact, and XLA on CPU reads a
    subnormal as zero (:func:`atlas.core.signs.nonzero`; the tests here read the bits), so such
    points get no certified sign (they are left to the exact tier).
    """
    out = False
    for o, sc in zip(originals, scaled):
        out = out | subnormal(o) | (nonzero(o) & (subnormal(sc) | ~nonzero(sc)))
    return out
