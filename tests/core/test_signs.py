"""Certified signs (:mod:`atlas.core.signs`) against exact rational evaluation of the float inputs."""

from fractions import Fraction

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from atlas.core import signs
from atlas.core.signs import UNKNOWN, evaluate_certified


def _expr(a, b, c, d, *, sub):
    """A Sturm-like expression with cancellation: ``(a b - c d)^2 - (a d - b c)^2 + a``."""
    return sub(sub(a * b, c * d) ** 2 + a, sub(a * d, b * c) ** 2)


def _exact_sign(*x):
    f = [Fraction(float(v)) for v in x]
    v = _expr(*f, sub=lambda p, q: p - q)
    return (v > 0) - (v < 0)


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_certified_sign_is_the_exact_sign(dtype):
    """Every certified code is the exact sign of the expression at the (rational) float inputs,
    near cancellation too (``a = 0``: the two squares nearly cancel when ``b ~ c``)."""
    rng = np.random.default_rng(3)
    x = rng.uniform(-1, 1, (4, 400)).astype(dtype)
    x[0, :200] = 0
    x[2, :200] = x[1, :200] * (1 + rng.uniform(-1e-6, 1e-6, 200)).astype(dtype)
    x[3, :100] = x[1, :100]
    _, _, code = evaluate_certified(_expr, *(jnp.asarray(v) for v in x))
    code = np.asarray(code)
    known = code != UNKNOWN
    assert known.mean() > 0.5
    for i in np.flatnonzero(known):
        assert code[i] == _exact_sign(*x[:, i]), i


def test_without_zeros_an_exact_zero_is_unknown():
    """``zeros=False``: a structural zero (every monomial has a zero input) is ``UNKNOWN`` instead
    of ``0``; every other code is unchanged, and the structural-zero evaluation is skipped."""
    x = [jnp.asarray([0.0, 0.5, 0.0]), jnp.asarray([0.0, 0.25, 0.3])]
    x += [jnp.asarray([0.0, 0.75, 0.1]), jnp.asarray([0.0, -0.5, 0.2])]
    with_zeros = np.asarray(evaluate_certified(_expr, *x)[2])
    without = np.asarray(evaluate_certified(_expr, *x, zeros=False)[2])
    assert with_zeros[0] == 0 and without[0] == UNKNOWN
    assert np.array_equal(with_zeros[1:], without[1:])
    calls = []

    def counted(*a, sub):
        calls.append(sub)
        return _expr(*a, sub=sub)

    evaluate_certified(counted, *x, zeros=False)
    assert [s for s in calls if s is jnp.add] == [jnp.add]  # the bound (absolute values)
    calls.clear()
    evaluate_certified(counted, *x)
    assert [s for s in calls if s is jnp.add] == [jnp.add] * 2  # + the structural zeros


def _exact_det2(ux, uy, vx, vy):
    v = Fraction(float(ux)) * Fraction(float(vy)) - Fraction(float(uy)) * Fraction(float(vx))
    return (v > 0) - (v < 0)


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_det2_sign_is_exact(dtype):
    """``sign(det B)`` equals the rational sign on directions with ``b2 ~ -b1`` and ``b2 ~ b1``
    (the grid lines where the float difference cancels), exact ties, axis directions, and on
    near-ties with exponents far apart (float64: integer mantissa products)."""
    rng = np.random.default_rng(5)
    beta = np.linspace(0, 2 * np.pi, 513)
    u = np.stack([np.cos(beta), np.sin(beta)]).astype(dtype)
    v = np.stack([np.cos(beta + np.pi), np.sin(beta + np.pi)]).astype(dtype)
    w = np.stack([-u[0], -u[1]])  # exactly opposite: det = 0
    m = 4000
    a, b, c = (rng.uniform(-1, 1, m) * 2.0 ** -rng.integers(0, 40, m) for _ in range(3))
    d = np.clip(b * c / a * (1 + rng.choice([0.0, 1e-16, -1e-16, 1e-7], m)), -1, 1)
    cases = [(u, v), (u, w), (u, u[::-1]), (u, np.roll(u, 1, axis=1))]
    cases.append((np.stack([a, b]).astype(dtype), np.stack([c, d]).astype(dtype)))
    for p, q in cases:
        got = np.asarray(
            jax.jit(signs.det2_sign)(*(jnp.asarray(x) for x in (p[0], p[1], q[0], q[1])))
        )
        ref = [_exact_det2(*x) for x in zip(p[0], p[1], q[0], q[1])]
        assert np.array_equal(got, ref)


def test_det2_sign_float64_unknown_only_off_the_normal_numbers():
    """Subnormal, infinite and NaN components give ``UNKNOWN`` (a flush of subnormals to zero
    must not turn a tiny nonzero product into a zero); zeros are exact."""
    x = jnp.asarray([5e-324, 1e-310, np.inf, np.nan, 0.0, 0.5])
    half = jnp.full(6, 0.5)
    got = np.asarray(signs.det2_sign(x, half, half, half))
    assert got.tolist() == [UNKNOWN] * 4 + [-1, 0]


def test_det2_accurate_within_gamma_3():
    """``det2_accurate`` is within ``gamma_3`` (relative) of the rational ``ux vy - uy vx`` on
    cancelling directions (``b2 ~ -b1``, ``b2 ~ b1``, exact ties) and on near-ties with exponents
    far apart; NaN for subnormal, infinite or NaN components."""
    rng = np.random.default_rng(8)
    beta = np.linspace(0, 2 * np.pi, 1025)
    c, s = np.cos(beta), np.sin(beta)
    m = 3000
    a, b, cc = (rng.uniform(-1, 1, m) * 2.0 ** -rng.integers(0, 40, m) for _ in range(3))
    d = np.clip(b * cc / a * (1 + rng.choice([0.0, 1e-16, -1e-16, 1e-7, 3.0], m)), -1, 1)
    det2 = jax.jit(signs.det2_accurate)  # as in the kernels: one program per shape
    g3 = signs.gamma(signs.DET2_ROUNDINGS, np.float64)
    cases = [(c, s, np.cos(beta + np.pi), np.sin(beta + np.pi)), (c, s, -c, -s), (a, b, cc, d)]
    cases.append((c, s, np.roll(c, 1), np.roll(s, 1)))
    for ux, uy, vx, vy in cases:
        got = np.asarray(det2(*(jnp.asarray(x) for x in (ux, uy, vx, vy))))
        for i, v in enumerate(got):
            exact = Fraction(float(ux[i])) * Fraction(float(vy[i]))
            exact -= Fraction(float(uy[i])) * Fraction(float(vx[i]))
            assert abs(Fraction(float(v)) - exact) <= g3 * abs(exact), i
    x = jnp.asarray([5e-324, np.inf, np.nan, 0.5])
    half = jnp.full(4, 0.5)
    assert np.isnan(np.asarray(det2(x, half, half, half))[:3]).all()
    # both products underflow to zero, the exact difference is not zero: not claimed
    t = jnp.asarray([1e-200])
    assert np.isnan(np.asarray(det2(t, t, t, 3 * t))).all()


def test_rounded_inputs_add_to_the_rounding_count():
    """An input carrying ``k`` roundings counts ``k`` in every product it enters."""
    square = lambda x, y, *, sub: sub(x * x, y)  # noqa: E731
    assert signs.error_model(square, 2, "float64", (1.0, 1.0))[0] == 2
    assert signs.error_model(square, 2, "float64", (1.0, 1.0), (3, 0))[0] == 3 + 3 + 1 + 1


def _product(x, y, *, sub):
    return x * y


@pytest.mark.parametrize("jitted", [True, False], ids=["jit", "op-by-op"])
def test_subnormal_input_is_not_a_structural_zero(jitted):
    """XLA on CPU reads a subnormal as zero (``x != 0`` is False there, jitted or not); the sign
    of ``x y`` at ``x = 1e-310``, ``y = 1`` is +1 exactly, never a certified 0."""
    x, y = jnp.asarray(1e-310), jnp.asarray(1.0)
    assert Fraction(float(x)) * Fraction(float(y)) > 0

    def sign(x, y):
        return evaluate_certified(_product, x, y)[2]

    if jitted:
        got = int(jax.jit(sign)(x, y))
    else:
        with jax.disable_jit():
            got = int(sign(x, y))
    assert got in (1, UNKNOWN)
    assert bool(jax.jit(signs.nonzero)(x)) and bool(jax.jit(signs.subnormal)(x))
    assert int(jax.jit(signs.sign_of)(-x)) == -1


def _disc_exact(k1, c1, k2, s2, s1, c2):
    return (k1 * c1 - k2 * s2) ** 2 + 4 * k1 * k2 * s1 * c2


@pytest.mark.parametrize("jitted", [True, False], ids=["jit", "op-by-op"])
def test_bound_holds_with_and_without_fused_multiply_add(jitted):
    """XLA's CPU compiler contracts ``a b + c`` into one fused multiply-add under jit (the last
    bit then differs from op-by-op evaluation), never in op-by-op runs.  An FMA removes a
    rounding, so the ``gamma_n`` bound covers both: on 3000 inputs within a few ulps of the zero
    set of the undamped discriminant ``(k1 c1 - k2 s2)^2 + 4 k1 k2 s1 c2`` (6 roundings, counted by
    hand) the error against exact rationals stays below the bound, every certified sign is
    exact, and the jitted values differ from op-by-op ones at some inputs (FMA at work)."""
    from atlas.core import expressions as ex

    rng = np.random.default_rng(11)
    k1, k2 = rng.uniform(0.1, 1, (2, 3000))
    c1, s2, s1 = rng.uniform(-1, 1, (3, 3000))
    c2 = -((k1 * c1 - k2 * s2) ** 2) / (4 * k1 * k2 * s1)
    c2 = c2 * (1 + rng.integers(-4, 5, 3000) * 2.0**-52)
    x = [jnp.asarray(v) for v in (k1, c1, k2, s2, s1, c2)]
    n, floor = signs.error_model(ex.disc_undamped, 6, "float64")
    assert n == 6

    def run(*a):
        return evaluate_certified(ex.disc_undamped, *a)

    if jitted:
        value, abs_value, sign = (np.asarray(v) for v in jax.jit(run)(*x))
    else:
        with jax.disable_jit():
            value, abs_value, sign = (np.asarray(v) for v in run(*x))
    u, tiny = 2.0**-53, float(np.finfo(np.float64).tiny)
    g = n * u / (1 - n * u)
    ratio, wrong = 0.0, 0
    for i in range(3000):
        exact = _disc_exact(*(Fraction(float(v[i])) for v in (k1, c1, k2, s2, s1, c2)))
        bound = g / (1 - g) * (abs_value[i] + floor * tiny) + floor * tiny
        ratio = max(ratio, float(abs(Fraction(float(value[i])) - exact)) / bound)
        if sign[i] != UNKNOWN:
            wrong += sign[i] != (exact > 0) - (exact < 0)
    assert ratio < 1 and wrong == 0, (ratio, wrong)
    with jax.disable_jit():
        plain = np.asarray(run(*x)[0])
    assert (plain != value).any() == jitted
