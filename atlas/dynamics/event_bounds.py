"""Bounds on the event functions of one contact configuration (paper Sec. 4.1, eqs. 1, 6-8).

On a segment of the modal form (:mod:`atlas.dynamics.fast_engine`) every gap is
``p0 + p1 tau + p2 tau^2 + Re sum_m u_m exp(lambda_m tau)``; these functions evaluate the gaps and
the event functions (gaps ``d_i``, forces ``phi_i = -k_i d_i - q_i d_i'``), bound their curvature
over a step, bracket the first crossing, and test whether a function keeps its sign over a horizon.
The bounds hold in exact arithmetic on the modal form; their floating-point evaluation is not
bounded here.  Pure array-in, array-out functions on ``(n, ...)`` lanes.
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "xp_of",
    "fori",
    "last_below",
    "take",
    "NEUTRAL",
    "sum4",
    "rows",
    "min_cols",
    "all_cols",
    "bins",
    "re_sum4",
    "evaluate",
    "gaps_at",
    "taylor",
    "event_functions",
    "curvature_bound",
    "flow_curvature_bound",
    "flat_step",
    "second_and_third",
    "taylor_terms",
    "third_bound",
    "taylor_steps",
    "first_root",
    "safe_steps",
    "positive_quadratic",
    "keeps_sign_bound",
    "keeps_sign",
    "event_terms",
    "keeps_sign_within",
    "no_event_certificate",
    "may_keep_signs",
    "locate_root",
]

#: relative size of a real part counted as zero (neutral), times the eigenvalue scale
NEUTRAL = 1e-9


def xp_of(*arrays):
    """The array namespace of ``arrays``: :mod:`jax.numpy` if any is a JAX array (or tracer),
    else :mod:`numpy`; every function here but :func:`may_keep_signs` serves both."""
    for x in arrays:
        if type(x) is not np.ndarray and type(x).__module__.startswith(("jax", "jaxlib")):
            import jax.numpy as jnp  # noqa: PLC0415 - NumPy callers load no JAX

            return jnp
    return np


def take(x, j):
    """``x[..., j]`` for the indices ``j`` (...) of the last axis; on JAX arrays as a masked sum
    (exact: the other terms are zeros), which compiles lean under ``jax.vmap``."""
    xp = xp_of(x, j)
    if xp is np:  # one flat gather (``take_along_axis`` costs more on small arrays)
        m, shape = x.shape[-1], np.broadcast_shapes(x.shape[:-1], j.shape)
        flat = np.broadcast_to(x, shape + (m,)).reshape(-1)
        jj = np.broadcast_to(j, shape).reshape(-1)
        return flat[np.arange(jj.size) * m + jj].reshape(shape)
    return xp.where(xp.arange(x.shape[-1]) == j[..., None], x, 0).sum(axis=-1)


def sum4(x):
    """``x.sum(axis=-1)`` of a real array, for a last axis of length 4 as elementwise additions
    in NumPy's order (``((x0 + x1) + x2) + x3``): the same values without the cost of a reduction
    over a short axis (NumPy or JAX arrays)."""
    if x.shape[-1] != 4:
        return x.sum(axis=-1)
    return ((x[..., 0] + x[..., 1]) + x[..., 2]) + x[..., 3]


def rows(x):
    """``np.flatnonzero`` of a 1-D NumPy array, without its wrappers (called several times a
    step by the engines)."""
    return x.nonzero()[0]


def min_cols(x):
    """``x.min(axis=1)`` of an ``(n, 4)`` array, as elementwise minima (NaN propagates)."""
    return np.minimum(np.minimum(x[:, 0], x[:, 1]), np.minimum(x[:, 2], x[:, 3]))


def re_sum4(z):
    """``z.sum(axis=-1).real`` of a complex array, for a last axis of length 4 in NumPy's order of
    a complex sum (``(z0 + z1) + (z2 + z3)``), on the real parts only (NumPy or JAX arrays)."""
    if z.shape[-1] != 4:
        return z.sum(axis=-1).real
    r = z.real
    return (r[..., 0] + r[..., 1]) + (r[..., 2] + r[..., 3])


def evaluate(P, U, lam, tau):
    """Gaps, velocities and accelerations (n, 2) at ``tau`` (n,) from the segment start, the
    polynomial's Taylor coefficients there (:func:`taylor`) and the modal terms ``U exp(lam
    tau)`` (n, 2, 4)."""
    xp = xp_of(P, U, lam, tau)
    UE = U * xp.exp(lam * tau[:, None])[:, None, :]
    p = _taylor(P, tau)
    d, v, acc = _gaps(p, UE, lam)
    return d, v, acc, xp.stack(p, axis=2), UE


def gaps_at(P, U, lam, tau):
    """The gaps, velocities and accelerations of :func:`evaluate` alone (the same arithmetic),
    without stacking the Taylor coefficients."""
    xp = xp_of(P, U, lam, tau)
    return _gaps(_taylor(P, tau), U * xp.exp(lam * tau[:, None])[:, None, :], lam)


def _gaps(p, UE, lam):
    lUE = UE * lam[:, None, :]
    d = p[0] + re_sum4(UE)
    v = p[1] + re_sum4(lUE)
    acc = 2 * p[2] + re_sum4(lUE * lam[:, None, :])
    return d, v, acc


def taylor(P, tau):
    """Taylor coefficients (n, m, 3; or 5 for a quartic ``P`` (n, m, 5)) at ``tau`` (n,) of the
    polynomials ``P`` (coefficients of ``1, t, t^2, ...``)."""
    return xp_of(P, tau).stack(_taylor(P, tau), axis=2)


def _taylor(P, tau):
    """:func:`taylor`'s coefficients as a list of (n, m) arrays."""
    t1 = tau[:, None]
    p = [P[:, :, 0] + t1 * (P[:, :, 1] + t1 * P[:, :, 2]), P[:, :, 1] + 2 * t1 * P[:, :, 2],
         P[:, :, 2]]  # fmt: skip
    if P.shape[2] > 3:  # cubic and quartic terms added last: + 0 where they vanish
        P3, P4 = P[:, :, 3], P[:, :, 4]
        p[0] = p[0] + t1**3 * (P3 + t1 * P4)
        p[1] = p[1] + t1**2 * (3 * P3 + 4 * t1 * P4)
        p[2] = p[2] + t1 * (3 * P3 + 6 * t1 * P4)
        p += [P3 + 4 * t1 * P4, P4]
    return p


def _poly_bounds(p, H):
    """Bounds (n, 2) of the second, third and fourth derivatives of the polynomial part over
    ``[tau, tau + H]`` beyond those of its quadratic (``2 |p2|``, 0, 0): from the cubic and
    quartic Taylor coefficients ``p3``, ``p4`` (zeros for a quadratic ``p`` (n, 2, 3))."""
    if p.shape[2] <= 3:
        return 0.0, 0.0, 0.0
    xp = xp_of(p, H)
    a3, a4, h = xp.abs(p[:, :, 3]), xp.abs(p[:, :, 4]), H[:, None]
    return h * (6 * a3 + 12 * h * a4), 6 * a3 + 24 * h * a4, 24 * a4


def event_functions(d, v, acc, k, q):
    """``f = (d1, d2, phi1, phi2)`` and ``f'`` (n, 4), ``phi_i = -k_i d_i - q_i d_i'``."""
    xp = xp_of(d, v, k, q)
    f = xp.concatenate([d, -k * d - q * v], axis=1)
    fp = xp.concatenate([v, -k * v - q * acc], axis=1)
    return f, fp


def curvature_bound(p, UE, lam, H, k, q, aUE=None):
    """``M >= |f''|`` (n, 4) over ``[tau, tau + H]`` for the four event functions (``aUE``:
    ``|UE|`` if already at hand)."""
    xp = xp_of(p, UE, lam, H)
    lr = xp.abs(lam)
    grow = xp.exp(xp.maximum(lam.real, 0.0) * H[:, None])[:, None, :]
    a = (xp.abs(UE) if aUE is None else aUE) * grow
    e2, e3, _ = _poly_bounds(p, H)
    m2 = 2 * xp.abs(p[:, :, 2]) + sum4(a * lr[:, None, :] ** 2) + e2
    m3 = sum4(a * lr[:, None, :] ** 3) + e3
    return xp.concatenate([m2, k * m2 + q * m3], axis=1)


def flow_curvature_bound(p, UE, lam, acc, H, k, q):
    """``(C, zn)``: ``C zn exp(max(mu, 0) s) >= |f''|`` (n, 4) at ``tau + s``, from the flow ``z' =
    A z`` of the gaps and velocities instead of the modal terms.  ``z'' = (d'', d''')`` obeys it
    too, so ``|D z''(tau + s)| <= exp(mu s) |D z''(tau)|`` with ``mu`` the logarithmic norm of ``D A
    D^-1`` (:func:`atlas.dynamics.modal_form.log_norm`, ``D = diag(1, 1, 1 / w, 1 / w)``, ``w = 1 /
    H_S``); then ``|d_i''| <= |D z''|`` and ``|phi_i''| = |k_i d_i'' + q_i d_i'''| <= (k_i^2 +
    q_i^2 w^2)^(1/2) |D z''|``.  The size ``zn = |D z''(tau)|`` is that of the accelerations and
    jerks at ``tau``, not of the modal terms: tight where large terms cancel (near-defective modal
    forms).  ``d''`` is ``acc`` (n, 2), ``d'''`` summed from the modal terms, both with a margin
    of ``1e-13`` of their terms' moduli for rounding.  NumPy arrays."""
    lam3 = lam[:, None, :] ** 3
    jerk = re_sum4(UE * lam3)
    aUE = np.abs(UE)
    err2 = 1e-13 * (sum4(aUE * np.abs(lam[:, None, :]) ** 2) + np.abs(p[:, :, 2]))
    err3 = 1e-13 * sum4(aUE * np.abs(lam3))
    if p.shape[2] > 3:  # a quartic's third derivative
        jerk = jerk + 6 * p[:, :, 3]
    w = 1.0 / H
    zn = np.sqrt(((np.abs(acc) + err2) ** 2).sum(axis=1)
                 + (((np.abs(jerk) + err3) / w[:, None]) ** 2).sum(axis=1))  # fmt: skip
    C = np.concatenate([np.ones_like(k), np.sqrt(k * k + (q * w[:, None]) ** 2)], axis=1)
    return C, zn


def flat_step(s, p, UE, lam, H, k, q):
    """``sigma_lo`` (n, 4) of functions with ``f = f' = 0``: ``s f >= C x^2 / 2 - M3 x^3 / 6``
    with ``C = s f''`` and ``M3`` bounding the third derivative on ``[tau, tau + H]`` (0 unless
    ``C > 0``)."""
    xp = xp_of(s, p, UE, lam)
    f2, M3 = second_and_third(p, UE, lam, H, k, q)
    C = s * f2
    return xp.where(C > 0, 3 * C / xp.maximum(M3, 1e-300), 0.0)


def second_and_third(p, UE, lam, H, k, q):
    """``(f2, M3)`` (n, 4): the second derivatives of the event functions at ``tau`` and a bound
    ``M3`` of their third derivatives on ``[tau, tau + H]`` (the modal terms' moduli grown by
    ``exp(max(Re lambda, 0) H)``, the cubic and quartic part's bounds)."""
    f2, terms = taylor_terms(p, UE, lam, k, q)
    return f2, third_bound(terms, H)


def taylor_terms(p, UE, lam, k, q):
    """``(f2, terms)``: the second derivatives ``f2`` (n, 4) of the event functions at ``tau``
    and the parts of :func:`third_bound` that do not depend on the window (one evaluation for
    several windows)."""
    xp = xp_of(p, UE, lam)
    lr = xp.abs(lam)[:, None, :]
    d2 = 2 * p[:, :, 2] + (UE * lam[:, None, :] ** 2).sum(axis=2).real
    d3 = (UE * lam[:, None, :] ** 3).sum(axis=2).real
    if p.shape[2] > 3:  # the cubic part's third derivative
        d3 = d3 + 6 * p[:, :, 3]
    f2 = xp.concatenate([d2, -k * d2 - q * d3], axis=1)
    return f2, (p, xp.abs(UE), lr**3, lr**4, xp.maximum(lam.real, 0.0), k, q)


def third_bound(terms, H):
    """``M3`` (n, 4): a bound of the event functions' third derivatives on ``[tau, tau + H]``
    (n,) from :func:`taylor_terms`' ``terms``: the modal terms' moduli grown by ``exp(max(Re
    lambda, 0) H)``, the cubic and quartic part's bounds."""
    p, aUE, lr3, lr4, grow_rate, k, q = terms
    xp = xp_of(aUE, H)
    a = aUE * xp.exp(grow_rate * H[:, None])[:, None, :]
    m3, m4 = (a * lr3).sum(axis=2), (a * lr4).sum(axis=2)
    if p.shape[2] > 3:  # the cubic and quartic part's bounds
        _, e3, e4 = _poly_bounds(p, H)
        m3, m4 = m3 + e3, m4 + e4
    return xp.concatenate([m3, k * m3 + q * m4], axis=1)


def taylor_steps(A, Bd, C, M3, W, err=0.0):
    """``(sigma_lo, sigma_hi)`` (n, 4) within ``[0, W]`` (n,) from the signed curvature ``C = s
    f2(tau)`` and ``M3`` bounding the third derivative on ``[tau, tau + W]``: for ``0 <= x <= W``,
    ``s f(tau + x)`` lies within ``A + Bd x + C x^2 / 2 -+ M3 x^3 / 6``, so between ``A + Bd x +
    (C -+ M3 W / 3) x^2 / 2`` (``A = s f >= 0``, ``Bd = s f'``): no sign change before the first
    root of the lower quadratic (``sigma_lo``, at most ``W``), one by the first root of the upper
    one (``sigma_hi``, ``inf`` beyond ``W``).  Tight where ``W`` is short: a gap curving away
    from its contact is not bounded as if it curved towards it.  ``err``: a bound of the
    rounding of ``C``.  NumPy arrays."""
    w = W[:, None]
    reach = M3 * w / 3 + err
    lo = first_root(A, Bd, C - reach)
    hi = first_root(A, Bd, C + reach)
    return np.minimum(lo, w), np.where(hi <= w, hi, np.inf)


def first_root(A, Bd, c):
    """First root ``x > 0`` of ``A + Bd x + c x^2 / 2`` (``A >= 0``; ``inf`` if none): the
    root :func:`safe_steps` gives with ``M = |c|`` (its lower one where ``c <= 0``, its upper
    one where ``c > 0``; the same arithmetic), from one square root.  NumPy arrays."""
    cm = np.where(c > 0, np.maximum(c, 1e-300), np.minimum(c, -1e-300))  # sign(c) max(|c|, 1e-300)
    with np.errstate(all="ignore"):
        disc = Bd * Bd - 2 * cm * A
        root = np.sqrt(np.maximum(disc, 0.0))
        x = np.where(Bd < 0, (2 * A) / (root - Bd), (Bd + root) / -cm)
        x[(c > 0) & ~((Bd < 0) & (disc >= 0))] = np.inf
    x[np.isnan(x)] = 0.0
    return x


def safe_steps(A, Bd, M):
    """Roots ``sigma_lo`` of ``A + Bd s - M s^2 / 2`` and ``sigma_hi`` of ``A + Bd s + M s^2 / 2``
    (first positive; ``inf`` if none) for ``A >= 0``: no sign change of ``f`` before ``sigma_lo``,
    one by ``sigma_hi``."""
    xp = xp_of(A, Bd, M)
    M = xp.maximum(M, 1e-300)
    with np.errstate(all="ignore"):
        B2, MA2, A2 = Bd * Bd, 2 * M * A, 2 * A  # each once (the same values)
        root = xp.sqrt(B2 + MA2)
        falling = Bd < 0
        lo = xp.where(falling, A2 / (root - Bd), (Bd + root) / M)
        disc = B2 - MA2
        hi = xp.where(falling & (disc >= 0), A2 / (xp.sqrt(xp.maximum(disc, 0.0)) - Bd), np.inf)
    if xp is np:  # NaN (0 * inf, inf - inf) -> 0, in place
        lo[np.isnan(lo)] = 0.0
        hi[np.isnan(hi)] = 0.0
        return lo, hi
    return xp.where(xp.isnan(lo), 0.0, lo), xp.where(xp.isnan(hi), 0.0, hi)


# ----------------------------------------------------------------------------- certificates


def positive_quadratic(a0, a1, a2, horizon):
    """``a0 + a1 s + a2 s^2 > 0`` for all ``s`` in ``[0, horizon]`` (``horizon`` may be inf)."""
    xp = xp_of(a0, a1, a2, horizon)
    at_end = xp.where(
        xp.isinf(horizon),
        (a2 > 0) | ((a2 == 0) & (a1 >= 0)),
        a0 + a1 * horizon + a2 * horizon**2 > 0,
    )
    vertex = -a1 / (2 * xp.where(a2 > 0, a2, 1.0))
    inside = (a2 > 0) & (a1 < 0) & (vertex < horizon)
    at_vertex = a0 - a1 * a1 / (4 * xp.where(a2 > 0, a2, 1.0)) > 0
    return (a0 > 0) & at_end & (~inside | at_vertex)


def keeps_sign(c, w, lam, valid, horizon):
    """Certificate that ``c0 + c1 s + c2 s^2 + Re sum_m w_m exp(lam_m s) > 0`` on
    ``[0, horizon]`` (arrays (..., 3), (..., M), (..., M), (..., M), (...)).

    Terms with ``Re lam <= 1e-9 |lam|`` are bounded by ``|w| exp(max(Re lam, 0) horizon)``; if
    some have ``Re lam`` above that, the largest such ``lam_1`` must be real with
    ``G = Re w_1 - sum_{other growing} |w_m| > 0``, and ``G exp(lam_1 s) >= G (1 + lam_1 s +
    lam_1^2 s^2 / 2)``; the resulting quadratic is tested by :func:`positive_quadratic`.

    Returns ``(ok, G, bounded, lam_1)`` (...) each: ``bounded`` the bound of the other terms.
    """
    with np.errstate(all="ignore"):
        return keeps_sign_bound(c, w, lam, valid, horizon)


def keeps_sign_bound(c, w, lam, valid, horizon):
    xp = xp_of(c, w, lam, horizon)
    re = lam.real
    scale = xp.abs(lam).max(axis=-1, keepdims=True)
    grow = valid & (re > NEUTRAL * scale)
    any_grow = grow.any(axis=-1)
    j1 = xp.argmax(xp.where(grow, re, -np.inf), axis=-1)
    lam1, w1 = take(lam, j1), take(w, j1)
    l1 = xp.where(any_grow, lam1.real, 0.0)
    real1 = xp.abs(lam1.imag) <= 1e-12 * xp.abs(lam1)
    aw = xp.abs(w)
    others = sum4(xp.where(grow, aw, 0.0)) - xp.where(any_grow, xp.abs(w1), 0.0)
    G = xp.where(any_grow, w1.real - others, 0.0)
    fac = xp.where(re > 0, xp.exp(re * horizon[..., None]), 1.0)
    bounded = sum4(xp.where(~grow & (aw > 0), aw * fac, 0.0))
    margin = 1e-12 * (xp.abs(c[..., 0]) + sum4(aw)) + 1e-300
    a0 = c[..., 0] + G - bounded - margin
    a1 = c[..., 1] + G * l1
    a2 = c[..., 2] + 0.5 * G * l1 * l1
    ok = (~any_grow | (real1 & (G > 0))) & positive_quadratic(a0, a1, a2, horizon)
    return ok, G, bounded, l1


def event_terms(p, UE, lam, k, q):
    """``(c (n, 4, 3), w (n, 4, M))``: the quadratic part (coefficients of ``1, s, s^2``) and
    the modal terms (of ``exp(lam_m s)``) of the four event functions from the gaps' quadratic
    part ``p`` (n, 2, 3) and modal terms ``UE`` (n, 2, M)."""
    xp = xp_of(p, UE, lam)
    kk, qq = k[:, :, None], q[:, :, None]
    c = xp.concatenate([p, xp.stack(
        [-kk[..., 0] * p[..., 0] - qq[..., 0] * p[..., 1],
         -kk[..., 0] * p[..., 1] - 2 * qq[..., 0] * p[..., 2],
         -kk[..., 0] * p[..., 2]], axis=-1)], axis=1)  # fmt: skip
    return c, xp.concatenate([UE, -(kk + qq * lam[:, None, :]) * UE], axis=1)


def keeps_sign_within(s, p, UE, lam, k, q, W):
    """(n, 4): each event function keeps its recorded sign ``s`` on ``[tau, tau + W]`` (W (n,)):
    ``s`` times its quadratic part stays above the moduli of its modal terms, each grown by
    ``exp(max(Re lam, 0) W)``, plus a margin of ``1e-12`` of its terms for rounding, over the
    whole window (:func:`positive_quadratic`).  An oscillation far from its contact is
    certified over a long window at once, where a curvature bound's parabola reaches zero
    after ``(2 A / M)^(1/2)``.  Quadratic ``p`` (n, 2, 3); NumPy arrays."""
    c, w = event_terms(p, UE, lam, k, q)
    aw = np.abs(w)
    grown = sum4(aw * np.exp(np.maximum(lam.real, 0.0) * W[:, None])[:, None, :])
    margin = 1e-12 * (np.abs(c[..., 0]) + sum4(aw)) + 1e-300
    sc = s[:, :, None] * c
    return positive_quadratic(sc[..., 0] - grown - margin, sc[..., 1], sc[..., 2],
                              np.repeat(W[:, None], 4, axis=1))  # fmt: skip


def no_event_certificate(s, p, UE, lam, valid, k, q, horizon):
    """Every monitored event function keeps its recorded sign ``s`` (n, 4) for all later times
    in the current configuration (:func:`keeps_sign`).  Returns ``(ok (n,), G (n, 4),
    bounded (n, 4), lam_1 (n,))``."""
    xp = xp_of(s, p, UE, lam)
    c, w = event_terms(p, UE, lam, k, q)
    sj = s[:, :, None]
    ok, G, bounded, l1 = keeps_sign(
        sj * c, sj * w, lam[:, None, :], valid[:, None, :], xp.repeat(horizon[:, None], 4, 1)
    )
    monitored = xp.concatenate([xp.ones_like(ok[:, :2]), s[:, :2] < 0], axis=1)
    return xp.all(ok | ~monitored, axis=1), G, bounded, l1[:, 0]


def may_keep_signs(s, p, UE, lam, valid, k, q):
    """A necessary condition of :func:`no_event_certificate` (n,), cheaper to test.  For each
    monitored function (``c0``, modal terms ``w_m``) :func:`keeps_sign` requires ``a0 = s c0 + G -
    bounded - margin > 0`` and, with a growing term, ``G > 0`` and ``lam_1`` real, where ``G = s Re
    w_1 - sum_{other growing} |w_m|`` and ``bounded >= sum_{not growing} |w_m|``: so ``a0 <= s c0 +
    [s Re w_1 + |w_1|] - sum |w_m|`` (the bracket 0 without a growing term, at most ``2 max |w|``
    with one: tested first, on every lane).  Rejects a lane only where ``G`` or that bound is below
    ``-1e-9 (|c0| + sum |w|)``, beyond the rounding of either side.  NumPy arrays."""
    re = lam.real
    gm = valid & (re > NEUTRAL * np.abs(lam).max(axis=1, keepdims=True))  # as in keeps_sign_bound
    grow = gm.any(axis=1)
    aw = np.abs(UE)
    w = np.concatenate([aw, np.abs(k[:, :, None] + q[:, :, None] * lam[:, None, :]) * aw], axis=1)
    tot = sum4(w)
    c0 = np.concatenate([p[:, :, 0], -k * p[:, :, 0] - q * p[:, :, 1]], axis=1)
    slack = -1e-9 * (np.abs(c0) + tot)
    monitored = np.concatenate([np.ones((s.shape[0], 2), dtype=bool), s[:, :2] < 0], axis=1)
    bound = s * c0 - tot + np.where(grow[:, None], 2 * w.max(axis=2), 0.0)
    out = ~((bound < slack) & monitored).any(axis=1)
    r = np.flatnonzero(out & grow)
    if r.size == 0:
        return out
    # the dominant growing term itself
    gr, lr = gm[r], lam[r]
    j1 = np.argmax(np.where(gr, re[r], -np.inf), axis=1)
    lam1 = take(lr, j1)
    UE1 = take(UE[r], np.stack([j1, j1], axis=1))
    w1 = np.concatenate([UE1, -(k[r] + q[r] * lam1[:, None]) * UE1], axis=1)
    sw1, aw1 = s[r] * w1.real, np.abs(w1)
    growing = sum4(np.where(gr[:, None, :], w[r], 0.0))
    sl = slack[r]
    fails = (s[r] * c0[r] - tot[r] + sw1 + aw1 < sl) | (sw1 - (growing - aw1) < sl)
    real1 = np.abs(lam1.imag) <= 1e-12 * np.abs(lam1)
    out[r] = ~(fails & monitored[r]).any(axis=1) & real1
    return out


# ----------------------------------------------------------------------------- batch


def fori(n, body, carry, until=None):
    """``carry = body(i, carry)`` for ``i < n`` (``carry`` a tuple of arrays): a Python loop on
    NumPy arrays (left as soon as ``until(carry)``, where given), a :func:`jax.lax.fori_loop` on
    JAX arrays (all ``n`` iterations; ``body`` must leave a finished carry unchanged)."""
    if xp_of(*carry) is np:
        for i in range(n):
            if until is not None and until(carry):
                break
            carry = body(i, carry)
        return carry
    import jax  # noqa: PLC0415 - NumPy callers load no JAX

    return jax.lax.fori_loop(0, n, body, carry)


def last_below(above, rest, rounds=64):
    """The lower end (n,) of a bisection of ``[0, rest]`` (n,) on ``above(x)`` (bool (n,)), a
    test that once true stays true as ``x`` grows (a nondecreasing bound over its limit): false
    at the returned time and before it (``rest`` approached where never true).  NumPy or JAX."""
    xp = xp_of(rest)

    def halve(_, lohi):
        lo, hi = lohi
        mid = 0.5 * (lo + hi)
        up = above(mid)
        return xp.where(up, lo, mid), xp.where(up, mid, hi)

    return fori(rounds, halve, (xp.zeros(rest.shape[0]), rest + 0.0))[0]


def locate_root(P, U, lam, tau, a, b, j, sj, k, q, xtol, max_iter=200):
    """Crossing of event function ``j`` (n,) with sign ``sj`` in ``[tau + a, tau + b]`` where
    ``sj f > 0`` at ``a`` and ``<= 0`` at ``b`` (a certified bracket): safeguarded Newton as
    ``rtsafe`` (a bisection whenever the Newton point leaves the bracket or its step is over half
    the last one; a Newton step below ``xtol / 2`` is replaced by a push of ``xtol / 2`` towards the
    root, so the far end of the bracket closes in too, and a push that does not cross is followed
    by a bisection) until the bracket is below ``xtol`` or after ``max_iter`` evaluations; returns
    the bracket ``(a, b)`` (relative to ``tau``)."""
    xp = xp_of(P, U, lam, tau, a)
    rows = xp.arange(j.size)
    i = j % 2
    gap = j < 2
    Ui, ki, qi = U[rows, i], k[rows, i], q[rows, i]
    p0, p1, p2 = P[rows, i, 0], P[rows, i, 1], P[rows, i, 2]
    quartic = P[rows, i][:, None] if P.shape[2] > 3 else None  # as :func:`taylor`

    def g(x):
        t = tau + x
        ue = Ui * xp.exp(lam * t[:, None])
        lue = ue * lam
        if quartic is None:
            c0, c1, c2 = p0 + t * (p1 + t * p2), p1 + 2 * t * p2, p2
        else:
            c0, c1, c2 = (taylor(quartic, t)[:, 0, j] for j in range(3))
        d = c0 + re_sum4(ue)
        v = c1 + re_sum4(lue)
        acc = 2 * c2 + re_sum4(lue * lam)
        f = xp.where(gap, d, -ki * d - qi * v)
        fp = xp.where(gap, v, -ki * v - qi * acc)
        return sj * f, sj * fp

    def newton(_, carry):
        x, gx, gpx, a, b, dx, failed = carry
        act = (b - a) > xtol
        with np.errstate(all="ignore"):
            step = -gx / gpx
        toward = xp.where(gx > 0, 0.5, -0.5) * xtol
        push = xp.abs(step) < 0.5 * xtol
        xn = xp.where(push, x + toward, x + step)
        bad = ~xp.isfinite(xn) | (xn <= a) | (xn >= b) | (xp.abs(step) > 0.5 * xp.abs(dx)) | failed
        xn = xp.where(bad, 0.5 * (a + b), xn)
        gn, gpn = g(xn)
        left = gn > 0
        failed = act & push & ~bad & (left == (gx > 0))
        dx = xp.where(act, xn - x, dx)
        a = xp.where(act & left, xn, a)
        b = xp.where(act & ~left, xn, b)
        x, gx, gpx = (xp.where(act, new, old) for new, old in ((xn, x), (gn, gx), (gpn, gpx)))
        return x, gx, gpx, a, b, dx, failed

    # dx: the last step; failed: the last push did not cross
    carry = (a, *g(a), a, b, 2 * (b - a), xp.zeros(j.size, dtype=bool))
    a, b = fori(max_iter, newton, carry, until=lambda c: not ((c[4] - c[3]) > xtol).any())[3:5]
    return a, b


def all_cols(x):
    """``x.all(axis=1)`` of a boolean ``(n, 4)`` array, as elementwise ``&``."""
    return (x[:, 0] & x[:, 1]) & (x[:, 2] & x[:, 3])


def bins(t, width, nbins):
    """The amplitude bin [0, nbins) of times ``t`` [H_S] in bins of ``width``."""
    xp = xp_of(t)
    return xp.minimum(xp.maximum(xp.ceil(t / width).astype(int) - 1, 0), nbins - 1)
