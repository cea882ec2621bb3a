"""II over a box of contact models where a direction lies on an axis (``gamma = c2 s1 = 0``) or
a component is tiny, against the independent sympy/mpmath reference (``tests/reference_sympy.py``:
the characteristic polynomial from its definition, exact root isolation).  The full-size model
grid is ``slow``: ``python -m pytest -m slow tests/core/test_ii_over_models_axes.py``."""

import numpy as np
import pytest
from reference_sympy import point_spectral

from atlas.core import ii_over_models as iim
from atlas.core import model_box as mb
from atlas.core import points
from atlas.core.verdicts import OverModels, Verdict

NO, YES, DEP, UND = (int(v) for v in OverModels)
CONS, STAB = iim.SIDES
BOX = mb.model_box(kappa=(0.01, 100.0), q1=(0.0, 1.0), q2=(0.0, 1.0))


def _reference(g, m) -> tuple[int, int]:
    """``(consistent_II, stable_II is STABLE)`` of model ``m`` at geometry ``g`` (reference)."""
    v = point_spectral(*g, *m)
    return int(v["consistent_II"]), int(v["stable_II"] == int(Verdict.STABLE))


def _grid(box: mb.ModelBox, n: int = 5) -> list:
    """``n^3`` models spread over a bounded box (geometric in ``kappa``, linear in ``q``)."""
    k = np.geomspace(*box.kappa, n)
    q1, q2 = (np.linspace(*r, n) for r in (box.q1, box.q2))
    return [(float(a), float(b), float(c)) for a in k for b in q1 for c in q2]


def _witnesses(r, name, i) -> tuple:
    w = [float(r[x][i]) for x in iim.witness_names(name)]
    return tuple(w[:3]), tuple(w[3:])


# b1 = (-1, 0) with b2 in QIV, and b2 = (0, -1) with b1 in QII: gamma = 0, c1 < 0, s2 < 0, and
# the II root, where there is one, lies below a larger root (never stable)
NEVER_STABLE = [
    (-1.0, 0.0, 0.6, -0.8),
    (-1.0, 0.0, 0.28, -0.96),
    (-0.6, 0.8, 0.0, -1.0),
    (-0.96, 0.28, 0.0, -1.0),
]


@pytest.mark.parametrize("n", [3, pytest.param(5, marks=pytest.mark.slow)])
def test_consistency_is_sampled_where_the_signs_decide_only_the_stability(n):
    """The signs say "never stable" but leave the consistency open: it depends on the model (the
    reference sees both sides on an ``n^3`` grid of the box), with both witnesses on their sides;
    the stability is unstable for every model (the reference never sees a stable II)."""
    r = iim.ii_over_models(*np.array(NEVER_STABLE).T, BOX, settle=False)
    assert r[CONS].tolist() == [DEP] * 4 and r[STAB].tolist() == [NO] * 4
    for i, g in enumerate(NEVER_STABLE):
        got = {_reference(g, m) for m in _grid(BOX, n)}
        assert got == {(0, 0), (1, 0)}, (g, got)
        yes, no = _witnesses(r, CONS, i)
        assert _reference(g, yes)[0] == 1 and _reference(g, no)[0] == 0, (g, yes, no)


def _corners_and_middle(box: mb.ModelBox) -> list:
    """The box's corners and middle (``inf`` -> ``1e6``, ``kappa > 0`` from ``0`` -> ``1e-6``)."""
    ends = [
        (max(lo, 1e-6) if name == "kappa" else lo, min(hi, 1e6))
        for name, (lo, hi) in (("kappa", box.kappa), ("q1", box.q1), ("q2", box.q2))
    ]
    mid = tuple(float(np.sqrt(a * b)) if a > 0 else b / 2 for a, b in ends)
    models = [(k, a, b) for k in ends[0] for a in ends[1] for b in ends[2]] + [mid]
    return [m for m in models if m[1] == m[2] or not box.equal]


# one of each rule: II iff L1 < L2 (s1 > 0; c2 < 0), L1 > L2 (s1 < 0; c2 > 0), L1 = L2 (diagonal)
ON_AXES = [
    (-0.6, 0.8, 0.0, -1.0),
    (-1.0, 0.0, -0.6, -0.8),
    (-0.6, -0.8, 0.0, -1.0),
    (-1.0, 0.0, 0.6, -0.8),
]
AXIS_BOXES = [
    mb.model_box(kappa=(0.01, 0.1), q1=(0.0, 0.1), q2=(1.0, 2.0)),  # L1 < L2 throughout
    mb.model_box(kappa=(10.0, 100.0), q1=(1.0, 2.0), q2=(0.0, 0.5)),  # L1 > L2 throughout
    mb.model_box(kappa=(0.0, 0.1), q1=(0.0, 0.1), q2=(1.0, 2.0)),  # kappa > 0, open at 0
    mb.model_box(kappa=(0.5, 2.0), q=(0.0, 1.0)),
]


@pytest.mark.parametrize("box", AXIS_BOXES, ids=str)
def test_axis_geometries_against_the_reference_at_the_corners(box):
    """Where a direction lies on an axis (``c1, s2 < 0``) the corners of the box decide (module
    docstring): every "for every model" code holds at the corners and middle of the box by the
    reference, and on the first two boxes (the sample sees one side only) the codes are decided;
    before the rule they were ``undecided``."""
    r = iim.ii_over_models(*np.array(ON_AXES).T, box, settle=False)
    for i, g in enumerate(ON_AXES):
        code = int(r[CONS][i])
        assert code != UND, g
        if code in (YES, NO):
            got = {_reference(g, m)[0] for m in _corners_and_middle(box)}
            assert got == {int(code == YES)}, (g, code, got)
        else:
            yes, no = _witnesses(r, CONS, i)
            assert _reference(g, yes)[0] == 1 and _reference(g, no)[0] == 0, (g, yes, no)
    if box in AXIS_BOXES[:2]:
        want = [YES, YES, NO, NO] if box == AXIS_BOXES[0] else [NO, NO, YES, YES]
        assert r[CONS].tolist() == want
        assert r[STAB].tolist() == [NO, YES, NO, NO] if box == AXIS_BOXES[0] else [NO] * 4


def test_the_corner_order_is_exact():
    """``L1 = L2`` exactly (``C = S = 1``, ``kappa = 1``, ``q1 = q2``: ``h1 = h2``) is 0, one
    ulp of ``kappa`` either side is -1 / +1; against the closed-form roots in mpmath (80 digits)."""
    mpmath = pytest.importorskip("mpmath")
    assert iim.root_order(1.0, 1.0, 1.0, 0.5, 0.5) == 0
    with mpmath.workdps(80):
        for k in (np.nextafter(1.0, 0.0), np.nextafter(1.0, 2.0), 0.3, 7.0):
            for C, S, q1, q2 in (
                (1.0, 1.0, 0.5, 0.5),
                (0.6, 0.8, 0.0, 1.0),
                (0.28, 0.96, 2.0, 0.0),
            ):
                L1 = (C * q1 + mpmath.sqrt(mpmath.mpf(C * q1) ** 2 + 4 * mpmath.mpf(C) * k)) / 2
                L2 = (S * q2 + mpmath.sqrt(mpmath.mpf(S * q2) ** 2 + 4 * mpmath.mpf(S))) / 2
                want = int(mpmath.sign(L1 - L2))
                assert want != 0 and iim.root_order(C, S, k, q1, q2) == want, (k, C, S)


def _ii_at_common_root(g, m) -> bool:
    """B diagonal: at the positive root ``L`` of ``h2`` (sympy, exact) ``l^2 I + B diag(d1, d2)``
    vanishes, so ``x = (1, 1)`` is an eigenvector with ``x1 x2 > 0``: II consistent."""
    sp = pytest.importorskip("sympy")
    c1, _, _, s2 = (sp.Rational(v) for v in g)
    k, q1, q2 = (sp.Rational(v) for v in m)
    lam = sp.Symbol("lam", positive=True)
    (L,) = sp.solve(lam**2 + s2 * (1 + q2 * lam), lam)
    mat = sp.Matrix([[L**2 + c1 * (k + q1 * L), 0], [0, L**2 + s2 * (1 + q2 * L)]])
    return L > 0 and sp.simplify(mat) == sp.zeros(2, 2)


@pytest.mark.parametrize("box", [BOX, mb.model_box(), mb.model_box(kappa=(0.5, 4.0), q=(0, 1))])
def test_a_diagonal_b_depends_and_is_never_stable(box):
    """``b1 = (-1, 0)``, ``b2 = (0, -1)`` (``beta1 = pi``, ``beta2 = 3 pi / 2``): II consistent
    exactly where ``h1``, ``h2`` share their positive root (a double root of ``p``, never
    strictly dominant).  Consistency depends on the model (the consistent witness has ``h1 =
    h2``, checked in sympy; the inconsistent one by the reference), stability is unstable for
    every model (the reference at the box's corners and middle).  Undecided before."""
    g = (-1.0, 0.0, 0.0, -1.0)
    r = iim.ii_over_models(*g, box, settle=False)
    assert (int(r[CONS]), int(r[STAB])) == (DEP, NO)
    yes, no = _witnesses(r, CONS, ())
    assert _ii_at_common_root(g, yes) and _reference(g, no)[0] == 0
    assert {_reference(g, m)[1] for m in _corners_and_middle(box) if m[0] != 1.0} == {0}


def test_a_diagonal_b_without_a_common_root_in_the_box():
    """The positive roots' ranges do not meet (``L1 <= 0.36 < 1 <= L2``): inconsistent for every
    model, by the corners (the reference agrees at the corners and middle)."""
    g = (-1.0, 0.0, 0.0, -1.0)
    box = mb.model_box(kappa=(0.01, 0.1), q1=(0.0, 0.1), q2=(0.0, 2.0))
    r = iim.ii_over_models(*g, box, settle=False)
    assert (int(r[CONS]), int(r[STAB])) == (NO, NO)
    assert {_reference(g, m)[0] for m in _corners_and_middle(box)} == {0}


def test_never_stable_stays_decided_on_an_unbounded_box():
    """On the whole model space (no proof tier) the sampled consistency must not reopen the
    stability the signs decided: unstable for every model (the reference at the corners and
    middle of the box, capped at 1e6), consistency depends."""
    box = mb.model_box()
    r = iim.ii_over_models(*np.array(NEVER_STABLE).T, box, settle=False)
    assert r[CONS].tolist() == [DEP] * 4 and r[STAB].tolist() == [NO] * 4
    for g in NEVER_STABLE:
        assert {_reference(g, m)[1] for m in _corners_and_middle(box)} == {0}, g


def _tiny_c1(x: float) -> np.ndarray:
    return np.array([(-x, -1.0, 0.6, 0.8), (-x, -1.0, 0.6, -0.8)])


@pytest.mark.parametrize("x", [1e-20])
def test_a_tiny_c1_depends_with_witnesses_far_out(x):
    """``b1 = (-x, -1)``, ``b2 = (0.6, +-0.8)``: II needs ``h1 < 0``, so ``kappa + q1 l`` beyond
    about ``0.6 / x^2`` (the sample moved by ``u = |gamma / c1|``): consistency and stability
    depend on the model, both witnesses on their sides by the reference.  The sample's blocks of
    geometries are padded to 64 rows (a few compiled shapes): the 62 padding rows go through the
    first pass only, so tier 2, the enclosures and the exact tier each see at most the two real
    rows' points, 1/32 of the first pass's."""
    geo = _tiny_c1(x)
    with points.tally() as work:
        r = iim.ii_over_models(*geo.T, mb.model_box(), settle=False)
    assert r[CONS].tolist() == [DEP, DEP] and r[STAB].tolist() == [DEP, DEP]
    for tier in ("tier2_points", "roots_points", "exact_points"):
        assert work[tier] <= work["points"] // 32, (tier, dict(work))
    for i, g in enumerate(map(tuple, geo)):
        for j, name in enumerate((CONS, STAB)):
            yes, no = _witnesses(r, name, i)
            assert _reference(g, yes)[j] == 1 and _reference(g, no)[j] == 0, (g, name, yes, no)


def test_the_moved_sample_of_a_subnormal_c1_overflows_nothing():
    """:func:`scaling` and :func:`rescaled` at ``|c1| = 5e-324`` and ``1e-300`` (``u = |s2| =
    0.8`` and ``u = |gamma / c1|``): no warning; a product is the exact one (Fractions, to 1e-12) where it
    is a float, NaN where it overflows (no float model)."""
    import math
    import warnings
    from fractions import Fraction

    models = np.array([(2.0**e, 2.0**e, 2.0**e) for e in range(-24, 25, 6)])
    top = Fraction(np.finfo(float).max) ** 2
    seen = set()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for c1 in (5e-324, 1e-300):
            C = Fraction(c1)
            for U in (Fraction(0.8), Fraction(0.6) / C):
                log2_u = math.log2(U.numerator) - math.log2(U.denominator)
                got = iim.rescaled(models, iim.scaling(c1, log2_u))
                squares = (U * U / (C * C), U / (C * C), 1 / U)  # the multipliers squared
                for m, row in zip(models, got):
                    want = [Fraction(float(v)) ** 2 * f for v, f in zip(m, squares)]
                    seen.add(any(w > top for w in want))
                    if any(w > top for w in want):
                        assert np.isnan(row).all()
                    else:
                        assert all(abs(Fraction(r) ** 2 / w - 1) < 1e-12 for r, w in zip(row, want))
    assert seen == {True, False}


@pytest.mark.slow
def test_a_subnormal_c1_overflows_nothing():
    """``c1`` subnormal (``5e-324``, ``1e-310``): the moved samples raise no warning (no
    multiplier overflows).  The codes stay ``undecided``: an II root needs ``h1 = l^2 - x d1 < 0``
    with ``d1 > 0.6 / x^2`` (from ``h1 h2 = 0.6 d1 d2``), so ``kappa > 1e300`` or
    ``q1 > sqrt(0.6) / (2 x^1.5) > 1e400``: no float model witnesses the consistent side."""
    import warnings

    geo = np.concatenate([_tiny_c1(5e-324), _tiny_c1(1e-310)])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        r = iim.ii_over_models(*geo.T, mb.model_box(), settle=False)
    assert set(r[CONS].tolist()) <= {DEP, UND} and set(r[STAB].tolist()) <= {DEP, UND}


def test_without_settlement_the_undecided_counts_agree():
    """``settle=False``: ``undecided_before`` (after the small budget) and ``undecided_after``
    count the same codes, the undecided ones of the result (before, geometries whose stability
    the signs decided were never sampled, and their open consistency was counted only after)."""
    geo = np.array(NEVER_STABLE + [(-1.0, 0.0, 0.0, -1.0)])
    r = iim.ii_over_models(*geo.T, BOX, settle=False)
    und = sum(int(np.sum(r[name] == UND)) for name in (CONS, STAB))
    assert r.stats["undecided_before"] == r.stats["undecided_after"] == und, r.stats
