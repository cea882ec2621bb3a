"""``atlas.bench.simulation``: gap events and event-time errors on hand-made sequences."""

import math

import numpy as np
import pytest

from atlas.bench.simulation import event_error, gap_events


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
