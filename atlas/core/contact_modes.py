"""Mechanics of two sliding contacts: directions, class codes, duals, Table 1, SF/FS/IF/FI/CC.

Convention (decided here, see README "Conventions"): an angle enters the computation only through its
direction vector ``(cos, sin)`` rounded to the working dtype, and the float nearest to a multiple of
``pi/2`` (in that dtype) gives the exact axis vector.  Every verdict is an exact function of these
direction vectors (and of ``kappa``, ``q``); the fast kernels certify their signs and the exact
reference (:mod:`atlas.core.exact`) evaluates the same rational numbers exactly.  Ties are therefore exact
events of the direction vectors: ``beta2 == beta1``, ``b2 == -b1``, axis directions.

All functions below except :func:`direction` are pure ``jax.numpy`` functions of arrays that
broadcast against each other (no I/O, jit/vmap-able).  The public verdicts are kept jitted kernels
in shape buckets (:func:`atlas.core.buckets.elementwise`): called on host arrays of any shape they
run as flat columns of a few lengths (numpy results), one program per length and dtype, where
op-by-op dispatch compiled each of their ~30 operations (about 1 s per new shape), and a later
process loads them; inside another kernel they are traced as they are.  Codes use :data:`atlas.core.verdicts.UNDECIDED_CODE`
(-1) or :data:`atlas.core.verdicts.UNDECIDED_FLAG` (3) where a cross product could not be certified.
"""

from __future__ import annotations

import math

import jax.numpy as jnp
import numpy as np

from atlas.core import buckets
from atlas.core.signs import CODE, UNKNOWN, det2_sign, sign_of
from atlas.core.verdicts import UNDECIDED_CODE, UNDECIDED_FLAG, Verdict

__all__ = [
    "direction",
    "class_code",
    "subclass_code",
    "dual_angles",
    "dual_vectors",
    "consistent_modes",
    "stable_SF",
    "stable_FS",
    "consistent_IF",
    "consistent_FI",
    "cc_possible",
    "invariants",
    "ALL_CLASSES",
    "CLASS_COLORS",
]

TWO_PI = 2.0 * np.pi

#: the 24 class codes ij in Table 2 order
ALL_CLASSES = tuple(10 * i + j for i in range(1, 5) for j in range(1, 7))
#: the colour of each class ij (Table 2 order; the ``class_code`` output declares them): colours of
#: matplotlib's tab20 / tab20b / tab20c, assigned so that classes sharing an edge on the beta1-beta2
#: plane differ by CIE76 Delta E >= 23 and any two classes by >= 10, in normal vision and for
#: deutan, protan and tritan vision (Machado et al. 2009, severity 1), chosen by a local search
#: over the 60 colours
CLASS_COLORS = dict(
    zip(
        ALL_CLASSES,
        (
            "#c7e9c0", "#a55194", "#dbdb8d", "#74c476", "#843c39", "#e7ba52",
            "#d62728", "#7b4173", "#e6550d", "#393b79", "#8c6d31", "#6baed6",
            "#636363", "#e7969c", "#6b6ecf", "#bdbdbd", "#756bb1", "#bcbd22",
            "#9edae5", "#bd9e39", "#a1d99b", "#5254a3", "#e377c2", "#31a354",
        ),
        strict=True,
    )
)  # fmt: skip


#: the angles [rad] whose float (in any dtype) yields the exact axis vector ``(cos, sin)``
_AXES = (
    (0.0, 1.0, 0.0),
    (np.pi / 2, 0.0, 1.0),
    (np.pi, -1.0, 0.0),
    (1.5 * np.pi, 0.0, -1.0),
    (TWO_PI, 1.0, 0.0),
)


def direction(angle, dtype=np.float64):
    """Direction vector ``(cos angle, sin angle)`` [1] of angles [rad], rounded to ``dtype``.

    Angles are reduced modulo ``2 pi``; the float nearest to ``k pi / 2`` in ``dtype`` (and to
    ``2 pi``) yields the exact axis vector.  Host-side numpy: it runs once per coordinate value.
    """
    dtype = np.dtype(dtype)
    x = np.asarray(angle, dtype=dtype)
    if not np.all(np.isfinite(x)):
        raise ValueError("angle: must be finite")
    inside = (x >= 0) & (x < dtype.type(TWO_PI))
    if not inside.all():
        x = np.where(inside, x, np.mod(x, dtype.type(TWO_PI)))
    x64 = x.astype(np.float64, copy=False)
    c, s = np.empty(x.shape, dtype), np.empty(x.shape, dtype)
    c[...], s[...] = np.cos(x64), np.sin(x64)  # rounded to dtype as astype rounds
    for a, ca, sa in _AXES:
        hit = x == dtype.type(a)
        if hit.any():
            c[hit], s[hit] = ca, sa
    return c, s


def _half(c, s):
    """0 if the angle is in [0, pi), 1 if in [pi, 2 pi) (exact)."""
    s, c = sign_of(s), sign_of(c)  # from the bits: XLA reads a subnormal as zero
    return jnp.where((s > 0) | ((s == 0) & (c > 0)), 0, 1)


def _angle_less(uc, us, vc, vs, cross_uv):
    """Three-valued comparison of angles in [0, 2 pi): -1 (u < v), 0 (equal), +1, or UNKNOWN.

    ``cross_uv`` is the certified sign of ``u x v``.
    """
    hu, hv = _half(uc, us), _half(vc, vs)
    same = jnp.where(cross_uv == UNKNOWN, UNKNOWN, -cross_uv)
    return jnp.where(hu < hv, -1, jnp.where(hu > hv, 1, same)).astype(jnp.int8)


def _rank(target_c, target_s, others):
    """Rank (1-based) of the target angle among ``others`` + itself; 0 on a tie, -1 if undecided.

    ``others`` is a list of ``(c, s, cross_other_target)``.
    """
    rank = jnp.ones(jnp.broadcast_shapes(target_c.shape, *(o[0].shape for o in others)), jnp.int8)
    tie = jnp.zeros(rank.shape, bool)
    unk = jnp.zeros(rank.shape, bool)
    for c, s, cross in others:
        cmp = _angle_less(c, s, target_c, target_s, cross)
        rank = rank + (cmp == -1)
        tie = tie | (cmp == 0)
        unk = unk | (cmp == UNKNOWN)
    return jnp.where(unk, UNDECIDED_CODE, jnp.where(tie, 0, rank)).astype(jnp.int8)


def _axes_like(x):
    one, zero = jnp.ones_like(x), jnp.zeros_like(x)
    return [(zero, one), (-one, zero), (zero, -one)]  # pi/2, pi, 3 pi/2


def _axis_cross(ac, as_, vc, vs):
    # with an axis vector one product is zero and the other +-component: the sign, exactly, from
    # the signs (the float difference would flush a subnormal component to zero)
    return (sign_of(ac) * sign_of(vs) - sign_of(as_) * sign_of(vc)).astype(CODE)


@buckets.elementwise
def class_code(c1, s1, c2, s2):
    """Class code ``ij`` (paper Sec. 3, SPEC §1) from the directions of ``b1``, ``b2``.

    ``i`` = rank of beta1 in {beta1, pi/2, pi, 3pi/2}; ``j`` = rank of beta2 in
    {beta1, beta1*, beta2, pi/2, pi, 3pi/2}.  0 = degenerate (tie), -1 = undecided (int8).
    """
    axes = _axes_like(c1)
    i = _rank(c1, s1, [(ac, as_, _axis_cross(ac, as_, c1, s1)) for ac, as_ in axes])
    d12 = det2_sign(c1, s1, c2, s2)
    d12n = jnp.where(d12 == UNKNOWN, UNKNOWN, -d12).astype(jnp.int8)
    others = [(c1, s1, d12), (-c1, -s1, d12n)]
    others += [(ac, as_, _axis_cross(ac, as_, c2, s2)) for ac, as_ in _axes_like(c2)]
    j = _rank(c2, s2, others)
    code = 10 * i.astype(jnp.int16) + j
    code = jnp.where((i == 0) | (j == 0), 0, code)
    code = jnp.where((i == UNDECIDED_CODE) | (j == UNDECIDED_CODE), UNDECIDED_CODE, code)
    return code.astype(jnp.int8)


@buckets.elementwise
def subclass_code(c1, s1, c2, s2, ca, sa):
    """Subclass code ``ijk``: ``k`` = rank of alpha in {alpha, beta1, beta2, pi/2, pi, 3pi/2}.

    0 = degenerate, -1 = undecided (int16).
    """
    ij = class_code(c1, s1, c2, s2).astype(jnp.int16)
    others = [(c1, s1, det2_sign(c1, s1, ca, sa)), (c2, s2, det2_sign(c2, s2, ca, sa))]
    others += [(ac, as_, _axis_cross(ac, as_, ca, sa)) for ac, as_ in _axes_like(ca)]
    k = _rank(ca, sa, others).astype(jnp.int16)
    code = 10 * ij + k
    code = jnp.where((ij == 0) | (k == 0), 0, code)
    code = jnp.where((ij == UNDECIDED_CODE) | (k == UNDECIDED_CODE), UNDECIDED_CODE, code)
    return code.astype(jnp.int16)


def dual_angles(beta1, beta2, alpha=None):
    """Dual (contact indices swapped): ``(pi/2 - beta2, pi/2 - beta1, pi/2 - alpha)`` mod 2 pi."""
    out = [
        np.mod(np.pi / 2 - np.asarray(beta2), TWO_PI),
        np.mod(np.pi / 2 - np.asarray(beta1), TWO_PI),
    ]
    if alpha is not None:
        out.append(np.mod(np.pi / 2 - np.asarray(alpha), TWO_PI))
    return tuple(out)


def dual_vectors(c1, s1, c2, s2, ca=None, sa=None):
    """Dual in vector form (exact): ``b1' = (s2, c2)``, ``b2' = (s1, c1)``, ``a' = (sa, ca)``."""
    out = (s2, c2, s1, c1)
    if ca is not None:
        out = out + (sa, ca)
    return out


def _and3(*flags):
    """Three-valued AND of Consistency codes (0 dominates, then UNDECIDED)."""
    out = jnp.ones(jnp.broadcast_shapes(*(f.shape for f in flags)), jnp.int8)
    for f in flags:
        und = (out == UNDECIDED_FLAG) | (f == UNDECIDED_FLAG)
        out = jnp.where((out == 0) | (f == 0), 0, jnp.where(und, UNDECIDED_FLAG, 1))
    return out.astype(jnp.int8)


def _positive(sign):
    """Consistency code of ``sign > 0`` for a certified sign code."""
    return jnp.where(sign == UNKNOWN, UNDECIDED_FLAG, (sign > 0).astype(jnp.int8)).astype(jnp.int8)


@buckets.elementwise
def consistent_modes(c1, s1, c2, s2, ca, sa):
    """Table 1 (Appendix A): consistency of FF, SF, FS, SS as ``Consistency`` codes (int8).

    FF: ``a1 < 0 & a2 < 0``; SF: ``b11 a1 > 0 & (b21/b11) a1 > a2``; FS symmetric;
    SS: ``a`` strictly inside the cone of ``b1, b2`` (a degenerate cone, ``det B = 0``, has no
    interior, so SS is inconsistent there).
    """
    sc1, ss2, sca, ssa = sign_of(c1), sign_of(s2), sign_of(ca), sign_of(sa)
    ff = ((sca < 0) & (ssa < 0)).astype(jnp.int8)
    # SF: c1 ca > 0  and  c1 * (ca s1 - sa c1) > 0
    a_b1 = det2_sign(ca, sa, c1, s1)
    sf = _and3(_positive(sc1 * sca), _positive(_mul_sign(sc1, a_b1)))
    # FS: s2 sa > 0  and  s2 * (c2 sa - s2 ca) > 0
    b2_a = det2_sign(c2, s2, ca, sa)
    fs = _and3(_positive(ss2 * ssa), _positive(_mul_sign(ss2, b2_a)))
    # SS: f1 = (a x b2)/D, f2 = (b1 x a)/D, D = b1 x b2, both > 0
    d = det2_sign(c1, s1, c2, s2)
    a_b2 = _neg_sign(b2_a)
    b1_a = _neg_sign(a_b1)
    ss = _and3(_positive(_mul_sign(d, a_b2)), _positive(_mul_sign(d, b1_a)))
    return {"FF": ff, "SF": sf, "FS": fs, "SS": ss}


def _mul_sign(a, b):
    return jnp.where((a == UNKNOWN) | (b == UNKNOWN), UNKNOWN, a * b).astype(jnp.int8)


def _neg_sign(a):
    return jnp.where(a == UNKNOWN, UNKNOWN, -a).astype(jnp.int8)


def _stable_from_diagonal(b_jj):
    # matrix (7): det = b_jj k_j, trace = -b_jj q_j (Appendix B); b_jj = 0 gives a double zero root
    b_jj = sign_of(b_jj)
    return jnp.where(
        b_jj > 0, Verdict.STABLE, jnp.where(b_jj < 0, Verdict.UNSTABLE, Verdict.NEUTRAL)
    ).astype(jnp.int8)


@buckets.elementwise
def stable_SF(c1):
    """SF stability (Sec. 4.2, App. B): stable iff ``b11 > 0``; ``b11 = 0`` is neutral."""
    return _stable_from_diagonal(c1)


@buckets.elementwise
def stable_FS(s2):
    """FS stability: stable iff ``b22 > 0``; ``b22 = 0`` is neutral."""
    return _stable_from_diagonal(s2)


@buckets.elementwise
def consistent_IF(c1, s1):
    """IF consistency (Sec. 4.3, SPEC-corrected): ``b11 < 0`` and ``b21 > 0``; stable if consistent."""
    return ((sign_of(c1) < 0) & (sign_of(s1) > 0)).astype(jnp.int8)


@buckets.elementwise
def consistent_FI(c2, s2):
    """FI consistency: ``b22 < 0`` and ``b12 > 0``; stable if consistent."""
    return ((sign_of(s2) < 0) & (sign_of(c2) > 0)).astype(jnp.int8)


@buckets.elementwise
def cc_possible(c1, s2):
    """Necessary condition for CC inverse chattering (Sec. 5.2): ``b11 > 0`` and ``b22 > 0``."""
    return ((sign_of(c1) > 0) & (sign_of(s2) > 0)).astype(bool)


def invariants(k1, k2, q1=0.0, q2=0.0, b1=1.0, b2=1.0) -> dict:
    """Physical contact parameters -> model invariants (SPEC §1).

    Parameters
    ----------
    k1, k2 : float
        Contact stiffnesses [force/length], ``> 0``.
    q1, q2 : float
        Contact damping coefficients [force time/length], ``>= 0``.
    b1, b2 : float
        Norms ``|b_1|``, ``|b_2|`` of the columns of ``B`` [1/mass], ``> 0``.

    Returns
    -------
    dict
        ``kappa = k1 |b1| / (k2 |b2|)``, ``q1 = q1 |b1| / sqrt(k2 |b2|)``,
        ``q2 = q2 |b2| / sqrt(k2 |b2|)`` (time scaled by contact 2).  Paper Fig. 2
        (``k = (100, 200)``, ``q = (20, 20)``, ``|b| = 1``) gives ``kappa = 0.5``,
        ``q1 = q2 = sqrt(2)``.
    """
    vals = {"k1": k1, "k2": k2, "q1": q1, "q2": q2, "b1": b1, "b2": b2}
    out = {}
    for key, v in vals.items():
        try:
            x = float(v)
        except (TypeError, ValueError):
            raise ValueError(f"{key}: cannot interpret {v!r} as a number") from None
        if not math.isfinite(x):
            raise ValueError(f"{key}: must be finite, got {v!r}")
        if key in ("q1", "q2"):
            if x < 0:
                raise ValueError(f"{key}: damping must be >= 0, got {x}")
        elif x <= 0:
            what = "stiffness" if key.startswith("k") else "|b|"
            raise ValueError(f"{key}: {what} must be > 0, got {x}")
        out[key] = x
    scale = math.sqrt(out["k2"] * out["b2"])
    return {
        "kappa": out["k1"] * out["b1"] / (out["k2"] * out["b2"]),
        "q1": out["q1"] * out["b1"] / scale,
        "q2": out["q2"] * out["b2"] / scale,
    }
