"""atlas.core.contact_space: B and a of any mechanism against an independent Lagrangian derivation
(sympy: Euler-Lagrange equations solved for the accelerations, gaps differentiated twice in time),
the planar Mechanism's closed forms, the one-contact verdicts, errors.  The three-rod derivation
is ``slow``: ``python -m pytest -m slow tests/core/test_contact_space.py``."""

from __future__ import annotations

import math

import numpy as np
import pytest
import sympy as sp

from atlas.core.contact_space import ContactSpace, contact_space, single_contact_verdicts
from atlas.core.rigid_body import CONTACT_KINDS, Mechanism

G = 9.81
t = sp.Symbol("t")


def _chain(Ls, ms):
    """A planar chain of uniform links (lengths ``Ls``, masses ``ms``: numbers, so that the
    expressions differentiated below stay small) hinged end to end; link 1 is free (``x, y`` of
    its first end and its angle), each further link adds its angle.  Returns the coordinates as
    functions of ``t``, the kinetic and potential energies, the chain's first and last end points
    (the contact points)."""
    n_links = len(Ls)
    Ls, ms = [sp.Float(x) for x in Ls], [sp.Float(x) for x in ms]
    q = [sp.Function(f"q{i}")(t) for i in range(2 + n_links)]
    joint = sp.Matrix([q[0], q[1]])
    first, T, V = joint, 0, 0
    for i in range(n_links):
        e = sp.Matrix([sp.cos(q[2 + i]), sp.sin(q[2 + i])])
        centre, joint = joint + Ls[i] / 2 * e, joint + Ls[i] * e
        v = centre.diff(t)
        T += ms[i] * (v[0] ** 2 + v[1] ** 2) / 2 + ms[i] * Ls[i] ** 2 / 24 * q[2 + i].diff(t) ** 2
        V += ms[i] * G * centre[1]
    return q, T, V, (first, joint)


def _lagrange_reference(values, state, normals, mu, s):
    """Independent reference and the matrices for the code under test, at one state.

    Reference: the Euler-Lagrange equations with the contact forces' virtual work
    (``f_j (n_j - mu_j s_j t_j) . dp_j``) solved for ``q''`` at the numeric state, the gaps
    ``n_j . p_j(q(t))`` differentiated twice in time: ``B = d(d'')/df``, ``a = -d''(f = 0)``.
    Matrices (a different route, in plain symbols for q and q'): ``M = d^2 T / dq'^2``,
    ``force = dT/dq - dV/dq - M' q'`` (``M' = sum_k dM/dq_k q'_k``),
    ``Jn = dd/dq``, ``Jt = d(t . p)/dq``, ``drift = q'^T (d^2 d / dq^2) q'``."""
    q, T, V, points = _chain(values["L"], values["m"])
    n = len(q)
    qs, vs, acs = sp.symbols(f"x0:{n}"), sp.symbols(f"v0:{n}"), sp.symbols(f"w0:{n}")
    f = sp.symbols("f0:2")
    to_sym = {q[i].diff(t, 2): acs[i] for i in range(n)}
    to_sym.update({q[i].diff(t): vs[i] for i in range(n)})
    to_sym.update({q[i]: qs[i] for i in range(n)})
    # structural replacement, outermost first (a second derivative before the first inside it)
    sub = lambda e: e.xreplace(to_sym)  # noqa: E731
    num = {x: sp.Float(v) for x, v in zip(qs + vs, [*state[0], *state[1]])}
    tang = [sp.Matrix([nj[1], -nj[0]]) for nj in normals]
    gaps = [(sp.Matrix(nj).T * p)[0] for nj, p in zip(normals, points)]
    slides = [(tj.T * p)[0] for tj, p in zip(tang, points)]
    L = T - V
    eqs = []
    for i in range(n):
        gen = sum(f[j] * (gaps[j].diff(q[i]) - mu[j] * s[j] * slides[j].diff(q[i])) for j in (0, 1))
        eqs.append(sub(L.diff(q[i].diff(t)).diff(t) - L.diff(q[i]) - gen).xreplace(num))
    A, rhs = sp.linear_eq_to_matrix(eqs, acs)
    acc = dict(zip(acs, A.LUsolve(rhs)))
    d2 = [sub(g.diff(t, 2)).xreplace(num).xreplace(acc) for g in gaps]
    B_ref = np.array([[float(sp.diff(d, fj)) for fj in f] for d in d2])
    a_ref = -np.array([float(d.subs({f[0]: 0, f[1]: 0})) for d in d2])
    # the matrices for the code under test, in the symbols x (q) and v (q')
    Ts, Vs, qd = sub(T), sub(V), sp.Matrix(vs)
    Msym = sp.hessian(Ts, vs)
    Mdot_qd = sum((Msym.diff(qs[k]) * vs[k] for k in range(n)), sp.zeros(n, n)) * qd
    force = [Ts.diff(qs[i]) - Vs.diff(qs[i]) - Mdot_qd[i] for i in range(n)]
    ev = lambda e: float(e.xreplace(num))  # noqa: E731
    Jn = [[ev(sub(g).diff(x)) for x in qs] for g in gaps]
    Jt = [[ev(sub(u).diff(x)) for x in qs] for u in slides]
    drift = [ev((qd.T * sp.hessian(sub(g), qs) * qd)[0]) for g in gaps]
    mats = dict(
        M=[[ev(x) for x in row] for row in Msym.tolist()],
        Jn=Jn, Jt=Jt, force=[ev(x) for x in force], drift=drift,
    )  # fmt: skip
    return B_ref, a_ref, mats


@pytest.mark.parametrize(
    "n_links, draws", [(1, 1), (2, 1), pytest.param(1, 3, marks=pytest.mark.slow)]
)
def test_any_mechanism_matches_the_lagrangian_derivation(n_links, draws):
    """A free rod (3 DOF) and a two-link chain (4 DOF) with its two ends on two surfaces, sliding,
    spinning: B and a equal the Euler-Lagrange reference to rounding (``draws`` random
    mechanisms; three rods in the ``slow`` case)."""
    rng = np.random.default_rng(40 + n_links)
    for _ in range(draws):
        ang = rng.uniform(0, 2 * np.pi, 2)
        normals = [(math.cos(x), math.sin(x)) for x in ang]
        n = 2 + n_links
        values = dict(L=rng.uniform(0.5, 2, n_links), m=rng.uniform(0.5, 3, n_links))
        state = (rng.uniform(-1, 1, n), rng.uniform(-2, 2, n))
        mu, s = rng.uniform(0, 1.5, 2), rng.choice([-1, 1], 2)
        B_ref, a_ref, mats = _lagrange_reference(values, state, normals, mu, s)
        cs = contact_space(mats["M"], mats["Jn"], mats["Jt"], mu, s, mats["force"], mats["drift"])
        scale = np.abs(B_ref).max()
        np.testing.assert_allclose(cs.B, B_ref, rtol=1e-11, atol=1e-13 * scale)
        np.testing.assert_allclose(cs.a, a_ref, rtol=1e-11, atol=1e-11 * np.abs(a_ref).max())


def _random_body(rng):
    ang = rng.uniform(0, 2 * np.pi, 2)
    return Mechanism(
        m=rng.uniform(0.5, 5), I=rng.uniform(0.05, 2),
        r1=tuple(rng.uniform(-1, 1, 2)), r2=tuple(rng.uniform(-1, 1, 2)),
        n1=(math.cos(ang[0]), math.sin(ang[0])), n2=(math.cos(ang[1]), math.sin(ang[1])),
        mu1=rng.uniform(0, 2), mu2=rng.uniform(0, 2), s1=int(rng.choice([1, -1])),
        kind1=str(rng.choice(CONTACT_KINDS)), kind2=str(rng.choice(CONTACT_KINDS)),
        F=tuple(rng.uniform(-5, 5, 2)), tau=rng.uniform(-1, 1), speed=rng.uniform(0, 2),
    )  # fmt: skip


def test_planar_mechanism_is_one_producer():
    """On 40 random bodies (both contact kinds, moving): the general entry point from the body's
    M = diag(m, m, I), Jacobians, [m g + F; tau] and the velocity terms (-omega^2 n.r at a vertex,
    -omega^2 n.r - 2 omega u at a body side, written here from the geometry) gives the body's
    closed-form B and a to rounding, and the same verdicts."""
    rng = np.random.default_rng(7)
    for _ in range(40):
        b = _random_body(rng)
        w, u = b.omega, b.sliding_speeds
        drift = [
            -(w**2) * np.dot(n, r) - (2 * w * uj if kind == "body_side" else 0.0)
            for r, n, kind, uj in ((b.r1, b.n1, b.kind1, u[0]), (b.r2, b.n2, b.kind2, u[1]))
        ]
        cs = contact_space(
            b.generalized_mass, b.normal_jacobian, b.tangent_jacobian, (b.mu1, b.mu2),
            (b.s1, b.s2), b.generalized_force, drift, k=(b.k1, b.k2), c=(b.c1, b.c2),
        )  # fmt: skip
        np.testing.assert_allclose(cs.B, b.B, rtol=1e-12, atol=1e-14)
        np.testing.assert_allclose(cs.a, b.a, rtol=1e-12, atol=1e-12)
    assert cs.verdicts()["subclass_code"] == b.verdicts()["subclass_code"]


@pytest.mark.parametrize("mu", [0.5, 1.2, 1.4, 3.0])
def test_single_contact_is_painleves_rod(mu):
    """The ladder's foot alone (a rod on a floor at tan(theta) = 2, at rest, gravity into the
    floor): b11 < 0 iff mu > 4/3 (the classical rod, Genot & Brogliato 1999).  Below: sliding is
    consistent and stable; above: sliding inconsistent, a jam (IWC) consistent; lift-off never
    (a1 = g > 0)."""
    lad = Mechanism.ladder(theta=math.atan(2.0), mu_floor=mu)
    cs = contact_space(
        lad.generalized_mass, lad.normal_jacobian[:1], lad.tangent_jacobian[:1], mu, 1,
        lad.generalized_force,
    )  # fmt: skip
    assert cs.n_contacts == 1 and cs.a[0] == pytest.approx(G, rel=1e-15)
    below = mu < 4 / 3
    assert cs.verdicts() == {
        "consistent_F": False, "consistent_S": below, "stable_S": below, "consistent_I": not below,
    }  # fmt: skip


def test_single_contact_lift_off():
    assert single_contact_verdicts(2.0, -1.0) == {
        "consistent_F": True, "consistent_S": False, "stable_S": True, "consistent_I": False,
    }  # fmt: skip


def test_three_contacts_give_B_and_a_but_no_verdicts():
    """Three point contacts of a planar body (a table on three legs): B is 3 x 3, the verdicts
    ask for two contacts in one line naming ``contacts``."""
    M = np.diag([2.0, 2.0, 0.5])
    Jn = [[0, 1, -0.3], [0, 1, 0.0], [0, 1, 0.3]]
    cs = contact_space(M, Jn, force=[0, -2 * G, 0], names=("a", "b", "c"))
    np.testing.assert_allclose(cs.a, [G, G, G])
    assert cs.B.shape == (3, 3)
    with pytest.raises(ValueError, match=r"^contacts: .*got 3 \(a, b, c\): choose the two"):
        cs.verdicts()


@pytest.mark.parametrize(
    "kwargs, name",
    [
        (dict(M=[[1, 0], [0, -1]]), "M"),
        (dict(M=[[1, 0.5], [0, 1]]), "M"),
        (dict(Jn=[[1, 0, 0]]), "Jn"),
        (dict(Jn=np.zeros((0, 2))), "Jn"),
        (dict(mu=-0.1, Jt=[[0, 1]]), "mu"),
        (dict(mu=0.5), "Jt"),
        (dict(s=0), "s"),
        (dict(force=[1, 2, 3]), "force"),
        (dict(drift=[1, 2]), "drift"),
        (dict(k=0.0), "k"),
        (dict(c=-1.0), "c"),
    ],
)
def test_one_line_errors(kwargs, name):
    args = dict(M=np.eye(2), Jn=[[1.0, 0.0]])
    args.update(kwargs)
    M, Jn = args.pop("M"), args.pop("Jn")
    with pytest.raises(ValueError, match=rf"^{name}: [^\n]*$"):
        contact_space(M, Jn, **args)


def test_contact_space_validates_its_own_data():
    with pytest.raises(ValueError, match="^a: expected shape"):
        ContactSpace(np.eye(2), [1.0])
    with pytest.raises(ValueError, match="^B: column b2 is zero"):
        ContactSpace([[1.0, 0.0], [0.0, 0.0]], [1.0, 1.0]).invariants()
