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
