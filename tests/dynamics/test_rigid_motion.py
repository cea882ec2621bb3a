"""atlas.dynamics.rigid_motion: the rigid SS motion of the built-in bodies against closed forms
(the frictionless ladder leaves the wall at sin(theta) = (2/3) sin(theta0); a two-legged body
sliding on equal friction stops at v / (mu g); Painleve's rod sliding on its tip reaches b11 = 0 at
the closed-form angle), and its energy."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from atlas.core.rigid_body import Mechanism
from atlas.dynamics.rigid_motion import follow

G = 9.81


@pytest.mark.parametrize("theta0", [math.acos(0.25), 1.0])
def test_frictionless_ladder_leaves_the_wall_at_the_closed_form_angle(theta0):
    """Released at rest: the wall force reaches zero at sin(theta) = (2/3) sin(theta0) (energy
    and the wall force of the rigid motion; the classical result), the floor force stays
    positive, and the energy m g y_c + (m v^2 + I omega^2) / 2 is conserved."""
    lad = Mechanism.ladder(theta=theta0, mu_floor=0.0, mu_wall=0.0)
    mo = follow(lad, t_end=3.0, dt=1e-2)
    assert mo.event == "lift-off of contact 2"
    theta = theta0 - mo.x[-1, 2]
    assert math.sin(theta) == pytest.approx(2 / 3 * math.sin(theta0), rel=1e-7)
    assert mo.forces[-1, 0] > 0 and abs(mo.forces[-1, 1]) < 1e-6 * mo.forces[0, 1]
    m, I = lad.m, lad.I
    energy = (
        m * G * mo.x[:, 1] + (m * (mo.v[:, 0] ** 2 + mo.v[:, 1] ** 2) + I * mo.v[:, 2] ** 2) / 2
    )
    np.testing.assert_allclose(energy, 0.0, atol=1e-7 * m * G * abs(lad.r1[1]))


def test_two_legged_body_stops_by_friction_at_v_over_mu_g():
    """Equal friction on both legs: the body translates (the admissible twist) and decelerates at
    mu g; it sticks at t = v0 / (mu g), having slid v0^2 / (2 mu g)."""
    v0, mu = 0.5, 0.3
    body = Mechanism.two_legged(mu1=mu, mu2=mu, speed=v0)
    mo = follow(body, t_end=1.0, dt=1e-2)
    assert mo.event in ("contact 1 sticks", "contact 2 sticks")
    assert mo.t[-1] == pytest.approx(v0 / (mu * G), rel=1e-9)
    assert mo.x[-1, 0] == pytest.approx(v0**2 / (2 * mu * G), rel=1e-9)
    np.testing.assert_allclose(mo.x[:, 2], 0.0, atol=1e-12)


def _rod_reference(mu, theta0, omega0, h, I, m):
    """Painleve's rod sliding on its tip (foot along +x, friction -mu f), written here by hand:
    theta' = -omega, I omega' = h f (cos - mu sin), f = a / b with a = g - omega^2 h sin (the
    foot's free normal acceleration, up) and b = 1/m + h^2 cos (cos - mu sin) / I; integrated
    by DOP853 (rtol 1e-12) until b reaches 1e-10 (f diverges at b = 0; b is linear in theta
    there, so the end lies ~1e-11 in t and theta before b = 0, far inside the test's 1e-7 and
    1e-9: each decade of b nearer costs the solver ~3x the steps).
    Returns (t, theta, omega) at the end."""
    parts = lambda th, om: (  # noqa: E731
        G - om * om * h * math.sin(th),
        1 / m + h * h * math.cos(th) * (math.cos(th) - mu * math.sin(th)) / I,
    )
    torque = lambda th: h * (math.cos(th) - mu * math.sin(th)) / I  # noqa: E731
    rhs = lambda t, y: [-y[1], torque(y[0]) * np.divide(*parts(*y))]  # noqa: E731
    stop = lambda t, y: parts(*y)[1] - 1e-10  # noqa: E731
    stop.terminal = True
    sol = solve_ivp(rhs, (0, 1), [theta0, omega0], "DOP853", rtol=1e-12, atol=1e-14, events=stop)
    return sol.t[-1], *sol.y[:, -1]


@pytest.mark.parametrize("dt", [1e-2, pytest.param(1e-3, marks=pytest.mark.slow)])
def test_painleves_rod_reaches_painleves_point(dt):
    """A uniform rod (m = 1 kg, L = 1 m, mu = 2) on its tip only, rising while its foot slides
    away (theta0 = 0.6 rad, omega0 = -0.5 rad/s, foot at 8 m/s).  b11 = 1/m + (h^2/I) cos (cos -
    mu sin) (SPEC §1: the foot's response to a unit normal force with friction against +x) is
    zero where 3 mu sin(2 theta) - 3 cos(2 theta) = 5 (h^2 m / I = 3), first at theta_P =
    (atan(1/mu) + asin(5 / (3 sqrt(1 + mu^2)))) / 2.  The sliding force f = a/b stays positive
    and diverges there while a -> 0 with b (a ~ b^gamma, gamma = 0.34 < 1): the rod reaches
    Painleve's point a = b = 0 (omega^2 = g / (h sin theta_P)) in finite time, which an
    independent integration of the reduced equation gives; it does not lift off first."""
    mu, theta0, omega0, u0 = 2.0, 0.6, -0.5, 8.0
    rod = Mechanism.ladder(theta=theta0, mu_floor=mu, L=1.0, m=1.0)
    h, c, s = 0.5, math.cos(theta0), math.sin(theta0)
    twist = (u0 - omega0 * h * s, -omega0 * h * c, omega0)
    mo = follow(rod, t_end=1.0, dt=dt, contacts=(1,), twist=twist)
    theta_p = (math.atan(1 / mu) + math.asin(5 / (3 * math.sqrt(1 + mu * mu)))) / 2
    assert 1 + 3 * math.cos(theta_p) * (math.cos(theta_p) - mu * math.sin(theta_p)) == (
        pytest.approx(0.0, abs=1e-14))  # fmt: skip
    assert mo.event == "B singular" and mo.contacts == (1,)
    theta = theta0 - mo.x[-1, 2]
    assert theta == pytest.approx(theta_p, abs=1e-9)
    assert np.all(mo.forces > 0) and mo.forces[-1, 0] > 1e6
    assert mo.space.verdicts()["consistent_S"]
    t_ref, theta_ref, omega_ref = _rod_reference(mu, theta0, omega0, h, rod.I, rod.m)
    assert theta_ref == pytest.approx(theta_p, abs=1e-9)
    assert mo.t[-1] == pytest.approx(t_ref, abs=1e-7)
    assert mo.v[-1, 2] ** 2 == pytest.approx(G / (h * math.sin(theta_p)), rel=5e-3)
    assert omega_ref**2 == pytest.approx(G / (h * math.sin(theta_p)), rel=5e-3)
    assert 0 < mo.space.a[0] < 0.05 * G


def test_follow_errors():
    with pytest.raises(ValueError, match="^t_end, dt: must be > 0"):
        follow(Mechanism.ladder(), t_end=0.0)
    with pytest.raises(ValueError, match="^contacts: one or both of 1, 2"):
        follow(Mechanism.ladder(), contacts=(1, 3))
    with pytest.raises(ValueError, match="^twist: opens or closes a closed contact"):
        follow(Mechanism.ladder(), contacts=(1,), twist=(0.0, 1.0, 0.0))
    with pytest.raises(ValueError, match="^twist: must be a finite"):
        follow(Mechanism.ladder(), contacts=(1,), twist=(0.0, 1.0))
