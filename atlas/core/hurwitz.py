"""Certified SS stability verdict (Hurwitz / Lienard-Chipart, paper Sec. 4.2) of
``M = [[0, I], [-B K, -B Q]]`` (paper eqs. 8-9).

Pure ``jax.numpy`` functions of broadcastable invariant parameters (SPEC §1): direction vectors
``(c1, s1)``, ``(c2, s2)`` of ``b1``, ``b2``, ``kappa = k1|b1|/(k2|b2|)`` and the damping
``q_j_hat = q_j |b_j| / sqrt(k2 |b2|)``; the polynomials are those of
:mod:`atlas.core.expressions` (``D = det B``, ``K = diag(kappa, 1)``).

With ``m = k1 q2 + k2 q1`` the third Hurwitz determinant is ``H3 = D G`` with

    G = s1 c2 m^2 + q1 q2 [ (k1 c1 - k2 s2)^2 + D a3 m ]          (derived here, see README)

For ``Q != 0``: ``D < 0`` -> unstable (``a0 < 0``); ``D = 0`` -> roots ``0, 0`` and those of
``l^2 + a3 l + a2``: neutral iff ``a3 >= 0`` and ``a2 >= 0``; ``D > 0``: stable iff ``a3 > 0`` and
``G > 0`` (Lienard-Chipart; ``a2 > 0`` follows), unstable if ``a3 <= 0`` or ``G < 0`` (Orlando's formula
``H3 = prod_{i<j}(l_i + l_j)``: no root on the imaginary axis when ``a0 H3 != 0``), neutral if
``G = 0`` (then ``p = (l^2 + a1/a3)(l^2 + a3 l + a0 a3/a1)``).  For ``Q = 0``: ``l^2 = mu`` with
``mu^2 + a2 mu + a0 = 0``; neutral iff ``disc = (k1 c1 - k2 s2)^2 + 4 k1 k2 s1 c2 >= 0``,
``a2 >= 0`` and ``D >= 0``, unstable otherwise (never stable).

Scaling: :func:`atlas.core.expressions.normalize` (``max(k) <= 1``), then the damping by
:func:`atlas.core.expressions.damping_scale` (``G`` evaluated as
:func:`atlas.core.expressions.G_scaled`): exact powers of two, every sign kept.
"""

from __future__ import annotations

import jax.numpy as jnp

from atlas.core import expressions as ex
from atlas.core import warm
from atlas.core.signs import CODE, UNKNOWN, det2_sign, evaluate_certified, nonzero
from atlas.core.verdicts import Verdict

__all__ = ["ss_verdict", "ss_verdict_jit", "ss_from_signs", "ss_margin"]

_G = ex.with_det(ex.G_scaled)


def _sign_parts(c1, s1, c2, s2, kappa, q1, q2):
    k1, k2, q1s, q2s, n = ex.normalize(kappa, q1, q2)
    sd = det2_sign(c1, s1, c2, s2)
    _, _, s_a2u = evaluate_certified(ex.a2_undamped, k1, c1, k2, s2)
    disc, disc_abs, s_disc = evaluate_certified(ex.disc_undamped, k1, c1, k2, s2, s1, c2)
    r1, r2, w2, w4 = ex.damping_scale(q1s, q2s)
    a3v, a3abs, s_a3 = evaluate_certified(ex.a3, c1, s2, r1, r2)
    # equal damping: sign(a3) = sign(c1 + s2), one rounding of a sum -> exact sign
    s_a3 = jnp.where(q1 == q2, jnp.sign(c1 + s2).astype(CODE), s_a3)
    G, G_abs, s_G = evaluate_certified(_G, c1, s1, c2, s2, k1, k2, r1, r2, w2, w4)
    lost = ex.lost_to_underflow((kappa, kappa, q1, q2, q1, q2), (k1, k2, q1s, q2s, r1, r2))
    lost = lost | ex.any_subnormal(c1, s1, c2, s2)
    unk = lambda sg: jnp.where(lost, UNKNOWN, sg).astype(CODE)  # noqa: E731
    return dict(
        sd=sd,
        s_a2u=unk(s_a2u),
        s_disc=unk(s_disc),
        s_a3=unk(s_a3),
        s_G=unk(s_G),
        disc=disc,
        disc_abs=disc_abs,
        G=G,
        G_abs=G_abs,
        damped=nonzero(q1) | nonzero(q2),  # q >= 0; a subnormal q is damping
    )


def _all_nonneg(*signs):
    ok = jnp.ones(jnp.broadcast_shapes(*(s.shape for s in signs)), bool)
    for s in signs:
        ok = ok & (s != UNKNOWN) & (s >= 0)
    return ok


def _any_neg(*signs):
    out = jnp.zeros(jnp.broadcast_shapes(*(s.shape for s in signs)), bool)
    for s in signs:
        out = out | (s == -1)
    return out


def ss_from_signs(p):
    """The SS verdict (Hurwitz, paper Sec. 4.2) from the certified sign codes ``p`` of its parts."""
    U, S, N, X = (
        int(Verdict.UNSTABLE),
        int(Verdict.STABLE),
        int(Verdict.NEUTRAL),
        int(Verdict.UNDECIDED),
    )
    sd, s_a2u, s_disc, s_a3, s_G = p["sd"], p["s_a2u"], p["s_disc"], p["s_a3"], p["s_G"]
    # undamped
    und = jnp.where(_any_neg(sd, s_a2u, s_disc), U, jnp.where(_all_nonneg(sd, s_a2u, s_disc), N, X))
    # damped, det B = 0
    d0 = jnp.where(_any_neg(s_a3, s_a2u), U, jnp.where(_all_nonneg(s_a3, s_a2u), N, X))
    # damped, det B > 0
    dpos = jnp.where(
        (s_a3 == -1) | (s_a3 == 0),
        U,
        jnp.where(
            s_a3 == 1, jnp.where(s_G == 1, S, jnp.where(s_G == -1, U, jnp.where(s_G == 0, N, X))), X
        ),
    )
    dmp = jnp.where(sd == -1, U, jnp.where(sd == 0, d0, jnp.where(sd == 1, dpos, X)))
    return jnp.where(p["damped"], dmp, und).astype(jnp.int8)


def ss_verdict(c1, s1, c2, s2, kappa, q1, q2):
    """Certified SS stability verdict (``Verdict`` codes, int8); see the module docstring."""
    return ss_from_signs(_sign_parts(c1, s1, c2, s2, kappa, q1, q2))


#: :func:`ss_verdict` as a kept kernel (:func:`atlas.core.warm.jit`), for point lists of any
#: length through :func:`atlas.core.buckets.call` (one program per dtype)
ss_verdict_jit = warm.jit(ss_verdict)


def ss_margin(c1, s1, c2, s2, kappa, q1, q2):
    """Smooth margin in [-1, 1] whose zero set is the curved (model-dependent) SS boundary.

    ``G / G_abs`` for damped points, ``disc / disc_abs`` for ``Q = 0``.  For contour plotting only.
    """
    p = _sign_parts(c1, s1, c2, s2, kappa, q1, q2)
    g = p["G"] / jnp.where(p["G_abs"] > 0, p["G_abs"], 1)
    d = p["disc"] / jnp.where(p["disc_abs"] > 0, p["disc_abs"], 1)
    return jnp.where(p["damped"], g, d)
