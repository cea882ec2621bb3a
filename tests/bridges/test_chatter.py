"""atlas.bridges.chatter on MuJoCo models that chatter (repeated make / break of a contact), against
references computed here: the contacts' gaps from MuJoCo's kinematics (sphere centre height minus
radius) for the engine's side, and the planar closed forms for the theory's side (a rod's foot:
``b11 = 1/m + (r x n)(r x (n - mu t)) / I``, ``a1 = g + omega^2 (R c)_z``; the ladder's ``B`` from
:class:`atlas.core.rigid_body.Mechanism` at the state's angle).

* Painleve's rod on its foot alone (mu = 0.5, 3 m/s): MuJoCo's foot hops again and again, where
  the rigid body keeps sliding (``b11 > 0``, ``a1 > 0``: no lift-off, and one contact has no
  inverse chattering): the solver's.
* The ladder at 3 m/s: MuJoCo's top chatters on the wall where ``b11, b22 > 0`` (CC's necessary
  condition): the theory does not exclude it.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from atlas import cli
from atlas.core.rigid_body import Mechanism

mujoco = pytest.importorskip("mujoco", reason="the mujoco extra is not installed")

from mjcf_bodies import mjcf  # noqa: E402

from atlas.bridges.chatter import behaviour  # noqa: E402
from atlas.bridges.chatter import text as chatter_text  # noqa: E402
from atlas.bridges.rollout import Rollout, rollout  # noqa: E402

RHO = 0.01  # the contact spheres' radius [m]
TOL = 1e-4  # touching in a rollout [m]
ROD = Mechanism.ladder(theta=math.atan(2.0), mu_floor=0.5)  # the top 0.1 m off the wall
LADDER = Mechanism.ladder(speed=3.0)


def _text(body):
    text, qvel = mjcf(body, rho=RHO)
    return text.replace("<option ", '<option timestep="2e-4" '), qvel


def _rot(phi, v):
    """``v`` (body x, z) turned by ``phi`` about -y (x towards z)."""
    c, s = math.cos(phi), math.sin(phi)
    return np.array([c * v[0] - s * v[1], s * v[0] + c * v[1]])


def _touching(samples, r, n):
    """Touching per sample: the gap ``n . (x + R c - r) - rho`` of the sphere (centre ``c`` =
    ``r + rho n`` on the body, ``x`` the body's position) above its plane through ``r``."""
    c, n, r = np.add(r, RHO * np.asarray(n)), np.asarray(n), np.asarray(r)
    gap = lambda s: n @ (np.array(s["qpos"][:2]) + _rot(s["qpos"][2], c) - r) - RHO  # noqa: E731
    return [gap(s) <= TOL for s in samples]


def _remakes(touch):
    """Contacts made again after the first break (counted from the reference gaps)."""
    first = next((i for i in range(1, len(touch)) if touch[i - 1] and not touch[i]), None)
    if first is None:
        return 0
    return sum(1 for i in range(first + 1, len(touch)) if touch[i] and not touch[i - 1])


def test_the_rods_foot_chatters_where_the_rigid_body_keeps_sliding():
    text, _ = _text(ROD)
    model = mujoco.MjModel.from_xml_string(text)
    res = rollout(model, None, 0.2, qpos=[0.1, 0, 0], qvel=[3.0, 0, 0], contacts="c1", every=5)
    touch = _touching(res.samples, ROD.r1, ROD.n1)
    c = np.asarray(ROD.r1) + RHO * np.asarray(ROD.n1)  # the foot sphere's centre (body frame)
    assert _remakes(touch) >= 2  # MuJoCo chatters (9 times at the time of writing)
    b = behaviour(res)
    assert b["kind"] == "chatter" and b["contacts"][0]["chatter"]
    first = next(i for i in range(1, len(touch)) if touch[i - 1] and not touch[i])
    assert b["contacts"][0]["first_break"] == res.samples[first]["t"]
    s = res.samples[first - 1]  # the sliding state the engine leaves
    assert b["judged_at"] == s["t"]
    phi, omega, vx = s["qpos"][2], s["qvel"][2], s["qvel"][0]
    r = _rot(phi, c) - (0.0, RHO)  # centre of mass -> contact point
    n, t = np.array([0.0, 1.0]), np.array([math.copysign(1.0, vx - omega * r[1]), 0.0])
    cross = lambda u, v: u[0] * v[1] - u[1] * v[0]  # noqa: E731
    b11 = 1 / ROD.m + cross(r, n) * cross(r, n - 0.5 * t) / ROD.I
    a1 = 9.81 + omega**2 * _rot(phi, c)[1]
    assert b11 > 0 and a1 > 0  # sliding consistent and stable, lift-off inconsistent
    assert b["theory"] == dict(lift_off=[], inverse_chattering=False, sliding=True)
    assert b["judgement"] == "solver"


def test_the_ladders_top_chatters_where_cc_is_not_excluded(tmp_path, capsys):
    """Through ``atlas mujoco --rollout --json`` on the MJCF file; the text report's line."""
    text, qvel = _text(LADDER)
    path = tmp_path / "ladder3.xml"
    path.write_text(text)
    args = ["mujoco", str(path), "--qvel", ",".join(map(repr, qvel)), "--rollout", "0.2"]
    assert cli.main([*args, "--every", "5", "--json"]) == 0
    rep = json.loads(capsys.readouterr().out)
    samples, b = rep["samples"], rep["behaviour"]
    touch = _touching(samples, LADDER.r2, LADDER.n2)
    assert _remakes(touch) >= 2 and b["kind"] == "chatter" and b["contacts"][1]["chatter"]
    first = next(i for i in range(1, len(touch)) if touch[i - 1] and not touch[i])
    s = samples[first - 1]
    theta = math.acos(0.25) - s["qpos"][2]  # the ladder's angle: x turns towards z
    B = Mechanism.ladder(theta=theta, speed=3.0).B
    assert B[0, 0] > 0 and B[1, 1] > 0  # CC's necessary condition holds
    assert b["judged_at"] == s["t"] and b["theory"]["inverse_chattering"]
    assert b["judgement"] == "allowed"
    # the text report's line of this behaviour (the text mode prints it after the states:
    # tests/bridges/test_mujoco_cli.py)
    line = chatter_text(b)
    assert line.startswith("engine: chatter (surf2/c2 breaks ") and "theory at " in line


def _sample(t, touching, sliding, verdicts):
    return dict(t=t, touching=touching, sliding=sliding, verdicts=verdicts)


SS = dict(consistent_SS=True, stable_SS=1, consistent_SF=False, consistent_FS=False,
          consistent_FF=False, cc_possible=False)  # fmt: skip


@pytest.mark.parametrize(
    "verdicts, judgement",
    [
        (SS, "solver"),
        (dict(SS, consistent_FS=True), "allowed"),
        (dict(SS, cc_possible=True), "allowed"),
        (dict(SS, stable_SS=0), "open"),  # SS unstable, nothing else consistent
        (dict(SS, consistent_SS=False), "open"),
        (None, "unjudged"),  # no judged state before the break
    ],
)
def test_the_judgement_of_a_lift_off_on_each_path(verdicts, judgement):
    """The rule of the module docstring on written sample lists (two contacts; contact 2 lifts
    off once at 0.2 s and stays off: a lift-off, not chatter)."""
    both, lifted = [True, True], [True, False]
    samples = [_sample(0.0, both, both, verdicts), _sample(0.1, both, both, verdicts),
               _sample(0.2, lifted, lifted, None), _sample(0.3, lifted, lifted, None)]  # fmt: skip
    b = behaviour(Rollout(("c1", "c2"), samples, [], 0.0))
    assert b["kind"] == "lift-off" and b["judgement"] == judgement
    assert b["judged_at"] == (None if verdicts is None else 0.1)
    assert b["contacts"][1] == dict(name="c2", breaks=1, makes=0, first_break=0.2, chatter=False)


def test_a_stop_and_steady_sliding_are_not_separations():
    both, stuck = [True, True], [True, False]
    stop = [_sample(0.0, both, both, SS), _sample(0.1, both, stuck, None)]
    b = behaviour(Rollout(("c1", "c2"), stop, [], 0.0))
    assert (b["kind"], b["stop"], b["judgement"]) == ("stop", 0.1, None)
    slide = [_sample(0.0, both, both, SS), _sample(0.1, both, both, SS)]
    assert behaviour(Rollout(("c1", "c2"), slide, [], 0.0))["kind"] == "sliding"
