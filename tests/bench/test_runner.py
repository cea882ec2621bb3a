"""``atlas.bench.run`` end to end on the ``tiny`` configuration: every section measured for real,
every file written, into the mode's default directory."""

import csv
import json
from pathlib import Path

import numpy as np
import pytest

from atlas.bench import runner
from atlas.bench.config import CONFIG, METHODS

HEAD_COLUMNS = (
    "case", "dtype", "method", "ns_per_point", "eig_over_method", "method_over_floor",
    "misclassified_sample", "misclassified", "undecided", "target_1000x",
)  # fmt: skip


def _filled(v):
    return v is not None and v != "" and not (isinstance(v, float) and np.isnan(v))


@pytest.mark.e2e
def test_tiny_run_end_to_end(tiny_bench):
    """The session's tiny run (``tiny_bench``, tests/bench/conftest.py), started in an empty
    directory: its report in the mode's default directory, every section measured."""
    cwd, code, printed = tiny_bench
    assert code == 0
    assert f"tiny report in {Path('outputs/tiny') / 'bench.md'}" in printed
    out = cwd / "outputs" / "tiny"
    assert not (cwd / "outputs" / "bench.md").exists()  # the full report is not touched
    md = (out / "bench.md").read_text()
    for word in ("Mode: **tiny**", "JAX", "Command:", "total duration", "## Headline",
                 "## Work-precision", "## Hard-case suites", "## Scaling", "### End to end",
                 "### Exact at kernel speed", "## Simulation", "## Notes, omissions"):  # fmt: skip
        assert word in md, word
    js = json.loads((out / "bench_headline.json").read_text())
    head = js["headline"]
    assert {r["method"] for r in head} == set(METHODS)
    assert {r["dtype"] for r in head} == set(CONFIG["tiny"]["dtypes"])
    for r in head:
        assert all(_filled(r[c]) for c in HEAD_COLUMNS), r
        assert r["ns_per_point"] > 0
        if r["method"].startswith("certified"):  # never misclassifies a decided point
            assert r["misclassified"].startswith("0/")
    # the end-to-end CLI run of the tiny atlas: its size and settlement are known up front
    (e2e,) = js["atlases"]
    assert e2e["points"] == 8 * 8 * 2 * 2 and e2e["undecided_after"] == 0
    assert e2e["file_mb"] > 0 and e2e["peak_rss_mb"] > 0
    (scale,) = _csv(out / "bench_scaling.csv")
    assert int(scale["points"]) == 1 << 18 and int(scale["bytes_written"]) == 3 << 18
    sim = _csv(out / "bench_simulation.csv")
    assert [r["method"] for r in sim] == ["simulate (exact)", "solve_ivp DOP853", "solve_ivp Radau"]
    assert float(sim[0]["error"]) < 1e-9  # simulate against solve_ivp at rtol 1e-13
    (lanes,) = js["engine_lanes"]  # both engines on the tiny run's 6 random lanes
    assert lanes["lanes"] == 6 and lanes["disagreements"] == 0
    assert "### Lane by lane" in md
    for name in ("work_precision.png", "convergence.png", "scaling.png", "simulation.png",
                 "work_precision.csv", "suites.csv", "atlases.csv", "curves.csv"):  # fmt: skip
        assert (out / f"bench_{name}").stat().st_size > 0
    # exactly the declared files (outputs/ is compared with the same list)
    assert sorted(f.name for f in out.iterdir()) == sorted(runner.files("tiny"))
    # start-up, the cheap part: one import and one --help, whole processes, against 0.5 s
    start = _csv(out / "bench_startup.csv")
    assert [(r["figure"], r["runs"], r["target"]) for r in start] == [
        ("import atlas", "1", "0.5"), ("atlas --help", "1", "0.5")
    ]  # fmt: skip
    assert all(float(r["median_s"]) > 0 and r["met"] in ("met", "missed") for r in start)
    assert "## Start-up" in md and len(js["startup"]) == 2
    (curve_ss, curve_ii) = _csv(out / "bench_curves.csv")
    assert float(curve_ss["max_bracket"]) <= 1e-10 and int(curve_ss["curves"]) > 0
    rows = [ln for ln in md.split("## Headline")[1].split("##")[0].splitlines() if ln[:3] == "| ("]
    assert rows and all("|  |" not in ln for ln in rows)


def _csv(path):
    with open(path) as fh:
        return list(csv.DictReader(fh))
