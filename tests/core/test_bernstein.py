"""Bernstein certificates against closed forms worked by hand."""

from fractions import Fraction as F

import numpy as np
import pytest

from atlas.core import bernstein as bz


def _x(n=1, i=0):
    return bz.Poly.var(i, n)


@pytest.mark.parametrize(
    "make, axis, expected",
    [
        (lambda x: x, bz.Axis(0, 1), [0, 1]),  # x = t
        (lambda x: x * x, bz.Axis(0, 1), [0, 0, 1]),  # t^2: b = (0, 0, 1)
        (lambda x: 2 * x + 1, bz.Axis(1, 3), [3, 7]),  # values at the ends
        (lambda x: x, bz.Axis(0, None), [0, 1]),  # x (1 - t) = t
        (lambda x: x + (-1), bz.Axis(0, None), [-1, 1]),  # (t - (1 - t)) = 2t - 1
    ],
)
def test_coefficients(make, axis, expected):
    b = bz.to_bernstein(make(_x()), [axis])
    ratio = F(int(b[-1]), expected[-1])  # the positive factor
    assert ratio > 0
    assert [F(int(v)) for v in b] == [ratio * e for e in expected]


def test_split_halves_are_the_halves():
    # p = (2x - 1)^2 on [0, 1]: on [0, 1/2] its values at the ends are 1, 0; on [1/2, 1]: 0, 1
    x = _x()
    b = bz.to_bernstein((2 * x + (-1)) ** 2, [bz.Axis(0, 1)])
    left, right = bz._split(b, 0)
    assert left[0] > 0 and left[-1] == 0 and right[0] == 0 and right[-1] > 0


def _de_casteljau(b, axis):
    """The textbook recurrence (pairwise sums, ``d`` rounds) on the rows of ``b`` along
    ``axis``: the halves scaled by ``2^d``."""
    rows = list(np.moveaxis(b, axis, 0))
    d, cur, left, right = len(rows) - 1, rows, [rows[0]], [rows[-1]]
    for _ in range(d):
        cur = [x + y for x, y in zip(cur, cur[1:])]
        left.append(cur[0])
        right.append(cur[-1])
    halves = (
        [left[r] * 2 ** (d - r) for r in range(d + 1)],
        [right[d - i] * 2**i for i in range(d + 1)],
    )
    return tuple(np.moveaxis(np.stack(h), 0, axis) for h in halves)


def test_split_equals_de_casteljau_and_the_half_boxes():
    """A random polynomial of degrees (5, 1, 3, 0) with integer coefficients up to 2^200 on a box
    with an unbounded axis: along each axis, :func:`bz._split`'s halves are the integers
    (Python ints, no other type) of the textbook recurrence, and each half is the Bernstein
    array of the polynomial on the half box (to_bernstein there) times a positive factor (the
    bounded axes)."""
    rng = np.random.default_rng(8)
    n, degs = 4, (5, 1, 3, 0)
    terms = {}
    for e in np.ndindex(*(d + 1 for d in degs)):
        terms[e] = int(rng.integers(-(2**62), 2**62)) * 2 ** int(rng.integers(0, 138))
    p = bz.Poly(terms, n)
    axes = [bz.Axis(0, 1), bz.Axis(F(1, 3), 2), bz.Axis(1, None), bz.Axis(F(-2), F(5, 7))]
    b = bz.to_bernstein(p, axes)
    for ax in range(n):
        halves = bz._split(b, ax)
        for got, want in zip(halves, _de_casteljau(b, ax)):
            assert got.shape == want.shape == b.shape
            assert all(type(g) is int and g == w for g, w in zip(got.flat, want.flat))
        lo, hi = axes[ax].lo, axes[ax].hi
        if degs[ax] == 0 or hi is None:  # t = 1/2 halves an unbounded axis by another map
            continue
        mid = (lo + hi) / 2
        for got, part in zip(halves, ((lo, mid), (mid, hi))):
            sub = list(axes)
            sub[ax] = bz.Axis(*part)
            want = bz.to_bernstein(p, sub)
            k = int(np.argmax([abs(v) for v in want.flat]))
            ratio = F(got.flat[k], want.flat[k])
            assert ratio > 0
            assert all(F(g) == ratio * w for g, w in zip(got.flat, want.flat))


def test_positive_quadratic_on_an_unbounded_axis():
    x = _x()
    p = (x + (-2)) ** 2 + F(1, 100)  # min 1/100 at x = 2
    assert bz.prove_any([(p, ">0")], [bz.Axis(0, None, True)]) == ("proved", None)


def test_negative_dip_gives_an_exact_counterexample():
    x = _x()
    p = (x + (-2)) ** 2 + F(-1, 100)  # < 0 on (1.9, 2.1)
    res, t = bz.prove_any([(p, ">0")], [bz.Axis(0, None, True)])
    assert res == "counterexample"
    (v,) = bz.point_of([bz.Axis(0, None, True)], t)
    assert F(19, 10) < v < F(21, 10)


def test_disjunction():
    x = _x()
    p = (x + (-2)) ** 2 + F(-1, 100)
    # p >= 0 or x < 1: true on [0, 1] (p(1) = 0.99), false at x = 2
    assert bz.prove_any([(p, ">=0"), (x + (-1), "<0")], [bz.Axis(0, 1)])[0] == "proved"
    assert bz.prove_any([(p, ">=0"), (x + (-1), "<0")], [bz.Axis(0, 3)])[0] == "counterexample"


def test_strict_sign_with_faces_left_out():
    x, y = _x(2, 0), _x(2, 1)
    box = [bz.Axis(0, 1), bz.Axis(0, 1)]
    # x y > 0 on (0, 1]^2, not on [0, 1] x (0, 1] (zero on x = 0)
    assert bz.prove_any([(x * y, ">0")], box, ({0: 0}, {1: 0}))[0] == "proved"
    res, t = bz.prove_any([(x * y, ">0")], box, ({1: 0},))
    assert res == "counterexample" and t[0] == 0


def test_corner_left_out_only():
    # x + y > 0 on [0, 1]^2 minus the origin (a pattern of two axes)
    x, y = _x(2, 0), _x(2, 1)
    box = [bz.Axis(0, 1), bz.Axis(0, 1)]
    assert bz.prove_any([(x + y, ">0")], box, ({0: 0, 1: 0},))[0] == "proved"
    assert bz.prove_any([(x + y, ">0")], box)[0] == "counterexample"


def test_budget_gives_unknown():
    x = _x()
    p = (x + (-1)) ** 2  # a double root inside: >= 0 but never strictly positive
    assert bz.prove_any([(p, ">0")], [bz.Axis(F(1, 3), 3)], budget=8)[0] in (
        "unknown",
        "counterexample",
    )
    assert bz.prove_any([(p, ">=0")], [bz.Axis(F(1, 3), 3)])[0] == "proved"


def test_random_polynomials_never_wrongly_proved():
    rng = np.random.default_rng(0)
    x, y = _x(2, 0), _x(2, 1)
    box = [bz.Axis(0, 2), bz.Axis(F(1, 2), None)]
    grid = [(F(i, 8), F(j, 4)) for i in range(17) for j in range(2, 40)]
    for _ in range(30):
        c = [F(int(v), 4) for v in rng.integers(-8, 9, size=6)]
        p = c[0] + c[1] * x + c[2] * y + c[3] * x * y + c[4] * x * x + c[5] * y * y + 3
        res, t = bz.prove_any([(p, ">0")], box, budget=512)
        vals = [sum(cf * a ** e[0] * b ** e[1] for e, cf in p.terms.items()) for a, b in grid]
        if res == "proved":
            assert min(vals) > 0
        elif res == "counterexample":
            a, b = bz.point_of(box, t)
            assert sum(cf * a ** e[0] * b ** e[1] for e, cf in p.terms.items()) <= 0


def test_constant_failing_where_every_vertex_is_left_out():
    # a negative constant on (0, inf): no vertex is in the box and nothing can be split; it is a
    # counterexample everywhere, never a proof
    box = [bz.Axis(0, None, True)]
    res, t = bz.prove_any([(bz.Poly.const(-1, 1), ">=0")], box)
    assert res == "counterexample" and 0 < t[0] < 1
    assert bz.prove_any([(bz.Poly.const(2, 1), ">0")], box)[0] == "proved"
    two = [bz.Axis(0, None, True), bz.Axis(0, None)]
    res, _ = bz.prove_any([(bz.Poly.const(0, 2), ">0")], two, ({1: 0},))
    assert res == "counterexample"
