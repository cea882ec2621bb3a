"""atlas.bridges.mujoco: MJCF versions of the built-in bodies give the planar closed forms' B and a
(plus the rolling term of their rounded vertices, a closed form), the contact model's mapping
against MuJoCo's own contact dynamics, contact selection and its one-line errors."""

from __future__ import annotations

import math
import sys

import numpy as np
import pytest

from atlas.core.rigid_body import Mechanism

mujoco = pytest.importorskip("mujoco", reason="the mujoco extra is not installed")

from mjcf_bodies import mjcf  # noqa: E402

from atlas.bridges import mujoco as bridge  # noqa: E402

RHO = 0.01  # rounding radius of the MJCF vertices [m]

BODIES = [
    (Mechanism.ladder(speed=0.7), False),
    (Mechanism.ladder(theta=0.4, mu_floor=1.9, mu_wall=0.2, speed=2.0), True),
    (Mechanism.two_legged(speed=0.5), True),
    (Mechanism.two_legged(mu1=1.2, mu2=2.5, speed=1.5, s1=-1), False),
    (Mechanism.leaning_rod(speed=0.5), False),
    (Mechanism.leaning_rod(theta=1.2, e=-0.2, mu_edge=1.5, speed=3.0), True),
]


def _model(body, free):
    text, qvel = mjcf(body, rho=RHO, free=free)
    return mujoco.MjModel.from_xml_string(text), qvel


@pytest.mark.parametrize("body, free", BODIES, ids=lambda x: getattr(x, "name", str(x)))
def test_builtin_bodies_reproduce_the_closed_forms(body, free):
    """B to rounding; a = the closed form + rho omega^2 (the rounded vertex rolls, mjcf_bodies),
    to the finite-difference error of the velocity term (1e-9); planar joints and a free joint."""
    model, qvel = _model(body, free)
    res = bridge.contact_data(model, qvel=qvel, contacts="c1,c2")
    np.testing.assert_allclose(res.space.B, body.B, rtol=0, atol=1e-13 * np.abs(body.B).max())
    a_ref = body.a + RHO * body.omega**2
    np.testing.assert_allclose(res.space.a, a_ref, rtol=0, atol=1e-9 * np.abs(a_ref).max())
    np.testing.assert_allclose(res.speeds, np.abs(body.sliding_speeds), rtol=1e-12)
    assert res.space.names == tuple(c.name for c in res.contacts) and res.space.approximate_model


def test_verdicts_that_do_not_depend_on_the_model_match():
    """Classes, consistency, lift-off and jams of the MJCF ladder equal the planar body's (the
    contact model differs: MuJoCo's approximate (k, c))."""
    for theta, mu in ((1.1, 1.6), (0.5, 0.3), (1.3, 0.9)):
        body = Mechanism.ladder(theta=theta, mu_floor=mu, mu_wall=0.3, speed=0.2)
        model, qvel = _model(body, False)
        got = bridge.contact_data(model, qvel=qvel, contacts="c1,c2").verdicts()
        want = body.verdicts()  # MuJoCo adds the rolling term rho omega^2 to a (~1e-4)
        keys = [k for k in want if k.startswith(("consistent_", "class", "subclass"))]
        keys = [k for k in keys if k != "consistent_II"] + ["stable_SF", "stable_FS"]
        assert {k: got[k] for k in keys} == {k: want[k] for k in keys}


def test_automatic_choice_and_single_contact():
    """Two touching contacts are taken automatically; a body on one contact (the ladder moved
    0.1 m off the wall) gets the one-contact verdicts (a rod on its tip: b11 > 0 at mu = 0.5,
    sliding consistent and stable)."""
    body = Mechanism.ladder(speed=0.7)
    model, qvel = _model(body, False)
    auto = bridge.contact_data(model, qvel=qvel)
    assert [c.name for c in auto.contacts] == ["surf1/c1", "surf2/c2"]
    one = bridge.contact_data(model, qpos=[0.1, 0, 0], qvel=qvel, contacts="c1")
    assert one.space.n_contacts == 1
    assert one.space.B[0, 0] == pytest.approx(body.B[0, 0], rel=1e-13)
    assert one.verdicts() == {
        "consistent_F": False, "consistent_S": True, "stable_S": True, "consistent_I": False,
    }  # fmt: skip


def _three_legs(xs=(-0.3, 0.0, 0.3)):
    legs = " ".join(
        f'<geom name="leg{i}" type="sphere" size="0.01" pos="{x} 0 -0.49"/>'
        for i, x in enumerate(xs)
    )
    return mujoco.MjModel.from_xml_string(
        f"""<mujoco><worldbody><geom name="floor" type="plane" size="0 0 1" pos="0 0 -0.5"/>
        <body name="b" pos="0 0 0"><freejoint/><geom type="box" size="0.4 0.1 0.05"
        contype="0" conaffinity="0"/>{legs}</body></worldbody></mujoco>"""
    )


@pytest.mark.parametrize(
    "case, contacts, qpos_dz, pattern",
    [
        ("three", None, 0.0, r"^model: 3 contacts touch at this state \(floor/leg0, floor/leg1, f"),
        ("choose two", "leg0,leg2", 0.0, r"^model: 3 contacts touch at this state \(floor/leg0, "),
        ("zero", None, 0.2, r"^contacts: no two geoms touch at this state"),
        ("name", "leg0,nothing", 0.0, r"^contacts: 'nothing' does not touch anything"),
        ("ambiguous", "floor", 0.0, r"^contacts: 'floor' matches 3 contacts"),
        ("same", "leg0,leg0/floor", 0.0, r"^contacts: .* are the same contact"),
        ("static", "leg0,leg1", 0.0, r"^qvel: contact floor/leg0 does not slide"),
    ],
)
def test_contact_choice_errors(case, contacts, qpos_dz, pattern):
    model = _three_legs((-0.3, 0.3) if case == "static" else (-0.3, 0.0, 0.3))
    qpos = model.qpos0.copy()
    qpos[2] += qpos_dz
    with pytest.raises(ValueError, match=pattern) as err:
        bridge.contact_data(model, qpos=qpos, contacts=contacts)
    assert "\n" not in str(err.value)


def test_one_of_two_touching_contacts_is_refused():
    """Both ends of the ladder touch: choosing one would drop the other's force (the theory covers
    the touching contacts together); the choice of both, in either order, is the answer."""
    model, qvel = _model(Mechanism.ladder(speed=0.7), False)
    with pytest.raises(ValueError, match=r"^model: surf2/c2 touches at this state but is not "):
        bridge.contact_data(model, qvel=qvel, contacts="c1")
    res = bridge.contact_data(model, qvel=qvel, contacts="c2,c1")
    assert [c.name for c in res.contacts] == ["surf2/c2", "surf1/c1"]


def test_bad_state_and_model():
    model = _three_legs()
    with pytest.raises(ValueError, match=r"^qvel: expected 6 finite numbers, got 2$"):
        bridge.contact_data(model, qvel=[1, 2])
    with pytest.raises(ValueError, match=r"^model: cannot load /nonexistent.xml: "):
        bridge.load("/nonexistent.xml")


def test_missing_extra_names_the_install_command(monkeypatch):
    monkeypatch.setitem(sys.modules, "mujoco", None)
    with pytest.raises(ImportError, match=r"^mujoco: .*pip install 'painleve-atlas\[mujoco\]'$"):
        bridge.require()


def test_contact_model_matches_mujocos_contact_dynamics():
    """A frictionless ball resting on a plane, MuJoCo's constraint with constant impedance
    (``solimp = 0.9 0.9``) and ``dampratio = 0.2``: the penetration oscillates with the damped
    frequency of the mapped spring-damper, ``sqrt(k/m - (c/2m)^2)``, measured from MuJoCo's own
    rollout (zero crossings around the rest penetration, dt = 1e-5 s), within 1 %."""
    m = 2.0
    model = mujoco.MjModel.from_xml_string(
        f"""<mujoco><option timestep="1e-5"/><worldbody>
        <geom name="floor" type="plane" size="0 0 1" condim="1" solref="0.01 0.2"
        solimp="0.9 0.9 0.001"/><body name="ball"><joint type="slide" axis="0 0 1"/>
        <geom name="ball" type="sphere" size="0.1" mass="{m}" condim="1" solref="0.01 0.2"
        solimp="0.9 0.9 0.001"/></body></worldbody></mujoco>"""
    )
    data = mujoco.MjData(model)
    data.qpos[0] = 0.1  # touching
    res = bridge.contact_data(model, data, contacts="ball")  # frictionless: no slip needed
    assert res.contacts[0].mu == 0.0 and res.space.B[0, 0] == pytest.approx(1 / m, rel=1e-14)
    k, c = res.space.k[0], res.space.c[0]
    wd = math.sqrt(k / m - (c / (2 * m)) ** 2)
    depth = []
    for _ in range(6000):
        mujoco.mj_step(model, data)
        depth.append(data.qpos[0])
    depth = np.array(depth)
    rest = depth[-2000:].mean()
    x = depth - rest
    ups = np.nonzero((x[:-1] < 0) & (x[1:] >= 0))[0]
    period = np.mean(np.diff(ups)) * 1e-5
    assert len(ups) >= 3 and 2 * math.pi / period == pytest.approx(wd, rel=0.01)


def _xyz(v):
    return " ".join(repr(float(x)) for x in v)


def _quat_matrix(q):
    w, x, y, z = q / np.linalg.norm(q)
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ])  # fmt: skip


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_spatial_body_matches_the_rigid_body_formulas(seed):
    """A free body in 3-D (full inertia tensor, turned, spinning, sliding in any direction) with
    two spheres on two planes: ``b_ij = n_i . w_j / m + (r_i x n_i) . I^-1 (r_j x w_j)`` (``I``
    in world axes, ``w_j = n_j - mu_j t_j``, ``t_j`` the slip direction at the contact point) and
    ``a_i = -n_i . (g + alpha x c_i + omega x (omega x c_i))`` for the sphere centres ``c_i``
    (free rotation: ``alpha = -I^-1 (omega x I omega)``), written here from Newton-Euler."""
    rng = np.random.default_rng(seed)
    m, inertia, rho = 3.0, rng.uniform(0.4, 0.7, 3), 0.02  # A + B >= C
    quat = rng.normal(size=4)
    R = _quat_matrix(quat)
    local = rng.uniform(-0.5, 0.5, (2, 3))
    normals = [np.array([0.0, 0.0, 1.0]), np.array([0.3, -0.4, 0.866])]
    normals[1] /= np.linalg.norm(normals[1])
    mu = rng.uniform(0.1, 1.5, 2)
    centres = [R @ lj for lj in local]  # relative to the centre of mass (at the origin)
    world, parts = [], []
    for j in (0, 1):
        p = centres[j] - rho * normals[j]
        bits = f'contype="{1 << j}" conaffinity="{1 << j}" friction="{float(mu[j])!r} 0 0"'
        world.append(
            f'<geom name="plane{j}" type="plane" size="0 0 1" pos="{_xyz(p)}" '
            f'zaxis="{_xyz(normals[j])}" {bits}/>'
        )
        parts.append(
            f'<geom name="s{j}" type="sphere" size="{rho}" pos="{_xyz(local[j])}" {bits}/>'
        )
    q = _xyz(quat / np.linalg.norm(quat))
    model = mujoco.MjModel.from_xml_string(f"""<mujoco><worldbody>{"".join(world)}
        <body pos="0 0 0" quat="{q}"><freejoint/><inertial pos="0 0 0" mass="{m}"
        diaginertia="{_xyz(inertia)}"/>{"".join(parts)}</body>
        </worldbody></mujoco>""")  # fmt: skip
    qvel = rng.uniform(-1, 1, 6)
    res = bridge.contact_data(model, qvel=qvel, contacts="s0,s1")
    v, omega = qvel[:3], R @ qvel[3:]  # MuJoCo: linear in world, angular in body axes
    Iw = R @ np.diag(inertia) @ R.T
    r = [c - rho * n for c, n in zip(centres, normals)]  # the contact points
    w = []
    for j in (0, 1):
        vel = v + np.cross(omega, r[j])
        t = vel - (normals[j] @ vel) * normals[j]
        w.append(normals[j] - mu[j] * t / np.linalg.norm(t))
    B = np.array([[normals[i] @ w[j] / m
                   + np.cross(r[i], normals[i]) @ np.linalg.solve(Iw, np.cross(r[j], w[j]))
                   for j in (0, 1)] for i in (0, 1)])  # fmt: skip
    alpha = -np.linalg.solve(Iw, np.cross(omega, Iw @ omega))
    g = np.array([0.0, 0.0, -9.81])
    a = [-(n @ (g + np.cross(alpha, c) + np.cross(omega, np.cross(omega, c))))
         for n, c in zip(normals, centres)]  # fmt: skip
    np.testing.assert_allclose(res.space.B, B, rtol=0, atol=1e-13 * np.abs(B).max())
    np.testing.assert_allclose(res.space.a, a, rtol=0, atol=1e-9 * np.abs(a).max())
