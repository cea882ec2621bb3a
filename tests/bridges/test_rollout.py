"""atlas.bridges.rollout: verdicts along MuJoCo trajectories against closed forms (the frictionless
ladder leaves the wall at sin(theta) = (2/3) sin(theta0)) and against MuJoCo's own behaviour (a
jam's stop time scales with the constraint time constant, a friction stop's does not)."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from atlas.core.rigid_body import Mechanism

mujoco = pytest.importorskip("mujoco", reason="the mujoco extra is not installed")

from mjcf_bodies import mjcf  # noqa: E402

from atlas.bridges import mujoco as bridge  # noqa: E402
from atlas.bridges.rollout import jam_test, rollout  # noqa: E402

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "ladder.xml"


def test_frictionless_ladder_leaves_the_wall_at_the_closed_form_angle():
    """The example ladder without friction (L = 4 m), released at rest at theta0 = acos(1/4).
    Rigid body: the wall force is ``m (L/2) cos(theta) (3 g sin(theta) / (2 L) - omega^2)``, so
    sliding on both contacts is consistent iff ``omega^2 < 3 g sin(theta) / (2 L)``: the verdict
    at every sampled MuJoCo state where both slide agrees with that closed form (away from 1 % of
    the boundary), on both sides.  Along the rigid motion (energy: ``omega^2 = 3 g (sin(theta0) -
    sin(theta)) / L``) it fails at ``sin(theta) = (2/3) sin(theta0)``, 40.20 deg; along MuJoCo's
    soft trajectory (a little slower) it fails within 1 deg after (measured between 39.97 and
    39.08 deg), and the top leaves the wall after that, the floor contact alone then sliding
    consistently."""
    model, data = bridge.load(EXAMPLE)
    model.geom_friction[:, 0] = 0.0
    res = rollout(model, data, 1.1, every=20)
    theta = lambda s: math.acos(0.25) - s["qpos"][2]  # noqa: E731  (the hinge turns x to z)
    both = [s for s in res.samples if s["verdicts"] and "consistent_SS" in s["verdicts"]]
    seen = set()
    for s in both:
        crit = 3 * 9.81 * math.sin(theta(s)) / (2 * 4.0)
        w2 = s["qvel"][2] ** 2
        if abs(w2 - crit) > 0.01 * crit:
            assert s["verdicts"]["consistent_SS"] == (w2 < crit), s["t"]
            seen.add(w2 < crit)
    assert seen == {True, False} and len(both) > 40
    flip = res.first("consistent_SS", False)
    closed = math.asin(2 / 3 * math.sin(math.acos(0.25)))
    before = res.samples[res.samples.index(flip) - 1]
    assert closed - math.radians(1.0) < theta(before) and theta(flip) < closed
    assert flip["verdicts"]["consistent_SF"]
    free = next(s for s in res.samples if not s["touching"][1])
    assert free["t"] > flip["t"] and free["verdicts"]["consistent_S"]


def _rod(mu, timeconst):
    """The ladder's foot alone (a rod on a floor at tan(theta) = 2, the top off the wall), foot
    sliding away at 1 m/s: Painleve's rod, b11 < 0 iff mu > 4/3."""
    text, _ = mjcf(Mechanism.ladder(theta=math.atan(2.0), mu_floor=mu))
    ref = f'solref="{timeconst} 1"'
    text = text.replace("<option ", '<option timestep="1e-4" ')
    text = text.replace('<geom name="surf1"', f'<geom name="surf1" {ref}')
    text = text.replace('<geom name="c1"', f'<geom name="c1" {ref}')
    return mujoco.MjModel.from_xml_string(text)


def test_jam_and_friction_stop_told_apart_by_the_time_constant():
    """Painleve's rod at mu = 2: only the jam (IWC) is consistent at the start, and MuJoCo's stop
    time halves with the constraint time constant (jam_test); at mu = 0.5 sliding is consistent
    and stable, a friction stop, nearly independent of it.  (With 20 / 5 ms: 55 / 14 ms against
    216 / 202 ms.)"""
    kw = dict(qpos=[0.1, 0, 0], qvel=[1.0, 0, 0], contacts="c1", every=10)
    state = {k: kw[k] for k in ("qpos", "qvel", "contacts")}
    jam, slide = _rod(2.0, 0.02), _rod(0.5, 0.02)
    assert bridge.contact_data(jam, **state).verdicts() == {
        "consistent_F": False, "consistent_S": False, "stable_S": False, "consistent_I": True,
    }  # fmt: skip
    v = bridge.contact_data(slide, **state).verdicts()
    assert v["consistent_S"] and v["stable_S"] and not v["consistent_I"]
    jt = jam_test(jam, None, 0.1, **kw)
    assert jt["kind"] == "jam" and 1.6 < jt["ratio"] < 2.5, jt
    ft = jam_test(slide, None, 0.3, **kw)
    assert ft["kind"] == "friction stop" and 0.85 < ft["ratio"] < 1.2, ft
    assert jam.geom_solref[0, 0] == 0.02  # restored


def test_rollout_errors():
    model, data = bridge.load(EXAMPLE)
    with pytest.raises(ValueError, match="^duration: must be > 0 s, got 0"):
        rollout(model, data, 0.0)
    with pytest.raises(ValueError, match="^every: must be >= 1 step, got 0"):
        rollout(model, data, 0.1, every=0)
