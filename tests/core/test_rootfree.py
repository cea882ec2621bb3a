"""Root-free certified verdicts (atlas.core.rootfree) against the exact tier and closed forms."""

import collections
import functools
import re

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from atlas.core import buckets, enclosures, exact, hardcases, hurwitz, points, rootfree
from atlas.core.contact_modes import direction
from atlas.core.invariants import KEYS
from atlas.core.signs import UNKNOWN
from atlas.core.verdicts import Verdict

NAMES = ("stable_SS", "consistent_II", "stable_II")
#: the driver's programs (one compilation per process, shared with every test that runs it):
#: the flat first pass and tier 2 (two compiled programs inside, not to be jitted as one)
_codes = points._kernel("codes", ss=True, ii=True, damped=None)
_tier2 = points._kernel("tier2", ss=True, ii=True)


def kernel_verdicts(pts, dtype):
    """First pass + tier 2 exactly as the driver chains them (no roots, no exact tier): the
    first pass in ``dtype`` on flat columns of the driver's small length (``points.FLAT_SMALL``:
    the program of every small point set; the kernel is elementwise, so the batch length does
    not change a verdict's certificate), tier 2 in ``points.LATER_DTYPE`` (an exact conversion)
    in batches of ``points.LATER_BATCH``."""
    cols = np.broadcast_arrays(*(np.atleast_1d(np.asarray(pts[k], dtype)) for k in KEYS))
    first = list(rootfree.unpack(_chunked(lambda *a: (_codes(*a),), cols, points.FLAT_SMALL)[0]))
    idx = np.flatnonzero(first[3])
    if idx.size:
        later = [c[idx].astype(points.LATER_DTYPE) for c in cols]
        second = _chunked(_tier2, later, points.LATER_BATCH)
        for a, b in zip(first[:3], second):
            a[idx] = np.where(a[idx] == 3, b, a[idx])
    return dict(zip(NAMES, first[:3])), cols


def _chunked(kernel, cols, length):
    """``kernel`` (returning a tuple of per-point arrays) on the columns in batches of
    ``length`` points, the last one padded by repeating its first point."""
    outs = []
    for start in range(0, cols[0].size, length):
        part = [c[start : start + length] for c in cols]
        n = part[0].size
        args = [jnp.asarray(np.concatenate([c, np.full(length - n, c[0], c.dtype)])) for c in part]
        outs.append([np.asarray(r)[:n] for r in kernel(*args)])
    return [np.concatenate(parts) for parts in zip(*outs)]


def assert_agrees_with_exact(pts, dtype, label, min_decided=0.5):
    got, cols = kernel_verdicts(pts, dtype)
    ref = exact.resolve(dict(zip(KEYS, (c.astype(np.float64) for c in cols))), names=NAMES)
    for k in NAMES:
        decided = got[k] != 3
        bad = np.flatnonzero(decided & (got[k] != ref[k]))
        assert bad.size == 0, (label, k, [[float(c[i]) for c in cols] for i in bad[:3]])
        assert decided.mean() >= min_decided, (label, k, decided.mean())


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
@pytest.mark.parametrize("name", list(hardcases.SUITES))
def test_hard_suites_agree_with_exact(name, dtype):
    assert_agrees_with_exact(hardcases.suite(name, dtype), dtype, name, min_decided=0.0)


def _random(rng, n, dtype, q1_zero=False, q2_zero=False, span=1.0):
    b1, b2 = rng.uniform(0, 2 * np.pi, (2, n)).astype(dtype)
    c1, s1 = direction(b1, dtype)
    c2, s2 = direction(b2, dtype)
    kap, q1, q2 = 10 ** rng.uniform(-span, span, (3, n))
    q1 = np.zeros(n) if q1_zero else q1
    q2 = np.zeros(n) if q2_zero else q2
    return dict(c1=c1, s1=s1, c2=c2, s2=s2, kappa=kap, q1=q1, q2=q2)


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
@pytest.mark.parametrize(
    "case",
    [
        dict(),  # q1 != q2, ratios within 10
        dict(q1_zero=True),
        dict(q2_zero=True),
        dict(span=12.0),  # kappa, q1, q2 from 1e-12 to 1e12
    ],
)
def test_random_damped_agree_with_exact(case, dtype):
    rng = np.random.default_rng([7, len(case), int(case.get("span", 1)), np.dtype(dtype).itemsize])
    pts = _random(rng, 300, dtype, **case)
    assert_agrees_with_exact(pts, dtype, str(case), min_decided=0.3)


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_axis_grid_agrees_with_exact(dtype):
    """A 16 x 16 beta grid through every axis line (beta = 0, pi/2, ...), one q = 0 or both."""
    g = (np.arange(16) * (2 * np.pi / 16)).astype(dtype)
    B1, B2, K, Q1, Q2 = np.meshgrid(g, g, [0.5, 2.0], [0.0, 0.1], [0.0, 0.2], indexing="ij")
    c1, s1 = direction(B1.ravel(), dtype)
    c2, s2 = direction(B2.ravel(), dtype)
    pts = dict(c1=c1, s1=s1, c2=c2, s2=s2, kappa=K.ravel(), q1=Q1.ravel(), q2=Q2.ravel())
    assert_agrees_with_exact(pts, dtype, "axis grid", min_decided=0.9)
    got, _ = kernel_verdicts(pts, dtype)
    # off the anti-diagonal beta2 = beta1 + pi (where det B ~ 0 needs exact arithmetic in f64)
    # the axis lines and q = 0 planes are decided in closed form
    anti = np.isclose(np.mod(B2.ravel() - B1.ravel(), 2 * np.pi), np.pi, atol=1e-4)
    for k in NAMES:
        assert np.all(got[k][~anti] != 3), k


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_quarter_turn_line_is_decided_with_equal_damping(dtype):
    """On beta2 = beta1 + pi/2, c1 = s2 up to rounding, so A = (c1 - s2) q lies below every error
    bound; with q1 = q2 its sign is that of one rounded difference (exact), and the II verdicts
    are decided by tier 2 at the latest (no root enclosures) in float64, all but a few in float32,
    in agreement with the exact tier (before: 56 % in float64, 65 % in float32)."""
    b1 = np.linspace(0.05, 2 * np.pi - 0.05, 400)
    b1 = b1[np.abs(np.sin(2 * b1)) > 0.05]  # off the axes: beta = k pi / 2
    c1, s1 = direction(b1.astype(dtype), dtype)
    c2, s2 = direction((b1 + np.pi / 2).astype(dtype), dtype)
    pts = dict(c1=c1, s1=s1, c2=c2, s2=s2, kappa=0.5, q1=0.1, q2=0.1)
    least = 1.0 if dtype == np.float64 else 0.99
    assert_agrees_with_exact(pts, dtype, "beta2 = beta1 + pi/2", min_decided=least)


@pytest.mark.parametrize("q", [0.1, 0.5, 1.0, 0.0])
def test_double_root_diagonal(q):
    """b1 = (-1, 0), b2 = (0, -1), kappa = 1, q1 = q2: p = (l^2 - 1 - q l)^2, h1 == h2, so the
    positive root is a double II root: consistent, never stable (not simple)."""
    got, _ = kernel_verdicts(
        dict(c1=-1.0, s1=0.0, c2=0.0, s2=-1.0, kappa=1.0, q1=q, q2=q), np.float64
    )
    assert got["consistent_II"][0] == 1
    assert got["stable_II"][0] == Verdict.UNSTABLE


def test_closed_forms_c2_zero():
    """c2 = 0 (b2 = (0, 1)): p = h1 h2; h2 = l^2 + (1 + q2 l) has no root with Re >= 0, h1 has
    one positive root r1 (c1 < 0), strictly dominant; row 2 gives x1 x2 > 0 iff s1 < 0."""
    for beta1, cons in ((1.2 * np.pi, 1), (0.8 * np.pi, 0)):
        c1, s1 = direction(np.float64(beta1), np.float64)
        got, _ = kernel_verdicts(
            dict(c1=c1, s1=s1, c2=0.0, s2=1.0, kappa=0.7, q1=0.1, q2=0.3), np.float64
        )
        assert got["consistent_II"][0] == cons
        assert got["stable_II"][0] == (Verdict.STABLE if cons else Verdict.UNSTABLE)


def test_closed_form_det_zero():
    """det B = 0 exactly: B = [[-1/2, 1/2], [-1/2, 1/2]] (columns b1 = -b2; the formulas hold for
    any B), kappa = 2, q1 = q2 = 0.1: p = l^2 (l^2 + a3 l + a2) with a3 = c1 q1 + s2 q2 = 0 and
    a2 = kappa c1 + s2 = -1/2, roots 0, 0, +-sqrt(1/2).  Every positive root is II iff
    c2 s2 > 0 (true), and sqrt(1/2) is simple and dominant: consistent and stable."""
    got, _ = kernel_verdicts(
        dict(c1=-0.5, s1=-0.5, c2=0.5, s2=0.5, kappa=2.0, q1=0.1, q2=0.1), np.float64
    )
    assert got["consistent_II"][0] == 1
    assert got["stable_II"][0] == Verdict.STABLE


def test_ss_matches_spectral_where_both_decide():
    """SS from the shared signs never contradicts :func:`atlas.core.hurwitz.ss_verdict`."""
    rng = np.random.default_rng(3)
    for dtype in (np.float64, np.float32):
        pts = _random(rng, 8000, dtype, span=6.0)
        pts["q1"][::7] = 0
        got, cols = kernel_verdicts(pts, dtype)
        # in batches of the small bucket (the witness checks' program), as the first pass
        ref = _chunked(lambda *a: (hurwitz.ss_verdict_jit(*a),), cols, buckets.SMALL)[0]
        both = (got["stable_SS"] != 3) & (ref != 3)
        assert np.all(got["stable_SS"][both] == ref[both])
        assert both.mean() > 0.98


def _fusions(jitted, *args):
    """The top-level fusions of the compiled program (XLA's units of code generation)."""
    text = jitted.lower(*args).compile().as_text()
    entry = text[text.index("ENTRY") :]
    return re.findall(r"^\s*(?:ROOT )?%\S+ = (\S+) fusion\(", entry, re.M)


#: the 5-D grid of ``tests/bench/test_model_axes.py`` (:mod:`atlas.bench.model_axes` at 12 x 12
#: beta, 8 kappa, 2 q1, 2 q2, damped) as the driver's first pass takes it (:func:`atlas.core.points._first_pass`): the
#: axes ordered q1, q2, kappa, beta1, beta2 from the outside in, beta padded to 16; per input of
#: ``codes`` its axis and length
_BENCH_GRID = ((3, 16), (3, 16), (4, 16), (4, 16), (2, 8), (0, 2), (1, 2))


@pytest.mark.parametrize("dtype", [jnp.float64, jnp.float32])
def test_first_pass_computes_every_sign_once(dtype):
    """Soundness (module docstring): the compiled first pass is one loop fusion over the points
    (flat columns and the grid layout), so each sign code exists once per point and every
    decision reads that copy.  XLA on CPU drops optimization barriers before fusion; if a new
    XLA splits this program, the test fails and the kernel must be split into programs."""
    x = np.ones(points.FLAT_SMALL, dtype)  # the driver's small flat program (numpy: no op)
    axis = lambda d, n: np.ones([n if i == d else 1 for i in range(5)], dtype)  # noqa: E731
    grid = tuple(axis(d, n) for d, n in _BENCH_GRID)  # the driver's program of that grid
    for damped, args in ((None, (x,) * 7), (True, grid)):
        kern = points._kernel("codes", ss=True, ii=True, damped=damped)
        # model inputs (one value a model, e.g. the exact bits of kappa) and single rows or
        # columns are computed once per model or per axis, not per point
        shape = np.broadcast_shapes(*(a.shape for a in args))
        per_point = [f for f in _fusions(kern, *args) if str(list(shape)).replace(" ", "") in f]
        assert len(per_point) == 1, per_point


def _primitives(fn, *args, **static):
    """How many times each primitive occurs in the traced program of ``fn``."""
    text = str(jax.make_jaxpr(functools.partial(fn, **static))(*args))
    return collections.Counter(re.findall(r"= (\w+)", text))


def test_evaluation_points_are_program_inputs():
    """The shifts of tier 2 and the roots of the enclosure path are computed in one program and
    certified in another, whose only copy is the rounded input: the certifying programs hold no
    Newton iteration (a loop) or root finder (its square roots)."""
    x, i, b = (jax.ShapeDtypeStruct((8,), t) for t in (jnp.float64, jnp.int8, jnp.bool_))
    decide = _primitives(rootfree._tier2_decide, *(x,) * 7, ss=True, ii=True, iters=24)
    dominance = _primitives(rootfree._tier2_dominance, *(x,) * 7, i, i, b, i, x, x)
    loops = ("scan", "while")
    assert sum(decide[k] for k in loops) >= 1 and sum(dominance[k] for k in loops) == 0
    z, zq = jax.eval_shape(enclosures._roots, *(x,) * 7)  # traced only: no program compiled
    roots, radii = (
        _primitives(enclosures._roots, *(x,) * 7),
        _primitives(enclosures._radii, z, zq, *(x,) * 7),
    )
    assert radii["sqrt"] < roots["sqrt"] / 4
    # the driver calls tier 2 as its two programs, never wrapped into one
    assert not hasattr(points._kernel("tier2", ss=True, ii=True), "lower")


def test_float32_sturm_signs_are_the_float64_signs():
    """Float32 inputs get the Sturm and discriminant signs of the float64 evaluation (exact
    conversion): the codes equal those of the same points given in float64."""
    rng = np.random.default_rng(11)
    pts = {
        k: np.asarray(v, np.float32) for k, v in _random(rng, 2000, np.float32, span=1.0).items()
    }
    names = frozenset(rootfree._STURM)
    signs_of = jax.jit(rootfree._signs, static_argnums=len(KEYS))  # as in the kernels
    narrow = signs_of(*(jnp.asarray(pts[k]) for k in KEYS), names)
    wide = signs_of(*(jnp.asarray(pts[k], jnp.float64) for k in KEYS), names)
    for k in names:
        assert np.array_equal(np.asarray(narrow[k]), np.asarray(wide[k])), k
    assert all((np.asarray(wide[k]) != UNKNOWN).mean() > 0.99 for k in names)


def test_counts_never_use_an_uncertified_sign():
    """Self-gating variations: any uncertified code gives NOT_COUNTED, and a difference of two
    counts with one not counted is outside 0..4."""

    @jax.jit  # one program (op by op: 15)
    def counts(one, unk):
        bad, good = rootfree._variations(one, unk, -one), rootfree._variations(one, -one)
        return rootfree._variations(one, -one, one), bad, bad - good, good - bad

    two, bad, *diffs = counts(np.ones(1, np.int32), np.full(1, UNKNOWN, np.int32))
    assert int(two[0]) == 2
    assert int(bad[0]) == rootfree.NOT_COUNTED
    for d in diffs:
        assert not 0 <= int(d[0]) <= 4


def test_pack_roundtrip():
    ss, cons, stab = np.array([0, 1, 2, 3]), np.array([3, 0, 1, 3]), np.array([1, 3, 0, 2])
    flag = np.array([True, False, True, False])
    got = rootfree.unpack(rootfree.pack(ss, cons, stab, flag))
    for i, (a, b) in enumerate(zip(got, (ss, cons, stab, flag, [True, True, False, True]))):
        assert np.array_equal(a, b), i
        assert a.dtype == (bool if i >= 3 else np.int8), i
    # the open bit covers only the outputs asked for
    only_ss = rootfree.unpack(rootfree.pack(ss, cons, stab, flag, ii_asked=False))[4]
    assert only_ss.tolist() == [False, False, False, True]
    only_ii = rootfree.unpack(rootfree.pack(ss, cons, stab, flag, ss_asked=False))[4]
    assert only_ii.tolist() == [True, True, False, True]
