"""``atlas.bench.simulation``: gap events and event-time errors on hand-made sequences; the
lane-by-lane comparison of both engines on a few lanes."""

import math

import numpy as np
import pytest

from atlas.bench.simulation import _lane_sets, engine_lanes, event_error, gap_events
from atlas.dynamics import engine_check, fast_engine


def test_gap_events_keep_impacts_and_liftoffs():
    t, tags = gap_events(
        [0.1, 0.2, 0.3, 0.4],
        ["impact", "force_on", "liftoff", "force_off"],
        [1, 2, 2, 1],
    )
    np.testing.assert_array_equal(t, [0.1, 0.3])
    assert tags == [(1, "impact"), (2, "liftoff")]


def test_event_error():
    tags = [(1, "impact"), (2, "liftoff")]
    t = np.array([1.0, 2.0])
    err, match = event_error(t, tags, t + [1e-6, -3e-6], tags)
    assert err == pytest.approx(3e-6, rel=1e-9) and match == 2
    assert event_error(t[:0], [], t[:0], []) == (0.0, 0)
    # another sequence of events: inf (reported as "mismatch"), and how far they agree
    assert event_error(t, tags, t, [(1, "impact"), (1, "liftoff")]) == (math.inf, 1)
    assert event_error(t, tags, t[:1], tags[:1]) == (math.inf, 1)


def test_engine_lanes_rows_are_computed_from_the_lanes():
    """The lane comparison of the bench on 6 random lanes: one row, every lane run by both
    engines, 0 disagreements; its step counts are those of the fast engine on the same lanes
    (counted again here), its per-lane cost ratios ordered median <= p99 <= worst."""
    (row,) = engine_lanes(dict(engine_random=(44, 6)))
    assert row["set"] == "6 random lanes (seed 44)"
    assert row["lanes"] == 6 and row["disagreements"] == 0 and row["disagree_lanes"] == ""
    L = engine_check.random_lanes(44, 6)
    k = np.stack([L.kappa, np.ones(6)], axis=1)
    q = np.stack([L.q, L.q], axis=1)
    res = fast_engine.run_batch(L.beta1, L.beta2, L.alpha, k, q, L.g0, reference=None,
                                t_end=150.0, horizon_cap=8.0, max_events=2000)  # fmt: skip
    assert row["steps_max"] == res.steps.max() and row["steps_median"] == np.median(res.steps)
    assert row["over_steps"] == int((res.steps > 10 * np.median(res.steps)).sum())
    assert 0 < row["ratio_median"] <= row["ratio_p99"] <= row["ratio_worst"]
    assert row["fallback"] == np.mean(res.decided_by == fast_engine.DECIDED_BY.index("fallback"))


def test_engine_lane_sets_are_the_random_lanes_and_the_degenerate_grid():
    """``engine_random`` and ``engine_grid`` name the lane sets (each off at 0 or missing); the
    grid's lanes are the 0:2pi:8 directions, both models of kappa and q, ``engine_grid`` runs a
    cell."""
    assert list(_lane_sets({})) == [] and list(_lane_sets(dict(engine_grid=0))) == []
    ((name, lanes),) = _lane_sets(dict(engine_grid=2))
    assert name.startswith("beta 0:2pi:8") and lanes.g0.shape == (8 * 8 * 2 * 2 * 2, 4)
    np.testing.assert_array_equal(np.unique(lanes.beta1), np.arange(8) * (math.pi / 4))
    assert set(lanes.kappa) == {0.1, 5.0} and set(lanes.q) == {0.05, 1.5}
    assert np.all(lanes.alpha == 0.3 * math.pi)
    names = [n for n, _ in _lane_sets(dict(engine_random=(3, 5), engine_grid=1))]
    assert names[0] == "5 random lanes (seed 3)" and len(names) == 2
