"""II verdicts without damping (``q1 = q2 = 0``) in closed form (paper Appendix C).

Pure ``jax.numpy`` functions of broadcastable invariant parameters (SPEC §1, polynomials of
:mod:`atlas.core.expressions`): signs only, no roots.
"""

from __future__ import annotations

import jax.numpy as jnp

from atlas.core import expressions as ex
from atlas.core.enclosures import real_quadratic
from atlas.core.signs import CODE, UNKNOWN, det2_sign, evaluate_certified
from atlas.core.verdicts import UNDECIDED_FLAG, Consistency, Verdict

__all__ = ["ii_undamped", "ii_undamped_full"]

X = UNDECIDED_FLAG  # = Verdict.UNDECIDED = Consistency.UNDECIDED


def _sgn_plus_sqrt(sy, se, sdisc):
    """sign(Y + sqrt(D)) for D = Y^2 + E, from the signs of Y, E, D (UNKNOWN propagates)."""
    out = jnp.where(sy == 1, 1, jnp.where(sy == -1, se, jnp.where(sdisc == 1, 1, 0)))
    unk = (sy == UNKNOWN) | ((sy == -1) & (se == UNKNOWN)) | ((sy == 0) & (sdisc == UNKNOWN))
    return jnp.where(unk, UNKNOWN, out).astype(CODE)


def _neg(s):
    return jnp.where(s == UNKNOWN, UNKNOWN, -s).astype(CODE)


def ii_undamped(c1, s1, c2, s2, kappa):
    """II verdicts for ``Q = 0`` in closed form (Appendix C): ``(consistent_II, stable_II, abscissa)``.

    ``l^2 = mu``, ``mu^2 + a2 mu + a0 = 0``, ``disc = X^2 + E`` with ``X = k1 c1 - k2 s2``,
    ``E = 4 k1 k2 s1 c2``.  Real ``l > 0`` needs real ``mu > 0``: ``mu+ > 0`` iff ``det B < 0`` or
    ``a2 < 0``; ``mu- > 0`` iff ``a2 < 0`` and ``det B > 0``.  Row 1 of the eigenvector equation:
    ``c2 (mu + c1 k1) < 0`` with ``2 (mu_pm + c1 k1) = X +- sqrt(disc)``; row 2 (used where
    ``c2 = 0``): ``s1 (mu + s2 k2) < 0`` with ``2 (mu_pm + s2 k2) = -X +- sqrt(disc)``.  The sign of
    ``Y + sqrt(Y^2 + E)`` is ``+1`` for ``Y > 0`` and ``sign(E)`` for ``Y < 0``.  II is stable iff
    ``sqrt(mu+)`` is an II root and strictly dominant (``mu+ > 0``, ``disc > 0``).
    """
    k1, k2, _, _, n = ex.normalize(kappa, jnp.zeros_like(kappa), jnp.zeros_like(kappa))
    sd = det2_sign(c1, s1, c2, s2)
    _, _, s_a2 = evaluate_certified(ex.a2_undamped, k1, c1, k2, s2)
    _, _, s_disc = evaluate_certified(ex.disc_undamped, k1, c1, k2, s2, s1, c2)
    _, _, s_x = evaluate_certified(ex.x_undamped, k1, c1, k2, s2)
    se = (jnp.sign(s1) * jnp.sign(c2)).astype(CODE)
    sc2, ss1 = jnp.sign(c2).astype(CODE), jnp.sign(s1).astype(CODE)
    # sign of (mu_pm + c1 k1) and (mu_pm + s2 k2)
    h1p = _sgn_plus_sqrt(s_x, se, s_disc)
    h1m = _neg(_sgn_plus_sqrt(_neg(s_x), se, s_disc))
    h2p = _sgn_plus_sqrt(_neg(s_x), se, s_disc)
    h2m = _neg(_sgn_plus_sqrt(s_x, se, s_disc))

    X3 = X  # three-valued logic: 0 false, 1 true, undecided

    def cond(h1, h2):  # Consistency code of the eigenvector condition at that mu
        v1 = jnp.where(h1 == UNKNOWN, X3, (sc2 * h1 < 0).astype(jnp.int8))
        v2 = jnp.where(h2 == UNKNOWN, X3, (ss1 * h2 < 0).astype(jnp.int8))
        return jnp.where(sc2 != 0, v1, jnp.where(ss1 != 0, v2, X3)).astype(jnp.int8)

    def tri_and(a, b):
        return jnp.where((a == 0) | (b == 0), 0, jnp.where((a == X3) | (b == X3), X3, 1)).astype(
            jnp.int8
        )

    def tri_or(a, b):
        return jnp.where((a == 1) | (b == 1), 1, jnp.where((a == X3) | (b == X3), X3, 0)).astype(
            jnp.int8
        )

    def pos(sign):
        return jnp.where(sign == UNKNOWN, X3, (sign > 0).astype(jnp.int8)).astype(jnp.int8)

    def neg(sign):
        return jnp.where(sign == UNKNOWN, X3, (sign < 0).astype(jnp.int8)).astype(jnp.int8)

    real_mu = jnp.where(s_disc == UNKNOWN, X3, (s_disc >= 0).astype(jnp.int8)).astype(jnp.int8)
    mu_p = tri_and(real_mu, tri_or(neg(sd), neg(s_a2)))
    mu_m = tri_and(real_mu, tri_and(neg(s_a2), pos(sd)))
    cons_p = tri_and(mu_p, cond(h1p, h2p))
    cons_m = tri_and(mu_m, cond(h1m, h2m))
    cons = tri_or(cons_p, cons_m)
    stab = tri_and(cons_p, pos(s_disc))
    lost = ex.lost_to_underflow((kappa, kappa), (k1, k2)) | ex.any_subnormal(c1, s1, c2, s2)
    cons = jnp.where(lost, int(Consistency.UNDECIDED), cons).astype(jnp.int8)
    stab = jnp.where(lost, int(Verdict.UNDECIDED), stab).astype(jnp.int8)
    # abscissa: max Re sqrt(mu) over the roots of mu^2 + a2 mu + a0 (time unit of contact 2)
    a2 = ex.a2_undamped(k1, c1, k2, s2, sub=jnp.subtract)
    a0 = ex.det(c1, s1, c2, s2, sub=jnp.subtract) * k1 * k2
    m1r, m1i, m2r, _ = real_quadratic(a2, a0)
    mod = jnp.sqrt(m1r * m1r + m1i * m1i)
    re_c = jnp.sqrt(jnp.maximum(mod + m1r, 0) / 2)
    re_r = jnp.sqrt(jnp.maximum(jnp.maximum(m1r, m2r), 0))
    absc = jnp.ldexp(jnp.where(m1i != 0, re_c, re_r), n)
    return cons, stab, absc


def ii_undamped_full(c1, s1, c2, s2, kappa):
    """II verdicts for ``q1 = q2 = 0``: :func:`ii_undamped`, and for diagonal ``B``
    (``c2 = s1 = 0``, where its eigenvector rows say nothing) the closed form: ``p = h1 h2`` with
    ``h1 = l^2 + c1 k1``, ``h2 = l^2 + s2 k2``; II needs a common positive root (``c1, s2 < 0``,
    ``c1 k1 = s2 k2``): a double eigenvalue, never stable."""
    cu, su, _ = ii_undamped(c1, s1, c2, s2, kappa)
    k1, k2 = ex.normalize(kappa, jnp.zeros_like(kappa), jnp.zeros_like(kappa))[:2]
    sx = evaluate_certified(ex.x_undamped, k1, c1, k2, s2)[2]
    common = (c1 < 0) & (s2 < 0) & (c1 == s2) & (k1 == k2)
    apart = (c1 >= 0) | (s2 >= 0) | (sx == 1) | (sx == -1)
    cons_d = jnp.where(common, 1, jnp.where(apart, 0, X))
    stab_d = jnp.where(cons_d == X, X, int(Verdict.UNSTABLE))
    diag = (c2 == 0) & (s1 == 0)
    lost = ex.lost_to_underflow((kappa, kappa), (k1, k2)) | ex.any_subnormal(c1, s1, c2, s2)
    cons = jnp.where(lost, X, jnp.where(diag, cons_d, cu))
    stab = jnp.where(lost, X, jnp.where(diag, stab_d, su))
    return cons.astype(jnp.int8), stab.astype(jnp.int8)
