"""The batched JAX stepper (atlas.dynamics.jax_engine) against the NumPy simulator (atlas.dynamics), which
is itself checked against closed forms and scipy solve_ivp in test_simulator.py and test_reference.py."""

import math

import numpy as np
import pytest

from atlas import dynamics as D
from atlas.dynamics import jax_engine as J

CASES = D.fig2_cases()


@pytest.fixture(scope="module")
def batch():
    """Fig. 2 a-e over t <= 10 and the stress case (Fig. 2d, t <= 60, ~145 rapid events), one
    vmapped call (one compilation)."""
    runs = [dict(CASES[n], t_end=10.0) for n in "abcde"] + [dict(CASES["d"], t_end=60.0)]
    params = [{k: p[k] for k in ("beta1", "beta2", "alpha", "k", "q")} for p in runs]
    res = J.simulate_batch(params, [p["g0"] for p in runs], [p["t_end"] for p in runs])
    return runs, res


@pytest.mark.parametrize("n", range(6))
def test_events_agree_with_numpy(batch, n):
    """Same event sequence; event times agree to 1e-12 and states to 1e-10 (bisection to
    h 2^-64 vs Brent to 1e-13 h)."""
    runs, res = batch
    ref = D.simulate(**runs[n])
    got = res[n]
    assert got["kinds"] == ref.kinds
    np.testing.assert_array_equal(got["contacts"], ref.contacts)
    np.testing.assert_allclose(got["t_events"], ref.t_events, rtol=0, atol=1e-12)
    np.testing.assert_allclose(got["states"], ref.states.reshape(-1, 4), rtol=0, atol=1e-10)
    np.testing.assert_allclose(got["g_final"], ref.g_final, rtol=0, atol=1e-10)
    assert got["status"] == ref.status and got["mode_final"] == ref.mode_final


def test_stress_case_many_events(batch):
    _, res = batch
    assert len(res[5]["kinds"]) > 100  # the no-skip scan of this case is in test_simulator.py


def test_event_cap_status():
    p = dict(CASES["d"])
    params = [{k: p[k] for k in ("beta1", "beta2", "alpha", "k", "q")}]
    (r,) = J.simulate_batch(params, [p["g0"]], 1e6, max_events=20)
    assert r["status"] == D.Status.EVENT_CAP
    assert 20 <= len(r["kinds"]) <= 24 and r["t_final"] < 1e6


@pytest.mark.slow
def test_map_outcomes_equal_numpy_engine():
    b1, b2 = D.outcome_grid(3)
    a = D.outcome_map(b1, b2, engine="numpy")
    b = D.outcome_map(b1, b2, engine="jax")
    np.testing.assert_array_equal(a["outcome"].values, b["outcome"].values)
    assert b.attrs["engine"] == "jax" and math.isfinite(b.attrs["trajectories_per_second"])
