"""``atlas.bench.report``: bench.md from a made-up result set (no measurement)."""

import csv
import math
import re
from pathlib import Path

import pytest

from atlas.bench import report

COMMITTED = Path(__file__).resolve().parents[2] / "outputs" / "bench.md"


def _skeleton(md: str) -> list[str]:
    """Headings and table header rows of a report, in order (what a run's numbers don't change);
    without the table of runs a report joined by ``atlas bench --only`` adds."""
    lines = md.splitlines()
    out = []
    for i, ln in enumerate(lines):
        if ln.startswith("#"):
            out.append(re.sub(r"\(\d+ x \d+ = [\d,]+ points", "(N points", ln))
        elif ln.startswith("|") and i + 1 < len(lines) and lines[i + 1].startswith("|---"):
            out.append(ln)
    return [ln for ln in out if ln != "| section | start | command |"]


def test_full_report_has_the_sections_and_columns_of_the_committed_one(results):
    """Same headings and table columns, in the same order, as outputs/bench.md of the full run."""
    if not COMMITTED.exists():
        pytest.skip("no committed outputs/bench.md")
    assert _skeleton(report.build_report(results)) == _skeleton(COMMITTED.read_text())


def test_sections_in_order(results):
    md = report.build_report(results)
    heads = [ln for ln in md.splitlines() if ln.startswith("#")]
    assert heads == [
        "# atlas bench: speed against error",
        "## Headline",
        "### 2-D and 5-D grids",
        "### Model-dependence map of the Fig. 1 plane",
        "### At 1e7 points (3163 x 3163 = 10,004,569 points)",
        "## Work-precision",
        "## Hard-case suites",
        "## Scaling",
        "### End to end: `atlas generate`",
        "### Exact at kernel speed",
        "## Boundary curves (`atlas boundaries`)",
        "## Simulation",
        "## Outcome maps: fast engine against the exact simulator",
        "### Lane by lane: fast engine against the exact simulator",
        "## Start-up",
        "### Where a cold run's seconds go",
        "## Notes, omissions",
    ]
    assert "Mode: **full**" in md and "total duration **1234 s**" in md
    assert "* a note" in md and "Exact reference: 42 distinct points evaluated in 3 s" in md


def test_optional_sections_left_out(results):
    results.large, results.atlases = [], []
    md = report.build_report(results)
    assert "### At 1e7 points" not in md and "### End to end" not in md
    assert "## Scaling" in md and "### Exact at kernel speed" in md


def test_numbers_of_the_made_up_run(results):
    """Values follow from the made-up rows: eig costs 2000x certified, H = h/2 and h^2."""
    md = report.build_report(results)
    head = results.head
    cert = [r for r in head if r["method"] == "certified"]
    assert cert and all(r["eig_over_method"] == pytest.approx(2000.0) for r in cert)
    met = sum(r["target_1000x"] == "met" for r in head)
    notmet = sum(r["target_1000x"] == "not met" for r in head)
    assert f"met in {met} of {met + notmet} rows" in md
    assert met == 4 * 2 * 3  # 4 cases x 2 dtypes x (certified, +exact, verdicts_jit: >= 1000x)
    # convergence orders: margin error h^2, mask errors h/2
    assert "* q=0: SS margin 2, SS mask 1, II mask 1" in md
    # shifted/axis = 1.2, atlas4d = 25x the 19,800 points/s before
    assert "ratio **1.2**" in md and "**25x** the 19800 points/s" in md
    assert "worst hard suite **41 us/point** (class_boundaries" in md
    # the suites' totals: 2 suites x 10 points, 1 undecided each
    assert "certified float64: 0 misclassified, 2 undecided of 20" in md
    assert "| d | solve_ivp DOP853 | 0.001 | 0.05 | 20 | mismatch | 1500 |" in md
    # start-up: the made-up figures against their targets, "-" where a figure has none
    assert "**Targets**: met in 1 of 2 figures." in md
    assert "| generate 512 points, cold | 5 | 20 | 20 | 20 | - | x warm | 8 | - | - |" in md


def test_tables_have_no_empty_cells(results):
    md = report.build_report(results)
    rows = [ln for ln in md.splitlines() if ln.startswith("| (")]
    assert rows and all("|  |" not in ln for ln in rows)


@pytest.mark.parametrize(
    "x, text",
    [
        ("abc", "abc"),
        (None, "n/a"),
        (math.nan, "n/a"),
        (math.inf, "mismatch"),
        (7, "7"),
        (0.0, "0"),
        (1234.6, "1235"),
        (0.0123456, "0.0123"),
        (-250.2, "-250"),
    ],
)
def test_fmt(x, text):
    assert report.fmt(x) == text


def test_table_headers_and_missing_cells():
    md = report.table([{"a": 1, "b": 0.5}, {"a": 2}], [("a", "A"), "b"])
    assert md.splitlines() == ["| A | b |", "|---|---|", "| 1 | 0.5 |", "| 2 |  |"]


def test_slope_of_power_laws():
    x = [1.0, 2.0, 4.0, 8.0]
    assert report.slope(x, [v**2 for v in x]) == pytest.approx(2.0)
    assert report.slope(x, [3 / v for v in x]) == pytest.approx(-1.0)
    assert math.isnan(report.slope(x, [1.0, math.nan, 0.0, -1.0]))  # fewer than 2 usable


def test_write_csv_columns_in_order_of_appearance(tmp_path):
    path = tmp_path / "t.csv"
    report.write_csv(path, [{"a": 1}, {"b": 2, "a": 3}])
    with open(path) as fh:
        assert list(csv.reader(fh)) == [["a", "b"], ["1", ""], ["3", "2"]]
    report.write_csv(tmp_path / "none.csv", [])
    assert not (tmp_path / "none.csv").exists()


def test_outcome_maps_section_lists_every_disagreement(results):
    """The fast-engine section: its table, and each disagreement of a map on its own line."""
    row = dict(map="8x8, kappa=0.5, q=0, alpha=0.35pi", trajectories=64, workers=2,
               fast_seconds=1.5, fast_per_s=42.0, core_seconds=2.0, core_per_s=32.0,
               identical=True, ref_cells=8, ref_per_s=30.0, speedup=1.1, early_settle=0.25,
               early_iwc=0.5, stepped=0.25, fallback=0.0, agreement=0.875,
               disagreements="(1,2): reference IWC (diverged at t = 17, 2 events), fast undetermined")  # fmt: skip
    results.maps = [row, dict(row, map="other", agreement=1.0, disagreements="")]
    md = report.build_report(results)
    heads = [ln for ln in md.splitlines() if ln.startswith("#")]
    assert heads[-5:] == ["## Outcome maps: fast engine against the exact simulator",
                          "### Lane by lane: fast engine against the exact simulator",
                          "## Start-up", "### Where a cold run's seconds go",
                          "## Notes, omissions"]  # fmt: skip
    assert "| map | trajectories | workers | fast_seconds | fast_per_s | core_seconds |" in md
    assert "* 8x8, kappa=0.5, q=0, alpha=0.35pi: (1,2): reference IWC" in md
    assert "* other:" not in md


def test_engine_lanes_table_follows_the_outcome_maps_and_lists_disagreements(results):
    """The lane-by-lane rows (``Results.lanes``) under the outcome maps: their table with the
    per-lane ratio and the counts against the median lane, each disagreeing set on its own line;
    no such table without rows."""
    row = dict(set="2000 random lanes (seed 44)", lanes=2000, disagreements=1, fallback=0.0,
               fast_cpu_s=20.0, exact_cpu_s=900.0, speedup=45.0, ratio_median=0.1,
               ratio_p99=0.6, ratio_worst=1.2, over_exact=3, steps_median=6.0, steps_max=130,
               over_steps=4, over_cost=4, worst_over_median=21.7, over_steps_per_event=1.1,
               event_steps_worst=12.5, event_cost_worst=12.5, over_event=2,
               over_exact_stepped=1, fallback_worst=1.15, met=False,
               disagree_lanes="lane 7: exact 3, fast 2")  # fmt: skip
    results.lanes = []
    assert "### Lane by lane" not in report.build_report(results)
    results.lanes = [row, dict(row, set="grid", disagreements=0, disagree_lanes="")]
    md = report.build_report(results)
    heads = [ln for ln in md.splitlines() if ln.startswith("#")]
    i = heads.index("## Outcome maps: fast engine against the exact simulator")
    assert heads[i + 1 : i + 3] == ["### Lane by lane: fast engine against the exact simulator",
                                    "## Start-up"]  # fmt: skip
    header = ("| set | lanes | disagreements | fallback | fast_cpu_s | exact_cpu_s | speedup | "
              "ratio_median | ratio_p99 | ratio_worst | over_exact | steps_median | steps_max | "
              "over_steps | over_cost | worst_over_median | over_steps_per_event | "
              "event_steps_worst | event_cost_worst | over_event | over_exact_stepped | "
              "fallback_worst | met |")  # fmt: skip
    assert header in md
    assert "| 4 | 4 | 21.7 | 1.1 | 12.5 | 12.5 | 2 | 1 | 1.15 | 0 |" in md
    assert "read as: no lane's cost is out of proportion to the work its physics needs" in md
    row_md = "| 2000 random lanes (seed 44) | 2000 | 1 | 0 | 20 | 900 | 45 | 0.1 | 0.6 | 1.2 | 3 |"
    assert row_md in md
    assert "* 2000 random lanes (seed 44): lane 7: exact 3, fast 2" in md
    assert "* grid:" not in md
