"""Root-free certified II verdicts with damping (paper Sec. 4.3, App. C), and the packed kernel.

Inputs are the invariant parameters of SPEC §1 (direction components ``c1, s1, c2, s2`` of ``b1``,
``b2``; ``kappa``; damping ``q1, q2 >= 0``, not both zero).  Every decision is taken from signs of
polynomial expressions certified by :mod:`atlas.core.signs` (exact signs of the inputs themselves, and
floating-point values with a derived error bound); an uncertified sign anywhere on a decision's
path gives ``UNDECIDED``, never a guess.

**Monotone curve** (``l > 0``, ``d_i = k_i + q_i l > 0``).  With ``h1 = l^2 + c1 d1 = d1 f1`` and
``h2 = l^2 + s2 d2 = d2 f2``, ``f1 = l^2/d1 + c1`` and ``f2 = l^2/d2 + s2`` strictly increase on
``l > 0`` from ``(c1, s2)``, and ``p = h1 h2 - c2 s1 d1 d2 = d1 d2 (f1 f2 - gamma)``, ``gamma = c2 s1``.
Positive roots of ``p`` are where the curve ``(f1, f2)`` crosses the hyperbola ``f1 f2 = gamma``.
The gap eigenvector is ``x ~ (c2 d2, -h1)``, so a root is II (``x1 x2 > 0``) iff ``c2 f1 < 0``,
equivalently ``s1 f2 < 0``: II roots are the crossings in the quadrant ``(-sgn c2, -sgn s1)``.

* ``gamma > 0``, II quadrant QI (``c2 < 0``): ``f1 f2`` increases along the curve in QI, so there is
  exactly one crossing unless the curve starts in the closed QI above the hyperbola:
  consistent iff not (``c1 >= 0``, ``s2 >= 0``, ``D > 0``), ``D = det B = c1 s2 - gamma``.
* ``gamma > 0``, QIII (``c2 > 0``): one crossing iff the curve starts in QIII above the hyperbola
  (``c1 < 0``, ``s2 < 0``, ``D > 0``); the curve must then also cross in QI at a larger ``l``, so II
  is never stable.
* ``gamma < 0``: all positive roots lie on one arc in QII or QIV.  Starting inside the arc's
  quadrant below the hyperbola (``D < 0``): an odd number of crossings (consistent).  Otherwise
  ("hard": ``D > 0`` start, or entering the quadrant from an axis) 0 or 2 crossings, decided by
  Descartes (``a3, a2 >= 0``: none) or a Sturm count of positive roots of the monic quartic
  ``(a, b, c, d) = (a3, a2, a1, a0)``: ``V(d, c, C2, -T0, Disc) - V(1, 1, P2, -T1, Disc)`` with
  ``P2 = 3a^2 - 8b``, ``C2 = ac - 16d`` and ``T1``, ``T0``, ``Disc`` below (checked against sympy's
  Sturm sequence in the tests).  Whether the curve enters QII from QIII (``c1, s2 < 0``) is the sign
  of ``h1`` at the positive root ``r2`` of ``h2``: with ``A = c1 q1 - s2 q2``, ``B = c1 k1 - s2 k2``,
  ``h1 - h2 = A l + B``, so ``sign h1(r2) = sign(A r2 + B)``; where ``A``, ``B`` have opposite signs,
  ``sign(A r2 + B) = -sign(A) sign(W)`` with ``W = A^2 h2(-B/A) = B^2 - s2 q2 A B + s2 k2 A^2``.

**Stability** (consistent cases except QIII): the largest real root ``l*`` is then the II root, and
II is stable iff ``l*`` is simple and strictly dominant.  The Routh array of ``p`` counts the roots
with ``Re > 0`` from the signs of ``a3``, ``H2 = a3 a2 - a1``, ``H3 = D G`` (``G`` of
:mod:`atlas.core.expressions`) and ``a0``: 1 or 2 such roots -> stable (two RHP roots with a real ``l*``
are both real, and simple where they came from a transversal crossing or a nonzero ``Disc``);
3 -> ``Disc > 0``: four simple real roots, stable; ``Disc < 0``: ``l*`` and a complex pair in the
right half plane, decided by :func:`tier2` (certified shifted Routh counts around a float estimate of
``l*``).  Everything else is left ``UNDECIDED`` for the enclosure path and the exact tier.

**Closed forms** where the quartic factors: ``c2 = 0``: ``p = h1 h2``, the II root is the positive
root ``r1`` of ``h1`` (``c1 < 0``) with ``s1 f2(r1) < 0``; ``s1 = 0`` symmetric; ``c2 = s1 = 0``
(diagonal ``B``): II needs a common root of ``h1`` and ``h2`` (a double eigenvalue: never stable);
``det B = 0``: ``p = l^2 (l^2 + a3 l + a2)`` and every positive root is II iff ``c2 s2 > 0``
(``c1 s1 > 0`` if ``c2 = 0``).

**Scaling** (exact powers of two, every sign kept): :func:`atlas.core.expressions.normalize` makes
``max(k) <= 1``, then ``l -> 2^e l`` brings ``k1, k2, q1, q2`` to ``<= 1``, the input bound of every
error model here (:func:`atlas.core.signs.error_model`).

**Two passes.**  :func:`codes` (every point) evaluates each polynomial once and bounds its rounding
error with the majorants ``|c|, |s| <= 1``, ``k_j <= max k``, ``q_j <= max q`` (no per-point
absolute-value evaluation); :func:`tier2` (the few points left, gathered) uses the sharp bound on
the absolute values and adds the shifted Routh counts.  Both are certified; the first is cheaper
and looser.  The first pass computes ``D = c1 s2 - s1 c2`` inside each expression (its bound covers
the cancellation, relative to ``|c1 s2| + |s1 c2|``); tier 2 (float64) reads ``D`` as an input
within ``gamma_3`` of ``det B`` (:func:`atlas.core.signs.det2_accurate`, integer mantissa products
where it cancels), so ``a1 = D m`` and ``a0 = D k1 k2`` keep their relative accuracy at
``|det B| ~ 1e-17`` (``b2 ~ -b1``), where every float bound on ``D`` fails.  The sign of ``det B``
itself is exact in both (:func:`atlas.core.signs.det2_sign`).

**Soundness.**  XLA on CPU removes optimization barriers before fusion and contracts a product
and a sum into one fused multiply-add (seen in the compiled code of this machine), so inside one
program a cheap value may be recomputed in every fusion that reads it, with and without FMA.  That
is harmless for the inputs (exact power-of-two scalings) and the intermediate values of a certified
expression (an FMA only removes roundings; any copy of a coefficient is within its bound), but not

* for a point at which expressions are evaluated (the shifts of :func:`tier2`, the roots of
  :mod:`atlas.core.enclosures`): these are computed in one compiled program and certified in
  another, where each is an input, one rounded number;
* for a sign code whose certification is checked in one place and whose value is used in another:
  counts are self-gating (:func:`_variations` gives :data:`NOT_COUNTED` unless every code is
  certified), the decisions read codes through ``== +1 / -1 / 0`` (facts, true of every copy), and
  the first pass :func:`codes` compiles to one loop fusion, each code computed once per point
  (tested on the compiled program).

The kernel returns one packed ``uint8`` (:func:`pack`).  Decisions use certified signs only ("not
certified positive" is never read as "<= 0").
"""

from __future__ import annotations

import functools

import jax
import jax.numpy as jnp
import numpy as np

from atlas.core import expressions as ex
from atlas.core import hurwitz, undamped, warm
from atlas.core.signs import (
    CODE,
    DET2_ROUNDINGS,
    UNKNOWN,
    det2_accurate,
    det2_sign,
    evaluate_certified,
    has_float64,
    nonzero,
    sign_of,
)
from atlas.core.verdicts import UNDECIDED_FLAG, Verdict

__all__ = ["ii_damped", "tier2", "codes", "pack", "unpack", "TIER2_BIT", "OPEN_BIT"]

X = UNDECIDED_FLAG  # = Verdict.UNDECIDED = Consistency.UNDECIDED
#: bit of the packed code that marks points for :func:`tier2`
TIER2_BIT = 6
#: bit of the packed code that marks points with an output asked for still ``UNDECIDED``
OPEN_BIT = 7


# --- the expressions, on the 9 inputs c1, s1, c2, s2, k1, k2, q1, q2 (all |.| <= 1) and D = det B
# (computed inside by the first pass, :func:`atlas.core.expressions.with_det`; an accurate input in
# tier 2), and the shift s of tier 2 ----------------------------------------------------------------

_INPUTS = ("c1", "s1", "c2", "s2", "k1", "k2", "q1", "q2", "D")


@functools.cache
def _on_inputs(expr, *names):
    """``expr`` of the inputs ``names`` as a function of the 9 inputs."""
    idx = tuple(_INPUTS.index(n) for n in names)

    def picked(*args, sub):
        return expr(*(args[i] for i in idx), sub=sub)

    return picked


@functools.cache
def _on_coefficients(expr, shift: bool = False):
    """``expr(a3, a2, a1, a0)`` of ``p`` (of ``p(l + s)`` with ``shift``, ``s`` a 10th input) as a
    function of the 9 inputs."""

    def composed(*args, sub):
        coef = ex.coefficients(*args[:9], sub=sub)
        if shift:
            coef = ex.shifted(*coef, args[9], sub=sub)
        return expr(*coef, sub=sub)

    return composed


def _a3_of(a3, a2, a1, a0, *, sub):
    return a3


def _a2_of(a3, a2, a1, a0, *, sub):
    return a2


def _a0_of(a3, a2, a1, a0, *, sub):
    return a0


def _H2_of(a3, a2, a1, a0, *, sub):
    return ex.hurwitz_H2(a3, a2, a1, sub=sub)


_BOUNDS8 = (1.0,) * 8
#: bounds and rounding counts of the 9 inputs with an accurate ``D`` (:func:`_csign`)
_BOUNDS9, _ROUNDED9 = _BOUNDS8 + (2.0,), (0,) * 8 + (DET2_ROUNDINGS,)
#: magnitude bound of the shift ``s`` of tier 2 (the Cauchy bound of ``p`` is <= 5 for inputs <= 1)
_SHIFT_BOUND = 8.0


def _accurate_det(c1, s1, c2, s2):
    """``(D,)`` within ``gamma_3`` of ``det B`` (:func:`atlas.core.signs.det2_accurate`; NaN where
    not proven, so no sign that reads it is certified there), or ``()`` for float32 (``D`` then
    computed inside): tier 2's extra input, so that the signs of ``a1 = D m``, ``a0 = D k1 k2``
    and the expressions built on them are certified where ``|det B| ~ 1e-17`` (``b2 ~ -b1``)."""
    if c1.dtype != jnp.float64:
        return ()
    return (det2_accurate(c1, s1, c2, s2),)


#: certified signs of the first pass (cheap: <= 3 ns a point each)
_CHEAP = dict(
    A=_on_inputs(ex.arc_A, "c1", "s2", "q1", "q2"),
    B=_on_inputs(ex.x_undamped, "k1", "c1", "k2", "s2"),
    W=_on_inputs(ex.arc_W, "c1", "s2", "k1", "k2", "q1", "q2"),
    a3=_on_coefficients(_a3_of),
    a2=_on_coefficients(_a2_of),
    H2=_on_coefficients(_H2_of),
    G=ex.G,
    a2_d0=_on_inputs(ex.a2_undamped, "k1", "c1", "k2", "s2"),
    disc_d0=_on_inputs(ex.disc_singular, "c1", "s2", "k1", "k2", "q1", "q2"),
)
#: signs of the Sturm count and of the discriminant (float64 also for float32 inputs); read only
#: as certified nonzero signs (:func:`_hard_count`, tier 2's ``Disc``), so they skip the
#: structural zeros (``zeros=False`` of :func:`atlas.core.signs.evaluate_certified`)
_STURM = dict(
    P2=_on_coefficients(ex.sturm_P2),
    C2=_on_coefficients(ex.sturm_C2),
    T1=_on_coefficients(ex.sturm_T1),
    T0=_on_coefficients(ex.sturm_T0),
    disc=_on_coefficients(ex.quartic_discriminant),
)
#: the discriminant of ``mu^2 + a2 mu + a0`` (``Q = 0``), for stable_SS
_DISC_U = _on_inputs(ex.disc_undamped, "k1", "c1", "k2", "s2", "s1", "c2")
#: the signs evaluated in float64 for float32 inputs
_WIDE = frozenset(_STURM)
#: the signs stable_SS needs (SPEC §1 conventions; decision logic of :mod:`atlas.core.hurwitz`)
_SS_NAMES = ("a3", "G", "a2_d0")


def _csign(fn, args, majorants=None, zeros=True, shift=None):
    """Certified sign code of ``fn`` on the 8 inputs (``D`` computed inside,
    :func:`atlas.core.expressions.with_det`)
    or on 9 (an accurate ``D`` last, :func:`_accurate_det`), and the ``shift`` of tier 2."""
    if len(args) == 8:
        fn, bounds, rounded = ex.with_det(fn), _BOUNDS8, (0,) * 8
    else:
        bounds, rounded = _BOUNDS9, _ROUNDED9
    if shift is not None:
        args, bounds, rounded = args + (shift,), bounds + (_SHIFT_BOUND,), rounded + (0,)
    kw = dict(bounds=bounds, rounded=rounded, majorants=majorants, zeros=zeros)
    return evaluate_certified(fn, *args, **kw)[2]


def _exact_sign(x, y, sign):
    """``sign(x + sign * y)`` from one rounded sum: exact where both ``|x|, |y|`` are at least
    ``2^(nmant + 1)`` times the smallest normal number (a nonzero result is then normal, so a
    flush of subnormals to zero cannot hide it); ``UNKNOWN`` elsewhere."""
    info = jnp.finfo(x.dtype)
    floor = info.tiny * 2.0 ** (info.nmant + 1)
    ok = (jnp.abs(x) >= floor) & (jnp.abs(y) >= floor)
    return jnp.where(ok, jnp.sign(x + sign * y), UNKNOWN).astype(CODE)


def _signs(c1, s1, c2, s2, kappa, q1, q2, names, sharp: bool = False) -> dict:
    """Certified sign codes of the expressions ``names`` (plus the input signs and ``det B``).

    Expressions not in ``names`` are the constant ``UNKNOWN``: the decisions that need them are
    left undecided (and the compiler drops them).  The first pass (``sharp=False``) bounds the
    rounding error with the majorants ``|c|, |s| <= 1``, ``k_j <= max k``, ``q_j <= max q``
    (:func:`atlas.core.signs.evaluate_certified`): only the values are evaluated per point; tier 2
    (``sharp=True``) uses the inputs' absolute values and the accurate ``D`` of
    :func:`_accurate_det` as an input.
    """
    k1, k2, q1s, q2s = ex.balance(kappa, q1, q2)
    args = (c1, s1, c2, s2, k1, k2, q1s, q2s)
    shape = jnp.broadcast_shapes(*(jnp.shape(a) for a in args))
    if sharp:
        args = args + _accurate_det(c1, s1, c2, s2)
    majorants = None
    if not sharp:
        km, qm = jnp.maximum(k1, k2), jnp.maximum(q1s, q2s)
        majorants = (1.0, 1.0, 1.0, 1.0, km, km, qm, qm)
    # float32 inputs: the Sturm and discriminant signs in float64 (the conversion is exact; in
    # float32 their bounds leave a band of points along every double-root curve to tier 2)
    wide = None
    if args[0].dtype == jnp.float32 and has_float64():
        wide = [jnp.asarray(a, jnp.float64) for a in args]
    sg = {n: sign_of(v) for n, v in zip(("c1", "s1", "c2", "s2"), args)}
    sg["D"] = det2_sign(c1, s1, c2, s2)
    for name, fn in {**_CHEAP, **_STURM, "disc_u": _DISC_U}.items():
        if name not in names:
            sg[name] = jnp.full(shape, UNKNOWN, CODE)
        else:
            wide_args = wide if name in _WIDE and wide is not None else args
            sg[name] = _csign(fn, wide_args, majorants, zeros=name not in _STURM)
    # equal damping or stiffness: a3 = (c1 + s2) q, A = (c1 - s2) q, B = (c1 - s2) k, and the
    # sign of one rounded sum or difference is exact; on the class line beta2 = beta1 + pi/2
    # (c1 = s2 up to rounding) A and B are below every error bound otherwise
    plus, minus = _exact_sign(c1, s2, 1), _exact_sign(c1, s2, -1)
    sq = sign_of(q1s)
    for name, same, exact in (("a3", q1s == q2s, plus * sq), ("A", q1s == q2s, minus * sq)):
        if name in names:
            sg[name] = jnp.where(same & (exact != UNKNOWN), exact, sg[name])
    if "B" in names:
        sg["B"] = jnp.where((k1 == k2) & (minus != UNKNOWN), minus, sg["B"])
    lost = ex.lost_to_underflow((kappa, kappa, q1, q2), (k1, k2, q1s, q2s))
    lost = lost | ex.any_subnormal(c1, s1, c2, s2)
    for name in sorted(names):  # sorted: the same program (and compilation-cache key) every run
        sg[name] = jnp.where(lost, UNKNOWN, sg[name]).astype(CODE)
    # A = B = 0 exactly (h1 == h2): c1 == s2 and q1 == q2, k1 == k2 as floats
    sg["h1_eq_h2"] = (c1 == s2) & (q1s == q2s) & (k1 == k2) & ~lost
    return sg


def _variations(*signs):
    """Sign variations of a sequence of sign codes, or :data:`NOT_COUNTED` unless every code is a
    certified nonzero sign.  Self-gating: a count is never formed from an uncertified code, even
    where a caller's own certification check was computed from another copy of the signs
    (module docstring, "Soundness")."""
    v = jnp.zeros(jnp.broadcast_shapes(*(jnp.shape(s) for s in signs)), jnp.int32)
    ok = jnp.ones(v.shape, bool)
    for a in signs:
        ok = ok & ((a == 1) | (a == -1))
    for a, b in zip(signs[:-1], signs[1:]):
        v = v + (a * b < 0).astype(jnp.int32)
    return jnp.where(ok, v, NOT_COUNTED)


#: the count of :func:`_variations` where a sign is not certified: far below any difference of
#: two counts (a count is 0-4), so no test on a count or a difference of counts can pass
NOT_COUNTED = -1000


def ii_damped(c1, s1, c2, s2, kappa, q1, q2, *, sturm: bool = True):
    """Certified ``(consistent_II, stable_II, needs_dominance)`` for damped points (module docstring).

    Codes are ``Consistency`` / ``Verdict`` values, ``UNDECIDED`` where the certified signs do not
    decide; ``needs_dominance`` marks consistent points whose dominance the shifted counts of
    :func:`tier2` can decide.  ``sturm=False`` skips the Sturm and discriminant signs (first pass).
    """
    names = frozenset(_CHEAP) | (frozenset(_STURM) if sturm else frozenset())
    return _ii_decide(_signs(c1, s1, c2, s2, kappa, q1, q2, names))


def _P(s):
    return s == 1


def _N(s):
    return s == -1


def _K(s):  # certified nonzero
    return (s == 1) | (s == -1)


def _nonneg(s):
    return (s == 1) | (s == 0)


_S, _U = int(Verdict.STABLE), int(Verdict.UNSTABLE)


def _h1_at_r2(g):
    """Certified ``h1(r2) > 0`` and ``< 0`` at the positive root ``r2`` of ``h2`` (module docstring:
    ``sign(A r2 + B)``, through ``W`` where ``A`` and ``B`` have opposite signs)."""
    sA, sB, sW = g["A"], g["B"], g["W"]
    pos = (_nonneg(sA) & _nonneg(sB) & (_P(sA) | _P(sB))) | (_P(sA) & _N(sB) & _N(sW))
    pos = pos | (_N(sA) & _P(sB) & _P(sW))
    nonpos_a, nonpos_b = _N(sA) | (sA == 0), _N(sB) | (sB == 0)
    neg = (nonpos_a & nonpos_b & (_N(sA) | _N(sB))) | (_P(sA) & _N(sB) & _P(sW))
    neg = neg | (_N(sA) & _P(sB) & _N(sW))
    return pos, neg


def _hard_count(g):
    """The hard arcs (0 or 2 crossings): Descartes, then the Sturm count of positive roots.
    Returns the consistency code and "exactly two positive roots" (certified)."""
    one = jnp.ones(g["D"].shape, CODE)
    descartes_none = _nonneg(g["a3"]) & _nonneg(g["a2"])
    sP2, sC2, sT1, sT0, sDl = g["P2"], g["C2"], g["T1"], g["T0"], g["disc"]
    sturm_ok = _K(sP2) & _K(sC2) & _K(sT1) & _K(sT0) & _K(sDl)
    npos = _variations(one, one, sC2, -sT0, sDl) - _variations(one, one, sP2, -sT1, sDl)
    counted = sturm_ok & (npos >= 0) & (npos <= 4)
    cons = jnp.where(
        descartes_none | (counted & (npos == 0)), 0, jnp.where(counted & (npos > 0), 1, X)
    )
    return cons, counted & (npos == 2) & ~descartes_none


def _routh(g):
    """Certified count of roots of ``p`` with ``Re > 0`` (Routh: ``a3, H2, H3 = D G, a0``), and
    whether it is certified; ``a3 = 0`` exactly by the epsilon method (``a1 = D m != 0``)."""
    s_a3, s_H2, s_G, sd = g["a3"], g["H2"], g["G"], g["D"]
    one = jnp.ones(sd.shape, CODE)
    ok = _K(s_a3) & _K(s_H2) & _K(s_G) & _K(sd)
    nrhp = _variations(*ex.routh_signs(one, s_a3, s_H2, sd * s_G, sd))
    a3_zero = (s_a3 == 0) & _K(sd)
    return ok | a3_zero, jnp.where(a3_zero, jnp.where(sd == 1, 2, 1), nrhp)


def _main_branch(g, h1pos, h1neg):
    """``c2 != 0``, ``s1 != 0``, ``det B`` certified nonzero: the quadrant analysis.
    Returns (consistency, stability, needs tier 2)."""
    sc1, ss1, sc2, ss2, sd = g["c1"], g["s1"], g["c2"], g["s2"], g["D"]
    c1p, c1n, s2p, s2n = sc1 > 0, sc1 < 0, ss2 > 0, ss2 < 0
    Dp, Dn = _P(sd), _N(sd)
    g0pos = ss1 == sc2
    qI, qIII = g0pos & (sc2 < 0), g0pos & (sc2 > 0)
    qII, qIV = ~g0pos & (sc2 > 0), ~g0pos & (sc2 < 0)
    hard_cons, hard_two = _hard_count(g)
    startI, startIII = (sc1 >= 0) & (ss2 >= 0), c1n & s2n
    cons = jnp.full(sd.shape, X, CODE)
    cons = jnp.where(qI, jnp.where(startI & Dp, 0, jnp.where(~startI | Dn, 1, X)), cons)
    cons = jnp.where(qIII, jnp.where(startIII & Dp, 1, jnp.where(~startIII | Dn, 0, X)), cons)
    enter2 = c1n & ((s2p & Dp) | (ss2 == 0))  # QII entered at a D > 0 start or from the f1 axis
    qii = jnp.where(sc1 >= 0, 0, jnp.where(c1n & s2p & Dn, 1, jnp.where(enter2, hard_cons, X)))
    # QIII start: QII is entered iff h1(r2) < 0
    qii = jnp.where(startIII, jnp.where(h1pos, 0, jnp.where(h1neg, hard_cons, X)), qii)
    cons = jnp.where(qII, qii, cons)
    enter4 = s2n & ((c1p & Dp) | (sc1 == 0))
    qiv = jnp.where(ss2 >= 0, 0, jnp.where(s2n & c1p & Dn, 1, jnp.where(enter4, hard_cons, X)))
    qiv = jnp.where(s2n & c1n, jnp.where(h1neg, 0, jnp.where(h1pos, hard_cons, X)), qiv)
    cons = jnp.where(qIV, qiv, cons)
    # consistency decided without a Sturm count: the II root is a transversal crossing
    not_hard = qI | qIII | (qII & ((sc1 >= 0) | (c1n & s2p & Dn)))
    not_hard = not_hard | (qIV & ((ss2 >= 0) | (s2n & c1p & Dn)))
    routh_ok, nrhp = _routh(g)
    simple = not_hard | hard_two
    dom = routh_ok & ((nrhp == 1) | (nrhp == 2)) & simple
    stab = jnp.where((cons == 0) | qIII, _U, jnp.where((cons == 1) & dom, _S, X))
    tier2 = (cons == 1) & ~qIII & routh_ok & (nrhp == 3) & (stab == X) & simple
    return cons, stab, tier2


def _one_factor_branch(s_own, s_root, s_other, other_pos, other_neg):
    """One factor carries the II root.  ``c2 = 0``: ``p = h1 h2``, the II root is the positive root
    ``r1`` of ``h1`` (needs ``c1 < 0``) with ``s1 f2(r1) < 0``: call with (s1, c1, s2, ...).
    ``s1 = 0``: the root ``r2`` of ``h2`` (``s2 < 0``) with ``c2 f1(r2) < 0``: (c2, s2, c1, ...).
    ``other_pos``/``other_neg``: the other ``f`` certified positive/negative at the root when it
    starts negative (from :func:`_h1_at_r2`)."""
    f_pos = (s_other >= 0) | ((s_other < 0) & other_pos)
    f_neg = (s_other < 0) & other_neg
    decided_neg = jnp.where(f_neg, (s_own > 0).astype(CODE), X)
    cons = jnp.where(s_root >= 0, 0, jnp.where(f_pos, s_own < 0, decided_neg).astype(CODE))
    stab = jnp.where(
        s_root >= 0, _U, jnp.where(f_pos, jnp.where(s_own < 0, _S, _U), jnp.where(f_neg, _U, X))
    )
    return cons, stab


def _diagonal_branch(g, h1pos, h1neg):
    """``c2 = s1 = 0`` (diagonal ``B``): II iff ``h1`` and ``h2`` share their positive root (a
    double eigenvalue: never stable)."""
    sc1, ss2 = g["c1"], g["s2"]
    common = (sc1 < 0) & (ss2 < 0) & g["h1_eq_h2"]
    no_common = (sc1 >= 0) | (ss2 >= 0) | (~g["h1_eq_h2"] & _K(g["W"])) | h1pos | h1neg
    cons = jnp.where(common, 1, jnp.where(no_common, 0, X))
    return cons, jnp.where(cons == X, X, _U)


def _singular_branch(g):
    """``det B = 0`` exactly: ``p = l^2 (l^2 + a3 l + a2)``; a positive root is II iff ``c2 s2 > 0``
    (``c1 s1 > 0`` if ``c2 = 0``)."""
    sc1, ss1, sc2, ss2, s_a3 = g["c1"], g["s1"], g["c2"], g["s2"], g["a3"]
    ii_sign = jnp.where(sc2 != 0, sc2 * ss2 > 0, ss1 * sc1 > 0)
    s_a2d, s_dq = g["a2_d0"], g["disc_d0"]
    haspos_y = _N(s_a2d) | (_N(s_a3) & _nonneg(s_dq))
    haspos_n = _nonneg(s_a2d) & (_nonneg(s_a3) | _N(s_dq))
    dom_y = _N(s_a2d) | (_N(s_a3) & _P(s_dq))
    dom_n = _nonneg(s_a2d) & (_nonneg(s_a3) | _N(s_dq) | (s_dq == 0))
    cons = jnp.where(~ii_sign | haspos_n, 0, jnp.where(haspos_y, 1, X))
    stab = jnp.where(~ii_sign | dom_n, _U, jnp.where(dom_y, _S, X))
    return cons, stab


def _ii_decide(g):
    """The case analysis of the module docstring on the sign codes ``g`` of :func:`_signs`:
    (consistent_II, stable_II, needs tier 2), int8 codes."""
    sc1, ss1, sc2, ss2, sd = g["c1"], g["s1"], g["c2"], g["s2"], g["D"]
    h1pos, h1neg = _h1_at_r2(g)
    main = (sc2 != 0) & (ss1 != 0) & _K(sd)
    main_cons, main_stab, main_tier2 = _main_branch(g, h1pos, h1neg)
    singular = (sd == 0) & ~((sc2 == 0) & (ss1 == 0))
    # sign of f2 at r1 = -(sign of h1 at r2) where both start negative (r2 < r1 iff h1(r2) < 0)
    branches = [  # (where, (consistency, stability)), later ones win
        (main, (main_cons, main_stab)),
        ((sc2 == 0) & (ss1 != 0) & ~singular, _one_factor_branch(ss1, sc1, ss2, h1neg, h1pos)),
        ((ss1 == 0) & (sc2 != 0) & ~singular, _one_factor_branch(sc2, ss2, sc1, h1pos, h1neg)),
        (singular, _singular_branch(g)),
        ((sc2 == 0) & (ss1 == 0), _diagonal_branch(g, h1pos, h1neg)),
    ]
    cons = stab = jnp.full(sd.shape, X, CODE)
    for where, (c, st) in branches:
        cons = jnp.where(where, c, cons)
        stab = jnp.where(where, st, stab)
    return cons.astype(jnp.int8), stab.astype(jnp.int8), main & main_tier2


# --- tier 2: dominance when three roots lie right of the imaginary axis ---------------------------


def _sb3_of(b3, b2, b1, b0, *, sub):
    return b3


def _sH3_of(b3, b2, b1, b0, *, sub):
    return ex.hurwitz_H3(b3, b2, b1, b0, sub=sub)


#: the signs of the shifted Routh count: ``b0 = p(s)``, ``b3``, ``H2``, ``H3`` of ``p(l + s)``
_SHIFTED = tuple(_on_coefficients(f, shift=True) for f in (_a0_of, _sb3_of, _H2_of, _sH3_of))


def _count_right(args, s):
    """Certified number of roots with ``Re > s`` (``-1`` if not certified) and sign ``p(s)``."""
    # read only as certified nonzero signs: no structural zeros
    sb0, sb3, sh2, sh3 = (_csign(f, args, zeros=False, shift=s) for f in _SHIFTED)
    ok = (jnp.abs(s) <= _SHIFT_BOUND) & (s > 0)
    for t in (sb0, sb3, sh2, sh3):
        ok = ok & ((t == 1) | (t == -1))
    one = jnp.ones_like(sb0)
    v = _variations(*ex.routh_signs(one, sb3, sh2, sh3, sb0))
    return jnp.where(ok, v, -1), sb0


def tier2(c1, s1, c2, s2, kappa, q1, q2, *, ss: bool = True, ii: bool = True, iters: int = 24):
    """Second pass on the points the first pass of :func:`codes` left undecided:
    ``(stable_SS, consistent_II, stable_II)`` (``UNDECIDED`` for outputs not asked for).

    ``stable_SS`` by :func:`atlas.core.hurwitz.ss_verdict` (sharp error bounds).  II: every sign of
    :func:`ii_damped` (with the Sturm count), then dominance where three roots have
    ``Re > 0`` and the largest real root ``l*`` is II: ``Disc > 0``: four simple real roots, ``l*``
    strictly dominant -> stable.  ``Disc < 0``: ``l*``, a negative root and a complex pair; a float
    estimate ``x`` of ``l*`` (bracketed Newton) gives shifts ``s = x (1 -/+ 4 sqrt(eps))``; one root
    right of ``s_lo`` with ``p(s_lo) < 0`` proves ``l* > s_lo >= Re(pair)`` (stable); two roots right
    of ``s_hi`` (the pair) prove the pair dominates (unstable).  Otherwise ``UNDECIDED``.

    Two compiled programs (module docstring, "Soundness"): :func:`_tier2_decide` (every sign, the
    decisions and the shifts) and :func:`_tier2_dominance` (the shifted counts), so each shift
    reaches the certified expressions as one rounded input.  Call it as it is (a ``jax.jit`` around
    it would merge the two programs again).  Program 2 is skipped where no point is left to it.
    """
    ss_code, cons, stab, dominance, s_disc, s_lo, s_hi = _tier2_decide(
        c1, s1, c2, s2, kappa, q1, q2, ss=ss, ii=ii, iters=iters
    )
    if not ii:
        return ss_code, cons, stab
    if not isinstance(dominance, jax.core.Tracer) and not np.asarray(dominance).any():
        # no dominance to settle: program 2 would only mark the undamped points undecided
        damped = (np.asarray(q1) != 0) | (np.asarray(q2) != 0)  # numpy keeps subnormals
        return ss_code, *(np.where(damped, v, X).astype(np.int8) for v in (cons, stab))
    return ss_code, *_tier2_dominance(
        c1, s1, c2, s2, kappa, q1, q2, cons, stab, dominance, s_disc, s_lo, s_hi
    )


@warm.jit(static_argnames=("ss", "ii", "iters"))
def _tier2_decide(c1, s1, c2, s2, kappa, q1, q2, *, ss, ii, iters):
    """Program 1 of :func:`tier2`: ``stable_SS``, the II decisions from the sharp signs, where
    dominance is left to the shifted counts, the sign of ``Disc``, and the shifts ``s_lo, s_hi``
    around a bracketed-Newton estimate of ``l*``."""
    shape = jnp.broadcast_shapes(*(jnp.shape(a) for a in (c1, s1, c2, s2, kappa, q1, q2)))
    xs = jnp.full(shape, X, jnp.int8)
    ss_code = hurwitz.ss_verdict(c1, s1, c2, s2, kappa, q1, q2) if ss else xs
    if not ii:
        zero = jnp.zeros(shape, c1.dtype)
        return ss_code, xs, xs, jnp.zeros(shape, bool), xs, zero, zero
    g = _signs(c1, s1, c2, s2, kappa, q1, q2, frozenset(_CHEAP) | frozenset(_STURM), sharp=True)
    cons, stab, dominance = _ii_decide(g)
    k1, k2, q1s, q2s = ex.balance(kappa, q1, q2)
    D = ex.det(c1, s1, c2, s2, sub=jnp.subtract)
    for accurate in _accurate_det(c1, s1, c2, s2):  # an estimate: the shifts are certified later
        D = jnp.where(jnp.isnan(accurate), D, accurate)
    a3, a2, a1, a0 = ex.coefficients(c1, s1, c2, s2, k1, k2, q1s, q2s, D, sub=jnp.subtract)
    hi = 1 + jnp.maximum(
        jnp.maximum(jnp.abs(a3), jnp.abs(a2)), jnp.maximum(jnp.abs(a1), jnp.abs(a0))
    )

    def newton(_, bracket):  # bracketed Newton from the right (bisection where it leaves)
        x, lo, hi = bracket
        f = (((x + a3) * x + a2) * x + a1) * x + a0
        fp = ((4 * x + 3 * a3) * x + 2 * a2) * x + a1
        hi = jnp.where(f > 0, x, hi)
        lo = jnp.where(f <= 0, x, lo)
        xn = x - f / jnp.where(fp != 0, fp, 1)
        return jnp.where((xn > lo) & (xn < hi) & (fp != 0), xn, 0.5 * (lo + hi)), lo, hi

    x, _, _ = jax.lax.fori_loop(0, iters, newton, (hi, jnp.zeros_like(hi), hi))
    delta = 4 * float(jnp.finfo(c1.dtype).eps) ** 0.5
    return ss_code, cons, stab, dominance, g["disc"], x * (1 - delta), x * (1 + delta)


@warm.jit
def _tier2_dominance(c1, s1, c2, s2, kappa, q1, q2, cons, stab, dominance, s_disc, s_lo, s_hi):
    """Program 2 of :func:`tier2`: certified root counts right of the shifts ``s_lo, s_hi`` (inputs
    of this program: one rounded number each) decide dominance; returns ``(consistent_II,
    stable_II)``."""
    args = (c1, s1, c2, s2, *ex.balance(kappa, q1, q2), *_accurate_det(c1, s1, c2, s2))
    n_lo, p_lo = _count_right(args, s_lo)
    n_hi, p_hi = _count_right(args, s_hi)
    stable = (s_disc == 1) | ((s_disc == -1) & (n_lo == 1) & (p_lo == -1))
    unstable = (s_disc == -1) & (n_hi == 2) & (p_hi == 1)
    S, U = int(Verdict.STABLE), int(Verdict.UNSTABLE)
    dom = jnp.where(stable, S, jnp.where(unstable, U, X))
    stab = jnp.where(dominance, dom, stab)
    damped = nonzero(q1) | nonzero(q2)  # a subnormal q is damping (XLA reads it as 0)
    cons, stab = jnp.where(damped, cons, X), jnp.where(damped, stab, X)
    return cons.astype(jnp.int8), stab.astype(jnp.int8)


# --- the packed kernel ----------------------------------------------------------------------------


def pack(ss, cons, stab, tier2_flag, *, ss_asked: bool = True, ii_asked: bool = True):
    """One ``uint8``: bits 0-1 ``stable_SS``, 2-3 ``consistent_II``, 4-5 ``stable_II``, 6 tier 2,
    7 "open": an output asked for (``ss_asked``, ``ii_asked``) is ``UNDECIDED``."""
    u8 = lambda a: jnp.asarray(a).astype(jnp.uint8)  # noqa: E731
    open_ = jnp.zeros(jnp.shape(tier2_flag), bool)
    if ss_asked:
        open_ = open_ | (ss == X)
    if ii_asked:
        open_ = open_ | (cons == X) | (stab == X)
    code = u8(ss) | (u8(cons) << 2) | (u8(stab) << 4) | (u8(tier2_flag) << TIER2_BIT)
    return code | (u8(open_) << OPEN_BIT)


def unpack(code):
    """Inverse of :func:`pack` on numpy arrays: ``(ss, cons, stab, tier2, open)`` (views of
    one-pass results: no conversions).  Always arrays, 0-d for one point: the driver fills the
    later tiers' verdicts into them in place."""
    code = np.asarray(code)
    field = lambda x, t: np.asarray(x).view(t)  # noqa: E731 - arrays, also for one point (0-d)
    return (
        field(code & 3, np.int8),
        field((code >> 2) & 3, np.int8),
        field((code >> 4) & 3, np.int8),
        field((code >> TIER2_BIT) & 1, bool),
        field(code >> OPEN_BIT, bool),
    )


def codes(c1, s1, c2, s2, kappa, q1, q2, *, ss: bool = True, ii: bool = True, damped=None):
    """Packed certified verdicts of every point: one fused kernel, no roots (:func:`pack`).

    ``stable_SS`` by the decision logic of :mod:`atlas.core.hurwitz` on the signs computed here (one
    copy shared with II); II from the closed form :func:`atlas.core.undamped.ii_undamped` where
    ``q1 = q2 = 0`` (except diagonal ``B``) and from the first pass of :func:`ii_damped` elsewhere.
    Bit 6 marks points with a verdict left for :func:`tier2` (``stable_SS``, or II where damped).  ``damped=True``
    (``False``) promises every point is damped (undamped) and skips the other branch.  Outputs not
    asked for are packed as ``UNDECIDED``.
    """
    shape = jnp.broadcast_shapes(*(jnp.shape(a) for a in (c1, s1, c2, s2, kappa, q1, q2)))
    xs = jnp.full(shape, X, jnp.int8)
    if not ii:  # SS alone: the cheaper signs of atlas.core.hurwitz (no shared work to amortize)
        s = hurwitz.ss_verdict(c1, s1, c2, s2, kappa, q1, q2) if ss else xs
        s, later = jnp.broadcast_to(s, shape), jnp.broadcast_to(s == X, shape)
        return pack(s, xs, xs, later, ss_asked=ss, ii_asked=False)
    if damped is False:  # all undamped: closed forms only
        s = hurwitz.ss_verdict(c1, s1, c2, s2, kappa, q1, q2) if ss else xs
        cons, stab = undamped.ii_undamped_full(c1, s1, c2, s2, kappa)
        later = (s == X) if ss else jnp.zeros(shape, bool)
        bc = lambda a: jnp.broadcast_to(a, shape)  # noqa: E731
        return pack(bc(s), bc(cons), bc(stab), bc(later), ss_asked=ss)
    names = set()
    if ss:
        names |= set(_SS_NAMES) | ({"disc_u"} if damped is not True else set())
    names |= set(_CHEAP) | set(_STURM)
    g = _signs(c1, s1, c2, s2, kappa, q1, q2, frozenset(names))
    is_damped = nonzero(q1) | nonzero(q2)  # a subnormal q is damping (XLA reads it as 0)
    if ss:
        parts = dict(sd=g["D"], s_a2u=g["a2_d0"], s_disc=g["disc_u"], s_a3=g["a3"], s_G=g["G"])
        s = hurwitz.ss_from_signs({**parts, "damped": is_damped})
    else:
        s = xs
    cd, sdm, _ = _ii_decide(g)
    if damped is True:
        cons, stab = cd, sdm
    else:
        cu, su = undamped.ii_undamped_full(c1, s1, c2, s2, kappa)
        cons, stab = jnp.where(is_damped, cd, cu), jnp.where(is_damped, sdm, su)
    later = is_damped & ((cons == X) | (stab == X))
    if ss:
        later = later | (s == X)
    # where damped and det B has no certified sign, tier 2 decides nothing (its det B sign is the
    # same code, and every damped decision of SS and II reads it): those points go straight on to
    # the root enclosures and the exact tier
    later = later & ~(is_damped & (g["D"] == UNKNOWN))
    return pack(
        jnp.broadcast_to(s, shape),
        jnp.broadcast_to(cons, shape),
        jnp.broadcast_to(stab, shape),
        jnp.broadcast_to(later, shape),
        ss_asked=ss,
    )
