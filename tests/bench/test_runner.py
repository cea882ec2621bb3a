"""Tests for ``atlas.bench``: quick mode fills the headline table; one small case recomputed."""

import json

import numpy as np
import pytest

from atlas.bench import runner as bench
from atlas.core import exact
from atlas.core import points as evaluate


def test_quick_run_fills_headline(tmp_path):
    assert bench.run(quick=True, out=str(tmp_path)) == 0
    md = (tmp_path / "bench.md").read_text()
    for word in (
        "Machine:",
        "JAX",
        "Command:",
        "total duration",
        "## Headline",
        "## Scaling",
        "## Simulation",
        "## Hard-case suites",
        "## Work-precision",
    ):
        assert word in md
    js = json.loads((tmp_path / "bench_headline.json").read_text())
    head = js["headline"]
    # the end-to-end CLI run of the tiny atlas: its size and settlement are known up front
    (e2e,) = [r for r in js["atlases"] if r["atlas"] == "tiny 4-D"]
    assert e2e["points"] == 16 * 16 * 2 * 2 and e2e["undecided_after"] == 0
    assert e2e["file_mb"] > 0 and e2e["peak_rss_mb"] > 0
    cols = (
        "case",
        "dtype",
        "method",
        "ns_per_point",
        "eig_over_method",
        "method_over_floor",
        "misclassified_sample",
        "misclassified",
        "undecided",
        "target_1000x",
    )
    assert {r["method"] for r in head} == set(bench.METHODS)
    assert {r["dtype"] for r in head} == {"float32", "float64"}
    for r in head:
        for c in cols:
            v = r[c]
            assert v is not None and v != "" and not (isinstance(v, float) and np.isnan(v)), (r, c)
        assert r["ns_per_point"] > 0
    # the certified path never misclassifies a decided point
    for r in head:
        if r["method"].startswith("certified"):
            assert r["misclassified"].startswith("0/")
    for name in (
        "bench_work_precision.png",
        "bench_convergence.png",
        "bench_scaling.png",
        "bench_simulation.png",
        "bench_work_precision.csv",
        "bench_suites.csv",
        "bench_atlases.csv",
    ):
        assert (tmp_path / name).stat().st_size > 0
    # the table in bench.md has no empty cells
    rows = [
        ln for ln in md.split("## Headline")[1].split("##")[0].splitlines() if ln.startswith("| (")
    ]
    assert rows and all("|  |" not in ln for ln in rows)


@pytest.mark.parametrize("dtype", ["float64", "float32"])
def test_small_case_recomputed_independently(dtype):
    """16 x 16 grid, damped: bench's counts against exact.resolve on every grid point."""
    cfg = dict(
        bench.CONFIG[True],
        sample=10**6,
        sample_small=10**6,
        disagree_cap=10**6,
        undecided_cap=10**6,
    )
    case = ("q=0.1", 0.5, 0.1, 0.1)
    rows, res, _, args = bench._measure_grid(
        case,
        dtype,
        16,
        bench.FLAGS,
        ["certified", "certified+exact", "eig"],
        cfg,
        bench.ExactCache(),
        np.random.default_rng(0),
        sample=10**6,
    )
    shape = (17, 17)
    pts = {
        k: np.broadcast_to(a, shape).ravel().astype(np.float64) for k, a in zip(bench.KEYS, args)
    }
    ref = exact.resolve(pts, names=bench.FLAGS)
    for m in ("certified", "eig"):
        fast = evaluate.spectral_points(
            *args,
            names=bench.FLAGS,
            dtype=dtype,
            method="certified" if m == "certified" else "eig",
            resolve=False,
        )
        bad = und = 0
        for i in range(17 * 17):
            v = [int(fast[k].ravel()[i]) for k in bench.FLAGS]
            e = [int(ref[k][i]) for k in bench.FLAGS]
            bad += any(a != 3 and a != b for a, b in zip(v, e))
            und += any(a == 3 for a in v)
        row = next(r for r in rows if r["method"] == m)
        assert row["checked"] == 17 * 17
        assert row["misclassified"] == bad
        assert row["misclassified_sample"] == bad
        assert row["undecided"] == und
    # certified+exact equals the driver's own settlement (resolve=True)
    settled = evaluate.spectral_points(*args, names=bench.FLAGS, dtype=dtype, resolve=True)
    for k in bench.FLAGS:
        np.testing.assert_array_equal(res["certified+exact"][k], settled[k].reshape(shape))
    assert next(r for r in rows if r["method"] == "certified")["misclassified"] == 0


def test_hausdorff_of_shifted_circle():
    beta = np.linspace(0, 2 * np.pi, 129)
    X, Y = np.meshgrid(beta, beta, indexing="ij")
    a = bench.contour_lines(beta, (X - 3) ** 2 + (Y - 3) ** 2 - 1, 0.0)
    b = bench.contour_lines(beta, (X - 3.1) ** 2 + (Y - 3) ** 2 - 1, 0.0)
    assert bench.hausdorff(a, b, 0.01) == pytest.approx(0.1, abs=2e-3)
    assert bench.hausdorff(a, a, 0.01) == pytest.approx(0.0, abs=1e-12)
