"""Tiled generation: schema (SPEC §2), agreement with the kernels, tiling, resolution, reductions.

All spectral runs use ``TILE = 1024`` on scenes of <= 1024 spectral points, so the eigenvalue kernel
compiles once per test session.
"""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from atlas.core import backend, exact
from atlas.core import contact_modes as mech
from atlas.core.config import CACHE_ENV
from atlas.core.invariants import KEYS
from atlas.core.verdicts import UNDECIDED_CODE, Consistency, Verdict
from atlas.data import engine
from atlas.data.engine import (
    MemorySink,
    RunOptions,
    Sink,
    block_shape,
    generate,
    run,
    tile_blocks,
)
from atlas.data.outputs import default_outputs
from atlas.data.scene import Scene, builtin

TILE = 1024


def tiny_scene(**kw):
    base = dict(beta1="0:2pi:16", beta2="0:2pi:16", alpha="0:2pi:4", kappa="0.5,2", q="0,0.5")
    base.update(kw)
    return Scene(name="tiny", **base)


@pytest.fixture(scope="module")
def tiny():
    return generate(tiny_scene(), tile_points=TILE, resolve=False)


@pytest.fixture(scope="module")
def fig1_small():
    return generate(builtin("fig1", beta1="0:2pi:32", beta2="0:2pi:32"), tile_points=TILE)


EXPECTED_DIMS = {
    "class_code": ("beta1", "beta2"),
    "subclass_code": ("beta1", "beta2", "alpha"),
    "consistent_FF": ("beta1", "beta2", "alpha"),
    "consistent_SF": ("beta1", "beta2", "alpha"),
    "consistent_FS": ("beta1", "beta2", "alpha"),
    "consistent_SS": ("beta1", "beta2", "alpha"),
    "stable_SF": ("beta1",),
    "consistent_IF": ("beta1",),
    "stable_FS": ("beta2",),
    "consistent_FI": ("beta2",),
    "cc_possible": ("beta1", "beta2"),
    "stable_SS": ("beta1", "beta2", "kappa", "q"),
    "consistent_II": ("beta1", "beta2", "kappa", "q"),
    "stable_II": ("beta1", "beta2", "kappa", "q"),
    "spectral_abscissa": ("beta1", "beta2", "kappa", "q"),
    "model_dependent_SS": ("beta1", "beta2"),
    "model_dependent_II": ("beta1", "beta2"),
}


def test_schema_dims_and_types(tiny):
    assert set(tiny.data_vars) == set(default_outputs())
    for name, dims in EXPECTED_DIMS.items():
        assert tiny[name].dims == dims, name
    assert tiny.class_code.dtype == np.int8
    assert tiny.subclass_code.dtype == np.int16
    for name in ("stable_SS", "consistent_II", "stable_II"):
        assert tiny[name].dtype == np.int8
    for name in (
        "consistent_SS",
        "stable_SF",
        "consistent_FI",
        "cc_possible",
        "model_dependent_II",
    ):
        assert tiny[name].dtype == bool
    assert tiny.spectral_abscissa.dtype == np.float64


def test_cf_attributes(tiny):
    a = tiny.attrs
    assert a["Conventions"] == "CF-1.10"
    for key in ("title", "source", "history", "references", "method", "dtype", "scene"):
        assert a[key]
    assert "JAX" in a["source"] and jax.__version__ in a["source"]
    assert a["history"][:4].isdigit() and "T" in a["history"][:20]
    ss = tiny.stable_SS.attrs
    assert list(ss["flag_values"]) == [0, 1, 2, 3]
    assert ss["flag_meanings"] == "unstable stable neutral undecided"
    ii = tiny.consistent_II.attrs
    assert list(ii["flag_values"]) == [0, 1, 3]
    assert ii["flag_meanings"] == "inconsistent consistent undecided"
    for c in ("beta1", "beta2", "alpha"):
        assert tiny[c].attrs["units"] == "rad" and tiny[c].attrs["long_name"]
    for c in ("kappa", "q"):
        assert tiny[c].attrs["units"] == "1" and tiny[c].attrs["long_name"]
    assert "undecided_fast" in a and "undecided_after_resolve" in a


def test_fixed_parameters_are_scalar_coords_and_attrs(fig1_small):
    ds = fig1_small
    assert ds.stable_SS.dims == ("beta1", "beta2")
    assert ds.kappa.ndim == 0 and float(ds.kappa) == 0.5
    assert ds.attrs["kappa"] == 0.5 and ds.attrs["q"] == 0.0
    assert "model_dependent_SS" not in ds


def _point_inputs(b1, b2):
    c1, s1 = mech.direction(np.array(b1))
    c2, s2 = mech.direction(np.array(b2))
    return [jnp.asarray(x) for x in (c1, s1, c2, s2)]


def _pointwise_verdicts(points) -> list[dict]:
    """The exact tier's verdicts (rational arithmetic, independent of every float kernel) at each
    ``(c1, s1, c2, s2, kappa, q1, q2)`` of ``points``."""
    cols = {n: np.array([float(p[i]) for p in points]) for i, n in enumerate(KEYS)}
    ref = exact.resolve(cols, names=("stable_SS", "consistent_II", "stable_II"))
    return [{n: int(v[m]) for n, v in ref.items()} for m in range(len(points))]


def test_fig1_equals_pointwise_kernels(fig1_small):
    """Sampled points of the fig1 scene (random, a tie, an axis, b2 = -b1): the verdicts equal
    the exact tier's at those points alone, the codes the kernels'."""
    ds = fig1_small
    rng = np.random.default_rng(0)
    idx = [(i, j) for i, j in rng.integers(0, 32, size=(6, 2))] + [(0, 0), (8, 24), (5, 21)]
    b1v, b2v = ds.beta1.values, ds.beta2.values
    k, q = jnp.asarray(0.5), jnp.asarray(0.0)
    pts = [(*_point_inputs(b1v[i], b2v[j]), k, q, q) for i, j in idx]
    for (i, j), (c1, s1, c2, s2, *_), v in zip(idx, pts, _pointwise_verdicts(pts)):
        for n in ("stable_SS", "consistent_II", "stable_II"):
            assert int(ds[n].values[i, j]) == v[n], (n, i, j)
        cls = int(mech.class_code(c1, s1, c2, s2))
        if cls != -1:
            assert int(ds.class_code.values[i, j]) == cls
        assert bool(ds.cc_possible.values[i, j]) == bool(mech.cc_possible(c1, s2))
        assert bool(ds.stable_SF.values[i]) == (int(mech.stable_SF(c1)) == Verdict.STABLE)
        assert bool(ds.consistent_FI.values[j]) == bool(mech.consistent_FI(c2, s2))


def test_tiling_does_not_change_results():
    s = tiny_scene(outputs="class_code,subclass_code,consistent_SS,stable_SS,model_dependent_SS")
    a = generate(s, tile_points=TILE, resolve=False)
    b = generate(s, tile_points=100, resolve=False)  # many partial tiles
    for n in a.data_vars:
        np.testing.assert_array_equal(a[n].values, b[n].values, err_msg=n)
    assert block_shape((16, 16, 2, 2), 100) == (1, 16, 2, 2)
    assert block_shape((16, 16, 2, 2), 30) == (1, 7, 2, 2)
    covered = np.zeros((5, 7, 3), int)
    for sl in tile_blocks((5, 7, 3), 8):
        covered[sl] += 1
    assert (covered == 1).all()


def test_model_dependence_reduction(tiny):
    ss = tiny.stable_SS.values
    stable = (ss == Verdict.STABLE) | (ss == Verdict.NEUTRAL)
    unstable = ss == Verdict.UNSTABLE
    expect = stable.any(axis=(2, 3)) & unstable.any(axis=(2, 3))
    assert expect.any() and not expect.all()  # the tiny scene has both kinds of points
    np.testing.assert_array_equal(tiny.model_dependent_SS.values, expect)
    c, s = tiny.consistent_II.values, tiny.stable_II.values
    dec = (c != 3) & (s != 3)
    states = [dec & (c == 0), dec & (c == 1) & (s == 0), dec & (c == 1) & (s == 1)]
    count = sum(x.any(axis=(2, 3)).astype(int) for x in states)
    assert (count > 1).any() and not (count > 1).all()
    np.testing.assert_array_equal(tiny.model_dependent_II.values, count > 1)


def test_unresolved_counts_reported(tiny):
    total = sum(
        int(tiny[n].attrs["undecided"]) for n in tiny.data_vars if "undecided" in tiny[n].attrs
    )
    assert tiny.attrs["undecided_after_resolve"] == total
    n3 = int((tiny.stable_SS.values == 3).sum())
    assert tiny.stable_SS.attrs["undecided"] == n3


def test_resolve_leaves_no_undecided(fig1_small):
    ds, st = run(tiny_scene(), MemorySink(), RunOptions(tile_points=TILE, resolve=True))
    assert ds.attrs["undecided_fast"] > 0  # the fast path did leave some
    assert ds.attrs["undecided_after_resolve"] == 0
    for n in ("stable_SS", "consistent_II", "stable_II"):
        assert not (ds[n].values == Consistency.UNDECIDED).any()
    assert not (ds.class_code.values == UNDECIDED_CODE).any()
    assert not (ds.subclass_code.values == UNDECIDED_CODE).any()
    assert fig1_small.attrs["undecided_after_resolve"] == 0
    # the run's diagnostics are returned with its result
    assert st["undecided"] == 0 and st["undecided_fast"] == ds.attrs["undecided_fast"]
    assert st["points"] == tiny_scene().points() and st["resolved_points"] > 0
    assert st["exact_failures"] == []


def test_eig_method_and_float32():
    s = builtin("fig1", beta1="0:2pi:32", beta2="0:2pi:32", outputs="stable_SS,class_code")
    e = generate(s, tile_points=TILE, method="eig")
    assert e.attrs["method"] == "eig"
    assert set(np.unique(e.stable_SS.values)) <= {0, 1, 2}
    f = generate(s, tile_points=TILE, dtype="float32", resolve=False)
    assert f.attrs["dtype"] == "float32"
    assert f.stable_SS.dtype == np.int8


@pytest.mark.parametrize(
    "kw, name",
    [
        (dict(method="lu"), "method"),
        (dict(dtype="float16"), "dtype"),
        (dict(tile_points=0), "tile_points"),
        (dict(tile_points=1.5), "tile_points"),
    ],
)
def test_bad_options(kw, name):
    with pytest.raises(ValueError, match=f"^{name}:"):
        generate(tiny_scene(outputs="class_code"), **kw)


def test_a_backend_that_failed_selftest_is_refused_before_any_work(tmp_path, monkeypatch):
    """With a failed self-check recorded, a certified run raises before the sink is begun or a
    kernel runs (no file is started, nothing is computed); an ``eig`` run, which certifies
    nothing, still runs."""
    monkeypatch.setenv(CACHE_ENV, str(tmp_path))
    backend.record({"passed": False, "disagreements": 1, "when": "a test"})
    calls = []

    class Counted(MemorySink):
        def begin(self, sch):
            calls.append("begin")
            super().begin(sch)

    monkeypatch.setattr(engine, "_kernel_group", lambda *a: calls.append("kernel"))
    scene = tiny_scene(outputs="class_code,stable_SS")
    with pytest.raises(backend.BackendFailed, match="failed atlas selftest"):
        run(scene, Counted(), RunOptions(tile_points=TILE))
    assert calls == []
    run(scene, Counted(), RunOptions(tile_points=TILE, method="eig"))
    assert calls[0] == "begin" and "kernel" in calls


def test_exact_failure_keeps_point_undecided(monkeypatch):
    def broken(points, names=()):
        raise ArithmeticError("no convergence")

    monkeypatch.setattr(exact, "resolve", broken)
    ds = generate(tiny_scene(outputs="stable_SS,stable_II"), tile_points=TILE, resolve=True)
    n3 = int((ds.stable_SS.values == 3).sum()) + int((ds.stable_II.values == 3).sum())
    assert n3 > 0 and ds.attrs["undecided_after_resolve"] == n3
    assert ds.attrs["exact_failures"] > 0 and "exact_failure_example" in ds.attrs


@pytest.mark.parametrize(
    "kw, name",
    [
        ({"resolve": "no"}, "resolve"),
        ({"dtype": "float16"}, "dtype"),
        ({"tile_points": True}, "tile_points"),
    ],
)
def test_options_refused_naming_the_parameter(kw, name):
    """A string is not a boolean (``"no"`` was read as True), float16 has no error model."""
    with pytest.raises(ValueError, match=f"^{name}: "):
        generate(Scene(beta1="0:2pi:4", beta2="0:2pi:4"), **kw)


def test_run_options_are_one_checked_object():
    """Every builder takes one RunOptions; a bad or unknown option is a one-line error naming it."""
    assert RunOptions.of(None, dtype="float32") == RunOptions(dtype="float32")
    with pytest.raises(ValueError, match="^tile_points:"):
        RunOptions(tile_points=True)
    with pytest.raises(ValueError, match="^method:"):
        RunOptions(method="guess")
    with pytest.raises(ValueError, match="^tile_pints: not a run option"):
        generate(tiny_scene(outputs="class_code"), tile_pints=TILE)
    assert isinstance(MemorySink(), Sink)
