"""The tiered driver (atlas.core.points): broadcasting, gathers, slabs, settlement, diagnostics.

The ``slow`` cases (the op-by-op subnormal run, float32 later tiers, the float32 model axes) run
by hand: ``python -m pytest -m slow tests/core/test_points.py``."""

import contextlib
import functools
from fractions import Fraction as F

import jax.numpy as jnp
import numpy as np
import pytest

from atlas.core import buckets, exact, hurwitz, model_box, points, rootfree, warm
from atlas.core.contact_modes import direction
from atlas.core.invariants import KEYS
from atlas.core.signs import UNKNOWN

FLAGS = ("stable_SS", "consistent_II", "stable_II")


def grid(n=12, dtype=np.float64):
    """A beta grid through the axis lines x kappa x (q1, q2) with zeros, as broadcastable axes."""
    g = np.arange(n) * (2 * np.pi / n)
    c, s = direction(g.astype(dtype), dtype)
    return (
        c[:, None, None, None, None],
        s[:, None, None, None, None],
        c[None, :, None, None, None],
        s[None, :, None, None, None],
        np.array([0.5, 2.0])[:, None, None],
        np.array([0.0, 0.1, 0.3])[:, None],
        np.array([0.0, 0.2]),
    )


@pytest.mark.parametrize("flat_limit", [0, points.FLAT_LIMIT])
def test_broadcast_equals_flat_points(monkeypatch, flat_limit):
    """The grid path (per-axis inputs, gathers by index; small grids as flat columns, or always
    on the grid with ``FLAT_LIMIT = 0``, there in the slabs and padded axes of
    :func:`test_slabs_and_padding`, whose program it shares) equals the same points given flat
    (flat columns)."""
    args = grid(10)
    shape = np.broadcast_shapes(*(a.shape for a in args))
    flat = [np.broadcast_to(a, shape).ravel() for a in args]
    ref = points.spectral_points(*flat, names=FLAGS + ("spectral_abscissa",))
    monkeypatch.setattr(points, "FLAT_LIMIT", flat_limit)
    if not flat_limit:
        monkeypatch.setattr(points, "BLOCK", 50)
    res = points.spectral_points(*args, names=FLAGS + ("spectral_abscissa",))
    st = res.stats
    for k in FLAGS:
        assert res[k].shape == shape
        assert np.array_equal(res[k].ravel(), ref[k]), k
    assert np.allclose(res["spectral_abscissa"].ravel(), ref["spectral_abscissa"])
    assert st["points"] == np.prod(shape) and st["undecided_after"] == 0
    assert set(st["undecided_by_name"]) == set(FLAGS)


def test_settled_points_match_exact():
    """Every verdict after settlement equals the exact tier (independent of the fast tiers)."""
    args = grid(8)
    res = points.spectral_points(*args, names=FLAGS)
    shape = res["stable_SS"].shape
    pts = dict(zip(KEYS, (np.broadcast_to(a, shape).ravel().astype(np.float64) for a in args)))
    ref = exact.resolve(pts, names=FLAGS)
    for k in FLAGS:
        assert np.array_equal(res[k].ravel(), ref[k]), k


def test_slabs_and_padding(monkeypatch):
    """Splitting a large grid into slabs (small BLOCK) and padding axes gives the same verdicts
    as the flat columns of a small grid."""
    args = grid(10)
    ref = points.spectral_points(*args, names=FLAGS, resolve=False)
    monkeypatch.setattr(points, "BLOCK", 50)
    monkeypatch.setattr(points, "FLAT_LIMIT", 0)
    got = points.spectral_points(*args, names=FLAGS, resolve=False)
    for k in FLAGS:
        assert np.array_equal(got[k], ref[k]), k


def test_only_what_is_asked():
    args = grid(6)
    res = points.spectral_points(*args, names=("stable_SS",))
    st = res.stats
    assert set(res) == {"stable_SS"}
    assert st["tier2_points"] >= 0 and st["roots_points"] == 0


def _ii_boundary():
    """Eight points across an II boundary that no fast tier decides, and their model."""
    b1 = np.full(8, 1.1069434970966943) - np.arange(8) * 1.25e-15
    b2 = np.full(8, 4.24853613984915) + np.arange(8) * 1.25e-15
    return (*direction(b1), *direction(b2)), (2.0, 0.1, 0.1)


def test_exact_failure_keeps_point_undecided(monkeypatch):
    """A failing exact tier leaves its points undecided and records them (the undecided points
    here: across an II boundary, :func:`_ii_boundary`)."""

    def broken(points, names=()):
        raise ArithmeticError("no convergence")

    monkeypatch.setattr(exact, "resolve", broken)
    geometry, model = _ii_boundary()
    res = points.spectral_points(*geometry, *model, names=FLAGS)
    st = res.stats
    und = np.zeros(res["stable_SS"].shape, bool)
    for k in FLAGS:
        und |= res[k] == 3
    assert st["undecided_before"] >= 4
    assert st["undecided_after"] == und.sum() == st["undecided_before"]
    assert len(st["exact_failures"]) == st["undecided_after"]


@pytest.mark.parametrize(
    "kw, name", [(dict(names=("nope",)), "names"), (dict(method="lu"), "method")]
)
def test_bad_options(kw, name):
    with pytest.raises(ValueError, match=f"^{name}:"):
        points.spectral_points(*grid(4), **kw)


def test_eig_baseline_shapes():
    res = points.spectral_points(*grid(4), names=FLAGS, method="eig")
    assert all(v.shape == (4, 4, 2, 3, 2) for v in res.values())


def test_scalar_point():
    """One point given as Python scalars (the notebook's click path)."""
    res = points.spectral_points(-1.0, 0.0, 0.0, -1.0, 1.0, 0.1, 0.1, names=FLAGS)
    assert all(v.shape == () for v in res.values())
    assert res["consistent_II"] == 1 and res["stable_II"] == 0  # double root: closed form
    # a point the fast tiers leave (b2 ~ -b1 at 45 degrees: stable_II undecided by the
    # enclosures), found on the 513-point headline grid: settled in place
    c1, s1 = direction(np.array(1.25 * np.pi))
    c2, s2 = direction(np.array(0.25 * np.pi))
    pt = dict(c1=float(c1), s1=float(s1), c2=float(c2), s2=float(s2), kappa=0.5, q1=0.1, q2=0.1)
    res = points.spectral_points(*pt.values(), names=FLAGS)
    st = res.stats
    assert st["undecided_before"] == 1 and st["undecided_after"] == 0
    ref = exact.resolve({k: np.array([v]) for k, v in pt.items()}, names=FLAGS)
    assert all(res[k] == ref[k][0] for k in FLAGS)


def _codes_grid(n=9):
    """Class, subclass and Table 1 codes of the certified fast path on an offset grid."""
    import jax.numpy as jnp

    from atlas.core import contact_modes as mech

    g = (np.arange(n) + 0.5) * (2 * np.pi / n)
    c, s = direction(g)
    ca, sa = direction(np.array(0.7))
    C1, S1, C2, S2 = c[:, None], s[:, None], c[None, :], s[None, :]
    j = [jnp.asarray(a) for a in (C1, S1, C2, S2, ca, sa)]
    codes = {
        "class_code": np.broadcast_to(np.asarray(mech.class_code(*j[:4])), (n, n)).copy(),
        "subclass_code": np.broadcast_to(np.asarray(mech.subclass_code(*j)), (n, n)).copy(),
    }
    modes = mech.consistent_modes(*j)
    codes.update({f"consistent_{m}": np.asarray(modes[m]).copy() for m in ("FF", "SS")})
    codes = {k: np.broadcast_to(v, (n, n)).copy() for k, v in codes.items()}
    return codes, (C1, S1, C2, S2, ca, sa)


def test_settle_codes_restores_certified_codes():
    """Codes blanked to undecided are settled by the exact tier to what the certified fast path
    (an independent implementation: certified float signs, not rationals) had decided."""
    from atlas.core.verdicts import UNDECIDED_CODE, UNDECIDED_FLAG

    ref, args = _codes_grid()
    assert (ref["class_code"] != UNDECIDED_CODE).all()  # the fast path decided every point
    assert len(np.unique(ref["class_code"])) > 10  # degenerate (0) and many classes
    codes = {k: v.copy() for k, v in ref.items()}
    rng = np.random.default_rng(1)
    masks = {k: rng.random(v.shape) < 0.3 for k, v in codes.items()}
    for k, m in masks.items():
        codes[k][m] = UNDECIDED_CODE if k.endswith("_code") else UNDECIDED_FLAG
    st = points.settle_codes(codes, masks, *args)
    anyu = np.logical_or.reduce(list(masks.values()))
    assert st["resolved_points"] == int(anyu.sum()) > 0 and st["exact_failures"] == []
    for k in ref:
        assert np.array_equal(codes[k], ref[k]), k


def test_settle_codes_records_failures_and_keeps_them_undecided():
    from atlas.core.verdicts import UNDECIDED_CODE

    c = np.array([1.0, np.nan])
    s = np.array([0.0, 0.5])
    codes = {"class_code": np.array([UNDECIDED_CODE, UNDECIDED_CODE])}
    masks = {"class_code": np.array([True, True])}
    st = points.settle_codes(codes, masks, c, s, np.array(0.6), np.array(0.8))
    assert st["resolved_points"] == 1 and len(st["exact_failures"]) == 1
    assert codes["class_code"][1] == UNDECIDED_CODE and codes["class_code"][0] > 0
    assert not hasattr(points, "last_counts")  # diagnostics are returned, never a global


def test_small_grids_share_one_compilation():
    """Grids of up to FLAT_LIMIT points run as flat columns of 4096 points: one compiled shape
    for every grid size and output choice (each compilation costs ~1 s, each grid here < 1 ms)."""
    kern = points._kernel("codes", ss=True, ii=True, damped=None)
    before = kern._cache_size()
    for n, names in ((3, FLAGS), (5, FLAGS[:1]), (7, FLAGS[1:]), (11, FLAGS)):
        points.spectral_points(*grid(n), names=names, resolve=False)
    assert kern._cache_size() - before <= 1


def test_flat_columns_pad_with_the_last_point():
    """Columns padded to the small flat batch (512 points), and beyond it to multiples of the
    flat batch (4096)."""
    a, b = np.arange(3.0)[:, None], np.array([10.0, 20.0])
    cols = points._flat_columns([a, b, np.array(5.0)], (3, 2))
    assert [c.shape for c in cols] == [(512,)] * 3 and (cols[2] == 5).all()
    more = points._flat_columns([np.arange(513.0), np.array(5.0)], (513,))
    assert [c.shape for c in more] == [(4096,)] * 2 and more[0][512:].tolist() == [512.0] * 3584
    assert cols[0][:7].tolist() == [0, 0, 1, 1, 2, 2, 2]
    assert cols[1][:7].tolist() == [10, 20, 10, 20, 10, 20, 20]


def _near_singular_points():
    """Damped points on ``b2 ~ -b1`` with ``0 < |det B| < 0.9 u S`` (exact, rational;
    ``S = |c1 s2| + |s1 c2|``): below the error bound of any float evaluation of
    ``c1 s2 - s1 c2`` (with or without a fused multiply-add)."""
    beta = np.linspace(0.1, 3.0, 1000)
    c1, s1 = direction(beta)
    c2, s2 = direction(beta + np.pi)
    u = np.finfo(np.float64).eps / 2
    exact_det = [F(a) * F(d) - F(b) * F(c) for a, b, c, d in zip(c1, s1, c2, s2)]
    scale = np.abs(c1 * s2) + np.abs(s1 * c2)
    keep = np.array([0 < abs(float(d)) < 0.9 * u * m for d, m in zip(exact_det, scale)])
    assert keep.sum() > 40
    pts = dict(c1=c1[keep], s1=s1[keep], c2=c2[keep], s2=s2[keep])
    pts.update(kappa=np.full(keep.sum(), 0.5), q1=0.1, q2=0.1)
    ref = exact.resolve({k: np.broadcast_to(v, (keep.sum(),)) for k, v in pts.items()}, names=FLAGS)
    return pts, ref


def test_near_singular_B_decided_by_the_fast_tiers():
    """``sign det B`` in float64 is exact (integer mantissa products) and tier 2 reads an accurate
    ``D`` (within ``gamma_3``), so the first pass and tier 2 decide every near-singular point, as
    the exact tier does (every damped decision reads ``sign det B``; ``a1``, ``a0`` are
    multiples of ``D``)."""
    pts, ref = _near_singular_points()
    got = points.spectral_points(*pts.values(), names=FLAGS, resolve=False)
    st = got.stats
    assert st["roots_points"] == 0 and st["undecided_after"] == 0
    for k in FLAGS:
        assert np.array_equal(got[k], ref[k]), k


def _unknown_det_sign(c1, *_):
    return jnp.full(jnp.shape(c1), UNKNOWN, jnp.int32)


@functools.cache
def _kernels_without_det_sign():
    """The driver's kernel factory for kernels traced while ``sign det B`` is uncertified: one
    per module, so the tests that patch the sign trace each kernel once, not once a test."""
    return functools.cache(points._kernel.__wrapped__)


def _without_det_sign(monkeypatch):
    """Patch ``sign det B`` to uncertified everywhere (:func:`_unknown_det_sign`); returns the
    kernel factory to use meanwhile (its kernels are traced with the patch, never without)."""
    monkeypatch.setattr(rootfree, "det2_sign", _unknown_det_sign)
    return _kernels_without_det_sign()


@pytest.mark.parametrize("det_known", [True, False])
def test_later_tiers_run_at_one_length_whatever_the_number_of_points(monkeypatch, det_known):
    """Tier 2 (``det B`` certified) and the enclosures (not: simulated) see batches of one
    length whatever the number of points they get, 8, 100 or 500: one program each for every
    caller (an atlas, a paper figure, the explorer's overlay), compiled once per process."""
    pts, _ = _near_singular_points()
    kernel = points._kernel if det_known else _without_det_sign(monkeypatch)
    monkeypatch.setattr(points, "HOST_POINTS", 0)
    seen = {}

    def recording(kind, *a, **k):
        kern = kernel(kind, *a, **k)
        if kind not in ("tier2", "roots"):
            return kern
        return lambda *cols: seen.setdefault(kind, set()).add(cols[0].shape) or kern(*cols)

    monkeypatch.setattr(points, "_kernel", recording)
    cols = [np.broadcast_to(np.asarray(v, np.float64), pts["c1"].shape) for v in pts.values()]
    shape = cols[0].shape
    code = points._first_pass(cols, shape, np.float64, ss=True, ii=True, damped=None)
    pts = {k: v[rootfree.unpack(code)[4]] for k, v in zip(pts, cols)}  # the open points
    tier = "tier2_points" if det_known else "roots_points"
    for n in (8, 100, 500):  # 500: two batches, and the first pass's small flat program
        some = {k: np.resize(v, n) for k, v in pts.items()}
        st = points.spectral_points(*some.values(), names=FLAGS, resolve=False).stats
        assert st[tier] > 0, (n, st)
    (length,) = seen["tier2" if det_known else "roots"]  # one length (the old code: 16, 256, 4096)
    assert length == (points.LATER_BATCH,)


def test_uncertified_det_B_skips_tier_2_and_is_settled_exactly(monkeypatch):
    """Where ``sign det B`` is not certified (an input not a normal number; simulated here
    everywhere), damped points go from the first pass straight to the enclosures: tier 2 could not
    decide them.  The exact tier settles them."""
    pts, ref = _near_singular_points()
    monkeypatch.setattr(points, "_kernel", _without_det_sign(monkeypatch))
    got = points.spectral_points(*pts.values(), names=FLAGS)
    st = got.stats
    assert st["tier2_points"] == 0
    assert st["roots_points"] == len(pts["c1"])
    for k in FLAGS:
        assert np.array_equal(got[k], ref[k]), k


@pytest.mark.parametrize(
    "n, chunk, sizes, lengths",
    [
        (1, 1 << 16, (4096,), [4096]),
        (4696, 1 << 16, (4096,), [4096, 4096]),  # not one batch of 65,536 (14x padding)
        (70000, 1 << 16, (4096,), [1 << 16, 4096, 4096]),
        (100, 64, (16,), [64, 64]),  # never longer than the chunk asked for
        (70, 64, (16,), [64, 16]),
        (1, 256, (256,), [256]),  # the later tiers: one length
        (600, 256, (256,), [256] * 3),
    ],
)
def test_batches_pad_little(n, chunk, sizes, lengths):
    got = list(points._batches(n, chunk, sizes))
    assert [b[2] for b in got] == lengths
    assert got[0][0] == 0 and got[-1][1] == n
    assert all(a[1] == b[0] for a, b in zip(got, got[1:]))


@pytest.mark.parametrize("later", [np.float64, pytest.param(np.float32, marks=pytest.mark.slow)])
def test_later_tiers_run_in_float64(monkeypatch, later):
    """Float32 inputs near ``b2 = -b1`` (directions of the 513-point headline grid): the later
    tiers in float64 (the inputs convert exactly) decide every point without the exact tier; in
    float32 some stay undecided."""
    monkeypatch.setattr(points, "LATER_DTYPE", later)
    beta = np.linspace(0.0, 2 * np.pi, 513)
    i = np.arange(0, 256)
    c1, s1 = direction(beta[i], np.float32)
    c2, s2 = direction(beta[i + 256], np.float32)
    pts = dict(c1=c1, s1=s1, c2=c2, s2=s2, kappa=np.full(i.size, 0.5, np.float32))
    pts.update(q1=np.float32(0.1), q2=np.float32(0.1))
    got = points.spectral_points(*pts.values(), names=FLAGS, dtype="float32", resolve=False)
    st = got.stats
    if later is np.float32:
        assert st["undecided_before"] > 0  # what float64 later tiers settle
        return
    assert st["undecided_before"] == 0
    ref = exact.resolve(
        {k: np.broadcast_to(np.asarray(v, np.float64), i.shape) for k, v in pts.items()},
        names=FLAGS,
    )
    for k in FLAGS:
        assert np.array_equal(got[k], ref[k]), k


def model_grid(n=12, dtype=np.float64):
    """A 5-D grid as ``atlas generate`` lays it out: ``(beta1, beta2, kappa, q1, q2)``, the model
    axes last and short; beta through the axis lines (multiples of pi/6), every model damped.  Its
    padded axes (16 beta values, 8 kappa, 2 q1, 2 q2) are those of the 5-D grid that
    ``tests/bench/test_model_axes.py`` runs through :mod:`atlas.bench.model_axes` (12 beta values,
    8 kappa), so the first pass runs that grid's compiled program."""
    g = np.arange(n) * (2 * np.pi / n)
    c, s = direction(g.astype(dtype), dtype)
    e = lambda a, ax: np.asarray(a, dtype).reshape([-1 if d == ax else 1 for d in range(5)])  # noqa: E731
    return (
        e(c, 0), e(s, 0), e(c, 1), e(s, 1),
        e([0.1, 0.5, 2.0, 5.0, 10.0], 2), e([0.05, 0.2], 3), e([0.0, 0.3], 4),
    )  # fmt: skip


@pytest.mark.parametrize("dtype", [np.float64, pytest.param(np.float32, marks=pytest.mark.slow)])
def test_model_axes_equal_their_slices(monkeypatch, dtype):
    """A 5-D grid (the first pass on the grid layout, model axes broadcast) gives, before and
    after settlement, every verdict of each (kappa, q1, q2) slice computed on its own as a 2-D
    grid with scalar model inputs (flat columns, the driver's shared program), and the tier counts
    add up; the settled verdicts equal the exact tier on a seeded sample."""
    monkeypatch.setattr(points, "HOST_POINTS", 0)  # a slice's handful would skip the later tiers
    args = model_grid(dtype=dtype)
    shape = np.broadcast_shapes(*(a.shape for a in args))
    for resolve in (False, True):
        with pytest.MonkeyPatch.context() as mp:
            mp.setattr(points, "FLAT_LIMIT", 0)  # the 5-D grid on the grid path of the first pass
            res = points.spectral_points(*args, names=FLAGS, dtype=dtype, resolve=resolve)
        tiers = {"tier2_points": 0, "roots_points": 0, "undecided_before": 0}
        for m in np.ndindex(shape[2:]):
            model = [np.broadcast_to(a, shape)[(0, 0, *m)] for a in args]
            plane = [a.reshape(a.shape[:2]) for a in args[:4]]
            one = points.spectral_points(
                *plane, *model[4:], names=FLAGS, dtype=dtype, resolve=resolve
            )
            for k in FLAGS:
                assert np.array_equal(res[k][(..., *m)], one[k]), (k, m, resolve)
            for k in tiers:
                tiers[k] += one.stats[k]
        assert {k: res.stats[k] for k in tiers} == tiers
    assert res.stats["undecided_after"] == 0
    idx = np.random.default_rng(5).choice(np.prod(shape), 300, replace=False)
    pts = {k: np.broadcast_to(a, shape).ravel()[idx].astype(np.float64) for k, a in zip(KEYS, args)}
    ref = exact.resolve(pts, names=FLAGS)
    for k in FLAGS:
        assert np.array_equal(res[k].ravel()[idx], ref[k]), k


def test_first_pass_layout_puts_the_longest_axis_inside():
    """The first pass evaluates a grid with its longest axis innermost, shorter axes outside."""
    assert points._layout((128, 128, 8, 2, 2)) == (3, 4, 2, 0, 1)
    assert points._layout((513, 513)) == (0, 1)
    assert points._layout((4, 300, 1)) == (2, 0, 1)


def test_grids_over_models_take_the_grid_kernel(monkeypatch):
    """Flat columns serve small grids and grids of one model; a grid over several models above
    ``FLAT_SIZES[0]`` points (a tile of ``atlas generate``) runs the grid kernel, which computes
    the per-model factors once a model.  The threshold is lowered to 1,024 points so that the
    grid is :func:`test_model_axes_equal_their_slices`'s, whose grid program it shares."""
    calls = []
    monkeypatch.setattr(points, "_on_flat", lambda *a: calls.append(1) or _on_flat(*a))
    monkeypatch.setattr(points, "FLAT_SIZES", (1 << 10,))
    g = model_grid()  # 12 x 12 x 5 x 2 x 2 = 2880 points
    points.spectral_points(*g, names=FLAGS, resolve=False)
    assert not calls
    plane = [a.reshape(a.shape[:2]) for a in g[:4]]
    points.spectral_points(*plane, 0.5, 0.1, 0.2, names=FLAGS, resolve=False)  # one model
    points.spectral_points(*model_grid(4), names=FLAGS, resolve=False)  # 320 points
    assert len(calls) == 2


_on_flat = points._on_flat


def test_point_lists_stay_flat(monkeypatch):
    """Points given as lists (a model per point) keep the flat columns: one compiled shape for
    every length up to ``FLAT_LIMIT``."""
    calls = []
    monkeypatch.setattr(points, "_on_flat", lambda *a: calls.append(1) or _on_flat(*a))
    g = model_grid(20)
    shape = np.broadcast_shapes(*(a.shape for a in g))
    g = [np.broadcast_to(a, shape).ravel() for a in g]
    points.spectral_points(*g, names=FLAGS, resolve=False)
    assert len(calls) == 1


def _small_atlas():
    """The 16 x 16 x 2 damped atlas of ``atlas generate``'s smallest example (q = 0.1)."""
    g = np.arange(16) * (2 * np.pi / 16)
    c, s = direction(g, np.float64)
    kappa = np.array([0.5, 2.0])
    return c[:, None, None], s[:, None, None], c[None, :, None], s[None, :, None], kappa, 0.1, 0.1


def test_a_handful_of_open_points_goes_to_the_exact_tier_without_later_tiers():
    """A first pass leaving at most ``HOST_POINTS`` open sends them to the exact tier: no tier-2
    or enclosure program runs (nothing to compile), and every verdict equals the exact tier's."""
    args = _small_atlas()
    res = points.spectral_points(*args, names=FLAGS)
    st = res.stats
    assert 0 < st["undecided_before"] <= points.HOST_POINTS
    assert st["tier2_points"] == st["roots_points"] == st["undecided_after"] == 0
    shape = res["stable_SS"].shape
    pts = dict(zip(KEYS, (np.broadcast_to(a, shape).ravel().astype(np.float64) for a in args)))
    ref = exact.resolve(pts, names=FLAGS)
    for k in FLAGS:
        assert np.array_equal(res[k].ravel(), ref[k]), k
    # a settlement budget below the open points keeps the later tiers
    budget = points.spectral_points(*args, names=FLAGS, max_resolve=st["undecided_before"] - 1)
    assert budget.stats["tier2_points"] > 0


def test_where_the_exact_tier_fails_the_later_tiers_still_decide(monkeypatch):
    """The exact tier failing on the handful of points: the later tiers run on them after all,
    so the verdicts are those of the tiers without the host path (``HOST_POINTS = 0``)."""

    def broken(points, names=()):
        raise ArithmeticError("no convergence")

    monkeypatch.setattr(exact, "resolve", broken)
    args = _small_atlas()
    got = points.spectral_points(*args, names=FLAGS)
    monkeypatch.setattr(points, "HOST_POINTS", 0)
    want = points.spectral_points(*args, names=FLAGS)
    assert got.stats["tier2_points"] == want.stats["tier2_points"] > 0
    assert got.stats["undecided_after"] == want.stats["undecided_after"]
    for k in FLAGS:
        assert np.array_equal(got[k], want[k]), k


def test_compiled_programs_serve_every_small_point_set(monkeypatch):
    """After :func:`points.compile_programs` (the explorer's background warm-up), point sets
    of 100 and 3,000 points whose open points reach tier 2 compile no program: the flat first
    pass and the later tiers run at the shared buckets.  Counted, not timed."""
    import jax

    pts, _ = _near_singular_points()
    monkeypatch.setattr(points, "HOST_POINTS", 0)
    points.compile_programs("float64")
    compiles = []

    def listen(event, seconds, **kw):
        compiles.append(event) if event.endswith("backend_compile_duration") else None

    jax.monitoring.register_event_duration_secs_listener(listen)
    try:
        for n in (100, 3000):
            some = {k: np.resize(np.broadcast_to(v, pts["c1"].shape), n) for k, v in pts.items()}
            st = points.spectral_points(*some.values(), names=FLAGS, resolve=False).stats
            assert st["tier2_points"] > 0, st
    finally:
        jax.monitoring.unregister_event_duration_listener(listen)
    assert compiles == []


@pytest.mark.parametrize(
    "extra, lengths",
    [
        (-1, [256] * 64),  # below the bulk threshold: the one shared length
        (300, [4096] * 4 + [256, 256]),  # the bulk in large batches, the rest in the shared length
    ],
)
def test_large_later_sets_run_their_bulk_in_large_batches(extra, lengths):
    """Tier 2 and the enclosures see :data:`LATER_BATCH` points except the bulk of a set of at
    least :data:`LATER_BULK_FROM` points (a 5-D grid's tier 2), which runs in :data:`LATER_BULK`
    batches; every point comes back in its place."""
    n = points.LATER_BULK_FROM + extra
    seen = []

    def kernel(*cols):
        seen.append(cols[0].size)
        return cols[0] * 2.0, cols[1]

    cols = [np.arange(n, dtype=np.float64) + i for i in range(len(points.PAD))]
    got = points._run_later(kernel, cols)
    assert seen == lengths
    assert np.array_equal(got[0], 2.0 * cols[0]) and np.array_equal(got[1], cols[1])


def test_host_first_settles_small_open_sets_exactly_until_the_later_tiers_have_run(monkeypatch):
    """Under :func:`points.host_first` (a first session's overlay), a first pass leaving more
    than ``HOST_POINTS`` but at most the limit open sends them to the exact tier while the later
    tiers have not run in this process: no later-tier program is needed, the verdicts are the
    exact tier's; once both have run, the later tiers take them again."""
    pts, _ = _near_singular_points()
    some = {k: np.resize(np.broadcast_to(v, pts["c1"].shape), 100) for k, v in pts.items()}
    monkeypatch.setattr(points, "_LATER_RAN", set())
    plain = points.spectral_points(*some.values(), names=FLAGS)
    assert plain.stats["tier2_points"] > 0  # the first pass leaves more than HOST_POINTS open
    monkeypatch.setattr(points, "_LATER_RAN", set())
    with points.host_first(128):
        cold = points.spectral_points(*some.values(), names=FLAGS)
    assert cold.stats["tier2_points"] == cold.stats["roots_points"] == 0
    assert points.HOST_POINTS < cold.stats["undecided_before"] <= 128
    ref = exact.resolve({k: v.astype(np.float64) for k, v in some.items()}, names=FLAGS)
    for k in FLAGS:
        assert np.array_equal(cold[k], ref[k]) and np.array_equal(plain[k], ref[k]), k
    points.compile_programs("float64")  # both later tiers run: the usual limit again
    with points.host_first(128):
        warm = points.spectral_points(*some.values(), names=FLAGS)
    assert warm.stats["tier2_points"] == plain.stats["tier2_points"]


def test_needed_leaves_unwanted_points_undecided():
    """``needed`` narrows the later tiers: points it never wants stay undecided and are
    counted; a point wanted in the exact rounds is settled as the exact tier alone settles it."""
    from atlas.core.verdicts import UNDECIDED_FLAG

    (c1, s1, c2, s2), model = _ii_boundary()
    names = ("consistent_II", "stable_II")
    full = points.spectral_points(c1, s1, c2, s2, *model, names=names)
    none = points.spectral_points(
        c1, s1, c2, s2, *model, names=names, needed=lambda idx, v, e: np.zeros(idx.size, bool)
    )
    open_ = np.flatnonzero(none["consistent_II"] == UNDECIDED_FLAG)
    assert open_.size >= 4  # a hard case for the fast tiers
    assert none.stats["exact_rounds"] == 0 and none.stats["tier2_points"] == 0
    assert none.stats["unneeded_points"] == full.stats["undecided_before"] == open_.size
    rounds = []

    def one(idx, verdicts, exact_round):
        rounds.append(exact_round)
        return idx == open_[0]

    got = points.spectral_points(c1, s1, c2, s2, *model, names=names, needed=one)
    assert True in rounds and False in rounds
    assert got.stats["exact_rounds"] == 1 and got.stats["unneeded_points"] == open_.size - 1
    want = exact.point_spectral(*(float(v[open_[0]]) for v in (c1, s1, c2, s2)), *model)
    assert got["consistent_II"][open_[0]] == want["consistent_II"]
    assert (got["consistent_II"][open_[1:]] == UNDECIDED_FLAG).all()


def test_tally_adds_up_the_work_of_every_call_per_tier(monkeypatch):
    """``tally`` counts the certified calls of a block and the points each tier received; the
    exact tier's count is the number of points it was given (counted at the exact tier), and
    nested blocks each see their own calls."""
    given, resolve = [], exact.resolve

    def counted(pts, names=None, **kw):
        given.append(len(pts["c1"]))
        return resolve(pts, names=names, **kw)

    monkeypatch.setattr(exact, "resolve", counted)
    small, big = _small_atlas(), grid(8)
    with points.tally() as outer:
        one = points.spectral_points(*small, names=FLAGS)
        with points.tally() as inner:
            two = points.spectral_points(*big, names=FLAGS)
    inside = sum(given)
    points.spectral_points(*small, names=FLAGS)  # outside: not counted
    assert inner["calls"] == 1 and outer["calls"] == 2 and sum(given) > inside > 0
    assert inner["exact_points"] == two.stats.get("exact_points", 0)
    assert outer["exact_points"] == inside
    for k in ("points", "tier2_points", "roots_points"):
        assert inner[k] == two.stats[k]
        assert outer[k] == one.stats[k] + two.stats[k]


#: ``b2 = -b1`` with subnormal components: ``det B = 0`` exactly; XLA reads the components as zero
_OPPOSITE_SUBNORMAL = [(1e-310, 1.0, -1e-310, -1.0), (-1e-310, 1.0, 1e-310, -1.0)]


def _ii_on_singular_b(c1, s1, c2, s2, kappa, q1, q2):
    """Exact II verdicts where ``det B = 0`` and ``a2 < 0``: ``p = l^2 (l^2 + a3 l + a2)`` has one
    simple root ``l > 0``, strictly dominant; at it ``h1 = -s2 (k2 + q2 l)``, so its gap
    eigenvector ``x ~ (-c2 d2, h1)`` has ``x1 x2 > 0`` iff ``c2 s2 > 0`` (paper Sec. 4.3): II is
    consistent, and stable, exactly there."""
    c1, s1, c2, s2, k1, q1, q2 = (F(float(v)) for v in (c1, s1, c2, s2, kappa, q1, q2))
    assert c1 * s2 - s1 * c2 == 0 and c1 * k1 + s2 < 0 and s2 != 0
    ii = int(c2 * s2 > 0)
    return {"consistent_II": ii, "stable_II": ii}


@pytest.mark.parametrize(
    "jitted", [True, pytest.param(False, marks=pytest.mark.slow)], ids=["jit", "op-by-op"]
)
def test_subnormal_directions_are_never_certified_wrong(jitted):
    """XLA on CPU reads subnormal direction components as zero (jitted or not): at ``b2 = -b1``
    with components ``+-1e-310`` the kernels certified II inconsistent where it is consistent
    exactly (108 consistent_II and 111 stable_II verdicts of 1920 on a sweep of such points).
    The kernel tiers must leave them undecided or be right; settled, they are right."""
    import jax

    rows = [d + m for d in _OPPOSITE_SUBNORMAL for m in ((0.5, 0.0, 0.0), (2.0, 0.1, 0.7))]
    x = [np.array(col) for col in zip(*rows)]
    names = ("consistent_II", "stable_II")
    with contextlib.ExitStack() as stack:
        if not jitted:
            stack.enter_context(jax.disable_jit())
        fast = points.spectral_points(*x, names=names, resolve=False)
        settled = points.spectral_points(*x, names=names)
    for i, row in enumerate(rows):
        want = _ii_on_singular_b(*row)
        for name in names:
            assert fast[name][i] in (want[name], 3), (row, name)
            assert settled[name][i] == want[name], (row, name)


def test_witness_checks_run_one_ss_program_whatever_their_number(monkeypatch):
    """The model box's witness checks (certified SS verdicts of point lists of any length) run
    :func:`atlas.core.hurwitz.ss_verdict` at one length, the shape buckets' small batch: one
    program for 5, 40, 300 or 700 points (before: one per power of two, 16 to 1024), with the
    exact tier's verdicts."""
    seen = set()
    call = warm.Kernel.__call__

    def recording(self, *args, **static):
        if self.name == "atlas.core.hurwitz.ss_verdict":
            seen.add(tuple(np.shape(a) for a in args))
        return call(self, *args, **static)

    monkeypatch.setattr(warm.Kernel, "__call__", recording)
    rng = np.random.default_rng(2)
    for n in (5, 40, 300, 700):
        b1, b2 = rng.uniform(0, 2 * np.pi, (2, n))
        geo = np.stack([*direction(b1), *direction(b2)], axis=1)
        models = rng.uniform(0.05, 2.0, (n, 3))
        models[::3, 1:] = 0.0  # undamped
        got = model_box._verify(geo, models)
        for i in range(0, n, 37):
            code = exact.ss_hurwitz(*geo[i].tolist(), *models[i].tolist())
            assert got[i] == np.isin(code, model_box._GOOD), (n, i)
    assert seen == {((buckets.SMALL,),) * 7}


def _edge_columns(dtype, n=700, seed=4):
    """``n`` points (one full small batch and a padded one) with edge values in every column:
    zeros of both signs, the smallest subnormal, the largest finite, infinities and NaN."""
    rng = np.random.default_rng(seed)
    fi = np.finfo(dtype)
    edge = np.array([0.0, -0.0, fi.smallest_subnormal, -fi.smallest_subnormal, fi.tiny, fi.max,
                     np.inf, -np.inf, np.nan, 1.0], dtype)  # fmt: skip
    b1, b2 = rng.uniform(0, 2 * np.pi, (2, n))
    cols = [*direction(b1.astype(dtype), dtype), *direction(b2.astype(dtype), dtype)]
    cols += [rng.uniform(0.05, 2.0, n).astype(dtype) for _ in range(3)]
    for c in cols:
        hit = rng.random(n) < 0.2
        c[hit] = rng.choice(edge, hit.sum())
    return cols


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_small_batches_equal_the_unpadded_call(dtype):
    """Padded batches of an elementwise kernel give, bit for bit, its unpadded calls on the same
    points (the first and the last :data:`atlas.core.buckets.SMALL` of 700, each point at another place
    of its batch), edge values included (subnormals, zeros, infinities, NaN; float32 too)."""
    cols = _edge_columns(dtype)
    got = buckets.call(hurwitz.ss_verdict_jit, *cols)
    m = buckets.SMALL
    head = np.asarray(hurwitz.ss_verdict_jit(*(c[:m] for c in cols)))
    tail = np.asarray(hurwitz.ss_verdict_jit(*(c[-m:] for c in cols)))
    assert got.dtype == head.dtype and got.shape == (700,)
    assert np.array_equal(got[:m], head) and np.array_equal(got[m:], tail[2 * m - 700 :])
