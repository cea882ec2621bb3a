"""The exact tier against closed forms worked by hand, an independent 50-digit eigen-solver and the
independent sympy/mpmath reference (tests/reference_sympy.py)."""

import functools
import math

import mpmath
import numpy as np
import pytest
import reference_sympy

from atlas.core import exact, hardcases
from atlas.core.invariants import KEYS
from atlas.core.verdicts import Consistency, Verdict

NAMES = ("stable_SS", "consistent_II", "stable_II")
S, U, N = int(Verdict.STABLE), int(Verdict.UNSTABLE), int(Verdict.NEUTRAL)


def _mp_eig(c1, s1, c2, s2, kappa, q1, q2):
    with mpmath.workdps(50):
        M = mpmath.matrix(
            [
                [0, 0, 1, 0],
                [0, 0, 0, 1],
                [-c1 * kappa, -c2, -c1 * q1, -c2 * q2],
                [-s1 * kappa, -s2, -s1 * q1, -s2 * q2],
            ]
        )
        return mpmath.eig(M, left=False, right=False)


def _verdicts(r: dict) -> tuple:
    return tuple(int(r[k]) for k in NAMES)


@functools.cache
def _reference(p: tuple) -> tuple | None:
    """The sympy reference verdicts of one point, None where it raises (exact multiple roots);
    cached, as several tests check the same suite sample against it."""
    try:
        return _verdicts(reference_sympy.point_spectral(*p))
    except (ArithmeticError, mpmath.libmp.NoConvergence):
        return None


def _compare_with_reference(points) -> tuple[list, int]:
    """(disagreements, skipped): the sympy reference raises on exact multiple roots (skipped)."""
    bad, skipped = [], 0
    for p in points:
        want = _reference(tuple(p))
        if want is None:
            skipped += 1
            continue
        got = _verdicts(exact.point_verdicts(*p))
        if got != want:
            bad.append((p, got, want))
    return bad, skipped


@functools.cache
def _suite(name, dtype) -> dict:
    return hardcases.suite(name, dtype)


def _suite_points(per_suite=None, seed=7) -> list:
    rng = np.random.default_rng(seed)
    pts = []
    for name in hardcases.SUITES:
        for dtype in ("float32", "float64"):
            s = _suite(name, dtype)
            n = len(s["c1"])
            idx = np.arange(n) if per_suite is None else rng.choice(n, min(n, per_suite), False)
            pts += [tuple(float(s[k][i]) for k in KEYS) for i in idx]
    return pts


# --- closed forms, worked by hand -------------------------------------------------------------


def test_roots_match_independent_eigensolver():
    rng = np.random.default_rng(0)
    for _ in range(20):
        b1, b2 = rng.uniform(0, 2 * np.pi, 2)
        args = (
            np.cos(b1),
            np.sin(b1),
            np.cos(b2),
            np.sin(b2),
            10 ** rng.uniform(-1, 1),
            rng.uniform(0, 1),
            rng.uniform(0, 1),
        )
        r = exact.point_spectral(*args)
        ev = [complex(z) for z in _mp_eig(*args)]
        ours = sorted(r["roots"], key=lambda z: (z.real, z.imag))
        ev = sorted(ev, key=lambda z: (z.real, z.imag))
        np.testing.assert_allclose(ours, ev, rtol=1e-12, atol=1e-12)
        assert r["spectral_abscissa"] == pytest.approx(
            max(z.real for z in ev), rel=1e-12, abs=1e-12
        )


@pytest.mark.parametrize("q", [0.1, 0.5, 1.0, 0.0])
def test_double_root_minus_identity(q):
    """B = -I, kappa = 1, q1 = q2 = q: h1 = h2 = l^2 - q l - 1, p = h1^2.  Double roots
    r+- = (q +- sqrt(q^2 + 4)) / 2; at r+ > 0 both rows vanish (diagonal B: II, any eigenvector),
    but r+ is double, so stable_II is UNSTABLE; SS unstable (r+ > 0).  The old mpmath reference
    raised NoConvergence here."""
    r = exact.point_spectral(-1.0, 0.0, 0.0, -1.0, 1.0, q, q)
    assert _verdicts(r) == (U, Consistency.CONSISTENT, U)
    rp, rm = (q + math.sqrt(q * q + 4)) / 2, (q - math.sqrt(q * q + 4)) / 2
    np.testing.assert_allclose(sorted(z.real for z in r["roots"]), [rm, rm, rp, rp], rtol=1e-14)
    assert all(z.imag == 0 for z in r["roots"])
    out = exact.resolve({k: np.array([v]) for k, v in zip(KEYS, (-1, 0, 0, -1, 1, q, q))})
    assert tuple(int(out[k][0]) for k in NAMES) == (U, 1, U)


def test_diagonal_B_distinct_roots_inconsistent():
    # B = -I, kappa = 4, q = 0.5: h1 = l^2 - 0.5 l - 4, h2 = l^2 - 0.5 l - 1 have different positive
    # roots, each eigenvector lies on an axis (x1 x2 = 0): II inconsistent
    assert _verdicts(exact.point_spectral(-1, 0, 0, -1, 4.0, 0.5, 0.5)) == (U, 0, U)


def test_identity_B_is_stable_with_damping_and_neutral_without():
    # B = I, K > 0: decoupled oscillators, l^2 + q l + k = 0
    assert exact.point_spectral(1, 0, 0, 1, 0.5, 0.1, 0.2)["stable_SS"] == Verdict.STABLE
    assert exact.point_spectral(1, 0, 0, 1, 0.5, 0, 0)["stable_SS"] == Verdict.NEUTRAL
    # one undamped contact (q1 = 0 or q2 = 0): +-i sqrt(k) stays on the axis
    assert exact.point_spectral(1, 0, 0, 1, 0.5, 0, 0.2)["stable_SS"] == Verdict.NEUTRAL
    assert exact.point_spectral(1, 0, 0, 1, 0.5, 0.2, 0)["stable_SS"] == Verdict.NEUTRAL


def test_minus_identity_B():
    # B = -I: l^2 = k_j, real roots +-sqrt(k): x along the axes -> II inconsistent (x1 x2 = 0)
    r = exact.point_spectral(-1, 0, 0, -1, 0.5, 0, 0)
    assert r["stable_SS"] == Verdict.UNSTABLE
    assert r["consistent_II"] == Consistency.INCONSISTENT


@pytest.mark.parametrize("s1, want", [(-1.0, (U, 1, S)), (1.0, (U, 0, U))])
def test_lower_triangular_B(s1, want):
    """c2 = 0: p = h1 h2 with h1 = l^2 - 1 (kappa = 1, q1 = 0), h2 = l^2 + 1 (s2 = 1, q2 = 0).
    Roots 1, -1, +-i.  At l = 1 the row-2 condition s1 h2(1) = 2 s1 < 0 holds iff s1 < 0; then
    l = 1 is the largest root, simple, right of Re(+-i) = 0: stable."""
    assert _verdicts(exact.point_spectral(-1.0, s1, 0.0, 1.0, 1.0, 0.0, 0.0)) == want


def test_upper_triangular_B():
    """s1 = 0: h2 = l^2 - 1 - l (s2 = -1, q2 = 1), root r2 = (1 + sqrt 5)/2; h1 = l^2 + 4 (c1 = 1,
    kappa = 4) > 0.  c2 h1(r2) < 0 iff c2 < 0; r2 is the largest root: stable for c2 < 0."""
    assert _verdicts(exact.point_spectral(1.0, 0.0, -1.0, -1.0, 4.0, 0.0, 1.0)) == (U, 1, S)
    assert _verdicts(exact.point_spectral(1.0, 0.0, 1.0, -1.0, 4.0, 0.0, 1.0)) == (U, 0, U)


def test_singular_B():
    """b1 = -b2 = (1/2, 1/2): det B = 0, p = l^2 (l^2 + a3 l + a2) with a3 = (q1 - q2)/2 = 0 and
    a2 = (kappa - 1)/2 = -1/4 (kappa = 1/2): roots 0, 0, +-1/2.  At l = 1/2,
    h1 = 1/4 + (1/2)(1/2 + 0.2/2) = 0.55 and c2 h1 < 0 (c2 = -1/2): II, simple, dominant."""
    assert _verdicts(exact.point_spectral(0.5, 0.5, -0.5, -0.5, 0.5, 0.2, 0.2)) == (U, 1, S)
    # b2 = b1: c2 s2 < 0 -> II inconsistent at any root of the quadratic (h1 = -s2 d2 there)
    assert _verdicts(exact.point_spectral(0.5, 0.5, 0.5, 0.5, 0.5, 0.2, 0.2))[1:] == (0, U)


def test_exact_dominance_tie_is_unstable():
    """p = (l - 1)(l + 1/4)(l^2 - 2 l + 2) at kappa = 1, q = (2, 0), c1 = -11/8, s2 = 37/8,
    c2 = 1, s1 = -375/64 (a3 = 2 c1, a2 = c1 + s2, a1 = 2 D, a0 = D = -1/2).  l* = 1 is II
    (c2 h1(1) = 1 - 33/8 < 0) and simple, but the pair 1 +- i has real part exactly l*: unstable.
    One ulp away in c1 the tie breaks; the sympy reference decides those."""
    tie = [-1.375, -5.859375, 1.0, 4.625, 1.0, 2.0, 0.0]
    coeffs = exact.characteristic_poly(*tie).coeffs()
    assert [float(c) for c in coeffs] == [-0.5, -1.0, 3.25, -2.75, 1.0]
    assert _verdicts(exact.point_spectral(*tie)) == (U, 1, U)
    near = []
    for d in (-np.inf, np.inf):
        p = list(tie)
        p[0] = float(np.nextafter(p[0], d))
        near.append(p)
    bad, skipped = _compare_with_reference(near)
    assert not bad and not skipped
    assert {_verdicts(exact.point_spectral(*p))[2] for p in near} == {S, U}


def test_ii_closed_form_q0():
    """Q = 0: II consistent iff -BK has a real eigenvalue mu > 0 with eigenvector x1 x2 > 0; SS
    neutral iff both eigenvalues are real and <= 0 (l^2 = mu), never stable."""
    rng = np.random.default_rng(5)
    n_cons = n_neutral = 0
    for _ in range(60):
        b1, b2 = rng.uniform(0, 2 * np.pi, 2)
        kap = 10 ** rng.uniform(-1, 1)
        B = np.array([[np.cos(b1), np.cos(b2)], [np.sin(b1), np.sin(b2)]])
        w, v = np.linalg.eig(-B @ np.diag([kap, 1.0]))
        ok = [
            (abs(w[i].imag) == 0 and w[i].real > 0 and v[0, i].real * v[1, i].real > 0)
            for i in range(2)
        ]
        want = Consistency.CONSISTENT if any(ok) else Consistency.INCONSISTENT
        r = exact.point_spectral(B[0, 0], B[1, 0], B[0, 1], B[1, 1], kap, 0, 0)
        assert r["consistent_II"] == want
        neutral = all(abs(m.imag) == 0 and m.real <= 0 for m in w)
        assert r["stable_SS"] == (Verdict.NEUTRAL if neutral else Verdict.UNSTABLE)
        n_cons += want == Consistency.CONSISTENT
        n_neutral += neutral
    assert n_cons > 5 and n_neutral >= 3


def test_class_25_two_positive_real_roots_only_smaller_is_ii():
    """Appendix C, Q3: in class 25 there are two positive real eigenvalues, the smaller is II."""
    b1, b2 = 0.9 * np.pi, 1.53 * np.pi
    r = exact.point_spectral(np.cos(b1), np.sin(b1), np.cos(b2), np.sin(b2), 0.5, 0, 0)
    pos = sorted(z.real for z in r["roots"] if z.imag == 0 and z.real > 0)
    assert len(pos) == 2
    assert r["consistent_II"] == Consistency.CONSISTENT and r["stable_II"] == Verdict.UNSTABLE


def test_non_finite_input_raises():
    with pytest.raises(ValueError, match="finite"):
        exact.point_spectral(1, 0, 0, 1, float("nan"), 0.1, 0.1)


# --- the independent sympy/mpmath reference ---------------------------------------------------


def test_agrees_with_reference_on_hard_suites_sample():
    """A seeded sample of every hard-case suite (float32 and float64 inputs); the same sample as
    the Hurwitz check below, so the reference runs once per point."""
    pts = _suite_points(per_suite=6)
    bad, skipped = _compare_with_reference(pts)
    assert not bad, f"{len(bad)} disagreements ({skipped} skipped), e.g. {bad[:3]}"
    assert skipped <= 0.05 * len(pts), f"reference raised on {skipped} of {len(pts)} points"


@pytest.mark.slow
def test_agrees_with_reference_on_all_suite_points():
    pts = _suite_points()
    bad, skipped = _compare_with_reference(pts)
    assert not bad, f"{len(bad)} disagreements ({skipped} skipped of {len(pts)}), e.g. {bad[:3]}"


def _random_damped(n, seed):
    """Random directions, kappa and q up to 1e12 apart, q1 != q2, q1 = 0, q2 = 0, q1 = q2."""
    rng = np.random.default_rng(seed)
    pts = []
    for i in range(n):
        b1, b2 = rng.uniform(0, 2 * np.pi, 2)
        kap = 10 ** rng.uniform(-12, 12)
        q1, q2 = 10 ** rng.uniform(-6, 6, 2)
        q1, q2 = ((q1, q2), (0.0, q2), (q1, 0.0), (q1, q1))[i % 4]
        p = (np.cos(b1), np.sin(b1), np.cos(b2), np.sin(b2), kap, q1, q2)
        pts.append(tuple(float(v) for v in p))
    return pts


def test_agrees_with_reference_on_random_damped_points():
    pts = _random_damped(80, seed=3)
    bad, skipped = _compare_with_reference(pts)
    assert not bad and not skipped, (bad[:3], skipped)
    verdicts = [_verdicts(exact.point_spectral(*p)) for p in pts]
    assert {v[2] for v in verdicts} == {S, U} and {v[0] for v in verdicts} >= {S, U}


def test_agrees_with_reference_on_dyadic_grid():
    """Small dyadic inputs hit exact degeneracies (zero entries, det B = 0, multiple roots, roots
    at 0, q1 = 0 or q2 = 0) and non-physical ones (kappa = 0, q < 0, taken by the flint tier)."""
    rng = np.random.default_rng(11)
    grid = np.array([-2, -1.5, -1, -0.5, 0, 0.5, 1, 1.5, 2])
    pts = [
        (*rng.choice(grid, 4), rng.choice([0.0, 0.25, 1, 3]), *rng.choice([-0.5, 0, 0.5, 1, 2], 2))
        for _ in range(150)
    ]
    pts = [tuple(float(v) for v in p) for p in pts]
    bad, skipped = _compare_with_reference(pts)
    assert not bad, f"{len(bad)} disagreements ({skipped} skipped), e.g. {bad[:3]}"
    assert skipped < 0.1 * len(pts)


# --- the two tiers against each other ---------------------------------------------------------


def _tiers_agree(points) -> int:
    """Every point the integer tier decides gets the same verdicts from the flint tier."""
    n = 0
    for p in points:
        s = exact._scaled(*p)
        ss, ii = exact._ss_closed(s.P), exact._ii_closed(s)
        if ss is None or ii is None:
            continue
        assert (ss, *ii) == exact._general(s), p
        n += 1
    return n


def test_integer_tier_agrees_with_flint_tier():
    """The sign logic of tier 1 (curve argument, Sturm, Tarski) against root enclosures and
    algebraic tie tests of tier 2, on every hard-suite point and on random damped points."""
    pts = _suite_points() + _random_damped(200, seed=4)
    assert _tiers_agree(pts) == len(pts)  # tier 1 covers all of them


def test_resolve_never_undecided_and_ss_only_is_consistent():
    for name in hardcases.SUITES:
        for dtype in ("float32", "float64"):
            P = _suite(name, dtype)
            pts = {k: P[k] for k in KEYS}
            full = exact.resolve(pts)
            ss = exact.resolve(pts, names=("stable_SS",))["stable_SS"]
            assert all(full[k].dtype == np.int8 and not (full[k] == 3).any() for k in NAMES)
            np.testing.assert_array_equal(ss, full["stable_SS"])


def _ss_hurwitz_check(per_suite):
    from atlas.core.contact_modes import direction

    pts = _suite_points(per_suite)
    beta = np.linspace(0.0, 2 * np.pi, 65)[1:16]
    c1, s1 = direction(beta, "float64")
    c2, s2 = direction(beta + np.pi, "float64")
    for q in ((0.0, 0.0), (0.1, 0.1), (0.05, 0.2)):
        pts += [(c1[i], s1[i], c2[i], s2[i], 0.5, *q) for i in range(beta.size)]
    for p in pts:
        want = _reference(tuple(p))
        assert want is not None and exact.ss_hurwitz(*p) == want[0], p


def test_ss_hurwitz_agrees_with_root_reference_on_hard_suites():
    """The rational Hurwitz settlement (used for SS-only undecided points) decides every physical
    point and equals the root-based reference: a seeded sample of every hard-case suite and the
    anti-diagonal b2 ~ -b1 where float64 cannot certify sign(det B)."""
    _ss_hurwitz_check(per_suite=6)


@pytest.mark.slow
def test_ss_hurwitz_agrees_with_root_reference_on_all_suite_points():
    _ss_hurwitz_check(per_suite=None)


# --- class codes --------------------------------------------------------------------------------


@pytest.mark.parametrize("codes", [(0.3, 0.3), (0.3, 0.3 + np.pi)])
def test_exact_codes_ties(codes):
    b1, b2 = codes
    c2, s2 = (-np.cos(b1), -np.sin(b1)) if b2 > np.pi else (np.cos(b1), np.sin(b1))
    assert exact.point_codes(np.cos(b1), np.sin(b1), c2, s2)["class_code"] == 0


def test_codes_match_50_digit_angles():
    """Exact angle ranks (half-plane, then cross-product sign) against 50-digit atan2 ranks."""

    def angle(c, s):
        with mpmath.workdps(50):
            return mpmath.atan2(mpmath.mpf(float(s)), mpmath.mpf(float(c))) % (2 * mpmath.pi)

    def rank(t, others):
        return 1 + sum(1 for o in others if angle(*o) < angle(*t))

    axes = [(0.0, 1.0), (-1.0, 0.0), (0.0, -1.0)]
    rng = np.random.default_rng(2)
    for _ in range(200):
        b1, b2, al = rng.uniform(0, 2 * np.pi, 3)
        u, v, a = [(float(np.cos(t)), float(np.sin(t))) for t in (b1, b2, al)]
        i = rank(u, axes)
        j = rank(v, [u, (-u[0], -u[1])] + axes)
        k = rank(a, [u, v] + axes)
        got = exact.point_codes(*u, *v, *a)
        assert got["class_code"] == 10 * i + j
        assert got["subclass_code"] == 100 * i + 10 * j + k
