"""atlas.core.rigid_body: B and a of real bodies (closed forms by hand), scalings, verdicts, errors."""

from __future__ import annotations

import math

import mpmath
import numpy as np
import pytest
import sympy

import atlas
from atlas.core import contact_modes
from atlas.core.rigid_body import CONTACT_KINDS, Mechanism, verdict_names, verdicts_at

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
        kind1=str(rng.choice(CONTACT_KINDS)),
        kind2=str(rng.choice(CONTACT_KINDS)),
        k1=rng.uniform(1e4, 1e6),
        k2=rng.uniform(1e4, 1e6),
        c1=rng.uniform(0, 50),
        c2=rng.uniform(0, 50),
        F=tuple(rng.uniform(-5, 5, 2)),
        tau=rng.uniform(-1, 1),
        speed=rng.uniform(0, 2),
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

    Gravity alone: a_i = -n_i.g, a = (g, 0).  Sliding: the foot at x = L c moves at
    x' = -L s theta' = v, so the ladder turns at w = -theta' = v / (L s), and a_i += w^2 n_i.r_i:
    a = (g - w^2 l s, -w^2 l c) (both contacts are body vertices: no transport term).
    """
    m, L, v = 12.0, 3.0, 0.7
    c, s = math.cos(theta), math.sin(theta)
    w = v / (L * s)
    mu1, mu2 = mu
    lad = Mechanism.ladder(L=L, theta=theta, m=m, mu_floor=mu1, mu_wall=mu2, speed=v)
    assert lad.omega == pytest.approx(w, rel=1e-14) and (lad.s1, lad.s2) == (1, 1)
    assert lad.sliding_speeds[1] == pytest.approx(v * c / s, rel=1e-14)  # the top: y' = L c theta'
    B = np.array(
        [
            [1 + 3 * c * c - 3 * mu1 * s * c, mu2 - 3 * mu2 * c * c - 3 * s * c],
            [-mu1 - 3 * s * c + 3 * mu1 * s * s, 1 + 3 * s * s + 3 * mu2 * s * c],
        ]
    )
    np.testing.assert_allclose(lad.B, B / m, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(lad.a, [G - w * w * L / 2 * s, -w * w * L / 2 * c], rtol=1e-12)
    np.testing.assert_array_equal(lad.replace(speed=0.0).a, [G, 0.0])


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
    """B = J_n M^-1 (J_n - diag(mu s) J_t)^T, a = -(J_n M^-1 [m g + F; tau] - w^2 n.r) (+ 2 w u at a
    body side): the matrix
    route, independent of the scalar formulas (random bodies and the leaning rod)."""
    rng = np.random.default_rng(1)
    bodies = [_random_body(rng) for _ in range(20)] + [Mechanism.leaning_rod()]
    for b in bodies:
        Jn, Jt, Minv = b.normal_jacobian, b.tangent_jacobian, np.linalg.inv(b.generalized_mass)
        W = Jn - np.diag([b.mu1 * b.s1, b.mu2 * b.s2]) @ Jt
        np.testing.assert_allclose(b.B, Jn @ Minv @ W.T, rtol=1e-11, atol=1e-13)
        load = np.array([b.m * b.g[0] + b.F[0], b.m * b.g[1] + b.F[1], b.tau])
        nr = [np.dot(b.n1, b.r1), np.dot(b.n2, b.r2)]
        side = [k == "body_side" for k in (b.kind1, b.kind2)]
        transport = 2 * b.omega * np.array(b.sliding_speeds) * side
        a = -(Jn @ Minv @ load - b.omega**2 * np.array(nr)) + transport
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
        speed=rt * b.speed,
    )
    gravity = b.replace(
        g=tuple(lam * x for x in b.g),
        F=tuple(lam * f for f in b.F),
        tau=lam * b.tau,
        speed=rt * b.speed,
    )
    contact = b.replace(k1=lam * b.k1, k2=lam * b.k2, c1=rt * b.c1, c2=rt * b.c2)
    return {"mass": mass, "length": length, "gravity": gravity, "contact": contact}


def _same_verdicts(u, v):
    for k in verdict_names():
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
            kind1=b.kind2, kind2=b.kind1, k1=b.k2, k2=b.k1, c1=b.c2, c2=b.c1,
            speed=abs(b.sliding_speeds[1]),
        )  # fmt: skip
        inv, dual = b.invariants, sw.invariants
        want = contact_modes.dual_angles(inv["beta1"], inv["beta2"], inv["alpha"])
        got = (dual["beta1"], dual["beta2"], dual["alpha"])
        np.testing.assert_allclose(np.cos(got), np.cos(want), atol=1e-12)
        np.testing.assert_allclose(np.sin(got), np.sin(want), atol=1e-12)
        assert dual["kappa"] == pytest.approx(1 / inv["kappa"], rel=1e-12)
        assert dual["q1"] == pytest.approx(inv["q2"] / math.sqrt(inv["kappa"]), rel=1e-12)
        assert dual["q2"] == pytest.approx(inv["q1"] / math.sqrt(inv["kappa"]), rel=1e-12)


def _generate(inv):
    scene = atlas.Scene(**inv, outputs=verdict_names())
    return atlas.generate(scene)


def test_verdicts_equal_generate_at_the_invariants():
    rng = np.random.default_rng(5)
    bodies = [Mechanism.ladder(), Mechanism.two_legged(), Mechanism.leaning_rod()]
    bodies += [Mechanism.ladder(theta=0.6, mu_floor=1.9, c1=5.0, c2=5.0)]
    bodies += [_random_body(rng) for _ in range(6)]
    for b in bodies:
        ds, got = _generate(b.invariants), b.verdicts()
        for k in verdict_names():
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
        assert all(one[k][()] == res[k][i, j] for k in verdict_names() if k != "spectral_abscissa")
    b = Mechanism.ladder(theta=0.6, mu_floor=1.9)
    v32, v64 = b.verdicts("float32"), b.verdicts()
    assert all(v32[k] == v64[k] for k in verdict_names() if k != "spectral_abscissa")


def test_paradox_of_the_ladder_is_seen():
    """A steep-friction ladder at tan(theta) = 2 with mu_floor = 1.9: b11 < 0 (SF unstable)."""
    v = Mechanism.ladder(theta=math.atan(2.0), mu_floor=1.9).verdicts()
    assert not v["stable_SF"] and Mechanism.ladder().verdicts()["stable_SF"]


def test_invariants_match_the_data_layer_copy():
    """Physical (k, q, |b|) -> (kappa, q1, q2): the paper's Fig. 2 numbers."""
    args = dict(k1=100.0, k2=200.0, q1=20.0, q2=20.0, b1=1.0, b2=1.0)
    got = contact_modes.invariants(**args)
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
        (dict(speed=-1.0), "speed"),
        (dict(kind2="edge"), "kind2"),
        (dict(s1=(1.0, 0.1)), "s1"),  # not tangent to the floor
        (dict(s2=-1), "s2"),  # two legs on a floor translate: s2 = s1
        (dict(r1=(0.0, 1.0), r2=(0.0, -1.0), n2=(0.0, -1.0)), "s2"),  # one normal line: give s2
        (dict(r1=(0.0, 1.0), r2=(0.0, -1.0), n2=(0.0, -1.0), s2=1, speed=1.0), "speed"),
        (dict(n2=(1.0, 0.0)), "s1"),  # the only twist turns about contact 1
        (dict(m=True), "m"),  # a boolean is not a mass
        (dict(m="1"), "m"),  # nor is a string
        (dict(I=1 + 2j), "I"),
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


# --- admissible sliding: the exact null space of the contact Jacobian -------------------------


def _sympy_sliding(body):
    """``(sign u1, sign u2)`` along the rational null space of J (sympy, on the float inputs taken
    exactly), oriented so that contact 1 slides along ``s1``; ``None`` for a 2-D twist space."""
    q = sympy.Rational
    J, T = [], []
    for r, n in ((body.r1, body.n1), (body.r2, body.n2)):
        (rx, ry), (nx, ny) = (q(x) for x in r), (q(x) for x in n)
        J.append([nx, ny, rx * ny - ry * nx])
        T.append([ny, -nx, rx * (-nx) - ry * ny])
    null = sympy.Matrix(J).nullspace()
    if len(null) != 1:
        return None
    u = [sympy.sign((sympy.Matrix([row]) * null[0])[0]) for row in T]
    return body.s1, int(u[1] * u[0] * body.s1)


def _builtin_bodies():
    bodies = [Mechanism.ladder(), Mechanism.two_legged(), Mechanism.leaning_rod()]
    for th in np.linspace(0.02, 0.48, 5) * np.pi:
        bodies += [Mechanism.ladder(theta=th, L=2.5), Mechanism.leaning_rod(theta=th, e=-0.3)]
    bodies += [Mechanism.two_legged(h=h, d=0.4) for h in (0.0, 0.05, 2.0)]
    return bodies + [Mechanism.leaning_rod(e=e, L=2.0) for e in (-0.99, 0.0, 0.99)]


def test_builtin_sliding_is_the_exact_null_space():
    """Every built-in body slides as its docstring says (s1 = s2 = +1), and that pair is the one
    the exact twist null space gives."""
    for b in _builtin_bodies():
        assert _sympy_sliding(b) == (b.s1, b.s2) == (1, 1), b


def test_random_bodies_derive_the_null_space_pair_and_refuse_the_other():
    rng = np.random.default_rng(6)
    for _ in range(25):
        b = _random_body(rng)
        assert _sympy_sliding(b) == (b.s1, b.s2)
        assert b.replace(s2=b.s2).s2 == b.s2  # the admissible pair given explicitly
        with pytest.raises(ValueError, match=r"^s2: inadmissible pair") as err:
            b.replace(s2=-b.s2)
        assert "\n" not in str(err.value)
        flipped = b.replace(s1=-b.s1)  # the common flip is the same line of twists
        assert (flipped.s1, flipped.s2) == (-b.s1, -b.s2)


def test_sliding_speeds_keep_both_contacts_closed():
    """The state's twist has zero normal speed at both contacts, contact 1 slides at ``speed``
    along ``s1``, and contact 2's speed has the sign ``s2``."""
    rng = np.random.default_rng(7)
    for b in [_random_body(rng) for _ in range(10)] + _builtin_bodies()[:3]:
        b = b.replace(speed=1.5)
        nu = np.array(b.twist)
        np.testing.assert_allclose(b.normal_jacobian @ nu, 0.0, atol=1e-12)
        u = b.tangent_jacobian @ nu
        np.testing.assert_allclose(u, b.sliding_speeds, rtol=1e-12, atol=1e-14)
        assert u[0] == pytest.approx(1.5 * b.s1) and np.sign(u[1]) == b.s2


def test_one_normal_line_takes_any_pair_at_zero_speed():
    """Contacts on one normal line (a body squeezed between two parallel surfaces): J has rank 1,
    the sliding speeds are independent, every given pair is accepted (only at zero speed)."""
    base = dict(m=1.0, I=0.5, r1=(0.0, 1.0), r2=(0.0, -1.0), n1=(0.0, -1.0), n2=(0.0, 1.0))
    base["mu1"] = base["mu2"] = 0.5
    assert _sympy_sliding(Mechanism(**base, s2=1)) is None
    for s1 in (1, -1):
        for s2 in (1, -1):
            b = Mechanism(**base, s1=s1, s2=s2)
            assert (b.s1, b.s2) == (s1, s2) and b.twist == (0.0, 0.0, 0.0)


# --- contact kinds: a is minus the gap's second derivative along the free motion ----------------


def _gap_second_derivative(b, h="1e-12"):
    """``(d1'', d2'')`` and ``(d1', d2')`` by central differences (50 digits) of the gap functions
    along the exact free motion from the state (gravity, F and tau, no contact force): centre of
    mass ``v t + acc t^2/2``, angle ``omega t + (tau/I) t^2/2``.  Geometry only: a body vertex keeps
    its body point on the fixed line ``n . p = n . r``; a body side keeps its line through the
    body point at the fixed vertex ``e = r``, with the normal turning with the body."""
    mp = mpmath.mp.clone()
    mp.dps = 50
    F = mp.mpf
    vx, vy, w = (F(x) for x in b.twist)
    acc = [F(b.g[k]) + F(b.F[k]) / F(b.m) for k in (0, 1)]
    spin = F(b.tau) / F(b.I)

    def gaps(t):
        xc = (vx * t + acc[0] * t * t / 2, vy * t + acc[1] * t * t / 2)
        phi = w * t + spin * t * t / 2
        c, s = mp.cos(phi), mp.sin(phi)
        rot = lambda p: (c * F(p[0]) - s * F(p[1]), s * F(p[0]) + c * F(p[1]))  # noqa: E731
        out = []
        for r, n, kind in ((b.r1, b.n1, b.kind1), (b.r2, b.n2, b.kind2)):
            q = [xc[k] + rot(r)[k] for k in (0, 1)]  # the body point at the contact at t = 0
            if kind == "body_vertex":
                out.append(sum(F(n[k]) * (q[k] - F(r[k])) for k in (0, 1)))
            else:
                nt = rot(n)
                out.append(sum(nt[k] * (q[k] - F(r[k])) for k in (0, 1)))
        return out

    h = F(h)
    lo, mid, hi = gaps(-h), gaps(F(0)), gaps(h)
    d2 = [float((hi[j] - 2 * mid[j] + lo[j]) / (h * h)) for j in (0, 1)]
    d1 = [float((hi[j] - lo[j]) / (2 * h)) for j in (0, 1)]
    return np.array(d2), np.array(d1)


@pytest.mark.parametrize("speed", [0.0, 0.3, 1.0, 4.0])
def test_a_is_minus_the_gap_second_derivative(speed):
    """For both contact kinds and several angular velocities: ``a = -d''`` without contact
    forces, with the contacts closed to first order (``d' = 0``) along the admissible twist."""
    rng = np.random.default_rng(8)
    bodies = [Mechanism.ladder(), Mechanism.leaning_rod(), Mechanism.two_legged()]
    bodies += [Mechanism.leaning_rod(theta=1.2, e=-0.2, mu_edge=1.5)]
    bodies += [
        _random_body(rng, kind1=k1, kind2=k2) for k1 in CONTACT_KINDS for k2 in CONTACT_KINDS
    ]
    omegas = set()
    for b in bodies:
        b = b.replace(speed=speed)
        omegas.add(round(b.omega, 6))
        d2, d1 = _gap_second_derivative(b)
        np.testing.assert_allclose(b.a, -d2, rtol=1e-10, atol=1e-11, err_msg=b.name)
        np.testing.assert_allclose(d1, 0.0, atol=1e-12)
    assert len(omegas) > 3 if speed else omegas == {0.0}


def test_edge_transport_term():
    """The leaning rod's edge (a body side): a2 at speed v exceeds the vertex formula by
    ``2 omega u2``; at the 1 m rod's default angle, omega = 2 rad/s makes it about half of a2."""
    rod = Mechanism.leaning_rod(speed=1.0)
    vertex = rod.replace(kind2="body_vertex")
    w, u2 = rod.omega, rod.sliding_speeds[1]
    assert rod.a[1] - vertex.a[1] == pytest.approx(2 * w * u2, rel=1e-12) and w * u2 > 0
    assert rod.a[0] == vertex.a[0]


def test_zero_speed_limit():
    """speed = 0: the static free acceleration ``a_i = -(n_i . acc + (r_i x n_i) tau / I)`` for
    every contact kind (the velocity terms vanish), and the limit of small speeds."""
    rng = np.random.default_rng(9)
    for b in [_random_body(rng) for _ in range(8)] + _builtin_bodies()[:3]:
        b0 = b.replace(speed=0.0)
        acc = np.add(b.g, np.divide(b.F, b.m))
        want = [
            -(np.dot(n, acc) + (r[0] * n[1] - r[1] * n[0]) * b.tau / b.I)
            for r, n in ((b.r1, b.n1), (b.r2, b.n2))
        ]
        np.testing.assert_allclose(b0.a, want, rtol=1e-13, atol=1e-13)
        assert b0.omega == 0.0 and b0.sliding_speeds == (0.0, 0.0)
        np.testing.assert_allclose(b.replace(speed=1e-7).a, b0.a, rtol=1e-12, atol=1e-12)
