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


def test_grid_lanes_are_the_outcome_maps_runs_for_every_model():
    """The runs of a 4-D outcome atlas: each model's block holds the initial states of its 2-D
    outcome map (``perturbed_initial_states``, the same normals for every model), run by run."""
    from atlas.dynamics import outcome

    b1, b2 = np.linspace(0, 2 * np.pi, 3, endpoint=False), np.linspace(0.1, 6, 4)
    L = C.grid_lanes(b1, b2, (0.1, 5.0), (0.05, 1.5), 0.3 * np.pi, n_perturb=2)
    assert L.g0.shape == (3 * 4 * 2 * 2 * 2, 4)
    for ik, kappa in enumerate((0.1, 5.0)):
        want = outcome.perturbed_initial_states(b1, b2, 0.3 * np.pi, kappa, n_perturb=2)
        for iq, q in enumerate((0.05, 1.5)):
            block = L.g0.reshape(3, 4, 2, 2, 2, 4)[:, :, ik, iq]
            np.testing.assert_array_equal(block, want)
            sel = (L.kappa == kappa) & (L.q == q)
            assert sel.sum() == 24
    assert np.array_equal(L.beta1, np.repeat(b1, 32))
    assert np.array_equal(L.q[:4], [0.05, 0.05, 1.5, 1.5])


def test_cost_ratios_share_the_batch_by_steps_and_add_a_fallbacks_exact_run():
    """Each lane's share of the fast batch is in proportion to its steps; a lane run by the exact
    simulator (fallback) also pays that run; the shares and fallback runs add up to the fast
    engine's CPU seconds."""
    r = dict(fast_s=3.0, steps=np.array([1, 3, 0, 4]), decided_by=np.array([0, 0, 3, 1]),
             exact_lane_s=np.array([0.5, 1.0, 1.0, 2.0]))  # fmt: skip
    x = C.cost_ratios(r)
    np.testing.assert_allclose(x, [0.25 / 0.5, 0.75 / 1.0, 1.0, 1.0 / 2.0])
    assert np.isclose((x * r["exact_lane_s"]).sum(), r["fast_s"])


def test_summary_counts_lanes_against_the_median_lane():
    """The reported numbers of a made-up comparison, by hand: five lanes, one a fallback (its
    exact run added to its cost), one with 12 steps for 11 events (over 10 times the median of
    1 step), one disagreement."""
    r = dict(fast_s=2.0, steps=np.array([1, 1, 12, 0, 2]), n_events=np.array([0, 1, 11, 0, 1]),
             decided_by=np.array([0, 1, 0, 3, 0]), exact_lane_s=np.array([1.0, 1.0, 2.0, 1.0, 1.0]),
             exact_s=6.0, disagree=np.array([4]))  # fmt: skip
    s = C.summary(r)
    # batch CPU 2.0 - 1.0 (the fallback's exact run) over 16 steps: 1/16 s a step
    cost = np.array([1, 1, 12, 16, 2]) / 16
    ratio = cost / r["exact_lane_s"]
    assert s["lanes"] == 5 and s["disagreements"] == 1 and s["fallback"] == 0.2
    assert s["speedup"] == 3.0 and s["fast_cpu_s"] == 2.0 and s["exact_cpu_s"] == 6.0
    assert s["ratio_median"] == pytest.approx(2 / 16)  # ratios 1/16, 1/16, 12/32, 1, 2/16
    assert s["ratio_worst"] == pytest.approx(1.0)  # the fallback: its exact run, 1 s
    assert s["over_exact"] == 0  # the fallback costs exactly its exact run: not over
    assert s["ratio_p99"] == pytest.approx(np.quantile(ratio, 0.99))
    assert s["steps_median"] == 1.0 and s["steps_max"] == 12
    assert s["over_steps"] == 1 and s["over_steps_per_event"] == pytest.approx(12 / 11)
    # fast cost: median lane 2/16 s; the 12-step lane (12/16) is 6x, the fallback (16/16) 8x
    assert s["over_cost"] == 0 and s["worst_over_median"] == pytest.approx(8.0)
    assert C.summary(r, over=5.0)["over_cost"] == 2


def test_per_event_target_by_hand():
    """The lane-cost target of a made-up comparison, by hand: four stepped lanes at 2, 1, 30 and
    2.5 steps per event (median 2.25; a lane without events counts one) and a fallback (its
    cost reported apart, over its exact run).  Batch CPU 4.4 s over 44 steps: 0.1 s a step."""
    r = dict(fast_s=6.4, steps=np.array([2, 4, 30, 3, 5]), n_events=np.array([1, 4, 1, 0, 2]),
             decided_by=np.array([0, 0, 0, 3, 0]), exact_lane_s=np.array([1.0, 1.0, 1.0, 2.0, 1.0]),
             exact_s=6.0, disagree=np.array([], dtype=int))  # fmt: skip
    x = C.per_event(r)
    # steps per event 2, 1, 30, 2.5 and cost per event 0.2, 0.1, 3.0, 0.25 s: 30 / 2.25 both
    assert x["event_steps_worst"] == pytest.approx(30 / 2.25)
    assert x["event_cost_worst"] == pytest.approx(3.0 / 0.225)
    assert x["over_event"] == 1  # the 30-step lane, over 22.5
    assert x["over_exact_stepped"] == 1  # the same lane: 3.0 s against 1 s exact
    assert x["fallback_worst"] == pytest.approx((0.3 + 2.0) / 2.0)  # its share and exact run
    assert x["met"] is False
    # over 15 times the median and 10 s exact for the long lane: met, the fallback aside
    y = C.per_event(dict(r, exact_lane_s=np.array([1.0, 1.0, 10.0, 2.0, 1.0])), over=15.0)
    assert y["over_event"] == y["over_exact_stepped"] == 0 and y["met"] is True
    s = C.summary(r)  # the literal column kept: 30 steps are under 10 times the median lane's 4
    assert s["met"] is False and s["over_event"] == 1 and s["over_steps"] == 0
    none = dict(r, decided_by=np.zeros(5, dtype=int), fast_s=4.4)
    assert C.per_event(none)["fallback_worst"] == 0.0


def test_grid_lanes_cost_under_ten_times_the_median_lane_per_event():
    """The runs of the ``0:2pi:8`` degenerate-direction grid at one run a cell (256 lanes), by
    the fast engine alone, counted (not timed): no stepped lane takes over 10 times the median
    lane's steps per event."""
    from atlas.bench.simulation import DEGENERATE_GRID
    from atlas.dynamics import fast_engine

    L = C.grid_lanes(**DEGENERATE_GRID)
    k, q = np.stack([L.kappa, np.ones_like(L.kappa)], axis=1), np.stack([L.q, L.q], axis=1)
    res = fast_engine.run_lanes(L.beta1, L.beta2, L.alpha, k, q, L.g0)
    n = res.steps.size
    r = dict(fast_s=1.0, steps=res.steps, n_events=res.n_events, decided_by=res.decided_by,
             exact_lane_s=np.ones(n))  # fmt: skip
    x = C.per_event(r)
    stepped = res.decided_by != fast_engine.DECIDED_BY.index("fallback")
    spe = res.steps[stepped] / np.maximum(res.n_events[stepped], 1)
    assert x["event_steps_worst"] == pytest.approx(spe.max() / np.median(spe))
    assert x["event_steps_worst"] < 10


def test_summary_of_a_lane_set_without_heavy_lanes():
    r = dict(fast_s=1.0, steps=np.array([3, 3]), n_events=np.array([1, 1]),
             decided_by=np.array([0, 0]), exact_lane_s=np.array([1.0, 1.0]), exact_s=2.0,
             disagree=np.array([], dtype=int))  # fmt: skip
    s = C.summary(r)
    assert s["over_steps"] == s["over_cost"] == 0 and s["over_steps_per_event"] == 0.0
    assert s["worst_over_median"] == 1.0 and s["ratio_median"] == s["ratio_worst"] == 0.5
    assert C.summary(dict(r, fast_s=3.0))["over_exact"] == 2  # 1.5 s a lane against 1 s
