"""Root frames (:mod:`atlas.data.root_frames`) against closed forms: line polynomials with known
roots (``t = tan(beta / 2)``: a pair ``1e-15`` apart, a pair within one float step, one ``1e-14``
off the multiple ``pi/2`` of ``t = 1``, a crossing at ``t = 0``) stand in for the germs, and every angle, distance and
sample is checked against mpmath at 100 digits."""

import math
from fractions import Fraction

import flint
import mpmath
import pytest

from atlas.data import boundary_germs, root_frames

A = Fraction(1, 3)  # a root t = 1/3 ...
PAIR = A + Fraction(1, 10**15)  # ... and its neighbour 1e-15 above it
NEAR_AXIS = 1 + Fraction(1, 10**14)  # a root just above t = 1 (beta = pi/2)
TWIN = Fraction(1, 7)  # a root t = 1/7 ...
TWIN_UP = TWIN + Fraction(1, 10**18)  # ... and one 1.9e-18 rad above: the same float angle
ROOTS = (0, TWIN, TWIN_UP, A, PAIR, 1, NEAR_AXIS, -2)
MODEL = (1.25, 0.5, 0.75)  # only a cache key here: the polynomials are the ones above


def _beta(t) -> mpmath.mpf:
    """``2 atan(t)`` [rad] at 100 digits, in ``[0, 2 pi)``."""
    b = 2 * mpmath.atan(mpmath.mpf(t.numerator) / t.denominator if isinstance(t, Fraction) else t)
    return b % (2 * mpmath.pi)


@pytest.fixture(autouse=True)
def _digits():
    with mpmath.workdps(100):
        yield


@pytest.fixture
def line(monkeypatch):
    """Line 0 of field II whose only germ has ``g_0 = prod (t - r)`` over :data:`ROOTS`."""
    g0 = flint.fmpq_poly([1])
    for r in ROOTS:
        g0 *= flint.fmpq_poly([-flint.fmpq(r.numerator, r.denominator) if r else 0, 1])
    rows = (g0, flint.fmpq_poly([1]))
    monkeypatch.setattr(boundary_germs, "germs", lambda fld, m, model: (rows,))
    root_frames._breaks.cache_clear()
    yield
    root_frames._breaks.cache_clear()


def _ball(t, rad=1e-30) -> flint.arb:
    """A 256-bit ball [rad] of radius ``rad`` around ``2 atan(t)`` (the enclosure a caller
    holds)."""
    with flint.ctx.workprec(256):
        return flint.arb(mpmath.nstr(_beta(t), 55)) + flint.arb(0, rad)


def _others():
    return [float(_beta(r)) for r in ROOTS]


def _quarter_gap(t) -> mpmath.mpf:
    """A quarter of the distance [rad] along the line from ``2 atan(t)`` to the nearest other
    root of :data:`ROOTS` or multiple of ``pi/2`` (100 digits)."""
    b = _beta(t)
    cand = [_beta(r) for r in ROOTS if r != t] + [k * mpmath.pi / 2 for k in range(5)]
    gaps = [abs(c - b) for c in cand]
    gaps = [min(g, 2 * mpmath.pi - g) for g in gaps if g > mpmath.mpf(10) ** -50]
    return min(gaps) / 4


@pytest.mark.parametrize("t", [A, PAIR, NEAR_AXIS, TWIN, TWIN_UP])
def test_crowded_roots_get_the_exact_frame(line, t):
    """A root with another break closer than SEPARATION: the ball holds the exact root, ``h`` is
    at most (and nearly) a quarter of the true distance to its neighbour, and the samples at
    ``+-h`` lie strictly between the root and its neighbours, however close; also for the twins
    whose angles round to one float (the caller's list holds that float twice)."""
    assert float(_beta(TWIN)) == float(_beta(TWIN_UP))
    with flint.ctx.workprec(256):
        fr = root_frames.frame("II", MODEL, 0, _ball(t), _others())
        assert fr is not None and fr.exact and not fr.crossing
        lo, hi = (mpmath.mpf(v.str(90, radius=False)) for v in (fr.beta.lower(), fr.beta.upper()))
    quarter = _quarter_gap(t)
    assert quarter < root_frames.SEPARATION
    assert lo <= _beta(t) <= hi and hi - lo < mpmath.mpf(10) ** -40
    assert 0.999 * quarter <= fr.h <= quarter
    for s in (-1, 1):
        got = root_frames.sample(fr, s * fr.h)
        beta_s = _beta(got)
        off = beta_s - _beta(t)
        assert s * off > 0 and abs(off) < 2 * quarter  # strictly beside, short of the neighbour
        assert abs(off - s * fr.h) <= mpmath.mpf(2) ** -240


def test_a_root_listed_twice_keeps_the_float_frame(line):
    """The root ``t = -2``, its float twice among the caller's angles (found by two polynomials)
    and every other break far: one exact root near it, so the float frame, ``h`` a quarter of
    the distance to ``3 pi/2``."""
    ball = _ball(Fraction(-2), 1e-15)
    beta = float(_beta(Fraction(-2)))
    fr = root_frames.frame("II", MODEL, 0, ball, [*_others(), beta])
    assert fr is not None and not fr.exact and fr.beta is ball
    assert fr.h == pytest.approx(float(_quarter_gap(Fraction(-2))), rel=1e-12)


def test_a_multiple_of_a_quarter_turn_is_a_crossing(line):
    """The root ``t = 1`` (``beta = pi/2``), ``1e-14`` from another root: exact frame, marked
    as a crossing of class lines."""
    with flint.ctx.workprec(256):
        fr = root_frames.frame("II", MODEL, 0, _ball(Fraction(1)), _others())
        assert fr is not None and fr.exact and fr.crossing
        assert fr.beta.contains(flint.arb.pi() / 2) and fr.beta.rad() < 1e-60


def test_an_enclosure_holding_two_roots_is_refused(line):
    """A ball around the pair ``1e-15`` apart holds two exact roots: no frame."""
    with flint.ctx.workprec(256):
        assert root_frames.frame("II", MODEL, 0, _ball(A, 1e-14), _others()) is None


@pytest.mark.parametrize(
    "beta, others, want",
    [
        (1.0, [1.0, 1.3], 0.3 / 4),  # the neighbour, nearer than pi/2
        (1.5, [1.5, 0.2], (math.pi / 2 - 1.5) / 4),  # pi/2 nearer than the neighbour
        (6.2, [6.2, 0.05], (2 * math.pi - 6.2) / 4),  # 2 pi, nearer than 0.05 around the torus
    ],
)
def test_separated_roots_get_the_float_frame(beta, others, want):
    """Every other break farther than SEPARATION: ``beta`` the caller's ball, ``h`` a quarter of
    the distance to the nearest other root or multiple of ``pi/2`` around the torus, samples
    the floats nearest ``tan((beta +- h) / 2)``."""
    ball = flint.arb(beta, 1e-15)
    fr = root_frames.frame("II", MODEL, 0, ball, others)
    assert not fr.exact and not fr.crossing and fr.beta is ball
    assert fr.h == pytest.approx(want, rel=1e-12, abs=1e-15)
    for s in (-1, 1):
        got = _beta(root_frames.sample(fr, s * fr.h))
        assert abs(got - (mpmath.mpf(beta) + s * mpmath.mpf(fr.h))) <= 4e-15
