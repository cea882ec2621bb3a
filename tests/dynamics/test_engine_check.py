"""The randomized comparison of both engines (atlas.dynamics.engine_check): seeded lanes over the
whole parameter space, 0 disagreements between the fast engine and the exact simulator."""

import numpy as np
import pytest

from atlas.dynamics import engine_check as C


def test_random_lanes_are_seeded_and_cover_the_degenerate_directions():
    a, b = C.random_lanes(3, 200), C.random_lanes(3, 200)
    assert np.array_equal(a.g0, b.g0) and np.array_equal(a.beta1, b.beta1)
    on_axis = np.isclose(np.mod(a.beta2, np.pi / 4), 0.0)
    assert 20 <= on_axis.sum() <= 90
    assert (a.q == 0).any() and a.kappa.min() >= 1e-2 and a.kappa.max() <= 10.0


@pytest.mark.parametrize("n", [0, -3])
def test_bad_size_one_line(n):
    with pytest.raises(ValueError, match="n must be >= 1"):
        C.random_lanes(0, n)


def test_both_engines_agree_on_random_lanes():
    r = C.compare(C.random_lanes(11, 40))
    assert r["disagree"].size == 0, r["disagree"]


@pytest.mark.slow
def test_both_engines_agree_on_a_thousand_random_lanes():
    r = C.compare(C.random_lanes(2026, 1000))
    assert r["disagree"].size == 0, r["disagree"]
