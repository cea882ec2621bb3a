"""Tests of the exact event-driven simulator (atlas.dynamics.simulator) against closed forms, an
invariant and a brute-force scan for skipped crossings; its limits and input checks."""

import math

import numpy as np
import pytest

from atlas import dynamics as S

PI = math.pi
CASES = S.fig2_cases()


# --------------------------------------------------------------------------- closed forms


def test_single_contact_damped_oscillator_closed_form():
    """Contact 1 active, contact 2 far away: d1'' = -b11 k1 d1 - b11 q1 d1' - a1 (paper eq. 7)."""
    beta1, beta2, alpha = 0.1 * PI, 0.3 * PI, 0.25 * PI
    k1, q1 = 100.0, 4.0
    b11 = math.cos(beta1)
    a1 = math.cos(alpha)
    w0 = math.sqrt(b11 * k1)
    zeta = b11 * q1 / (2 * w0)
    wd = w0 * math.sqrt(1 - zeta**2)
    d_eq = -a1 / (b11 * k1)
    x0 = 0.2 * d_eq  # small enough that the force stays positive
    g0 = (d_eq + x0, 1e3, 0.0, 1e3)  # contact 2 far away and leaving
    res = S.simulate(beta1, beta2, alpha, k=(k1, 1.0), q=(q1, 0.0), g0=g0, t_end=3.0)
    assert res.n_events == 0
    assert res.status == S.Status.T_END
    t = np.linspace(0, 3.0, 301)
    x = np.exp(-zeta * w0 * t) * (x0 * np.cos(wd * t) + x0 * zeta * w0 / wd * np.sin(wd * t))
    g = res.sample(t)
    np.testing.assert_allclose(g[:, 0], d_eq + x, rtol=0, atol=1e-13 * abs(d_eq))
    # free gap: d2'' = b21 f1 - a2 integrated by the same closed form, checked at the end
    assert g[-1, 1] > 1e3


def test_free_flight_is_a_parabola():
    """FF: d'' = -a exactly (paper eq. 1 with f = 0)."""
    alpha = 1.2 * PI  # a points into the third quadrant: both gaps accelerate away
    g0 = np.array([0.5, 0.25, 0.1, -0.2])
    res = S.simulate(0.1 * PI, 0.6 * PI, alpha, g0=g0, t_end=5.0, stop_when_settled=False)
    a = np.array([math.cos(alpha), math.sin(alpha)])
    t = np.linspace(0, 5, 11)
    expect = g0[:2] + np.outer(t, g0[2:]) - 0.5 * np.outer(t**2, a)
    g = res.sample(t)
    assert res.n_events == 0
    np.testing.assert_allclose(g[:, :2], expect, rtol=1e-13, atol=1e-14)


def test_modal_energies_conserved_in_undamped_ss_phase():
    """q = 0, SS mode (Fig. 2b, no event): d'' = -B K (d - d*); with B K = V diag(mu) V^-1 every
    modal energy y_j'^2 + mu_j y_j^2, y = V^-1 (d - d*), is an invariant."""
    p = dict(CASES["b"], t_end=20.0)
    res = S.simulate(**p)
    assert res.n_events == 0
    B = np.array(
        [[math.cos(p["beta1"]), math.cos(p["beta2"])], [math.sin(p["beta1"]), math.sin(p["beta2"])]]
    )
    BK = B @ np.diag(p["k"])
    mu, V = np.linalg.eig(BK)
    assert np.all(np.abs(mu.imag) < 1e-12) and np.all(mu.real > 0)
    mu, V = mu.real, V.real
    a = np.array([math.cos(p["alpha"]), math.sin(p["alpha"])])
    d_star = -np.linalg.solve(BK, a)
    g = res.sample(np.linspace(0, 20.0, 2001))
    y = np.linalg.solve(V, (g[:, :2] - d_star).T).T
    yp = np.linalg.solve(V, g[:, 2:].T).T
    energy = yp**2 + mu * y**2
    np.testing.assert_allclose(energy, energy[0] + 0 * energy, rtol=1e-10)


def test_sample_matches_scipy_expm():
    res = S.simulate(**dict(CASES["d"], t_end=5.0))
    import scipy.linalg

    ts = np.linspace(0, 5.0, 37)
    seg = np.searchsorted(res._seg_t, ts, side="right") - 1
    ref = np.array(
        [
            (scipy.linalg.expm(res._system.modes[res._seg_mask[s]].E * (t - res._seg_t[s])))
            @ res._seg_z[s]
            for t, s in zip(ts, seg, strict=True)
        ]
    )[:, :4]
    np.testing.assert_allclose(res.sample(ts), ref, rtol=1e-12, atol=1e-15)


# --------------------------------------------------------------------------- robustness


@pytest.mark.parametrize("theta", [1.0, pytest.param(0.5, marks=pytest.mark.slow)])
def test_no_crossing_skipped_brute_force_scan(theta):
    """Many rapid events (Fig. 2d, ~230 events): every gap sign change seen on a very fine scan of
    the exact trajectory is a recorded impact/lift-off, and vice versa."""
    p = dict(CASES["d"], t_end=60.0)
    res = S.simulate(**p, theta=theta)
    t = np.linspace(0, res.t_final, 600_001)
    d = res.sample(t)[:, :2]
    for i in range(2):
        neg = d[:, i] <= 0
        scan = int(np.count_nonzero(neg[1:] != neg[:-1]))
        recorded = sum(
            1
            for k, c in zip(res.kinds, res.contacts, strict=True)
            if c == i + 1 and k in (S.IMPACT, S.LIFTOFF)
        )
        assert scan == recorded
    assert res.n_events > 100
    # the coarse and the default sub-step give the same event sequence
    ref = S.simulate(**p, theta=0.25)
    assert ref.kinds == res.kinds
    np.testing.assert_allclose(res.t_events, ref.t_events, rtol=0, atol=1e-10)


def test_grazing_double_crossing_inside_one_substep_is_found():
    """A free gap that dips just below 0 within one sub-step: d1(t) = d0 + v t + t^2/2 (a1 = -1)
    with its minimum -1e-9 at t = 0.01.  The first sub-step (0.2) ends with d1 > 0 again, so only
    the extremum test can find the impact at t = 0.01 - sqrt(2e-9)."""
    alpha = PI  # a = (-1, 0): d1'' = +1 in free flight
    tmin, depth = 0.01, 1e-9
    v = -tmin  # d1' = v + t vanishes at tmin
    d0 = 0.5 * tmin**2 - depth
    width = math.sqrt(2 * depth)
    res = S.simulate(
        0.25 * PI, 0.75 * PI, alpha, k=(100.0, 100.0), g0=(d0, 1.0, v, 1.0), t_end=0.05
    )
    kinds = [(k, c) for k, c in zip(res.kinds, res.contacts, strict=True)]
    assert kinds[:1] == [(S.IMPACT, 1)]
    np.testing.assert_allclose(res.t_events[0], tmin - width, rtol=1e-6)


def test_event_cap_returns_status():
    res = S.simulate(**dict(CASES["d"], t_end=1e6), max_events=50)
    assert res.status == S.Status.EVENT_CAP
    assert res.n_events >= 50 and res.n_events <= 52
    assert res.t_final < 1e6


def test_step_cap_returns_status():
    res = S.simulate(**dict(CASES["b"], t_end=1e9), max_steps=1000)
    assert res.status == S.Status.STEP_CAP


@pytest.mark.parametrize(
    "kwargs, name",
    [
        ({"k": (-1.0, 1.0)}, "k"),
        ({"k": (1.0, 0.0)}, "k"),
        ({"q": (-0.1, 0.0)}, "q"),
        ({"beta1": float("nan")}, "beta1"),
        ({"alpha": float("inf")}, "alpha"),
        ({"g0": (0.0, float("nan"), 0.0, 0.0)}, "g0"),
        ({"b_norm": (0.0, 1.0)}, "b_norm"),
        ({"t_end": -1.0}, "t_end"),
        ({"max_events": 0}, "max_events"),
        ({"max_events": 1.5}, "max_events"),
        ({"max_steps": "10"}, "max_steps"),
        ({"stop_when_settled": "no"}, "stop_when_settled"),
    ],
)
def test_bad_input_raises_naming_parameter(kwargs, name):
    args = dict(beta1=0.1, beta2=2.0, alpha=0.5)
    args.update(kwargs)
    with pytest.raises(ValueError, match=f"^{name}"):
        S.simulate(**args)
