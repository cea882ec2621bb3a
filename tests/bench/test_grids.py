"""``atlas.bench.grids``: one grid, every method, checked against an independent exact run."""

import numpy as np
import pytest

from atlas.bench import grids
from atlas.bench.config import CONFIG, FLAGS, KEYS
from atlas.core import exact, points


def test_misclassified_counts_decided_differences_only():
    ref = {"stable_SS": [1, 0, 1, 0], "stable_II": [1, 1, 0, 0]}
    fast = {"stable_SS": [1, 3, 0, 0], "stable_II": [0, 1, 3, 0]}
    # point 0: II wrong; point 1: SS undecided; point 2: SS wrong, II undecided; point 3: right
    assert grids.misclassified(fast, ref, ("stable_SS", "stable_II")) == (2, 2)
    assert grids.misclassified(fast, ref, ("stable_SS",)) == (1, 1)


def test_grid_inputs_spacing_and_broadcast():
    beta, args = grids.grid_inputs(8, 0.5, 0.1, 0.2, "float32")
    np.testing.assert_allclose(np.diff(beta), 2 * np.pi / 8)
    c1, s1, c2, s2, kappa, q1, q2 = args
    assert c1.shape == (9, 1) and c2.shape == (1, 9) and c1.dtype == np.float32
    np.testing.assert_allclose(c1[:, 0] ** 2 + s1[:, 0] ** 2, 1, rtol=1e-6)
    assert (float(kappa), float(q2)) == (0.5, pytest.approx(0.2))


def test_exact_cache_evaluates_each_point_once():
    cache = grids.ExactCache()
    _, args = grids.grid_inputs(4, 0.5, 0.1, 0.1, "float64")
    pts = grids.flat_points(args, (5, 5), np.array([0, 7, 7, 12]))
    out = cache.get(pts, ("stable_SS",))
    assert len(cache.store) == 3 and set(out) == {"stable_SS"}
    assert out["stable_SS"][1] == out["stable_SS"][2]
    ref = exact.resolve(pts, names=("stable_SS",))
    np.testing.assert_array_equal(out["stable_SS"], ref["stable_SS"])


def test_run_method_names_the_parameter():
    with pytest.raises(ValueError, match="^method: "):
        grids.run_method("qr", (), FLAGS, "float64", False)


@pytest.mark.parametrize("dtype", ["float64", "float32"])
def test_small_case_recomputed_independently(dtype):
    """16 x 16 grid, damped: bench's counts against exact.resolve on every grid point."""
    cfg = dict(
        CONFIG["quick"],
        sample=10**6,
        sample_small=10**6,
        disagree_cap=10**6,
        undecided_cap=10**6,
        budget=0.0,  # the counts, not the times: one timed call a method
        min_repeats=1,
    )
    case = ("q=0.1", 0.5, 0.1, 0.1)
    rows, res, _, args = grids.measure_grid(
        case, dtype, 16, FLAGS, ["certified", "certified+exact", "eig"], cfg,
        grids.ExactCache(), np.random.default_rng(0), sample=10**6,
    )  # fmt: skip
    shape = (17, 17)
    pts = {k: np.broadcast_to(a, shape).ravel().astype(np.float64) for k, a in zip(KEYS, args)}
    ref = exact.resolve(pts, names=FLAGS)
    for m in ("certified", "eig"):
        fast = points.spectral_points(
            *args, names=FLAGS, dtype=dtype,
            method="certified" if m == "certified" else "eig", resolve=False,
        )  # fmt: skip
        bad = und = 0
        for i in range(17 * 17):
            v = [int(fast[k].ravel()[i]) for k in FLAGS]
            e = [int(ref[k][i]) for k in FLAGS]
            bad += any(a != 3 and a != b for a, b in zip(v, e))
            und += any(a == 3 for a in v)
        row = next(r for r in rows if r["method"] == m)
        assert row["checked"] == 17 * 17
        assert row["misclassified"] == bad
        assert row["misclassified_sample"] == bad
        assert row["undecided"] == und
    # certified+exact equals the driver's own settlement (resolve=True)
    settled = points.spectral_points(*args, names=FLAGS, dtype=dtype, resolve=True)
    for k in FLAGS:
        np.testing.assert_array_equal(res["certified+exact"][k], settled[k].reshape(shape))
    assert next(r for r in rows if r["method"] == "certified")["misclassified"] == 0
    assert next(r for r in rows if r["method"] == "certified+exact")["undecided"] == 0
