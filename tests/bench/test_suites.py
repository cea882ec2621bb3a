"""``atlas.bench.suites``: the headline rows and the parsing of ``atlas generate``'s summary."""

import pytest

from atlas.bench.config import CONFIG
from atlas.bench.suites import HEADLINE_CASES, headline, parse_summary


def test_parse_summary_of_generate():
    line = (
        "atlas generate: out/a.nc: 1024 points in 0.52 s (1.97e+03 points/s), 0.01 MB; "
        "undecided 12 before, 0 after exact resolution"
    )
    assert parse_summary(line) == dict(
        points=1024, seconds=0.52, points_per_second=1970.0, undecided_before=12, undecided_after=0
    )


def test_parse_summary_of_distributed_generate():
    line = (
        "atlas generate: a.nc (store a.zarr): 4096 points in 2.00 s (2.05e+03 points/s) on "
        "LocalCluster with 2 worker(s); 4 tiles: 4 computed, 0 verified, 0 missing and 0 corrupt "
        "before; undecided 7 before, 1 after exact resolution"
    )
    s = parse_summary(line)
    assert (s["points"], s["undecided_before"], s["undecided_after"]) == (4096, 7, 1)
    assert s["seconds"] == 2.0


def _row(case, outputs, dtype, n, method, seconds, **kw):
    return dict(
        case=case, outputs=outputs, dtype=dtype, n=n, method=method, seconds=seconds,
        points=(n + 1) ** 2, ns_per_point=seconds / (n + 1) ** 2 * 1e9, floor_ns=0.5,
        misclassified_sample=0, sample=10, misclassified=kw.get("bad", 0), checked=12,
        undecided=kw.get("und", 0),
    )  # fmt: skip


def test_headline_picks_the_largest_grid_and_compares_with_eig():
    cfg = dict(CONFIG["quick"], res=(8, 16))
    wp = [
        _row("q=0", "all", "float64", 16, "certified", 0.001, und=3),
        _row("q=0", "all", "float64", 16, "verdicts_jit", 0.5),
        _row("q=0", "all", "float64", 16, "eig", 2.0, bad=1),
        _row("q=0", "all", "float64", 8, "certified", 1.0),  # not the headline grid
        _row("q=0.1", "SS", "float64", 16, "certified", 0.004),  # no eig row: no ratio
    ]
    head = headline(wp, cfg)
    assert [(r["case"], r["method"]) for r in head] == [
        ("(a) SS verdict alone, q=0.1", "certified"),
        ("(b) all verdicts, undamped (Fig. 1 scene, q=0)", "certified"),
        ("(b) all verdicts, undamped (Fig. 1 scene, q=0)", "verdicts_jit"),
        ("(b) all verdicts, undamped (Fig. 1 scene, q=0)", "eig"),
    ]
    a, cert, vjit, eig = head
    assert a["target_1000x"] == "not met" and a["eig_over_method"] != a["eig_over_method"]  # NaN
    assert cert["eig_over_method"] == pytest.approx(2000.0) and cert["target_1000x"] == "met"
    assert vjit["eig_over_method"] == pytest.approx(4.0) and vjit["target_1000x"] == "not met"
    assert eig["target_1000x"] == "baseline" and eig["misclassified"] == "1/12"
    assert cert["undecided"] == 3 and cert["method_over_floor"] == pytest.approx(
        0.001 / 289 * 1e9 / 0.5
    )


def test_headline_cases_are_work_precision_cases():
    names = {c[0] for c in CONFIG["full"]["cases"]}
    assert {case for case, _ in HEADLINE_CASES.values()} == names
