"""Named, seeded hard-case suites (SPEC §4), shared by the tests and ``atlas bench``.

Each suite returns 1-D arrays ``beta1, beta2`` [rad], direction components ``c1, s1, c2, s2`` [1],
``kappa`` [1], ``q1, q2`` [1] in the requested dtype.  Boundary locations are computed in 50-digit
arithmetic (mpmath) and then offset by relative amounts ``1e-4 .. 0`` before rounding to the dtype, so
"offset 0" is the float nearest to the exact boundary.
"""

from __future__ import annotations

import functools
import operator

import mpmath
import numpy as np

from atlas.core import expressions as ex
from atlas.core.contact_modes import direction

__all__ = ["SUITES", "suite", "OFFSETS"]

OFFSETS = (1e-4, 1e-8, 1e-12, 1e-15, 0.0, -1e-15, -1e-12, -1e-8, -1e-4)
_mp = mpmath.mp
_SUB = operator.sub  # the expressions of atlas.core.expressions on mpmath numbers


def _pack(beta1, beta2, kappa, q1, q2, dtype):
    dtype = np.dtype(dtype)
    beta1, beta2, kappa, q1, q2 = np.broadcast_arrays(
        *(np.asarray(v, np.float64) for v in (beta1, beta2, kappa, q1, q2))
    )
    b1 = np.mod(beta1, 2 * np.pi).astype(dtype)
    b2 = np.mod(beta2, 2 * np.pi).astype(dtype)
    c1, s1 = direction(b1, dtype)
    c2, s2 = direction(b2, dtype)
    return {
        "beta1": b1,
        "beta2": b2,
        "c1": c1,
        "s1": s1,
        "c2": c2,
        "s2": s2,
        "kappa": kappa.astype(dtype),
        "q1": q1.astype(dtype),
        "q2": q2.astype(dtype),
    }


def _q_to_zero(rng, dtype):
    n = 24
    b1, b2 = rng.uniform(0, 2 * np.pi, (2, n))
    kap = 10 ** rng.uniform(-1, 1, n)
    qs = np.array([0.0, 1e-30, 1e-20, 1e-12, 1e-6, 1e-4, 1e-2])
    B1, Q = np.meshgrid(b1, qs, indexing="ij")
    B2, _ = np.meshgrid(b2, qs, indexing="ij")
    K, _ = np.meshgrid(kap, qs, indexing="ij")
    return _pack(B1.ravel(), B2.ravel(), K.ravel(), Q.ravel(), Q.ravel(), dtype)


def _q_subnormal(rng, dtype):
    """Subnormal damping (float64 ``5e-324 .. 2e-308``; ``1e-40``, ``1e-45``: subnormal in
    float32), on one contact or both: XLA on CPU reads subnormals as zero, IEEE does not."""
    n = 20
    b1, b2 = rng.uniform(0, 2 * np.pi, (2, n))
    kap = 10 ** rng.uniform(-1, 1, n)
    qs = np.array([5e-324, 1e-315, 1e-310, 2e-308, 1e-40, 1e-45])
    B1, Q = np.meshgrid(b1, qs, indexing="ij")
    B2, _ = np.meshgrid(b2, qs, indexing="ij")
    K, _ = np.meshgrid(kap, qs, indexing="ij")
    b1, b2, k, q = (np.tile(a.ravel(), 2) for a in (B1, B2, K, Q))
    one_side = np.repeat([True, False], q.size // 2)
    return _pack(b1, b2, k, q, np.where(one_side, 0.0, q), dtype)


def _G_parts(b1, b2, kap):
    """G/q^2 = G2 + q^2 X for q1 = q2 = q (kappa, 1 stiffness), 50 digits: the parts of degree 2
    and 4 of :func:`atlas.core.expressions.G_scaled` at ``q = 1``; also ``det B`` and ``a3/q``."""
    with mpmath.workdps(50):
        c1, s1, c2, s2 = mpmath.cos(b1), mpmath.sin(b1), mpmath.cos(b2), mpmath.sin(b2)
        k, one = mpmath.mpf(kap), mpmath.mpf(1)
        det = ex.det(c1, s1, c2, s2, sub=_SUB)
        args = (c1, s1, c2, s2, k, one, one, one, det)
        g2 = ex.G_scaled(*args, 1, 0, sub=_SUB)
        x = ex.G_scaled(*args, 0, 1, sub=_SUB)
        return g2, x, det, ex.a3(c1, s2, one, one, sub=_SUB)


def _near_hurwitz(rng, dtype):
    """q offsets around the damped SS stability boundary G = 0 (Hurwitz H3 = 0)."""
    rows = []
    while len(rows) < 10 * len(OFFSETS):
        b1, b2 = rng.uniform(0, 2 * np.pi, 2)
        kap = 10 ** rng.uniform(-1, 1)
        g2, x, det, a3 = _G_parts(b1, b2, kap)
        if det > 0 and a3 > 0 and g2 * x < 0:
            with mpmath.workdps(50):
                qstar = mpmath.sqrt(-g2 / x)
            rows += [(b1, b2, kap, float(qstar * (1 + mpmath.mpf(d)))) for d in OFFSETS]
    b1, b2, kap, q = map(np.array, zip(*rows))
    return _pack(b1, b2, kap, q, q, dtype)


def _near_discriminant(rng, dtype):
    """q = 0, kappa offsets around disc = (k c1 - s2)^2 + 4 k s1 c2 = 0 (double mu: double roots)."""
    rows = []
    while len(rows) < 10 * len(OFFSETS):
        b1, b2 = rng.uniform(0, 2 * np.pi, 2)
        with mpmath.workdps(50):
            c1, s1, c2, s2 = mpmath.cos(b1), mpmath.sin(b1), mpmath.cos(b2), mpmath.sin(b2)
            # disc = A k^2 + B k + C (A = c1^2, B = 4 s1 c2 - 2 c1 s2, C = s2^2) from its values
            # at k = 0, 1, -1
            d0, dp, dm = (ex.disc_undamped(k, c1, 1, s2, s1, c2, sub=_SUB) for k in (0, 1, -1))
            A, B, C = (dp + dm) / 2 - d0, (dp - dm) / 2, d0
            disc = B * B - 4 * A * C
            if disc <= 0:
                continue
            for kstar in ((-B + mpmath.sqrt(disc)) / (2 * A), (-B - mpmath.sqrt(disc)) / (2 * A)):
                if 1e-3 < kstar < 1e3:
                    rows += [(b1, b2, float(kstar * (1 + mpmath.mpf(d))), 0.0) for d in OFFSETS]
                    break
    b1, b2, kap, q = map(np.array, zip(*rows))
    return _pack(b1, b2, kap, q, q, dtype)


def _near_detB(rng, dtype):
    """beta2 -> beta1 and beta2 -> beta1 + pi (det B -> 0), relative offsets."""
    n = 8
    b1 = rng.uniform(0.1, 2 * np.pi - 0.1, n)
    kap = 10 ** rng.uniform(-1, 1, n)
    q = np.where(rng.random(n) < 0.5, 0.0, 10 ** rng.uniform(-3, 0, n))
    rows = []
    for i in range(n):
        for base in (b1[i], b1[i] + np.pi):
            for d in OFFSETS:
                rows.append((b1[i], base * (1 + d), kap[i], q[i]))
    b1_, b2_, k_, q_ = map(np.array, zip(*rows))
    return _pack(b1_, b2_, k_, q_, q_, dtype)


def _offdiag_to_zero(rng, dtype):
    """b12 -> 0 (beta2 -> pi/2, 3pi/2) or b21 -> 0 (beta1 -> 0, pi)."""
    rows = []
    offs = (1e-4, 1e-8, 1e-12, 1e-16, 0.0, -1e-8)
    for _ in range(4):
        other = rng.uniform(0, 2 * np.pi)
        kap = 10 ** rng.uniform(-1, 1)
        q = rng.choice([0.0, 0.05, 1.0])
        for base in (np.pi / 2, 1.5 * np.pi):
            rows += [(other, base * (1 + d), kap, q) for d in offs]
        for base in (np.pi, 2 * np.pi):
            rows += [(base * (1 + d), other, kap, q) for d in offs]
        rows += [(d, other, kap, q) for d in (1e-4, 1e-8, 1e-16)]
    b1, b2, kap, q = map(np.array, zip(*rows))
    return _pack(b1, b2, kap, q, q, dtype)


def _n_real_roots(b1, b2, kap, q):
    """Real roots of the quartic ``p`` (SPEC §1, ``q1 = q2 = q``, ``k2 = 1``) with 40-digit
    coefficients: the Sturm count ``V(-inf) - V(+inf)`` of its sequence's leading coefficients
    (signs of ``P2``, ``T1``, ``Disc`` of :mod:`atlas.core.expressions`, at 80 digits: exact for
    these coefficients) where none is zero (distinct roots, a sequence of every degree), else
    the roots of ``mpmath.polyroots`` off the real axis by less than ``1e-25``."""
    with mpmath.workdps(40):
        c1, s1, c2, s2 = mpmath.cos(b1), mpmath.sin(b1), mpmath.cos(b2), mpmath.sin(b2)
        det = ex.det(c1, s1, c2, s2, sub=_SUB)
        co = ex.coefficients(c1, s1, c2, s2, kap, 1, q, q, det, sub=_SUB)
    with mpmath.workdps(80):
        p2, t1, disc = (
            int(mpmath.sign(f(*co, sub=_SUB)))
            for f in (ex.sturm_P2, ex.sturm_T1, ex.quartic_discriminant)
        )
    if p2 and t1 and disc:
        return _variations(1, -1, p2, t1, disc) - _variations(1, 1, p2, -t1, disc)
    with mpmath.workdps(40):
        r = mpmath.polyroots([1, *co], maxsteps=200, extraprec=80)
        return sum(1 for z in r if abs(mpmath.im(z)) < mpmath.mpf(10) ** -25)


def _variations(*signs) -> int:
    """Sign changes along a sequence of nonzero signs."""
    return sum(a != b for a, b in zip(signs, signs[1:]))


def _double_roots(rng, dtype):
    """Damped cases where two real roots merge into a complex pair (real-complex switch).

    beta2 is scanned for a change in the number of real roots, bisected to 40 digits, offset.
    """
    rows = []
    tries = 0
    while len(rows) < 6 * len(OFFSETS) and tries < 200:
        tries += 1
        b1 = rng.uniform(0, 2 * np.pi)
        kap = 10 ** rng.uniform(-1, 1)
        q = 10 ** rng.uniform(-2, 0)
        grid = np.linspace(0, 2 * np.pi, 41)[1:-1]
        counts = [_n_real_roots(b1, g, kap, q) for g in grid]
        hits = [i for i in range(len(grid) - 1) if counts[i] != counts[i + 1]]
        if not hits:
            continue
        i = hits[rng.integers(len(hits))]
        lo, hi, clo = mpmath.mpf(grid[i]), mpmath.mpf(grid[i + 1]), counts[i]
        with mpmath.workdps(40):
            for _ in range(60):
                mid = (lo + hi) / 2
                if _n_real_roots(b1, mid, kap, q) == clo:
                    lo = mid
                else:
                    hi = mid
            bstar = (lo + hi) / 2
            rows += [(b1, float(bstar * (1 + mpmath.mpf(d))), kap, q) for d in OFFSETS]
    b1, b2, kap, q = map(np.array, zip(*rows))
    return _pack(b1, b2, kap, q, q, dtype)


def _extreme_ratios(rng, dtype):
    """kappa and q1/q2 ratios up to 1e24."""
    n = 6
    rows = []
    for _ in range(n):
        b1, b2 = rng.uniform(0, 2 * np.pi, 2)
        for kap in (1e-24, 1e-12, 1.0, 1e12, 1e24):
            for q1, q2 in ((0.0, 0.0), (1e-12, 1e12), (1e12, 1e-12), (1.0, 1e-24), (1e-24, 1.0)):
                rows.append((b1, b2, kap, q1, q2))
    b1, b2, kap, q1, q2 = map(np.array, zip(*rows))
    return _pack(b1, b2, kap, q1, q2, dtype)


def _class_boundaries(rng, dtype):
    """Angles exactly on class boundaries: axes, beta2 = beta1, beta2 = beta1 + pi."""
    axes = [0.0, np.pi / 2, np.pi, 1.5 * np.pi]
    rows = []
    for kap, q in ((0.5, 0.0), (2.0, 0.1)):
        for a in axes:
            for b in axes:
                rows.append((a, b, kap, q))
            r = rng.uniform(0, 2 * np.pi)
            rows += [(a, r, kap, q), (r, a, kap, q)]
        for _ in range(6):
            r = rng.uniform(0, 2 * np.pi)
            rows += [(r, r, kap, q), (r, r + np.pi, kap, q)]
    b1, b2, kap, q = map(np.array, zip(*rows))
    return _pack(b1, b2, kap, q, q, dtype)


SUITES = {
    "q_to_zero": _q_to_zero,
    "q_subnormal": _q_subnormal,
    "near_hurwitz": _near_hurwitz,
    "near_discriminant": _near_discriminant,
    "near_detB": _near_detB,
    "offdiag_to_zero": _offdiag_to_zero,
    "double_roots": _double_roots,
    "extreme_ratios": _extreme_ratios,
    "class_boundaries": _class_boundaries,
}


def suite(name: str, dtype=np.float64, seed: int = 0) -> dict:
    """The named hard-case suite as arrays in ``dtype`` (seeded, reproducible)."""
    if name not in SUITES:
        raise ValueError(f"suite: unknown name {name!r}; choose from {', '.join(SUITES)}")
    s = _suite_float64(name, seed)
    return _pack(s["beta1"], s["beta2"], s["kappa"], s["q1"], s["q2"], dtype)


@functools.cache
def _suite_float64(name: str, seed: int) -> dict:
    """The suite in float64, built once per process (the mpmath bisections take seconds); every
    dtype is rounded from it (rows do not depend on the dtype)."""
    rng = np.random.default_rng([seed, list(SUITES).index(name)])
    return SUITES[name](rng, np.float64)
