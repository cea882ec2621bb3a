"""Every touching contact is analysed, on each path of the bridge: a MuJoCo model with three touching
contacts (a three-legged bench, an MJCF file) is refused in one line naming ``model`` and the
contacts on the API, the CLI (with or without ``--contacts``) and the rollout, including a third
contact that lands during the rollout (the bench tipping onto its raised leg).  The theory covers
one or two sliding contacts; a contact left out would add a force that neither ``Q`` nor ``B``
holds (these paths computed with the chosen two and dropped the third without a word).

Reference for "touches": the leg sphere's height above the floor plane ``z = 0`` minus its radius,
from MuJoCo's kinematics (not from the bridge's collision pass)."""

from __future__ import annotations

import re

import pytest

from atlas import cli

mujoco = pytest.importorskip("mujoco", reason="the mujoco extra is not installed")

from atlas.bridges import mujoco as bridge  # noqa: E402
from atlas.bridges.rollout import rollout  # noqa: E402

RADIUS = 0.01  # of the leg spheres [m]


def _bench(lift2=0.0, xs=(-0.3, 0.0, 0.3)):
    """A 2 kg bench on a free joint with three sphere legs on the line ``y = 0`` (symmetric in
    ``y``: it cannot roll sideways), leg 2 raised by ``lift2`` [m]."""
    legs = " ".join(
        f'<geom name="leg{i}" type="sphere" size="{RADIUS}" mass="0.01" '
        f'pos="{x} 0 {-0.49 + (lift2 if i == 2 else 0.0)}"/>'
        for i, x in enumerate(xs)
    )
    return f"""<mujoco><option timestep="0.0005"/><worldbody>
    <geom name="floor" type="plane" size="0 0 1" friction="0.3 0 0"/>
    <body name="bench" pos="0 0 0.5"><freejoint/>
    <geom type="box" size="0.4 0.1 0.05" contype="0" conaffinity="0" mass="2"/>{legs}</body>
    </worldbody></mujoco>"""


SLIDING = "1,0,0,0,0,0"  # the bench sliding along x at 1 m/s
LISTING = "3 contacts touch at this state (floor/leg0, floor/leg1, floor/leg2)"


@pytest.mark.parametrize("choice", [[], ["--contacts", "leg0,leg2"], ["--rollout", "0.01"]])
def test_three_touching_contacts_are_refused_by_the_cli(tmp_path, capsys, choice):
    path = tmp_path / "bench.xml"
    path.write_text(_bench())
    assert cli.main(["mujoco", str(path), "--qvel", SLIDING, *choice]) == 2
    err = capsys.readouterr().err
    assert err.startswith("atlas: error: model: " + LISTING) and err.count("\n") == 1, err


def test_two_of_three_legs_are_refused_by_the_api():
    model = mujoco.MjModel.from_xml_string(_bench())
    for contacts in (None, "leg0,leg1", ["leg2"]):
        with pytest.raises(ValueError, match="^model: " + re.escape(LISTING)):
            bridge.contact_data(model, qvel=[1, 0, 0, 0, 0, 0], contacts=contacts)


def _gap2(model, qpos):
    """Leg 2's distance to the floor [m] at ``qpos``, from MuJoCo's kinematics."""
    data = mujoco.MjData(model)
    data.qpos[:] = qpos
    mujoco.mj_kinematics(model, data)
    gid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, "leg2")
    return float(data.geom_xpos[gid][2]) - RADIUS


def test_a_third_contact_landing_in_a_rollout_stops_the_verdicts():
    """Legs 0 and 1 at x = -0.3, -0.1 slide; the centre of mass (x = 0) lies beyond leg 1, so the
    bench tips onto leg 2 (x = 0.3, raised 2 mm).  Wherever leg 2 touches (0.1 mm, the rollout's
    tolerance), no verdict is given and the sample says why, naming ``model`` and leg 2; before
    it lands, verdicts are given."""
    model = mujoco.MjModel.from_xml_string(_bench(0.002, (-0.3, -0.1, 0.3)))
    res = rollout(model, None, 0.05, qvel=[1, 0, 0, 0, 0, 0], every=10, tol=1e-4)
    assert res.contacts == ("floor/leg0", "floor/leg1")
    landed = [s for s in res.samples if _gap2(model, s["qpos"]) <= 1e-4]
    assert landed and res.samples[0]["verdicts"] is not None
    for s in landed:
        assert s["verdicts"] is None, s["t"]
        if any(s["touching"]):
            assert s["why"].startswith("model: floor/leg2 touches at this state"), s
    assert any(any(s["touching"]) for s in landed)
