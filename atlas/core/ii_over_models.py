"""II consistency and II stability over a box of contact models: for every model, for none, or
depends (certified).

**The question.**  For one geometry (direction components ``c1, s1, c2, s2``, SPEC §1) and a
:class:`atlas.core.model_box.ModelBox`, is II consistent (a real eigenvalue ``l > 0`` of ``M``
whose gap eigenvector has ``x1 x2 > 0``) for every model of the box, for none, or does it depend
on the model; the same for II stability (the strictly dominant eigenvalue is such an eigenvalue;
``stable_II`` is *unstable* wherever II is inconsistent, as in the point kernels).

**The polynomials** (:mod:`atlas.core.exact`, paper eq. 9): with ``d1 = kappa + q1 l``,
``d2 = 1 + q2 l``, ``h1 = l^2 + c1 d1``, ``h2 = l^2 + s2 d2``, ``gamma = c2 s1``, the characteristic
polynomial is ``p = h1 h2 - gamma d1 d2`` and a positive root ``l`` is an II root iff
``c2 h1(l) < 0``.  At a root ``h1 h2 = gamma d1 d2``, so ``h1 != 0`` when ``gamma != 0``.  At a
simple root ``l``, ``p(l + x) = x (x^3 + b3 x^2 + b2 x + b1)`` with ``b1 = p'``, ``b2 = p''/2``,
``b3 = p'''/6``; the other three roots have real part ``< l`` iff that cubic is Hurwitz, and it
stops being Hurwitz only through ``b1 = 0`` (a double root at ``l``) or ``b3 b2 = b1``, i.e.
``T = p' - p'' p''' / 12 = 0`` (a complex pair with real part ``l``; ``T`` of
:func:`atlas.core.exact._tie_poly`).

**The proof** (``gamma != 0``, ``D = det B != 0``, exact integers).  On the model box (connected)
the roots of ``p`` move continuously; ``p(0) = kappa D != 0`` and ``p`` is monic, so a positive
root appears or disappears only through a double root, and it cannot change from II to not II
(``h1 != 0`` at a root).  Hence if no model of the box has an II root ``l`` with ``p'(l) = 0``,
II consistency is the same for every model; if moreover none has an II root with
``p'(l) T(l) = 0``, II stability is the same for every model (the dominant eigenvalue stays a
simple, strictly dominant II root, or stays something else).  Both are proved by
:func:`atlas.core.bernstein.prove_any` on the box ``l in (0, inf)`` times the model box: every
sub-box has ``p > 0``, ``p < 0``, ``c2 h1 > 0`` or ``p' != 0`` (``p' T != 0``) with a certified
sign.  Then one model decides for all of them: the first sample model, whose verdict the point
kernels certify.  Where the geometry's signs alone decide consistency (the curve argument of
:mod:`atlas.core.exact`: ``gamma > 0``, or ``gamma < 0`` with the arc's quadrant and ``D < 0``
fixed by the signs of ``c1, s2, c2``), that is used instead of the first proof.

**Perron-Frobenius** (``c1 <= 0``, ``s2 <= 0``, ``c2 < 0``, ``s1 < 0``: both directions in the
third quadrant, classes 34 and 35).  ``p`` is the characteristic polynomial of
``A = [[0, I], [-B diag(kappa, 1), -B diag(q1, q2)]]`` (state ``(x1, x2, x1', x2')``; an
eigenvalue ``l`` has the eigenvector ``(x, l x)`` with ``(l^2 + B diag(d1, d2)) x = 0``,
``x2 / x1 = -h1 / (c2 d2)``).  Its off-diagonal entries are ``1``, ``0``, ``-c1 kappa``,
``-s2``, ``-c2``, ``-s1 kappa``, ``-c2 q2``, ``-s1 q1``, all ``>= 0``: ``A`` is Metzler, and
irreducible for every model (the cycle ``x1 <- x1' <- x2 <- x2' <- x1`` uses ``1, -c2, 1,
-s1 kappa > 0`` only).  So (Perron-Frobenius, ``A + s I`` primitive for ``s`` large) its largest
real eigenvalue is simple, every other eigenvalue has a strictly smaller real part, and no other
eigenvalue has a nonnegative eigenvector.  An II root ``l > 0`` (``x1 x2 > 0``) has the positive
eigenvector ``(x, l x)`` (up to sign): it *is* that eigenvalue.  Hence II is stable exactly where
it is consistent, for every model, and the signs decide both (no search, no sample).

**A symmetric pencil** (``gamma > 0`` and ``D < 0``: classes 33, 34, 43, 44, where ``c1 > 0`` or
``s2 > 0`` leaves ``A`` not Metzler).  With ``B^-1`` the eigenvalue problem is
``l^2 M x = (l Q + K) x``, ``M = -B^-1 = [[s2, -c2], [-s1, c1]] / |D|``, ``K = diag(kappa, 1)``,
``Q = diag(q1, q2)``.  ``M``'s off-diagonal entries have the product ``gamma / D^2 > 0``, so
``S = diag(1, t)``, ``t^2 = c2 / s1``, makes ``M' = S M S^-1`` symmetric (``S`` commutes with
``K``, ``Q``), with ``det M' = 1 / D < 0``: one positive and one negative eigenvalue.  For an
eigenvalue ``l`` with eigenvector ``y`` of ``l^2 M' y = (l Q + K) y``, the real numbers
``m = y* M' y``, ``r = y* Q y >= 0``, ``k = y* K y > 0`` give ``m l^2 - r l - k = 0``: for
``m > 0`` both roots are real, for ``m <= 0`` every root has ``Re l <= 0``.  So every eigenvalue
with ``Re l > 0`` is real.  A real ``l > 0`` is one iff
``f(l) = max_y y' M' y / y' (K / l^2 + Q / l) y = 1``, and ``f`` (a maximum of ratios that
strictly increase with ``l`` where the numerator is positive) strictly increases, with
``f'(l) > 0`` (the maximiser's ratio): exactly one positive eigenvalue, simple
(``p(0) = kappa D < 0``, ``p`` monic), and every other eigenvalue has ``Re l <= 0``.  It is
the strictly dominant eigenvalue, so again II is stable exactly where it is consistent, for every
model (``c2 < 0``: consistent; ``c2 > 0``: never), decided by the signs.

**The threshold rule** (``gamma < 0``, ``D < 0``: classes 15 and 32, ``c1 s2 < 0``; II
consistent by the signs where ``c1 c2 < 0``).  By the scaling law (:func:`scaling`) the verdict
depends only on ``e = |D| / |c1 s2|`` in ``(0, 1)``; class 32 is class 15 under
``l = sqrt(kappa) m``, ``(kappa, q1, q2) -> (1 / kappa, q2 / sqrt(kappa), q1 / sqrt(kappa))``.
Unit class 15: ``p = (l^2 + d1)(l^2 - d2) + (1 - e) d1 d2``, ``p(0) = -e kappa < 0``.  Where
``e >= 1/3`` (``3 |gamma| <= 2 |c1 s2|``, compared exactly: :func:`below_threshold`) the largest
real root ``L`` is simple and every other root has real part ``< L``, for every model: the set
of models where this holds is open, contains ``(1, 0, 0)`` (``p = l^4 - e``), and its boundary
in the (connected) model space would need a model with roots ``L, -rho, L +- i sqrt(b)`` (a tie;
the fourth root is negative as ``p(0) < 0``) or ``L, L, w, -rho`` with ``0 < w <= L`` (a double
top root; the other two are real and of opposite signs, as ``p(0) < 0``).  Matching the coefficients of ``l^0, l^3, l^1`` fixes ``kappa, q1, q2`` rationally
and the ``l^2`` one leaves ``H(L, rho, b or w, e) = 0``; on every region of ``u = L rho``
(``< 1/3``, ``[1/3, 1/2)``, ``>= 1/2``) either ``q1 >= 0``, ``q2 >= 0`` are incompatible or
``-H`` is a nonnegative combination of them plus a polynomial with nonnegative coefficients and a
positive term (exact identities, ``tests/core/test_ii_over_models_threshold.py``).  So no such
model exists, and II (every positive root is II here) is stable exactly where it is consistent.
Above the threshold a fast pair overtakes the II root at far models (:func:`far_models`).

**Tiers.**  (1) signs (with Perron-Frobenius, the symmetric pencil and the threshold rule); (2) a fixed sample of
models per geometry (:func:`_staged_sample`: a coarse one first, all of it where a side is still
missing, then :func:`far_models`), certified verdicts of :func:`atlas.core.points.spectral_points` (exact tier
where the float kernel cannot decide): both values seen -> ``DEPENDS`` with those two models as
witnesses; (3) one value seen: the proof above with a small budget, ``UNDECIDED`` where it does
not close, then (4) the settlement repeats it with a large budget.  (3) and (4) run on bounded
boxes only: on a box with an unbounded axis the subdivision of ``l in (0, inf)`` times the model
box did not close one code (72 geometries, 3 per class, in four such boxes, budget 48; 699 open
codes of a 48^2 grid, budget 512), so there the sample's open codes stay ``UNDECIDED`` at once.
``D = 0`` exactly (``b2 = t b1``): ``p = l^2 (l^2 + a3 l + kappa c1 + s2)`` and every eigenvalue
``l != 0`` has the eigenvector ``b1``, so II is inconsistent for every model where ``c1 s1 <= 0``;
for ``t > 0`` and ``c1 s1 > 0`` it is consistent (and stable, Perron-Frobenius) for every model
in the third quadrant (``kappa c1 + s2 < 0``: one positive root) and inconsistent in the first
(every coefficient ``>= 0``).

**A direction on an axis** (``gamma = c2 s1 = 0``, ``D = c1 s2 != 0``; :func:`_axis_rule`).  Then
``p = h1 h2``.  With ``s1 = 0``, ``c2 != 0`` the second row of ``(l^2 + B diag(d1, d2)) x = 0``
reads ``h2 x2 = 0``: a root of ``h1`` alone has ``x2 = 0`` (not II), and a root ``L`` of ``h2``
has ``x1 / x2 = -c2 d2 / h1(L)``, II iff ``c2 h1(L) < 0`` (a common root has ``x2 = 0``).  ``h2``
has a positive root iff ``s2 < 0``, exactly one; ``h1(L) < 0`` iff ``L`` lies below ``h1``'s
positive root ``L1`` (which exists iff ``c1 < 0``).  So II is inconsistent for every model where
``s2 > 0``; where ``s2 < 0 < c1`` it is consistent exactly where ``c2 < 0``, for every model;
where ``c2 > 0`` an II root lies below ``L1``, which dominates (never stable); where ``c2 < 0``
an II root lies above every other root's real part (``L1`` and three roots with ``Re <= 0``), so
II is stable exactly where it is consistent.  ``c2 = 0``, ``s1 != 0`` is the same with the two
contacts exchanged; with ``c2 = s1 = 0`` a root of one factor alone is never II, so II is
inconsistent for every model unless ``c1 < 0`` and ``s2 < 0``.  There (:func:`axis_ranges_rule`)
``h1``, ``h2`` have one positive root each, ``L1`` (increasing in ``kappa``, ``q1``) and ``L2``
(increasing in ``q2``); II holds iff ``L1 < L2`` (``s1 > 0`` or ``c2 < 0``), ``L1 > L2``
(``s1 < 0`` or ``c2 > 0``), or ``L1 = L2`` (``c2 = s1 = 0``: ``B`` diagonal, every ``x`` is an
eigenvector at a common root, a double root of ``p`` above the two negative ones: never strictly
dominant, so never stable), so two corners of the box bound ``L1 - L2`` and decide "for every
model" or "for none" exactly; where they do not, the sample finds ``DEPENDS`` (with ``B``
diagonal its consistent witness has ``h1 = h2``: ``kappa = s2 / c1``, ``q1 = q2 s2 / c1``) or
leaves ``UNDECIDED``.  ``b2 = -b1`` is
decided by the sample only (``DEPENDS``) or left ``UNDECIDED``.  No tolerance decides anything.
"""

from __future__ import annotations

import functools
import math
from fractions import Fraction

import numpy as np

from atlas.core import bernstein as bz
from atlas.core import model_box as mb
from atlas.core.verdicts import OverModels, Verdict

__all__ = [
    "ii_over_models",
    "ii_consistent_over_models",
    "ii_stable_over_models",
    "II_OUTPUTS",
    "SIDES",
]

#: the code outputs and the two sides of each (the witness names' middle word)
SIDES = {
    "ii_consistent_over_models": ("consistent", "inconsistent"),
    "ii_stable_over_models": ("stable", "unstable"),
}


def witness_names(name: str) -> tuple:
    """``<prefix>_witness_<side>_<kappa|q1|q2>`` of the code output ``<prefix>_over_models``."""
    prefix = name.removesuffix("_over_models")
    return tuple(f"{prefix}_witness_{s}_{v}" for s in SIDES[name] for v in ("kappa", "q1", "q2"))


SIDES_CONS, SIDES_STAB = SIDES


def label(name: str, code: int) -> str:
    """The words of a code of output ``name`` (``consistent for every model`` ...)."""
    yes, no = SIDES[name]
    words = {int(OverModels.STABLE): yes, int(OverModels.UNSTABLE): no}
    return f"{words[code]} for every model" if code in words else OverModels(code).label


#: every result of :func:`ii_over_models`
II_OUTPUTS = tuple(x for name in SIDES for x in (name, *witness_names(name)))
BUDGET, SETTLE_BUDGET = 48, 512
_U, _S, _D, _X = (int(OverModels[k]) for k in ("UNSTABLE", "STABLE", "DEPENDS", "UNDECIDED"))


# --- exact polynomials in (l, kappa, q1, q2) or (l, kappa, q) -----------------------------------------


def _dl(p: bz.Poly) -> bz.Poly:
    """``dp/dl`` (``l`` is variable 0)."""
    return bz.Poly({(e[0] - 1,) + e[1:]: c * e[0] for e, c in p.terms.items() if e[0]}, p.n)


def _polys(ints, N: int, equal: bool) -> dict:
    """``p``, ``c2 h1``, the derivatives ``p1 = p'``, ``p3 = p'''``, and ``T`` (each
    times a positive constant) in ``(l, kappa, q1, q2)`` (``(l, kappa, q)`` with ``equal``), for
    direction components ``ints / N`` (integers)."""
    C1, S1, C2, S2 = ints
    n = 3 if equal else 4
    var = lambda i: bz.Poly.var(i, n)  # noqa: E731
    l, k = var(0), var(1)
    q1, q2 = (var(2), var(2)) if equal else (var(2), var(3))
    d1, d2 = k + q1 * l, 1 + q2 * l
    h1, h2 = N * l * l + C1 * d1, N * l * l + S2 * d2  # N h1, N h2
    p = h1 * h2 + (-C2 * S1) * d1 * d2  # N^2 p
    p1 = _dl(p)
    p2 = _dl(p1)
    p3 = _dl(p2)
    T = 12 * N * N * p1 + (-1) * p2 * p3  # 12 N^4 T
    return {"p": p, "c2h1": C2 * h1, "p1": p1, "p3": p3, "T": T}


def _axes(box: mb.ModelBox) -> list:
    """``l in (0, inf)`` and the box's axes (:class:`atlas.core.bernstein.Axis`)."""
    lo_k, hi_k = box.kappa
    ax = lambda lo, hi, open_lo=False: bz.Axis(lo, None if hi == math.inf else hi, open_lo)  # noqa: E731
    out = [bz.Axis(0, None, True), ax(lo_k, hi_k, lo_k == 0), ax(*box.q1)]
    return out if box.equal else out + [ax(*box.q2)]


@functools.lru_cache(maxsize=256)
def _proofs(ints: tuple, N: int, box: mb.ModelBox) -> dict:
    """The condition lists of the proofs, by kind (module docstring): ``cons`` / ``stab``: no
    model has an II root with ``p' = 0`` / ``p' T = 0`` (consistency / stability the same for every
    model); ``no_cons``: no model has an II root; ``no_stab``: no model has a stable II root
    (``p1 > 0``, ``p3 > 0``, ``T < 0``: the deflated cubic Hurwitz)."""
    P = _polys(list(ints), N, box.equal)
    axes = _axes(box)
    bern = {k: bz.to_bernstein(v, axes) for k, v in P.items()}
    root = [(bern["p"], ">0"), (bern["p"], "<0")]
    ii = root + [(bern["c2h1"], ">0")]
    T = [(bern["T"], "<0"), (bern["T"], ">0")]
    if ints[2] < 0 < ints[2] * ints[1]:  # gamma > 0, c2 < 0: the II root is always simple
        stab = ii + T
    else:
        stab = ii + [[(bern["p1"], a), t] for a in ("<0", ">0") for t in T]
    return {
        "cons": ii + [(bern["p1"], ">0"), (bern["p1"], "<0")],
        "stab": stab,
        "no_cons": root + [(bern["c2h1"], ">=0")],
        "no_stab": root
        + [(bern["c2h1"], ">=0"), (bern["p1"], "<=0"), (bern["p3"], "<=0"), (bern["T"], ">=0")],
    }


def _prove(ints, N: int, box: mb.ModelBox, kind: str, budget: int) -> bool:
    """Whether proof ``kind`` (:func:`_proofs`) closes within ``budget`` boxes; ``False`` where it
    does not apply (``gamma = 0`` or ``D = 0``)."""
    C1, S1, C2, S2 = ints
    if budget <= 0 or C2 * S1 == 0 or C1 * S2 == S1 * C2:
        return False
    conds = _proofs(tuple(ints), N, box)[kind]
    return bz.prove_any(conds, _axes(box), (), budget)[0] == "proved"


# --- the geometry's signs ---------------------------------------------------------------------------


def _sg(x) -> int:
    return int(x > 0) - int(x < 0)


def signs_rule(c1, s1, c2, s2, d) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(consistency, never_stable, dominant)`` from the signs (arrays of -1, 0, 1) of ``c1, s1,
    c2, s2`` and ``D = det B``: consistency ``1`` / ``0`` for every model or ``-1`` where it may
    depend on the model (the curve argument of :mod:`atlas.core.exact`; ``D = 0``: the module
    docstring); ``never_stable``:
    ``gamma > 0``, ``c2 > 0``, an II root (in QIII) is followed by a larger root in QI, never II;
    ``dominant``: II stable exactly where consistent, for every model: ``c1, s2 <= 0`` and
    ``c2, s1 < 0`` (Perron-Frobenius) or ``gamma > 0`` and ``D < 0`` (the symmetric pencil;
    module docstring)."""
    c1, s1, c2, s2, d = np.broadcast_arrays(*(np.asarray(v) for v in (c1, s1, c2, s2, d)))
    valid = (d != 0) & (c2 * s1 != 0)
    gpos, gneg = valid & (c2 == s1), valid & (c2 != s1)
    first_q = (c1 >= 0) & (s2 >= 0)
    cons = np.full(c1.shape, -1, np.int8)
    cons[gpos & (c2 < 0)] = ~(first_q & (d > 0))[gpos & (c2 < 0)]
    cons[gpos & (c2 > 0)] = ((c1 < 0) & (s2 < 0) & (d > 0))[gpos & (c2 > 0)]
    cons[gneg & first_q] = 0
    arc = np.where(c1 < 0, -1, 1)  # the quadrant of every positive root: QII (-1) or QIV (+1)
    fixed = gneg & ~first_q & ~((c1 < 0) & (s2 < 0))
    cons[fixed] = np.where(arc * c2 > 0, 0, np.where(d < 0, 1, -1))[fixed]
    # D = 0, b2 = t b1: p = l^2 (l^2 + a3 l + kappa c1 + s2) and every eigenvalue l != 0 has the
    # eigenvector b1: no II root where c1 s1 <= 0; for t > 0 one positive root iff c1 < 0
    zero = d == 0
    along = zero & (c1 * s1 > 0)
    cons[zero & ~along] = 0
    cons[along & (c2 == c1)] = (c1 < 0)[along & (c2 == c1)]
    metzler = (c1 <= 0) & (s2 <= 0) & (c2 < 0) & (s1 < 0)
    g0cons, g0never, g0dominant = _axis_rule(c1, s1, c2, s2, d)
    cons = np.where(g0cons >= 0, g0cons, cons).astype(np.int8)
    return cons, (gpos & (c2 > 0)) | g0never, metzler | (gpos & (d < 0)) | g0dominant


def _axis_rule(c1, s1, c2, s2, d) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`signs_rule` where ``gamma = c2 s1 = 0`` and ``D = c1 s2 != 0`` (module docstring,
    a direction on an axis): ``p = h1 h2``, and with ``s1 = 0`` the II roots are the roots ``L`` of
    ``h2`` with ``c2 h1(L) < 0`` (with ``c2 = 0``: the roots of ``h1`` with ``s1 h2 < 0``)."""
    g0 = (d != 0) & (c2 * s1 == 0)
    row = g0 & (s1 == 0) & (c2 != 0)  # B upper triangular: II roots are roots of h2
    col = g0 & (c2 == 0) & (s1 != 0)  # B lower triangular: II roots are roots of h1
    cons = np.full(c1.shape, -1, np.int8)
    cons[row & (s2 > 0)] = 0  # h2 has no positive root
    cons[row & (s2 < 0) & (c1 > 0)] = (c2 < 0)[row & (s2 < 0) & (c1 > 0)]  # h1(L) > 0
    cons[col & (c1 > 0)] = 0
    cons[col & (c1 < 0) & (s2 > 0)] = (s1 < 0)[col & (c1 < 0) & (s2 > 0)]
    cons[g0 & (c2 == 0) & (s1 == 0) & ((c1 > 0) | (s2 > 0))] = 0  # a root of one factor only
    # c2 > 0 (row): c2 h1(L) < 0 puts L below h1's positive root, which dominates; c2 < 0: above
    # it, so L is simple and strictly dominant (and the same with s1, h2 for col)
    # c2 = s1 = 0 (B diagonal): an II root is a common root of h1 and h2, a double root of p
    # above the other two (negative) roots: never strictly dominant
    never = (row & (c2 > 0)) | (col & (s1 > 0)) | (g0 & (c2 == 0) & (s1 == 0))
    dominant = (row & (c2 < 0)) | (col & (s1 < 0))
    return cons, never, dominant


def _sign_sqrt(x: Fraction, r: Fraction, y: Fraction) -> int:
    """Exact sign of ``x sqrt(r) + y`` (``r >= 0``)."""
    a, b = _sg(x) if r else 0, _sg(y)
    if a == b or b == 0 or a == 0:
        return a or b
    return _sg(x * x * r - y * y) * a


def root_order(C, S, kappa, q1, q2) -> int:
    """Exact sign of ``L1 - L2``, ``L1`` the positive root of ``h1 = l^2 - C (kappa + q1 l)``
    (``C q1`` at ``kappa = 0``), ``L2`` that of ``h2 = l^2 - S (1 + q2 l)`` (``C, S > 0``;
    ``C = -c1``, ``S = -s2``): ``L1 < L2`` iff ``h2(L1) = (C q1 - S q2) L1 + C kappa - S < 0``,
    ``L1 = (C q1 + sqrt(C^2 q1^2 + 4 C kappa)) / 2``."""
    C, S, k, q1, q2 = (Fraction(v) for v in (C, S, kappa, q1, q2))
    a = C * q1 - S * q2
    return _sign_sqrt(a, (C * q1) ** 2 + 4 * C * k, a * C * q1 + 2 * (C * k - S))


def axis_ranges_rule(geo: np.ndarray, box: mb.ModelBox) -> np.ndarray:
    """II consistency over ``box`` (1 every model, 0 none, -1 depends or not this rule's) of the
    rows of ``geo`` with ``c1 < 0``, ``s2 < 0`` and ``c2 s1 = 0`` (module docstring, a direction
    on an axis): II iff ``t = L1 - L2 < 0`` (``s1 > 0`` or ``c2 < 0``), ``t > 0`` (``s1 < 0``
    or ``c2 > 0``) or ``t = 0`` (``s1 = c2 = 0``), and ``t`` increases with ``kappa``, ``q1``
    and decreases with ``q2``: its supremum and infimum over the box are at two corners
    (:func:`root_order`, exact; an unbounded axis gives ``+-inf``; ``kappa > 0`` leaves the
    infimum unattained).  With ``q1 = q2`` the corners bound ``t`` (taken as attained)."""
    out = np.full(len(geo), -1, np.int8)
    (k0, k1), (a0, a1), (b0, b1) = box.kappa, box.q1, box.q2
    lo_open = k0 == 0 and not box.equal
    for i in np.flatnonzero((geo[:, 0] < 0) & (geo[:, 3] < 0) & (geo[:, 1] * geo[:, 2] == 0)):
        c1, s1, c2, s2 = geo[i]
        if s1 != 0 and c2 != 0:  # a product below the smallest subnormal: not on an axis
            continue
        hi = 1 if math.inf in (k1, a1) else root_order(-c1, -s2, k1, a1, b0)
        lo = -1 if b1 == math.inf else root_order(-c1, -s2, k0, a0, b1)
        above = lo > 0 or (lo == 0 and lo_open)  # t > 0 for every model
        if s1 > 0 or c2 < 0:
            out[i] = 1 if hi < 0 else 0 if lo >= 0 else -1
        elif s1 < 0 or c2 > 0:
            out[i] = 1 if above else 0 if hi <= 0 else -1
        else:
            out[i] = 0 if hi < 0 or above else -1
    return out


def common_root_model(g, box: mb.ModelBox):
    """A model of ``box`` at which ``h1 = h2`` (so II is consistent) for ``g = (c1, 0, 0, s2)``,
    ``c1, s2 < 0``: ``(s2 / c1, q2 s2 / c1, q2)`` for a sample value ``q2``, where it is exact in
    floats (checked by the exact tier), else ``None``."""
    from atlas.core import exact  # noqa: PLC0415

    c1, s2 = Fraction(float(g[0])), Fraction(float(g[3]))
    for q2 in np.unique(mb.sample_models(box, True)[2]):
        m = (float(s2 / c1), float(q2 * s2 / c1), float(q2))
        exact_ = Fraction(m[0]) == s2 / c1 and Fraction(m[1]) == Fraction(m[2]) * s2 / c1
        inside = all(r[0] <= v <= r[1] for v, r in zip(m, (box.kappa, box.q1, box.q2)))
        if exact_ and inside and m[0] > 0 and (m[1] == m[2] or not box.equal):
            if exact.point_spectral(*map(float, g), *m)["consistent_II"] == 1:
                return m
    return None


def below_threshold(geo: np.ndarray) -> np.ndarray:
    """Exact ``3 |gamma| <= 2 |c1 s2|`` per row of ``geo`` (``c1, s1, c2, s2``): the float
    comparison where it exceeds its rounding bound, exact rationals elsewhere."""
    c1, s1, c2, s2 = np.asarray(geo, np.float64).T
    g, c = np.abs(c2 * s1), np.abs(c1 * s2)
    diff = 2 * c - 3 * g
    bound = 8 * np.finfo(np.float64).eps * (3 * g + 2 * c) + 1e-300
    out = diff > 0
    for i in np.flatnonzero(np.abs(diff) <= bound):
        a, b, t, e = (Fraction(float(v)) for v in np.asarray(geo, np.float64)[i])
        out[i] = 3 * abs(t * b) <= 2 * abs(a * e)
    return out


def threshold_rule(geo: np.ndarray, d: np.ndarray) -> np.ndarray:
    """``gamma < 0``, ``D < 0`` (exact signs ``d``) and ``3 |gamma| <= 2 |c1 s2|``: the strictly
    dominant eigenvalue is a simple positive root for every model (module docstring, the
    threshold rule), so II is stable exactly where it is consistent."""
    geo = np.asarray(geo, np.float64)
    gneg = np.sign(geo[:, 2]) * np.sign(geo[:, 1]) < 0  # the factors' signs: no underflow
    out = gneg & (d < 0)
    out[out] = below_threshold(geo[out])
    return out


def consistency_by_signs(c1, s1, c2, s2) -> int | None:
    """:func:`signs_rule`'s consistency of one geometry (exact inputs, e.g. the integers of
    :func:`atlas.core.model_box.integers`): 1 / 0, ``None`` where it may depend on the model."""
    cons = int(signs_rule(*map(_sg, (c1, s1, c2, s2, c1 * s2 - s1 * c2)))[0])
    return None if cons < 0 else cons


def never_stable_by_signs(c1, s1, c2, s2) -> bool:
    """:func:`signs_rule`'s ``never_stable`` of one geometry (exact inputs)."""
    return bool(signs_rule(*map(_sg, (c1, s1, c2, s2, c1 * s2 - s1 * c2)))[1])


def stable_by_signs(c1, s1, c2, s2) -> bool:
    """Whether the signs prove II stable for every model (consistent by :func:`signs_rule` and
    ``dominant``, or the threshold rule: ``gamma < 0``, ``D < 0``, ``3 |gamma| <= 2 |c1 s2|``) at
    one geometry (ints or floats, compared exactly)."""
    c1, s1, c2, s2 = (Fraction(v if isinstance(v, int) else float(v)) for v in (c1, s1, c2, s2))
    d = c1 * s2 - s1 * c2
    cons, _, dominant = signs_rule(*map(_sg, (c1, s1, c2, s2, d)))
    below = c2 * s1 < 0 and d < 0 and 3 * abs(c2 * s1) <= 2 * abs(c1 * s2)
    return int(cons) == 1 and (bool(dominant) or below)


# --- the sample (certified point verdicts) -----------------------------------------------------------

#: the exponents ``e`` of :func:`far_models`
FAR_EXPONENTS = (48, 200, 800)


def far_models(box: mb.ModelBox) -> tuple:
    """The models of the box among ``(2^e, 0, 2^(e/4))`` and their duals ``(2^-e, 2^(-e/4), 0)``
    (``e`` in :data:`FAR_EXPONENTS`), as flat ``(kappa, q1, q2)`` arrays: candidates (never a
    decision) for a complex pair overtaking the II root where ``gamma < 0`` and ``D < 0``.  With
    ``kappa -> inf``, ``q1 = 0``, ``1 << q2 << sqrt(kappa)``, contact 1 is a fast oscillator
    ``l ~ +-i sqrt(c1 kappa)`` whose real part tends to ``-gamma q2 / (2 c1)`` and the real root
    to ``-D q2 / c1``: the pair overtakes it where ``3 |gamma| > 2 c1 |s2|`` (``c1 > 0``; class 15;
    the duals, ``kappa -> 0``: ``3 |gamma| > 2 s2 |c1|``, class 32)."""
    e = np.array(FAR_EXPONENTS, np.float64)
    far = np.stack([np.exp2(e), np.zeros_like(e), np.exp2(e / 4)], 1)
    dual = np.stack([np.exp2(-e), np.exp2(-e / 4), np.zeros_like(e)], 1)
    m = np.concatenate([far, dual])
    inside = lambda v, r: (r[0] <= v) & (v <= r[1])  # noqa: E731
    keep = inside(m[:, 0], box.kappa) & inside(m[:, 1], box.q1) & inside(m[:, 2], box.q2)
    keep &= (m[:, 1] == m[:, 2]) | (not box.equal)
    return tuple(m[keep].T)


def _sample(geo: np.ndarray, models: np.ndarray, scale=None, chunk: int = 1 << 21) -> dict:
    """Per output, the first of ``models`` (``(m, 3)``: ``kappa, q1, q2``; at geometry ``i``
    :func:`rescaled` by ``scale[i]`` if given, skipped where that is no float model) on each side
    (certified point verdicts) at each geometry: ``{name: (seen, models)}``, ``seen`` ``(n, 2)``
    bool, ``models`` ``(n, 2, 3)`` (NaN where not seen)."""
    from atlas.core.points import spectral_points  # noqa: PLC0415 - JAX only when needed

    firsts = {name: np.full((len(geo), 2), -1, np.int64) for name in SIDES}
    step = max(1, chunk // len(models))
    for i in range(0, len(geo), step):
        block = geo[i : i + step]
        size = min(step, max(64, 1 << (len(block) - 1).bit_length()))  # a few shapes: compiled once
        block = np.concatenate([block, np.repeat(block[:1], size - len(block), 0)])
        if scale is None:
            m = np.broadcast_to(models, (size, *models.shape))
        else:
            sc = scale[i : i + step]
            sc = np.concatenate([sc, np.repeat(sc[:1], size - len(sc), 0)])
            m = rescaled(models[None], sc[:, None])
        valid = ~np.isnan(m[..., 0])
        if not valid.any():  # no float model here: nothing to evaluate
            continue
        g = [block[:, j, None] for j in range(4)]
        m = [np.where(valid, m[..., j], 1.0) for j in range(3)]
        n = min(step, len(geo) - i)
        wanted = valid.copy()
        wanted[n:] = False  # the padding rows and the stand-ins: first pass only
        needed = lambda idx, verdicts, exact, w=wanted.reshape(-1): w[idx]  # noqa: E731
        v = spectral_points(*g, *m, names=("consistent_II", "stable_II"), needed=needed)
        valid = valid[:n]
        ci, si = np.asarray(v["consistent_II"])[:n], np.asarray(v["stable_II"])[:n]
        sides = {
            "ii_consistent_over_models": (ci == 1, ci == 0),
            "ii_stable_over_models": (
                si == int(Verdict.STABLE),
                np.isin(si, (int(Verdict.UNSTABLE), int(Verdict.NEUTRAL))),
            ),
        }
        for name, (good, bad) in sides.items():
            for j, m in enumerate((good & valid, bad & valid)):
                firsts[name][i : i + n, j] = np.where(m.any(1), np.argmax(m, 1), -1)
    padded = np.concatenate([models, np.full((1, 3), np.nan)])  # index -1: NaN
    moved = (lambda m: m) if scale is None else (lambda m: rescaled(m, scale[:, None]))  # noqa: E731
    return {name: (f >= 0, moved(padded[f])) for name, f in firsts.items()}


def scaling(c1, log2_u) -> np.ndarray:
    """``log2`` of the ``(kappa, q1, q2)`` multipliers ``(u / |c1|, sqrt(u) / |c1|, 1 / sqrt(u))``
    (``u > 0`` given as ``log2 u``, ``c1 != 0``; no overflow for subnormal ``|c1|``).  With
    ``l = sqrt(u) m``, ``p`` at the model times them and geometry ``c1, s1, c2, s2`` is ``u^2``
    times ``p`` at the model and the geometry with ``c1' = sign c1``, ``s2' = s2 / u``,
    ``gamma' = gamma / (|c1| u)`` (the II condition ``c2 h1 < 0`` keeps its sign): ``u = |s2|``
    gives ``(sign c1, sign s1, sign c2 |gamma / (c1 s2)|, sign s2)``, ``u = |gamma / c1|``
    gives ``(sign c1, sign s1, sign c2, s2 |c1 / gamma|)``, so the sample of a geometry with
    components or ``|gamma / (c1 s2)|`` far from 1 is a unit one's moved there."""
    lc, lu = np.log2(np.abs(c1)), np.asarray(log2_u, np.float64)
    return np.stack([lu - lc, lu / 2 - lc, -lu / 2], -1)


def rescaled(models, log2_scale) -> np.ndarray:
    """``models`` (``(..., 3)``: ``kappa, q1, q2``) times ``2^log2_scale`` (broadcast), NaN rows
    where the product is not a float model (overflow, or ``kappa`` rounded to 0): not in the
    model space, never evaluated."""
    e = np.clip(np.floor(log2_scale), -4096, 4096)
    with np.errstate(over="ignore", under="ignore", invalid="ignore"):
        out = np.ldexp(models * np.exp2(log2_scale - e), e.astype(np.int32))
    bad = ~np.isfinite(out).all(-1) | ~(out[..., 0] > 0)
    return np.where(bad[..., None], np.nan, out)


def _merge(out: dict, rows: np.ndarray, more: dict) -> None:
    """Add the sides ``more`` saw at ``rows`` of ``out`` (both :func:`_sample` results)."""
    for name, (seen, models) in out.items():
        new = ~seen[rows] & more[name][0]
        seen[rows] |= new
        models[rows] = np.where(new[..., None], more[name][1], models[rows])


def _staged_sample(geo: np.ndarray, box: mb.ModelBox, cons: np.ndarray) -> dict:
    """:func:`_sample` with every eighth model of :func:`atlas.core.model_box.sample_models`, then
    all of them where a side is missing (of the consistency only where the signs' ``cons`` does
    not decide it), then :func:`far_models` where the stability's unstable side is still missing
    and ``3 |gamma| > 1.9 |c1 s2|`` (the far models' limit, with room: a choice of candidates,
    never a decision; the far models mostly need the exact tier), and on the whole model space,
    where ``|c1|`` or ``|s2| < 2^-20`` and a side is still missing, the sample scaled to the
    geometry (:func:`scaling` with ``u = |s2|``), then the fine one, and the same with
    ``u = |gamma / c1|`` where ``|gamma / (c1 s2)|`` is outside ``[2^-20, 2^20]``."""
    grid = np.stack(mb.sample_models(box, False), 1)
    out = _sample(geo, grid[::8])

    def missing():
        full = {name: out[name][0].all(1) for name in SIDES}
        return ~full[SIDES_STAB] | ((cons < 0) & ~full[SIDES_CONS])

    rest = np.flatnonzero(missing())
    if len(rest):
        _merge(out, rest, _sample(geo[rest], grid))
    c1, s1, c2, s2 = geo.T
    near = 3 * np.abs(c2 * s1) > 1.9 * np.abs(c1 * s2)
    far = np.stack(far_models(box), 1)
    rest = np.flatnonzero(missing() & ~out[SIDES_STAB][0][:, 1] & near)
    if len(rest) and len(far):
        _merge(out, rest, _sample(geo[rest], far))
    whole = box == mb.ModelBox()
    with np.errstate(divide="ignore"):  # log2 0 = -inf: such rows are left out
        lc, ls = np.log2(np.abs(c1)), np.log2(np.abs(s2))
        lg = np.log2(np.abs(c2)) + np.log2(np.abs(s1))  # log2 |gamma|, no underflow
    ok = whole & np.isfinite(lc) & np.isfinite(ls) & np.isfinite(lg)
    stages = (
        (ok & (np.minimum(lc, ls) < -20), ls),  # u = |s2|
        (ok & (np.abs(lg - lc - ls) > 20), lg - lc),  # u = |gamma / c1|
    )
    for where, log2_u in stages:
        rest = np.flatnonzero(missing() & where)
        for fine in (False, True):
            rest = rest[missing()[rest]]
            if len(rest):
                models = np.stack(mb.sample_models(box, fine), 1)
                _merge(out, rest, _sample(geo[rest], models, scaling(c1[rest], log2_u[rest])))
    seen, models = out[SIDES_CONS]
    for i in np.flatnonzero((s1 == 0) & (c2 == 0) & (c1 < 0) & (s2 < 0) & ~seen[:, 0]):
        m = common_root_model(geo[i], box)
        if m is not None:
            seen[i, 0], models[i, 0] = True, m
    return out


# --- the driver -------------------------------------------------------------------------------------


def _contradiction(ints, N):
    return RuntimeError(f"ii_over_models: the sample contradicts the signs at {ints} / {N}")


def _decide(ints, N, box, seen: dict, budget: int) -> dict:
    """Codes of one geometry from its sample (``seen[name]``: which sides were seen) and proofs."""
    by_sign = consistency_by_signs(*ints)
    sc, ss = seen["ii_consistent_over_models"], seen["ii_stable_over_models"]
    prove = lambda *kinds: any(_prove(ints, N, box, k, budget) for k in kinds)  # noqa: E731
    if by_sign is not None:
        if sc[by_sign]:  # sides (consistent, inconsistent): by_sign 1 excludes side 1
            raise _contradiction(ints, N)
        cons = _S if by_sign else _U
    elif all(sc):
        cons = _D
    elif sc[0] and prove("cons"):
        cons = _S
    elif sc[1] and prove("no_cons", "cons"):
        cons = _U
    else:
        cons = _X
    if all(ss):
        stab = _D
    elif cons == _U or never_stable_by_signs(*ints):
        if ss[0]:
            raise _contradiction(ints, N)
        stab = _U
    elif ss[1] and prove("no_stab", "stab"):
        stab = _U
    elif ss[0] and prove("stab"):
        stab = _S
    else:
        stab = _X
    return {"ii_consistent_over_models": cons, "ii_stable_over_models": stab}


def _sample_codes(cons, never, sc: np.ndarray, ss: np.ndarray, geo: np.ndarray) -> dict:
    """Tier 2 for all open geometries at once: their codes from the signs' consistency ``cons``
    (1, 0, -1), ``never`` (never stable: unstable for every model) and the sides the sample saw
    (``sc``, ``ss``: ``(n, 2)`` bool, sides :data:`SIDES`); ``UNDECIDED`` where one side only was
    seen and the signs do not decide."""
    n = np.arange(len(cons))
    bad = (cons >= 0) & sc[n, np.clip(cons, 0, 1)]  # side 1 seen where the signs say 1, ...
    c = np.where(cons >= 0, np.where(cons == 1, _S, _U), np.where(sc.all(1), _D, _X))
    unstable = (c == _U) | never
    bad |= unstable & ss[:, 0]
    if bad.any():
        raise _contradiction(*mb.integers(tuple(geo[np.argmax(bad)].tolist())))
    st = np.where(ss.all(1), _D, np.where(unstable, _U, _X))
    return {SIDES_CONS: c.astype(np.int8), SIDES_STAB: st.astype(np.int8)}


def _proved_codes(geo, box: mb.ModelBox, sc, ss, settle: bool) -> tuple[list, int]:
    """Tiers 3 and 4 for the geometries ``geo`` the sample left open (bounded boxes): their
    codes (one dict each) and the codes left open by the small budget."""
    out, before = [], 0
    for g, c, s in zip(geo, sc, ss):
        ints, N = mb.integers(tuple(g.tolist()))
        seen = {SIDES_CONS: tuple(c), SIDES_STAB: tuple(s)}
        got = _decide(ints, N, box, seen, BUDGET)
        if _X in got.values():
            before += sum(v == _X for v in got.values())
            if settle:
                got = _decide(ints, N, box, seen, SETTLE_BUDGET)
        out.append(got)
    return out, before


def ii_over_models(c1, s1, c2, s2, box: mb.ModelBox, *, settle: bool = True) -> dict:
    """Certified II consistency and II stability over the model ``box`` (module docstring) for
    broadcastable direction components: the codes of :data:`SIDES`
    (:class:`atlas.core.verdicts.OverModels`: 1 consistent / stable for every model, 0 the
    opposite for every model, 2 depends, 3 undecided; int8) and their witnesses
    (:func:`witness_names`, float64, NaN where the code is not ``DEPENDS``).  ``settle=False``
    leaves what the small budget did not decide ``UNDECIDED``; on a box with an unbounded axis
    no proof is tried (module docstring, Tiers).  ``.stats``: counts."""
    box = mb.checked(box)
    arrs = np.broadcast_arrays(*(np.asarray(v, np.float64) for v in (c1, s1, c2, s2)))
    shape = arrs[0].shape
    geo = np.stack([a.ravel() for a in arrs], axis=1)
    bounded = math.inf not in (box.kappa[1], box.q1[1], box.q2[1])
    sd = mb.det_signs(geo)
    cons, never, dominant = signs_rule(*np.sign(geo.T), sd)
    ranges = axis_ranges_rule(geo, box)
    cons = np.where(ranges >= 0, ranges, cons).astype(np.int8)
    dominant = dominant | threshold_rule(geo, sd)
    codes = {name: np.full(len(geo), _X, np.int8) for name in SIDES}
    codes[SIDES_CONS][cons >= 0] = cons[cons >= 0]
    codes[SIDES_STAB][(cons == 0) | never] = _U
    codes[SIDES_STAB][(cons == 1) & dominant] = _S
    wit = {name: np.full((len(geo), 6), np.nan) for name in SIDES}
    todo = np.flatnonzero((codes[SIDES_STAB] == _X) | (codes[SIDES_CONS] == _X))  # signs: open
    sample = _staged_sample(geo[todo], box, cons[todo])
    sc, ss = (sample[name][0] for name in SIDES)
    got = _sample_codes(cons[todo], never[todo], sc, ss, geo[todo])
    stats = {"points": len(geo), "by_signs": len(geo) - len(todo)}
    stats["undecided_before"] = int(sum(np.sum(v == _X) for v in got.values()))
    open_ = np.flatnonzero((got[SIDES_CONS] == _X) | (got[SIDES_STAB] == _X))
    if bounded and len(open_):
        proved, stats["undecided_before"] = _proved_codes(
            geo[todo[open_]], box, sc[open_], ss[open_], settle
        )
        for name in SIDES:
            got[name][open_] = [r[name] for r in proved]
    for name in SIDES:
        codes[name][todo] = got[name]
        dep = np.flatnonzero(got[name] == _D)
        wit[name][todo[dep]] = sample[name][1][dep].reshape(len(dep), 6)
    stats["undecided_after"] = int(sum(np.sum(c == _X) for c in codes.values()))
    out = mb.BoxResult()
    for name in SIDES:
        out[name] = codes[name].reshape(shape)
        out.update({w: wit[name][:, j].reshape(shape) for j, w in enumerate(witness_names(name))})
    out.stats = stats
    return out


#: the point functions of the two outputs, named like them (:mod:`atlas.data.box_points`): both
#: are decided together
ii_consistent_over_models = ii_stable_over_models = ii_over_models
