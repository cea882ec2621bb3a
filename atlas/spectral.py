"""Certified spectral kernels for ``M = [[0, I], [-B K, -B Q]]`` (paper eqs. 8-9, Appendix C).

Pure ``jax.numpy`` functions of broadcastable arrays; no I/O.  Inputs are the invariant parameters
of SPEC §1: direction vectors ``(c1, s1)``, ``(c2, s2)`` of ``b1``, ``b2`` (see
:func:`atlas.mechanics.direction`), ``kappa = k1|b1|/(k2|b2|)`` and the damping
``q_j_hat = q_j |b_j| / sqrt(k2 |b2|)``; time is scaled by contact 2.

Characteristic polynomial (``D = det B = c1 s2 - s1 c2``, ``K = diag(kappa, 1)``)::

    p(l) = det(l^2 I + B (K + l Q)) = l^4 + a3 l^3 + a2 l^2 + a1 l + a0
    a3 = c1 q1 + s2 q2,  a2 = k1 c1 + k2 s2 + D q1 q2,  a1 = D (k1 q2 + k2 q1),  a0 = D k1 k2

**SS stability.**  With ``m = k1 q2 + k2 q1`` the third Hurwitz determinant is ``H3 = D G`` with

    G = s1 c2 m^2 + q1 q2 [ (k1 c1 - k2 s2)^2 + D a3 m ]          (derived here, see README)

For ``Q != 0``: ``D < 0`` -> unstable (``a0 < 0``); ``D = 0`` -> roots ``0, 0`` and those of
``l^2 + a3 l + a2``: neutral iff ``a3 >= 0`` and ``a2 >= 0``; ``D > 0``: stable iff ``a3 > 0`` and
``G > 0`` (Lienard-Chipart; ``a2 > 0`` follows), unstable if ``a3 <= 0`` or ``G < 0`` (Orlando's formula
``H3 = prod_{i<j}(l_i + l_j)``: no root on the imaginary axis when ``a0 H3 != 0``), neutral if
``G = 0`` (then ``p = (l^2 + a1/a3)(l^2 + a3 l + a0 a3/a1)``).  For ``Q = 0``: ``l^2 = mu`` with
``mu^2 + a2 mu + a0 = 0``; neutral iff ``disc = (k1 c1 - k2 s2)^2 + 4 k1 k2 s1 c2 >= 0``,
``a2 >= 0`` and ``D >= 0``, unstable otherwise (never stable).

**II.**  A real root ``l > 0`` with gap eigenvector ``x``, ``x1 x2 > 0``.  Row 1 of
``(l^2 I + B D(l)) x = 0`` gives ``x ~ (c2 d2, -h1)``, ``h1 = l^2 + c1 (k1 + l q1)``: consistent iff
``c2 h1(l) < 0`` (valid when ``c2 != 0``); row 2 gives ``s1 h2(l) < 0``, ``h2 = l^2 + s2 (k2 + l q2)``
(valid when ``s1 != 0``).  Roots are located by a closed form polished by Weierstrass (Durand-Kerner)
steps and *enclosed* by Gershgorin disks of the Weierstrass correction ``W_i``: all roots lie in
``U_i {|z - z_i| <= n |W_i|}`` and a connected component of ``m`` disks holds ``m`` roots (Carstensen
1991; the roots of ``p`` are the eigenvalues of ``diag(z) - W 1^T``).  ``|W_i|`` is bounded from above
with the rounding error of the coefficients and of Horner's scheme, so every decision taken from the
disks is proven; where disks cannot separate what a verdict needs, the verdict is ``UNDECIDED``.

Scaling: ``K`` is multiplied by ``4^-n`` and ``Q`` by ``2^-n`` (exact powers of two) so that
``max(k) <= 1``; this rescales time and keeps every sign (SS) and every II verdict.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from ._signs import UNKNOWN, det2_sign, evaluate_certified, gamma
from .verdicts import Consistency, Verdict

__all__ = [
    "normalize",
    "coefficients",
    "ss_verdict",
    "ss_margin",
    "ii_verdicts",
    "verdicts",
    "quartic_roots",
    "eig_verdicts",
    "build_M",
]

_DK_STEPS = 3


def normalize(kappa, q1, q2):
    """Exact power-of-two rescaling: returns ``k1, k2, q1s, q2s, n`` with ``max(k1, k2) <= 1``.

    Eigenvalues of the rescaled problem are those of the original divided by ``2**n``.
    """
    big = jnp.maximum(kappa, jnp.ones_like(kappa))
    n = jnp.ceil(jnp.log2(big) / 2).astype(jnp.int32)
    k1 = jnp.ldexp(kappa, -2 * n)
    k2 = jnp.ldexp(jnp.ones_like(kappa), -2 * n)
    return k1, k2, jnp.ldexp(q1, -n), jnp.ldexp(q2, -n), n


# --- polynomial expressions, written once; evaluated as values and as absolute bounds ------------


def _a2_undamped(k1, c1, k2, s2, *, sub):
    return k1 * c1 + k2 * s2


def _disc_undamped(k1, c1, k2, s2, s1, c2, *, sub):
    return sub(k1 * c1, k2 * s2) ** 2 + 4 * k1 * k2 * s1 * c2


def _a3(c1, r1, s2, r2, *, sub):
    return c1 * r1 + s2 * r2


def _G(s1, c2, k1, c1, k2, s2, r1, r2, w2, w4, *, sub):
    m = k1 * r2 + k2 * r1
    a3 = c1 * r1 + s2 * r2
    det = sub(c1 * s2, s1 * c2)
    return (
        w2 * (s1 * c2 * m * m + r1 * r2 * sub(k1 * c1, k2 * s2) ** 2) + w4 * r1 * r2 * det * a3 * m
    )


def _coefficients(c1, s1, c2, s2, k1, k2, q1, q2, *, sub):
    det = sub(c1 * s2, s1 * c2)
    a3 = c1 * q1 + s2 * q2
    a2 = k1 * c1 + k2 * s2 + det * q1 * q2
    a1 = det * (k1 * q2 + k2 * q1)
    a0 = det * k1 * k2
    return a3, a2, a1, a0


def coefficients(c1, s1, c2, s2, kappa, q1, q2):
    """Coefficients ``(a3, a2, a1, a0)`` of ``p`` in the *unscaled* invariant parameters."""
    one = jnp.ones_like(kappa)
    return _coefficients(c1, s1, c2, s2, kappa, one, q1, q2, sub=jnp.subtract)


def _damping_scale(q1s, q2s):
    """Power-of-two scale of the damping: ``r = q / 2**e``, weights of the q^2 and q^4 parts of G."""
    qm = jnp.maximum(q1s, q2s)
    safe = jnp.where(qm > 0, qm, jnp.ones_like(qm))
    e = jnp.round(jnp.log2(safe)).astype(jnp.int32)
    r1, r2 = jnp.ldexp(q1s, -e), jnp.ldexp(q2s, -e)
    one = jnp.ones_like(qm)
    w2 = jnp.where(e > 0, jnp.ldexp(one, -2 * e), one)
    w4 = jnp.where(e > 0, one, jnp.ldexp(one, 2 * e))
    return r1, r2, w2, w4


def _sign_parts(c1, s1, c2, s2, kappa, q1, q2):
    k1, k2, q1s, q2s, n = normalize(kappa, q1, q2)
    sd = det2_sign(c1, s1, c2, s2)
    _, _, s_a2u = evaluate_certified(_a2_undamped, k1, c1, k2, s2)
    disc, disc_abs, s_disc = evaluate_certified(_disc_undamped, k1, c1, k2, s2, s1, c2)
    r1, r2, w2, w4 = _damping_scale(q1s, q2s)
    a3v, a3abs, s_a3 = evaluate_certified(_a3, c1, r1, s2, r2)
    # equal damping: sign(a3) = sign(c1 + s2), one rounding of a sum -> exact sign
    s_a3 = jnp.where(q1 == q2, jnp.sign(c1 + s2).astype(jnp.int8), s_a3)
    G, G_abs, s_G = evaluate_certified(_G, s1, c2, k1, c1, k2, s2, r1, r2, w2, w4)
    return dict(
        sd=sd,
        s_a2u=s_a2u,
        s_disc=s_disc,
        s_a3=s_a3,
        s_G=s_G,
        disc=disc,
        disc_abs=disc_abs,
        G=G,
        G_abs=G_abs,
        damped=(q1s > 0) | (q2s > 0),
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


def _ss_from_signs(p):
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
        jnp.where(s_a3 == 1, jnp.where(s_G == 1, S, jnp.where(s_G == -1, U, X)), X),
    )
    dmp = jnp.where(sd == -1, U, jnp.where(sd == 0, d0, jnp.where(sd == 1, dpos, X)))
    return jnp.where(p["damped"], dmp, und).astype(jnp.int8)


def ss_verdict(c1, s1, c2, s2, kappa, q1, q2):
    """Certified SS stability verdict (``Verdict`` codes, int8); see the module docstring."""
    return _ss_from_signs(_sign_parts(c1, s1, c2, s2, kappa, q1, q2))


def ss_margin(c1, s1, c2, s2, kappa, q1, q2):
    """Smooth margin in [-1, 1] whose zero set is the curved (model-dependent) SS boundary.

    ``G / G_abs`` for damped points, ``disc / disc_abs`` for ``Q = 0``.  For contour plotting only.
    """
    p = _sign_parts(c1, s1, c2, s2, kappa, q1, q2)
    g = p["G"] / jnp.where(p["G_abs"] > 0, p["G_abs"], 1)
    d = p["disc"] / jnp.where(p["disc_abs"] > 0, p["disc_abs"], 1)
    return jnp.where(p["damped"], g, d)


# --- roots and their enclosure ------------------------------------------------------------------


def _csqrt(z):
    return jnp.sqrt(z)


def _cbrt(z):
    r = jnp.abs(z)
    th = jnp.angle(z)
    return jnp.where(r > 0, jnp.cbrt(r) * jnp.exp(1j * th / 3), 0)


def _quadratic_roots(b, c):
    """Roots of ``z^2 + b z + c`` (complex, cancellation-free)."""
    b = b.astype(jnp.result_type(b, 1j))
    c = c.astype(b.dtype)
    s = _csqrt(b * b - 4 * c)
    s = jnp.where(jnp.real(jnp.conj(b) * s) >= 0, s, -s)
    z1 = -(b + s) / 2
    z2 = jnp.where(z1 != 0, c / jnp.where(z1 != 0, z1, 1), -b - z1)
    return z1, z2


def _poly_eval(coef, z):
    """Horner evaluation of the monic polynomial with ``coef = (a3, a2, a1, a0)``."""
    acc = jnp.ones_like(z)
    for a in coef:
        acc = acc * z + a
    return acc


def quartic_roots(a3, a2, a1, a0, undamped):
    """Approximate roots of the monic quartic (closed form + Weierstrass polishing).

    Undamped points (``a3 = a1 = 0``) use the exact biquadratic structure ``+-sqrt(mu)``.
    """
    cdt = jnp.result_type(a3, 1j)
    a3c, a2c, a1c, a0c = (x.astype(cdt) for x in (a3, a2, a1, a0))
    # biquadratic
    mu1, mu2 = _quadratic_roots(a2, a0)
    r1, r2 = _csqrt(mu1), _csqrt(mu2)
    biq = (r1, -r1, r2, -r2)
    # Ferrari: l = y - a3/4, y^4 + p y^2 + qq y + r
    sh = a3c / 4
    p = a2c - 6 * sh * sh
    qq = a1c - 2 * a2c * sh + 8 * sh**3
    r = a0c - a1c * sh + a2c * sh * sh - 3 * sh**4
    # resolvent 8 m^3 + 8 p m^2 + (2 p^2 - 8 r) m - qq^2 = 0  ->  m^3 + B m^2 + C m + Dd
    B, C, Dd = p, p * p / 4 - r, -qq * qq / 8
    # depressed cubic m = t - B/3
    P = C - B * B / 3
    Qc = 2 * B**3 / 27 - B * C / 3 + Dd
    disc = _csqrt(Qc * Qc / 4 + P**3 / 27)
    u = _cbrt(-Qc / 2 + jnp.where(jnp.abs(-Qc / 2 + disc) >= jnp.abs(-Qc / 2 - disc), disc, -disc))
    omega = jnp.exp(2j * jnp.pi / 3).astype(cdt)
    best = jnp.zeros_like(u)
    for kk in range(3):
        uk = u * omega**kk
        tk = uk - jnp.where(uk != 0, P / (3 * jnp.where(uk != 0, uk, 1)), 0)
        mk = tk - B / 3
        best = jnp.where(jnp.abs(mk) > jnp.abs(best), mk, best)
    m = best
    s2m = _csqrt(2 * m)
    safe = jnp.where(s2m != 0, s2m, 1)
    t = jnp.where(s2m != 0, qq / (2 * safe), 0)
    y1, y2 = _quadratic_roots(-s2m, p / 2 + m + t)
    y3, y4 = _quadratic_roots(s2m, p / 2 + m - t)
    fer = (y1 - sh, y2 - sh, y3 - sh, y4 - sh)
    z = jnp.stack([jnp.where(undamped, b, f) for b, f in zip(biq, fer)], axis=-1)
    coef = (a3c[..., None], a2c[..., None], a1c[..., None], a0c[..., None])
    for _ in range(_DK_STEPS):
        w = _weierstrass(coef, z)
        z = jnp.where(undamped[..., None] | ~jnp.isfinite(w), z, z - w)
    return z


def _pairwise_diff_prod(z):
    n = z.shape[-1]
    prods = []
    for i in range(n):
        pr = jnp.ones_like(z[..., i])
        for j in range(n):
            if j != i:
                pr = pr * (z[..., i] - z[..., j])
        prods.append(pr)
    return jnp.stack(prods, axis=-1)


def _weierstrass(coef, z):
    return _poly_eval(coef, z) / _pairwise_diff_prod(z)


def _enclosure(coef, coef_abs, z, dtype):
    """Radii ``R_i`` of proven inclusion disks ``|z - z_i| <= R_i`` (Gershgorin on ``W``)."""
    n = z.shape[-1]
    u = float(jnp.finfo(dtype).eps) / 2
    g = gamma(64, dtype)
    tiny = float(jnp.finfo(dtype).tiny)
    val = jnp.abs(_poly_eval(coef, z))
    az = jnp.abs(z)
    bound = jnp.ones_like(az)
    for a in coef_abs:
        bound = bound * az + a
    err = g * bound + 1e6 * tiny
    den = jnp.abs(_pairwise_diff_prod(z)) * (1 - 64 * u)
    wup = (val + err) * (1 + 64 * u) / den
    wup = jnp.where(jnp.isfinite(wup) & (den > 0), wup, jnp.inf)
    return n * wup


def _interval_quadratic_sign(sgn, b, c, lo, hi, dtype):
    """Certified sign of ``sgn * (l^2 + b l + c)`` over ``l in [lo, hi]`` (``0 <= lo``).

    Returns +1 (positive on all of it), -1 (negative on all of it) or UNKNOWN.
    """
    g = gamma(16, dtype)
    bl = jnp.minimum(b * lo, b * hi)
    bh = jnp.maximum(b * lo, b * hi)
    low = lo * lo + bl + c
    high = hi * hi + bh + c
    slack = g * (hi * hi + jnp.abs(b) * hi + jnp.abs(c)) + 1e6 * float(jnp.finfo(dtype).tiny)
    pos = low > slack
    neg = high < -slack
    s = jnp.where(pos, 1, jnp.where(neg, -1, UNKNOWN))
    s = jnp.where(sgn > 0, s, jnp.where(s == UNKNOWN, UNKNOWN, -s))
    s = jnp.where(sgn == 0, UNKNOWN, s)
    return s.astype(jnp.int8)


def _ii_from_roots(z, R, c1, s1, c2, s2, k1, k2, q1s, q2s, exact_zero_pair, dtype):
    """II consistency and stability verdicts from enclosed roots (see module docstring)."""
    u = float(jnp.finfo(dtype).eps) / 2
    n = z.shape[-1]
    x, y = jnp.real(z), jnp.imag(z)
    lo_f, hi_f = 1 - 8 * u, 1 + 8 * u
    # exact roots (known zeros) have R = 0 and never count as overlapping each other
    exact = R == 0

    def overlap(zi, zj, Ri, Rj, both_exact):
        return (jnp.abs(zi - zj) * lo_f <= (Ri + Rj) * hi_f) & ~both_exact

    iso, conj_clear, dom = [], [], []
    for i in range(n):
        o = jnp.zeros(x[..., i].shape, bool)
        cc = jnp.ones(x[..., i].shape, bool)
        d = jnp.ones(x[..., i].shape, bool)
        for j in range(n):
            if j == i:
                continue
            be = exact[..., i] & exact[..., j]
            o = o | overlap(z[..., i], z[..., j], R[..., i], R[..., j], be)
            cc = cc & ~overlap(jnp.conj(z[..., i]), z[..., j], R[..., i], R[..., j], be)
            d = d & (
                (x[..., i] - R[..., i]) * 1
                > (x[..., j] + R[..., j])
                + 8 * u * (jnp.abs(x[..., i]) + jnp.abs(x[..., j]) + R[..., i] + R[..., j])
            )
        iso.append(~o)
        conj_clear.append(cc)
        dom.append(d)
    iso, conj_clear, dom = (jnp.stack(v, -1) for v in (iso, conj_clear, dom))
    meets_axis = jnp.abs(y) <= R * hi_f + 8 * u * jnp.abs(z)
    real = iso & conj_clear & meets_axis
    lo = jnp.maximum(x - R, 0) * lo_f
    hi = (x + R) * hi_f
    pos_possible = meets_axis & (x + R * hi_f > 0)
    e = lambda a: a[..., None]  # noqa: E731
    # row 1: c2 * (l^2 + c1 q1 l + c1 k1) < 0 ; row 2: s1 * (l^2 + s2 q2 l + s2 k2) < 0
    one = jnp.ones_like(lo)
    h1 = _interval_quadratic_sign(one, e(c1 * q1s), e(c1 * k1), lo, hi, dtype)
    h2 = _interval_quadratic_sign(one, e(s2 * q2s), e(s2 * k2), lo, hi, dtype)
    known1, known2 = h1 != UNKNOWN, h2 != UNKNOWN
    r1 = jnp.where(known1, jnp.sign(e(c2)) * h1, 0)  # row 1 usable where c2 != 0
    r2 = jnp.where(known2, jnp.sign(e(s1)) * h2, 0)  # row 2 usable where s1 != 0
    cons_row = (r1 < 0) | (r2 < 0)
    # x2 = 0 when s1 = 0 and h2 != 0; x1 = 0 when c2 = 0 and h1 != 0: x1 x2 = 0, not II
    incons_row = (r1 > 0) | (r2 > 0) | ((e(s1) == 0) & known2) | ((e(c2) == 0) & known1)
    cons_cert = real & (x - R * hi_f > 0) & cons_row
    incons_cert = ~pos_possible | incons_row
    C, I, X = int(Consistency.CONSISTENT), int(Consistency.INCONSISTENT), int(Consistency.UNDECIDED)
    consistent = jnp.where(jnp.any(cons_cert, -1), C, jnp.where(jnp.all(incons_cert, -1), I, X))
    # stability: strictly dominant root
    stable_dom = jnp.any(dom & cons_cert, -1)
    unstable_dom = jnp.any(dom & incons_cert, -1)
    # a certified non-real root strictly right of every root that may be real -> no real dominant
    nonreal = ~meets_axis
    cplx_right = []
    for i in range(n):
        ok = nonreal[..., i]
        for j in range(n):
            if j != i:
                ok = ok & (
                    ~meets_axis[..., j]
                    | (
                        (x[..., i] - R[..., i])
                        > (x[..., j] + R[..., j])
                        + 8 * u * (jnp.abs(x[..., i]) + jnp.abs(x[..., j]))
                    )
                )
        cplx_right.append(ok)
    cplx_right = jnp.any(jnp.stack(cplx_right, -1), -1)
    S, U, XX = int(Verdict.STABLE), int(Verdict.UNSTABLE), int(Verdict.UNDECIDED)
    stable = jnp.where(
        consistent == I, U, jnp.where(stable_dom, S, jnp.where(unstable_dom | cplx_right, U, XX))
    )
    return consistent.astype(jnp.int8), stable.astype(jnp.int8)


def _roots_and_radii(c1, s1, c2, s2, kappa, q1, q2):
    dtype = c1.dtype
    k1, k2, q1s, q2s, n = normalize(kappa, q1, q2)
    shape = jnp.broadcast_shapes(
        c1.shape, s1.shape, c2.shape, s2.shape, kappa.shape, q1.shape, q2.shape
    )
    bc = lambda a: jnp.broadcast_to(a, shape)  # noqa: E731
    c1, s1, c2, s2, k1, k2, q1s, q2s, n = (bc(a) for a in (c1, s1, c2, s2, k1, k2, q1s, q2s, n))
    sd = det2_sign(c1, s1, c2, s2)
    dzero = sd == 0
    coef = _coefficients(c1, s1, c2, s2, k1, k2, q1s, q2s, sub=jnp.subtract)
    coef_abs = _coefficients(*(jnp.abs(a) for a in (c1, s1, c2, s2, k1, k2, q1s, q2s)), sub=jnp.add)
    # exact zeros of a1, a0 where det B = 0 exactly
    a3, a2, a1, a0 = coef
    a1 = jnp.where(dzero, 0, a1)
    a0 = jnp.where(dzero, 0, a0)
    coef = (a3, a2, a1, a0)
    undamped = (q1s == 0) & (q2s == 0)
    z = quartic_roots(a3, a2, a1, a0, undamped)
    cdt = z.dtype
    cc = tuple(a.astype(cdt)[..., None] for a in coef)
    cca = tuple(a[..., None] for a in coef_abs)
    R = _enclosure(cc, cca, z, dtype)
    # det B = 0: roots 0, 0 exactly, and the two roots of l^2 + a3 l + a2
    zq1, zq2 = _quadratic_roots(a3, a2)
    zq = jnp.stack([zq1, zq2], -1)
    cq = (a3.astype(cdt)[..., None], a2.astype(cdt)[..., None])
    cqa = (coef_abs[0][..., None], coef_abs[1][..., None])
    Rq = _enclosure(cq, cqa, zq, dtype)
    zd = jnp.concatenate([zq, jnp.zeros_like(zq)], -1)
    Rd = jnp.concatenate([Rq, jnp.zeros_like(Rq)], -1)
    z = jnp.where(dzero[..., None], zd, z)
    R = jnp.where(dzero[..., None], Rd, R)
    return z, R, (c1, s1, c2, s2, k1, k2, q1s, q2s, n, dzero)


def ii_verdicts(c1, s1, c2, s2, kappa, q1, q2):
    """Certified ``(consistent_II, stable_II)`` codes and the spectral abscissa of ``M``.

    ``consistent_II`` uses ``Consistency`` codes, ``stable_II`` uses ``Verdict`` codes (II is
    stable iff the strictly dominant eigenvalue is a II eigenvalue; it is never neutral).
    The abscissa (max Re of the approximate roots) is in the time unit of contact 2.
    """
    z, R, (c1, s1, c2, s2, k1, k2, q1s, q2s, n, dzero) = _roots_and_radii(
        c1, s1, c2, s2, kappa, q1, q2
    )
    cons, stab = _ii_from_roots(z, R, c1, s1, c2, s2, k1, k2, q1s, q2s, dzero, c1.dtype)
    absc = jnp.ldexp(jnp.max(jnp.real(z), -1), n)
    return cons, stab, absc


def verdicts(c1, s1, c2, s2, kappa, q1, q2, *, ii=True):
    """All spectral verdicts: dict with ``stable_SS``, ``consistent_II``, ``stable_II``,
    ``spectral_abscissa``, ``margin_SS`` (arrays broadcast over the inputs)."""
    out = {"stable_SS": ss_verdict(c1, s1, c2, s2, kappa, q1, q2)}
    if ii:
        cons, stab, absc = ii_verdicts(c1, s1, c2, s2, kappa, q1, q2)
        out.update(consistent_II=cons, stable_II=stab, spectral_abscissa=absc)
    return out


# --- baseline: batched general eigen-solver -----------------------------------------------------


def build_M(c1, s1, c2, s2, kappa, q1, q2):
    """The 4x4 matrix ``M`` of eq. (9) in invariant parameters (``K = diag(kappa, 1)``)."""
    shape = jnp.broadcast_shapes(
        c1.shape, s1.shape, c2.shape, s2.shape, kappa.shape, q1.shape, q2.shape
    )
    bc = lambda a: jnp.broadcast_to(a, shape)  # noqa: E731
    c1, s1, c2, s2, kappa, q1, q2 = (bc(a) for a in (c1, s1, c2, s2, kappa, q1, q2))
    zero, one = jnp.zeros_like(c1), jnp.ones_like(c1)
    rows = [
        [zero, zero, one, zero],
        [zero, zero, zero, one],
        [-c1 * kappa, -c2, -c1 * q1, -c2 * q2],
        [-s1 * kappa, -s2, -s1 * q1, -s2 * q2],
    ]
    return jnp.stack([jnp.stack(r, -1) for r in rows], -2)


def eig_verdicts(c1, s1, c2, s2, kappa, q1, q2, *, tol=None):
    """Baseline a user would write: ``eig`` of ``M`` with a tolerance. NOT certified.

    stable (all Re < -tol), neutral (max |Re| <= tol), unstable otherwise; II from eigenvalues with
    ``|Im| <= tol`` and ``Re > tol`` whose eigenvector gap part has ``x1 x2 > 0``.
    """
    dtype = c1.dtype
    tol = float(jnp.finfo(dtype).eps) ** 0.5 if tol is None else tol
    M = build_M(c1, s1, c2, s2, kappa, q1, q2)
    w, v = jnp.linalg.eig(M)
    re, im = jnp.real(w), jnp.imag(w)
    smax = jnp.max(re, -1)
    ss = jnp.where(
        smax < -tol, Verdict.STABLE, jnp.where(smax <= tol, Verdict.NEUTRAL, Verdict.UNSTABLE)
    ).astype(jnp.int8)
    x1, x2 = jnp.real(v[..., 0, :]), jnp.real(v[..., 1, :])
    iitype = (jnp.abs(im) <= tol) & (re > tol) & (x1 * x2 > 0)
    cons = jnp.any(iitype, -1).astype(jnp.int8)
    idx = jnp.argmax(re, -1)
    dom_ii = jnp.take_along_axis(iitype, idx[..., None], -1)[..., 0]
    second = jnp.sort(re, -1)[..., -2]
    stab = (dom_ii & (second < smax - tol)).astype(jnp.int8)
    return {"stable_SS": ss, "consistent_II": cons, "stable_II": stab, "spectral_abscissa": smax}


verdicts_jit = jax.jit(verdicts, static_argnames=("ii",))
eig_verdicts_jit = jax.jit(eig_verdicts)
