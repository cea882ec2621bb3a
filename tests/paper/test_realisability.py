"""atlas.paper.realisability: every subclass by one rigid body under its weight, verified exactly."""

from __future__ import annotations

from fractions import Fraction

import pytest
import sympy

from atlas.paper import realisability as R


@pytest.fixture(scope="module")
def found():
    return R.search()


def _sympy_subclass(p) -> int:
    """Independent reference: B = J M^-1 (J - diag(mu s) T)^T and a = -J M^-1 [m g; 0] in sympy
    rationals (the matrix route), angles atan2 to 50 digits, ranks by the SPEC §1 definition."""
    q = lambda x: sympy.Rational(x.numerator, x.denominator)  # noqa: E731
    rows_n, rows_t = [], []
    for j in (1, 2):
        (rx, ry), (nx, ny) = [tuple(q(v) for v in p[f"{k}{j}"]) for k in ("r", "n")]
        tx, ty = ny, -nx
        rows_n.append([nx, ny, rx * ny - ry * nx])
        rows_t.append([tx, ty, rx * ty - ry * tx])
    Jn, Jt = sympy.Matrix(rows_n), sympy.Matrix(rows_t)
    Minv = sympy.diag(1 / q(p["m"]), 1 / q(p["m"]), 1 / q(p["I"]))
    D = sympy.diag(q(p["mu1"]) * p["s1"], q(p["mu2"]) * p["s2"])
    B = Jn * Minv * (Jn - D * Jt).T
    g = sympy.Matrix([q(p["m"]) * q(p["g"][0]), q(p["m"]) * q(p["g"][1]), 0])
    a = -(Jn * Minv * g)
    pi = sympy.pi.evalf(50)

    def angle(x, y):
        t = sympy.atan2(y, x).evalf(50)
        return t + 2 * pi if t < 0 else t

    b1, b2, al = angle(B[0, 0], B[1, 0]), angle(B[0, 1], B[1, 1]), angle(a[0], a[1])
    axes = [pi / 2, pi, 3 * pi / 2]
    b1s = b1 + pi if b1 < pi else b1 - pi
    rank = lambda x, others: 1 + sum(1 for o in others if o < x)  # noqa: E731
    return 100 * rank(b1, axes) + 10 * rank(b2, [b1, b1s, *axes]) + rank(al, [b1, b2, *axes])


def _sympy_sliding(p):
    """``(sign u1, sign u2)`` of the contacts' sliding speeds along the rational null space of
    ``J`` (sympy), or ``None`` where it is 2-D; the sign of the null vector is arbitrary."""
    q = lambda x: sympy.Rational(x.numerator, x.denominator)  # noqa: E731
    J, T = [], []
    for j in (1, 2):
        (rx, ry), (nx, ny) = [tuple(q(v) for v in p[f"{k}{j}"]) for k in ("r", "n")]
        J.append([nx, ny, rx * ny - ry * nx])
        T.append([ny, -nx, -rx * nx - ry * ny])
    null = sympy.Matrix(J).nullspace()
    if len(null) != 1:
        return None
    return tuple(int(sympy.sign((sympy.Matrix([t]) * null[0])[0])) for t in T)


def test_every_subclass_is_realised_by_one_rigid_body_and_verified_exactly(found):
    """Every example's (s1, s2) is a sliding a rigid body can perform: the exact twist null space
    (sympy) ties the two speeds with the stored signs, and both contacts slide."""
    result, stats = found
    assert tuple(result) == R.ALL_SUBCLASSES and len(result) == 144
    assert stats["verified"] == stats["rigid"] == 144 and stats["wheel"] == 0
    for code, r in result.items():
        assert r.verified and r.impossible is None and r.system == R.RIGID
        u1, u2 = _sympy_sliding(r.params)
        assert u1 != 0 and u2 != 0 and r.params["s2"] == r.params["s1"] * u1 * u2
        assert R.admissible(r.params)
        assert R.exact_codes(r.params)["subclass_code"] == code
        assert 0 <= r.params["mu1"] <= 2 and 0 <= r.params["mu2"] <= 2
        assert r.margin > 0.1  # far from every boundary of the subclass


def test_examples_against_an_independent_sympy_classifier(found):
    result, _ = found
    for code, r in result.items():
        assert _sympy_subclass(r.params) == code


def test_float_mechanisms_agree(found):
    """The float Mechanism of each example reports the same subclass and Table 1 modes."""
    result, _ = found
    for code in R.ALL_SUBCLASSES[::7]:
        params = result[code].params
        v, ref = R.mechanism(params).verdicts(), R.exact_codes(params)
        assert v["subclass_code"] == code
        for k in ("consistent_FF", "consistent_SF", "consistent_FS", "consistent_SS"):
            assert bool(v[k]) == bool(ref[k])


def test_frictionless_bodies_only_reach_classes_12_and_42():
    """Without friction B is symmetric positive definite: exactly the 12 subclasses of classes 12
    and 42 exist (module docstring); the search finds all of them and none other."""
    res = R.search(1 << 17, mu_max=0).found
    got = {c for c, r in res.items() if r.verified}
    assert got == {c for c in R.ALL_SUBCLASSES if c // 10 in R.FRICTIONLESS_CLASSES}
    assert all(r.impossible for c, r in res.items() if c not in got)


def test_deterministic_and_markdown(found):
    result, stats = found
    one, two = R.search(1 << 14, seed=3).found, R.search(1 << 14, seed=3).found
    assert {c: r.params for c, r in one.items()} == {c: r.params for c, r in two.items()}
    assert any(not r.found for r in one.values())  # a small search misses some subclasses...
    assert all(r.note.startswith("none found") for r in one.values() if not r.found)
    wheel = [r for r in one.values() if r.system == R.WHEEL]
    assert wheel and all(r.verified for r in wheel)  # ...and the driven wheel realises some
    for r in wheel:
        assert R.exact_codes(r.params)["subclass_code"] == r.subclass
        assert _sympy_sliding(r.params)[0] != 0  # contact 1 slides along the body's twist
        assert not R.admissible(r.params)  # a pair only the wheel's motor gives
    text = R.markdown(result, stats)
    assert "144 / 144 subclasses realised by one rigid body" in text
    assert len([ln for ln in text.splitlines() if ln[:2] == "| " and ln[2:5].isdigit()]) == 144


def test_exact_codes_rejects_inexact_normals(found):
    p = dict(found[0][121].params)
    p["n1"] = (Fraction(1, 2), Fraction(1, 2))
    with pytest.raises(ValueError, match=r"^n1: "):
        R.exact_codes(p)


@pytest.mark.parametrize(
    "kw, name", [(dict(samples=0), "samples"), (dict(mu_max="0.15"), "mu_max")]
)
def test_bad_input(kw, name):
    with pytest.raises(ValueError, match=rf"^{name}: "):
        R.search(**kw)


def test_admissible_pairs(found):
    """A rigid body's pair flipped at contact 2 is refused for the rigid body and accepted with
    the driven wheel; the float Mechanism refuses it too."""
    p = dict(found[0][214].params)
    flipped = {**p, "s2": -p["s2"]}
    assert R.admissible(p) and not R.admissible(flipped)
    assert R.admissible(flipped, R.WHEEL)
    with pytest.raises(ValueError, match=r"^s2: inadmissible pair"):
        R.mechanism(flipped)
    assert R.mechanism({**p, "s2": None}).s2 == p["s2"]
