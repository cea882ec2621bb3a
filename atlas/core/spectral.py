"""The spectral verdicts of ``M = [[0, I], [-B K, -B Q]]`` (paper eqs. 8-9), assembled from their parts.

Inputs are the invariant parameters of SPEC §1 (:class:`atlas.core.invariants.Invariants`):
direction vectors ``(c1, s1)``, ``(c2, s2)`` of ``b1``, ``b2`` (see
:func:`atlas.core.contact_modes.direction`), ``kappa = k1|b1|/(k2|b2|)`` and the damping
``q_j_hat = q_j |b_j| / sqrt(k2 |b2|)``; time is scaled by contact 2.  The parts:

* :mod:`atlas.core.expressions`  the polynomials (``p = l^4 + a3 l^3 + a2 l^2 + a1 l + a0``, ``G``...);
* :mod:`atlas.core.hurwitz`      ``stable_SS`` (Hurwitz, certified signs);
* :mod:`atlas.core.undamped`     the II verdicts at ``Q = 0`` in closed form;
* :mod:`atlas.core.enclosures`   the II verdicts from certified root enclosures (any damping);
* :mod:`atlas.core.baseline`     the uncertified ``eig`` baseline (comparisons only).

The tier driver of every caller is :func:`atlas.core.points.spectral_points`; :func:`verdicts`
here evaluates these parts directly on broadcast arrays (no root-free tiers, no exact tier).
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from atlas.core import expressions as ex
from atlas.core.enclosures import ii_verdicts
from atlas.core.hurwitz import ss_verdict
from atlas.core.signs import CODE, UNKNOWN, det2_sign, sign_of
from atlas.core.undamped import ii_undamped
from atlas.core.verdicts import Consistency, Verdict

__all__ = [
    "coefficients",
    "ii_possible",
    "verdicts",
    "verdicts_jit",
]


def coefficients(c1, s1, c2, s2, kappa, q1, q2):
    """Coefficients ``(a3, a2, a1, a0)`` of ``p`` in the *unscaled* invariant parameters."""
    one = jnp.ones_like(kappa)
    D = ex.det(c1, s1, c2, s2, sub=jnp.subtract)
    return ex.coefficients(c1, s1, c2, s2, kappa, one, q1, q2, D, sub=jnp.subtract)


def ii_possible(c1, s1, c2, s2):
    """``False`` where II is certainly inconsistent: no ``f > 0`` with ``B f`` in the open third
    quadrant (the paper's necessary condition, Sec. 4.3).  Exact sign logic; where ``det B`` cannot
    be certified the answer is ``True`` (the full analysis decides).

    An II eigenvector ``x > 0`` at ``l > 0`` gives ``y = (K + l Q) x > 0`` with ``B y = -l^2 x``.
    The open cone ``{f1 b1 + f2 b2, f > 0}`` meets the open third quadrant iff ``b1`` or ``b2`` lies
    in it, or (``det B != 0``) the cone contains the direction ``(-1, -1)``, i.e.
    ``sign(c2 - s2) = sign(s1 - c1) = sign(det B)``; for ``det B = 0`` the cone is a ray or a line.
    """
    in3 = lambda c, s: (sign_of(c) < 0) & (sign_of(s) < 0)  # noqa: E731
    sd = det2_sign(c1, s1, c2, s2)
    d = jnp.sign(c2 - s2).astype(CODE)  # one rounding: exact sign
    e = jnp.sign(s1 - c1).astype(CODE)
    through = (sd != 0) & (sd != UNKNOWN) & (d == sd) & (e == sd)
    opposite = (sd == 0) & (c1 == -c2) & (s1 == -s2) & (in3(c1, s1) | in3(-c1, -s1))
    return in3(c1, s1) | in3(c2, s2) | through | opposite | (sd == UNKNOWN)


def verdicts(c1, s1, c2, s2, kappa, q1, q2, *, ii=True, damped=None):
    """All spectral verdicts: dict with ``stable_SS``, ``consistent_II``, ``stable_II`` and
    ``spectral_abscissa`` (arrays broadcast over the inputs).

    ``damped=False`` promises ``q1 = q2 = 0`` everywhere (closed forms only, no root finding);
    ``None`` handles any mix (undamped points still use the closed forms).
    """
    out = {"stable_SS": ss_verdict(c1, s1, c2, s2, kappa, q1, q2)}
    if not ii:
        return out
    cu, su, au = ii_undamped(c1, s1, c2, s2, kappa)
    if damped is False:
        shape = out["stable_SS"].shape
        out.update(
            consistent_II=jnp.broadcast_to(cu, shape),
            stable_II=jnp.broadcast_to(su, shape),
            spectral_abscissa=jnp.broadcast_to(au, shape),
        )
        return out
    cons, stab, absc = ii_verdicts(c1, s1, c2, s2, kappa, q1, q2)
    undamped = (q1 == 0) & (q2 == 0)
    possible = ii_possible(c1, s1, c2, s2)
    cons = jnp.where(possible, cons, int(Consistency.INCONSISTENT))
    stab = jnp.where(possible, stab, int(Verdict.UNSTABLE))
    out.update(
        consistent_II=jnp.where(undamped, cu, cons).astype(jnp.int8),
        stable_II=jnp.where(undamped, su, stab).astype(jnp.int8),
        spectral_abscissa=jnp.where(undamped, au, absc),
    )
    return out


verdicts_jit = jax.jit(verdicts, static_argnames=("ii", "damped"))
