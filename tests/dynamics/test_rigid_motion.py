"""atlas.dynamics.rigid_motion: the rigid SS motion of the built-in bodies against closed forms
(the frictionless ladder leaves the wall at sin(theta) = (2/3) sin(theta0); a two-legged body
sliding on equal friction stops at v / (mu g)), and its energy."""

from __future__ import annotations

import math

import numpy as np
import pytest

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
    energy = m * G * mo.x[:, 1] + (m * (mo.v[:, 0] ** 2 + mo.v[:, 1] ** 2) + I * mo.v[:, 2] ** 2) / 2
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


def test_follow_errors():
    with pytest.raises(ValueError, match="^t_end, dt: must be > 0"):
        follow(Mechanism.ladder(), t_end=0.0)
