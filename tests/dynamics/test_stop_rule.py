"""The stop rule shared by both engines (atlas.dynamics.stop_rule): the limits, the located first
time on closed forms."""

import math

import numpy as np

from atlas.dynamics import stop_rule as SR


def _free(n):
    """Inputs of ``stopped`` for ``n`` states in FF (no active contact: no alignment test)."""
    return np.zeros(n, dtype=int), np.zeros((n, 5, 5)), np.full((n, 5), np.nan)


def test_limits_of_the_rule():
    """Gap above 1e4 scale, any gap below -1e6 scale, or a NaN stops a run; inside, nothing."""
    mask, E, zq = _free(5)
    g = np.array([[1e4 - 1, 0, 0, 0], [1e4 + 1, 0, 0, 0], [0, -1e6 + 1, 0, 0],
                  [0, -1e6 - 1, 0, 0], [np.nan, 0, 0, 0]])  # fmt: skip
    amp, pen = SR.limits(np.ones(5))
    assert SR.stopped(g, mask, E, zq, amp, pen).tolist() == [False, True, False, True, True]


def test_locate_finds_the_first_crossing_of_the_amplitude_limit():
    """d(t) = exp(t) passes 1e4 at ln(1e4), and d(t) = 2e4 sin(t) at asin(1/2), whatever the
    start of the interval (the located time at most 2 xtol above the closed form)."""
    mask, E, zq = _free(3)
    amp, pen = SR.limits(np.ones(3))

    def state_at(tau, rows):
        d = np.where(rows == 0, np.exp(tau), 2e4 * np.sin(tau))
        return np.stack([d, 0 * d, 0 * d, 0 * d], axis=1)

    def holds(g, rows):
        return SR.stopped(g, mask[rows], E[rows], zq[rows], amp[rows], pen[rows])

    a = np.array([0.0, 0.0, 0.3])
    b = np.array([20.0, 2.5, 2.0])
    tau, g = SR.locate(state_at, holds, a, b, 1e-12)
    exact = [math.log(1e4), math.asin(0.5), math.asin(0.5)]
    assert np.all(tau >= exact) and np.all(tau <= np.array(exact) + 2e-12)
    assert np.all(g[:, 0] > 1e4)
