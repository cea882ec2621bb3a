"""Class codes, duals, Table 1 and the single-contact verdicts (paper Sec. 3, App. A-B)."""

import jax.numpy as jnp
import numpy as np
import pytest

from atlas.core import contact_modes as me
from atlas.core import exact, warm
from atlas.core.verdicts import Consistency, Verdict

PI = np.pi


def vec(*angles, dtype=np.float64):
    out = []
    for a in angles:
        c, s = me.direction(np.asarray(a), dtype)
        out += [jnp.asarray(c), jnp.asarray(s)]
    return out


@pytest.mark.parametrize(
    "b1, b2, alpha, expected",
    [
        # paper Fig. 2 caption: a and b belong to subclass 132, d/e to 142 or 143 (Sec. 6.4-6.5)
        (0.2 * PI, 0.65 * PI, 0.35 * PI, 132),
        (0.05 * PI, 0.65 * PI, 0.35 * PI, 132),
        # by hand: beta1 in Q1; pi/2 < pi < beta2 < beta1* -> j = 4; beta1 < alpha < pi/2 -> k = 2
        (0.2 * PI, 1.1 * PI, 0.3 * PI, 142),
        (0.2 * PI, 1.1 * PI, 0.1 * PI, 141),
    ],
)
def test_subclass_codes_of_paper_points(b1, b2, alpha, expected):
    c1, s1, c2, s2, ca, sa = vec(b1, b2, alpha)
    assert int(me.subclass_code(c1, s1, c2, s2, ca, sa)) == expected
    assert int(me.class_code(c1, s1, c2, s2)) == expected // 10


def test_fig2d_e_are_in_class_14():
    for b2 in (1.07 * PI, 1.1 * PI):
        c1, s1, c2, s2, ca, sa = vec(0.15 * PI, b2, 0.2 * PI)
        assert int(me.subclass_code(c1, s1, c2, s2, ca, sa)) in (142, 143)


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_ties_are_degenerate(dtype):
    axes = [0.5 * PI, PI, 1.5 * PI]
    for a in axes:  # beta1 on an axis tie
        c1, s1, c2, s2 = vec(a, 0.3, dtype=dtype)
        assert int(me.class_code(c1, s1, c2, s2)) == 0
    for b in axes:  # beta2 on an axis tie
        c1, s1, c2, s2 = vec(0.3, b, dtype=dtype)
        assert int(me.class_code(c1, s1, c2, s2)) == 0
    c1, s1, c2, s2 = vec(0.3, 0.3, dtype=dtype)  # beta2 = beta1
    assert int(me.class_code(c1, s1, c2, s2)) == 0
    # beta2 = beta1* exactly (opposite vectors)
    assert int(me.class_code(c1, s1, -c1, -s1)) == 0
    # alpha ties
    c1, s1, c2, s2, ca, sa = vec(0.3, 2.0, 0.3, dtype=dtype)
    assert int(me.subclass_code(c1, s1, c2, s2, ca, sa)) == 0
    # beta1 = 0 is not a tie: rank 1 in {0, pi/2, pi, 3pi/2}
    c1, s1, c2, s2 = vec(0.0, 0.3, dtype=dtype)
    assert int(me.class_code(c1, s1, c2, s2)) == 12


def _offset_grid(n):
    return (np.arange(n) + 0.5) * 2 * PI / n


def test_all_144_subclasses_nonempty():
    """Paper Sec. 3: the classification is non-redundant (every subclass occurs)."""
    b = _offset_grid(64)
    a = _offset_grid(96)
    c, s = me.direction(b)
    ca, sa = me.direction(a)
    codes = me.subclass_code(
        jnp.asarray(c)[:, None, None],
        jnp.asarray(s)[:, None, None],
        jnp.asarray(c)[None, :, None],
        jnp.asarray(s)[None, :, None],
        jnp.asarray(ca)[None, None, :],
        jnp.asarray(sa)[None, None, :],
    )
    found = set(np.unique(np.asarray(codes)).tolist()) - {0, -1}
    expected = {100 * i + 10 * j + k for i in range(1, 5) for j in range(1, 7) for k in range(1, 7)}
    assert found == expected


def test_dual_is_an_involution_and_maps_classes():
    rng = np.random.default_rng(1)
    b1, b2, al = rng.uniform(0, 2 * PI, (3, 500))
    c1, s1, c2, s2, ca, sa = vec(b1, b2, al)
    d = me.dual_vectors(c1, s1, c2, s2, ca, sa)
    dd = me.dual_vectors(*d)
    for x, y in zip(dd, (c1, s1, c2, s2, ca, sa)):
        np.testing.assert_array_equal(np.asarray(x), np.asarray(y))
    # angle form and vector form of the dual agree on class codes (away from ties)
    e1, e2, ea = me.dual_angles(b1, b2, al)
    v = vec(e1, e2)
    cc_angle = np.asarray(me.class_code(*v))
    cc_vec = np.asarray(me.class_code(*d[:4]))
    ok = (cc_angle > 0) & (cc_vec > 0)
    assert ok.sum() > 450
    np.testing.assert_array_equal(cc_angle[ok], cc_vec[ok])


def test_codes_and_consistency_agree_with_exact_reference():
    rng = np.random.default_rng(2)
    b1, b2, al = rng.uniform(0, 2 * PI, (3, 300))
    # add near-ties: beta2 within 1 ulp-ish of beta1 and beta1 + pi
    b2[:40] = b1[:40] * (1 + rng.choice([1e-16, 1e-15, 1e-12, 0.0], 40))
    b2[40:80] = np.mod(b1[40:80] + PI, 2 * PI) * (1 + rng.choice([1e-16, 1e-15, 0.0], 40))
    c1, s1, c2, s2, ca, sa = vec(b1, b2, al)
    fast_cls = np.asarray(me.class_code(c1, s1, c2, s2))
    fast_sub = np.asarray(me.subclass_code(c1, s1, c2, s2, ca, sa))
    fast_cons = {k: np.asarray(v) for k, v in me.consistent_modes(c1, s1, c2, s2, ca, sa).items()}
    ref = exact.resolve_codes(*(np.asarray(x) for x in (c1, s1, c2, s2, ca, sa)))
    dec = fast_cls != -1
    np.testing.assert_array_equal(fast_cls[dec], ref["class_code"][dec])
    dec = fast_sub != -1
    np.testing.assert_array_equal(fast_sub[dec], ref["subclass_code"][dec])
    for m in ("FF", "SF", "FS", "SS"):
        dec = fast_cons[m] != Consistency.UNDECIDED
        np.testing.assert_array_equal(fast_cons[m][dec], ref[f"consistent_{m}"][dec])
    print("undecided class codes:", int((fast_cls == -1).sum()), "of", fast_cls.size)


def test_table1_against_force_solution():
    """Appendix A from first principles: solve the constraint equations directly."""
    rng = np.random.default_rng(3)
    b1, b2, al = rng.uniform(0, 2 * PI, (3, 400))
    c1, s1, c2, s2, ca, sa = (np.asarray(x) for x in vec(b1, b2, al))
    cons = {
        k: np.asarray(v)
        for k, v in me.consistent_modes(*map(jnp.asarray, (c1, s1, c2, s2, ca, sa))).items()
    }
    for i in range(400):
        B = np.array([[c1[i], c2[i]], [s1[i], s2[i]]])
        a = np.array([ca[i], sa[i]])
        # SS: B f = a with f > 0
        f = np.linalg.solve(B, a)
        assert cons["SS"][i] == int(np.all(f > 0))
        # SF: f1 = a1/b11 > 0 and d2'' = -a2 + b21 f1 > 0
        f1 = a[0] / B[0, 0]
        assert cons["SF"][i] == int(f1 > 0 and -a[1] + B[1, 0] * f1 > 0)
        f2 = a[1] / B[1, 1]
        assert cons["FS"][i] == int(f2 > 0 and -a[0] + B[0, 1] * f2 > 0)
        assert cons["FF"][i] == int(a[0] < 0 and a[1] < 0)


def test_single_contact_stability_matches_appendix_B():
    """SF stable iff b11 > 0: eigenvalues of [[0, 1], [-b11 k, -b11 q]] (eq. 7)."""
    rng = np.random.default_rng(4)
    for b11 in np.concatenate([rng.uniform(-2, 2, 50), [0.0]]):
        k, q = rng.uniform(0.1, 10), rng.uniform(0.01, 5)
        ev = np.linalg.eigvals(np.array([[0, 1], [-b11 * k, -b11 * q]]))
        v = int(me.stable_SF(jnp.asarray(b11)))
        if b11 > 0:
            assert v == Verdict.STABLE and np.all(ev.real < 0)
        elif b11 < 0:
            assert v == Verdict.UNSTABLE and np.max(ev.real) > 0
            assert np.all(np.abs(ev.imag) == 0)  # saddle: two real eigenvalues of opposite sign
        else:
            assert v == Verdict.NEUTRAL


def test_if_fi_cc_conditions():
    # IF: b11 < 0 and b21 > 0 -> beta1 in the second quadrant (SPEC: the paper prints b12)
    c1, s1 = vec(0.7 * PI)
    assert int(me.consistent_IF(c1, s1)) == 1
    c1, s1 = vec(1.2 * PI)
    assert int(me.consistent_IF(c1, s1)) == 0
    c2, s2 = vec(1.8 * PI)
    assert int(me.consistent_FI(c2, s2)) == 1
    c1, s1, c2, s2 = vec(0.1 * PI, 0.3 * PI)
    assert bool(me.cc_possible(c1, s2))


def test_the_verdicts_are_kept_kernels(tmp_path):
    """Under the kernel cache the public verdicts are kept as exported programs (a later process
    loads them instead of tracing and lowering them again), with the plain jit's results."""
    g = np.linspace(0.1, 6.2, 9)
    c1, s1, c2, s2 = np.cos(g), np.sin(g), np.cos(g[::-1]), np.sin(g[::-1])
    want = np.asarray(me.class_code(c1, s1, c2, s2))
    with warm.kernel_cache(str(tmp_path)):
        got = np.asarray(me.class_code(c1, s1, c2, s2))
    assert list(tmp_path.glob("atlas.core.contact_modes.class_code-*.jaxexport"))
    np.testing.assert_array_equal(got, want)


@pytest.mark.parametrize("jitted", [True, False], ids=["jit", "op-by-op"])
def test_subnormal_components_keep_their_sign(jitted):
    """XLA on CPU reads a subnormal as zero (jitted or not): a component ``-1e-310`` is negative
    exactly, so ``a = (-1e-310, -1)`` makes FF consistent, ``b11 = 1e-310`` SF stable,
    ``b22 = -1e-310`` FS unstable, ``(b11, b21) = (-1e-310, 1)`` IF consistent (paper Table 1,
    Sec. 4.2-4.3); read as zero they were inconsistent, neutral, neutral, inconsistent."""
    from fractions import Fraction

    import jax

    tiny = 1e-310
    assert 0 < Fraction(tiny) < Fraction(float(np.finfo(np.float64).tiny))
    tiny, one = jnp.asarray(tiny), jnp.asarray(1.0)
    c1, s1 = jnp.cos(jnp.asarray(0.3)), jnp.sin(jnp.asarray(0.3))
    cases = [
        (lambda: me.consistent_modes(c1, s1, one, tiny, -tiny, -one)["FF"], 1),
        (lambda: me.consistent_modes(c1, s1, one, tiny, -tiny, -one)["SF"], 0),
        (lambda: me.stable_SF(tiny), int(Verdict.STABLE)),
        (lambda: me.stable_FS(-tiny), int(Verdict.UNSTABLE)),
        (lambda: me.consistent_IF(-tiny, one), 1),
        (lambda: me.consistent_FI(one, -tiny), 1),
        (lambda: me.cc_possible(tiny, tiny), True),
    ]
    for run, want in cases:
        if jitted:
            got = run()
        else:
            with jax.disable_jit():
                got = run()
        assert np.asarray(got).item() == want
