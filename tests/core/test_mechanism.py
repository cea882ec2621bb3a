"""atlas.core.mechanism: B and a of real bodies (closed forms by hand), scalings, verdicts, errors."""

from __future__ import annotations

import math

import numpy as np
import pytest

import atlas
from atlas.core import mechanics
from atlas.core.mechanism import VERDICT_NAMES, Mechanism, verdicts_at

G = 9.81


def _random_body(rng, **kw):
    """A generic body: contacts in [-1, 1]^2, any normals, mu in [0, 2], damped contacts."""
    ang = rng.uniform(0, 2 * np.pi, 2)
    body = dict(
        m=rng.uniform(0.5, 5),
        I=rng.uniform(0.05, 2),
        r1=tuple(rng.uniform(-1, 1, 2)),
        r2=tuple(rng.uniform(-1, 1, 2)),
        n1=(math.cos(ang[0]), math.sin(ang[0])),
        n2=(math.cos(ang[1]), math.sin(ang[1])),
        mu1=rng.uniform(0, 2),
        mu2=rng.uniform(0, 2),
        s1=int(rng.choice([1, -1])),
        s2=int(rng.choice([1, -1])),
        k1=rng.uniform(1e4, 1e6),
        k2=rng.uniform(1e4, 1e6),
        c1=rng.uniform(0, 50),
        c2=rng.uniform(0, 50),
        F=tuple(rng.uniform(-5, 5, 2)),
        tau=rng.uniform(-1, 1),
        omega=rng.uniform(-2, 2),
    )
    body.update(kw)
    return Mechanism(**body)


@pytest.mark.parametrize("theta", [0.3, 1.0, math.atan(2.0), 1.3258])
@pytest.mark.parametrize("mu", [(0.0, 0.0), (0.4, 0.3), (1.5, 0.9)])
def test_ladder_closed_form(theta, mu):
    """Ladder of length L = 2l, mass m, I = m L^2/12 = m l^2/3, angle theta, c = cos, s = sin.

    Foot (contact 1) at r1 = (l c, -l s) on the floor, n1 = (0, 1), t1 = (1, 0), sliding away from
    the wall (s1 = +1): w1 = n1 - mu1 t1 = (-mu1, 1).  Top (contact 2) at r2 = (-l c, l s) on the wall,
    n2 = (1, 0), t2 = (0, -1), sliding down (s2 = +1): w2 = n2 - mu2 t2 = (1, mu2).
    Cross products: r1 x n1 = l c, r2 x n2 = -l s, r1 x w1 = l c - mu1 l s,
    r2 x w2 = -l (mu2 c + s).  With l^2/I = 3/m, b_ij = n_i.w_j/m + (r_i x n_i)(r_j x w_j)/I:

        m b11 = 1 + 3 c^2 - 3 mu1 s c          m b12 = mu2 - 3 mu2 c^2 - 3 s c
        m b21 = -mu1 - 3 s c + 3 mu1 s^2       m b22 = 1 + 3 s^2 + 3 mu2 s c

    Gravity alone: a_i = -n_i.g, a = (g, 0); with angular velocity w, a_i += w^2 n_i.r_i:
    a = (g - w^2 l s, -w^2 l c).
    """
    m, L, w = 12.0, 3.0, 0.7
    c, s = math.cos(theta), math.sin(theta)
    mu1, mu2 = mu
    lad = Mechanism.ladder(L=L, theta=theta, m=m, mu_floor=mu1, mu_wall=mu2, omega=w)
    B = np.array(
        [
            [1 + 3 * c * c - 3 * mu1 * s * c, mu2 - 3 * mu2 * c * c - 3 * s * c],
            [-mu1 - 3 * s * c + 3 * mu1 * s * s, 1 + 3 * s * s + 3 * mu2 * s * c],
        ]
    )
    np.testing.assert_allclose(lad.B, B / m, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(lad.a, [G - w * w * L / 2 * s, -w * w * L / 2 * c], rtol=1e-12)
    np.testing.assert_array_equal(lad.replace(omega=0.0).a, [G, 0.0])


def test_ladder_painleve_threshold():
    """b11 < 0 iff mu1 > (1 + 3 c^2) / (3 s c) (the classical rod, Genot & Brogliato 1999); the
    minimum over theta is 4/3, at tan(theta) = 2."""
    theta = math.atan(2.0)
    for mu, sign in ((4 / 3 - 1e-9, 1), (4 / 3 + 1e-9, -1), (1.0, 1), (2.0, -1)):
        assert np.sign(Mechanism.ladder(theta=theta, mu_floor=mu).B[0, 0]) == sign
    # below 4/3 no angle has Painleve's paradox at the foot
    for theta in np.linspace(0.05, 1.5, 60):
        assert Mechanism.ladder(theta=theta, mu_floor=1.33).B[0, 0] > 0


@pytest.mark.parametrize("mu", [(0.0, 0.0), (0.3, 0.7), (1.8, 1.2)])
def test_two_legged_closed_form(mu):
    """Legs at r1 = (-d, -h), r2 = (d, -h) on the floor, n = (0, 1), t = (1, 0), both sliding along
    +x (s = +1): w_j = (-mu_j, 1), r_j x n = r_jx, r_j x w_j = r_jx - mu_j h.  Hence

        b11 = 1/m + d (d + mu1 h)/I      b12 = 1/m - d (d - mu2 h)/I
        b21 = 1/m - d (d + mu1 h)/I      b22 = 1/m + d (d - mu2 h)/I

    and a = (g, g) under gravity.
    """
    m, I, d, h = 4.0, 0.3, 0.2, 0.45
    mu1, mu2 = mu
    body = Mechanism.two_legged(d=d, h=h, m=m, I=I, mu1=mu1, mu2=mu2)
    B = [
        [1 / m + d * (d + mu1 * h) / I, 1 / m - d * (d - mu2 * h) / I],
        [1 / m - d * (d + mu1 * h) / I, 1 / m + d * (d - mu2 * h) / I],
    ]
    np.testing.assert_allclose(body.B, B, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(body.a, [G, G], rtol=1e-15)


def test_B_from_jacobians():
    """B = J_n M^-1 (J_n - diag(mu s) J_t)^T, a = -(J_n M^-1 [m g + F; tau] - w^2 n.r): the matrix
    route, independent of the scalar formulas (random bodies and the leaning rod)."""
    rng = np.random.default_rng(1)
    bodies = [_random_body(rng) for _ in range(20)] + [Mechanism.leaning_rod()]
    for b in bodies:
        Jn, Jt, Minv = b.normal_jacobian, b.tangent_jacobian, np.linalg.inv(b.generalized_mass)
        W = Jn - np.diag([b.mu1 * b.s1, b.mu2 * b.s2]) @ Jt
        np.testing.assert_allclose(b.B, Jn @ Minv @ W.T, rtol=1e-11, atol=1e-13)
        load = np.array([b.m * b.g[0] + b.F[0], b.m * b.g[1] + b.F[1], b.tau])
        nr = [np.dot(b.n1, b.r1), np.dot(b.n2, b.r2)]
        a = -(Jn @ Minv @ load - b.omega**2 * np.array(nr))
        np.testing.assert_allclose(b.a, a, rtol=1e-11, atol=1e-12)


def test_frictionless_B_symmetric_positive_definite():
    rng = np.random.default_rng(2)
    for _ in range(20):
        B = _random_body(rng, mu1=0.0, mu2=0.0).B
        assert B[0, 1] == pytest.approx(B[1, 0], rel=1e-12)
        assert np.all(np.linalg.eigvalsh((B + B.T) / 2) > 0)


def test_leaning_rod_geometry():
    """The edge normal is perpendicular to the rod, and the sliding vectors give s1 = s2 = +1."""
    rod = Mechanism.leaning_rod(theta=0.4)
    axis = np.subtract(rod.r2, rod.r1)
    assert np.dot(rod.n2, axis) == pytest.approx(0.0, abs=1e-15)
    assert (rod.s1, rod.s2) == (1, 1)


def _inv(b):
    return np.array([b.invariants[k] for k in ("beta1", "beta2", "alpha", "kappa", "q1", "q2")])


def _scalings(b, lam):
    """The four scalings of the module docstring (SPEC §1 invariants)."""
    rt = math.sqrt(lam)
    mass = b.replace(m=lam * b.m, I=lam * b.I, F=tuple(lam * f for f in b.F), tau=lam * b.tau)
    mass = mass.replace(k1=lam * b.k1, k2=lam * b.k2, c1=lam * b.c1, c2=lam * b.c2)
    length = b.replace(
        r1=tuple(lam * x for x in b.r1),
        r2=tuple(lam * x for x in b.r2),
        I=lam * lam * b.I,
        tau=lam * b.tau,
        omega=b.omega / rt,
    )
    gravity = b.replace(
        g=tuple(lam * x for x in b.g),
        F=tuple(lam * f for f in b.F),
        tau=lam * b.tau,
        omega=rt * b.omega,
    )
    contact = b.replace(k1=lam * b.k1, k2=lam * b.k2, c1=rt * b.c1, c2=rt * b.c2)
    return {"mass": mass, "length": length, "gravity": gravity, "contact": contact}


def _same_verdicts(u, v):
    for k in VERDICT_NAMES:
        if k == "spectral_abscissa":
            assert u[k] == pytest.approx(v[k], rel=1e-9, abs=1e-12), k
        else:
            assert u[k] == v[k], k


@pytest.mark.parametrize("lam", [0.01, 3.7, 250.0])
def test_scalings_keep_invariants_and_verdicts(lam):
    rng = np.random.default_rng(3)
    bodies = [_random_body(rng) for _ in range(4)] + [Mechanism.ladder(c1=30.0, c2=10.0)]
    for b in bodies:
        ref, verdicts = _inv(b), b.verdicts()
        for name, scaled in _scalings(b, lam).items():
            np.testing.assert_allclose(_inv(scaled), ref, rtol=1e-10, err_msg=name)
            _same_verdicts(scaled.verdicts(), verdicts)
    # and the scalings are not vacuous: B and a do change under the mass and gravity scalings
    s = _scalings(bodies[0], lam)
    assert not np.allclose(s["mass"].B, bodies[0].B)
    assert not np.allclose(s["gravity"].a, bodies[0].a)


def test_swapped_contacts_give_the_dual():
    """Swapping the contacts swaps rows and columns of B: the dual of SPEC §1."""
    rng = np.random.default_rng(4)
    for _ in range(5):
        b = _random_body(rng)
        sw = b.replace(
            r1=b.r2, r2=b.r1, n1=b.n2, n2=b.n1, mu1=b.mu2, mu2=b.mu1, s1=b.s2, s2=b.s1,
            k1=b.k2, k2=b.k1, c1=b.c2, c2=b.c1,
        )  # fmt: skip
        inv, dual = b.invariants, sw.invariants
        want = mechanics.dual_angles(inv["beta1"], inv["beta2"], inv["alpha"])
        got = (dual["beta1"], dual["beta2"], dual["alpha"])
        np.testing.assert_allclose(np.cos(got), np.cos(want), atol=1e-12)
        np.testing.assert_allclose(np.sin(got), np.sin(want), atol=1e-12)
        assert dual["kappa"] == pytest.approx(1 / inv["kappa"], rel=1e-12)
        assert dual["q1"] == pytest.approx(inv["q2"] / math.sqrt(inv["kappa"]), rel=1e-12)
        assert dual["q2"] == pytest.approx(inv["q1"] / math.sqrt(inv["kappa"]), rel=1e-12)


def _generate(inv):
    scene = atlas.Scene(**inv, outputs=VERDICT_NAMES)
    return atlas.generate(scene)


def test_verdicts_equal_generate_at_the_invariants():
    rng = np.random.default_rng(5)
    bodies = [Mechanism.ladder(), Mechanism.two_legged(), Mechanism.leaning_rod()]
    bodies += [Mechanism.ladder(theta=0.6, mu_floor=1.9, c1=5.0, c2=5.0)]
    bodies += [_random_body(rng) for _ in range(6)]
    for b in bodies:
        ds, got = _generate(b.invariants), b.verdicts()
        for k in VERDICT_NAMES:
            want = ds[k].values[()]
            if k == "spectral_abscissa":
                assert got[k] == pytest.approx(float(want), rel=1e-9, abs=1e-12)
            else:
                assert got[k] == want and np.asarray(got[k]).dtype == ds[k].dtype, (b.name, k)


def test_verdicts_at_broadcasts_and_float32():
    beta1 = np.linspace(0.1, 6.2, 7)
    res = verdicts_at(beta1[:, None], 1.9, np.array([0.4, 3.5]), 0.5, 0.2, 0.3)
    assert all(v.shape == (7, 2) for v in res.values())
    for i, j in ((0, 0), (3, 1), (6, 1)):
        one = verdicts_at(beta1[i], 1.9, [0.4, 3.5][j], 0.5, 0.2, 0.3)
        assert all(one[k][()] == res[k][i, j] for k in VERDICT_NAMES if k != "spectral_abscissa")
    b = Mechanism.ladder(theta=0.6, mu_floor=1.9)
    v32, v64 = b.verdicts("float32"), b.verdicts()
    assert all(v32[k] == v64[k] for k in VERDICT_NAMES if k != "spectral_abscissa")


def test_paradox_of_the_ladder_is_seen():
    """A steep-friction ladder at tan(theta) = 2 with mu_floor = 1.9: b11 < 0 (SF unstable)."""
    v = Mechanism.ladder(theta=math.atan(2.0), mu_floor=1.9).verdicts()
    assert not v["stable_SF"] and Mechanism.ladder().verdicts()["stable_SF"]


def test_invariants_match_the_data_layer_copy():
    """Physical (k, q, |b|) -> (kappa, q1, q2): the paper's Fig. 2 numbers."""
    args = dict(k1=100.0, k2=200.0, q1=20.0, q2=20.0, b1=1.0, b2=1.0)
    got = mechanics.invariants(**args)
    assert got["kappa"] == 0.5 and got["q1"] == pytest.approx(math.sqrt(2))  # paper Fig. 2


_BASE = dict(m=1.0, I=1.0, r1=(1.0, -1.0), r2=(-1.0, -1.0), n1=(0.0, 1.0), n2=(0.0, 1.0))


@pytest.mark.parametrize(
    "change, name",
    [
        (dict(m=0.0), "m"),
        (dict(m=-1.0), "m"),
        (dict(I=0.0), "I"),
        (dict(m=float("nan")), "m"),
        (dict(I=float("inf")), "I"),
        (dict(n1=(0.0, 0.0)), "n1"),
        (dict(n2=(0.0,)), "n2"),
        (dict(r2=(1.0, -1.0)), "r2"),
        (dict(r1=(float("nan"), 0.0)), "r1"),
        (dict(mu1=-0.1), "mu1"),
        (dict(mu2="x"), "mu2"),
        (dict(k1=0.0), "k1"),
        (dict(k2=-5.0), "k2"),
        (dict(c1=-1.0), "c1"),
        (dict(s1=0), "s1"),
        (dict(s2=(0.0, 1.0)), "s2"),
        (dict(g=(0.0, float("inf"))), "g"),
        (dict(tau=float("nan")), "tau"),
    ],
)
def test_one_line_errors(change, name):
    with pytest.raises(ValueError) as err:
        Mechanism(**{**_BASE, **change})
    msg = str(err.value)
    assert msg.startswith(f"{name}: ") and "\n" not in msg


def test_zero_free_acceleration_is_an_error():
    body = Mechanism(**_BASE, g=(0.0, 0.0))
    with pytest.raises(ValueError, match=r"^a: "):
        _ = body.invariants
