"""``atlas bench --only``: some sections re-measured, the others of the report in ``--out`` kept
from its files, every section naming the run that measured it; refusals before any work."""

import json
import math
import shutil
from pathlib import Path

import pytest

from atlas.bench import partial, run
from atlas.bench.config import CONFIG
from atlas.bench.report import Results, build_report, write_csv
from atlas.cli import main

VALID = ", ".join(partial.SECTIONS)


def _refused(argv, capsys) -> str:
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err
    return err


def test_an_unknown_section_is_refused_naming_the_parameter_and_the_valid_names(tmp_path, capsys):
    out = tmp_path / "report"
    err = _refused(["bench", "--only", "simulation,timing", "--out", str(out)], capsys)
    assert err == f"atlas: error: only: unknown section 'timing'; valid: {VALID}"
    assert not out.exists()  # refused before any work


def test_only_without_an_existing_report_is_refused(tmp_path, capsys):
    out = tmp_path / "report"
    err = _refused(["bench", "--only", "simulation", "--out", str(out)], capsys)
    assert err.startswith("atlas: error: only: needs an existing full report in")
    assert not out.exists()


def test_only_over_a_report_of_another_size_is_refused(tmp_path, capsys):
    (tmp_path / "bench.md").write_text("# a tiny report\n")
    meta = dict(mode="tiny", start="2026-01-01T00:00:00+0000", command="atlas bench")
    (tmp_path / "bench_headline.json").write_text(json.dumps(dict(meta=meta)))
    err = _refused(["bench", "--only", "suites", "--out", str(tmp_path)], capsys)
    assert "only: the report in" in err and "is a tiny run, this one full" in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bench.md", "bench_headline.json"]


def test_a_report_missing_a_kept_sections_file_is_refused(tmp_path):
    (tmp_path / "bench.md").write_text("# a tiny report\n")
    meta = dict(mode="tiny", start="2026-01-01T00:00:00+0000", command="atlas bench")
    (tmp_path / "bench_headline.json").write_text(json.dumps(dict(meta=meta)))
    with pytest.raises(ValueError, match="^only: the report in .* lacks bench_work_precision.csv"):
        run(config="tiny", out=str(tmp_path), only="simulation")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bench.md", "bench_headline.json"]


def test_distributed_is_refused_where_the_configuration_does_not_measure_it(tmp_path):
    with pytest.raises(ValueError, match="^only: the tiny configuration does not measure"):
        run(config="tiny", out=str(tmp_path), only="distributed")


def test_csv_rows_read_back_as_written(tmp_path):
    rows = [
        dict(case="q=0", n=16, ns=12.5, err=math.inf, h=math.nan, dtype="float64"),
        dict(case="(b) q=0.1", n=32, ns=1e-7, extra="met"),  # a column the first row lacks
    ]
    write_csv(tmp_path / "bench_x.csv", rows)
    back = partial._read_csv(tmp_path / "bench_x.csv")
    assert back[1] == rows[1] and back[0].keys() == rows[0].keys()
    assert back[0]["err"] == math.inf and math.isnan(back[0]["h"])
    assert {k: v for k, v in back[0].items() if k != "h"} == {
        k: v for k, v in rows[0].items() if k != "h"
    }
    assert isinstance(back[0]["n"], int)


@pytest.fixture
def tiny_report(tiny_bench):
    """A whole ``tiny`` run, measured for real: the session's (tests/bench/conftest.py)."""
    cwd, code, _ = tiny_bench
    assert code == 0
    return cwd / "outputs" / "tiny"


def _without_stamps(md: str) -> list[str]:
    """The report's lines but the header's run lines and the per-section stamps."""
    if "**This report joins" in md:
        head, _, rest = md.partition("**This report joins")
        md = head + "## Headline" + rest.split("## Headline", 1)[1]
    drop = ("Mode:", "Machine:", "*Measured by the run")
    return [ln for ln in md.splitlines() if ln and not ln.startswith(drop)]


@pytest.mark.e2e
def test_only_remeasures_its_sections_and_keeps_the_others(tiny_report, tmp_path):
    old = tiny_report
    md_old = (old / "bench.md").read_text()
    meta_old = json.loads((old / "bench_headline.json").read_text())["meta"]
    assert "joins several runs" not in md_old and "*Measured by" not in md_old  # one run
    assert set(meta_old["sections"]) == set(partial.SECTIONS) - {"distributed"}
    out = tmp_path / "tiny"
    shutil.copytree(old, out)
    assert run(config="tiny", out=str(out), only="simulation") == 0
    js = json.loads((out / "bench_headline.json").read_text())
    meta = js["meta"]
    assert meta["start"] != meta_old["start"] or meta["command"] != meta_old["command"]
    assert "only='simulation'" in meta["command"]
    this = dict(start=meta["start"], command=meta["command"])
    runs = meta["sections"]
    assert runs["simulation"] == this
    first = dict(start=meta_old["start"], command=meta_old["command"])
    assert all(v == first for k, v in runs.items() if k != "simulation")
    # the kept sections' files are untouched; the simulation's rewritten
    for f in sorted(old.iterdir()):
        same = (out / f.name).read_bytes() == f.read_bytes()
        assert same == (f.name not in ("bench.md", "bench_headline.json",
                                       "bench_simulation.csv", "bench_simulation.png")), f.name  # fmt: skip
    for key in ("headline", "refs", "exact", "model_grids", "atlases", "outcome_maps", "startup"):
        assert js[key] == json.loads((old / "bench_headline.json").read_text())[key], key
    # the report: every kept section as it was, each under the run that measured it
    md = (out / "bench.md").read_text()
    assert "**This report joins several runs**" in md
    sim_new = md.split("## Simulation")[1].split("\n## ")[0]
    assert f"*Measured by the run started {this['start']} (`{this['command']}`).*" in sim_new
    stamp_old = f"*Measured by the run started {first['start']} (`{first['command']}`).*"
    for heading in ("## Headline", "## Work-precision", "## Hard-case suites", "## Scaling",
                    "### End to end", "## Boundary curves", "## Outcome maps", "## Start-up"):  # fmt: skip
        after = md.split(heading)[1].split("\n#")[0]
        assert stamp_old in after, heading
    sim_old = md_old.split("## Simulation")[1].split("\n## ")[0]
    kept_old = _without_stamps(md_old.replace(sim_old, ""))
    kept_new = _without_stamps(md.replace(sim_new, ""))
    assert kept_new == kept_old


ROOT = Path(__file__).resolve().parents[2]
#: the report's sections built from CSV files alone (the others come from bench_headline.json)
CSV_HEADINGS = ("## Work-precision", "## Hard-case suites", "## Scaling", "## Boundary curves",
                "## Simulation")  # fmt: skip


def _section(md: str, heading: str) -> list[str]:
    """The lines of one section of ``md`` (to the next heading of its level or above), without
    the lines of what older reports did not store (the reference grids' settlement)."""
    body = md.split(heading, 1)[1].split("\n## ", 1)[0]
    return [ln for ln in body.splitlines() if not ln.startswith("Reference grids:")]


def test_the_committed_report_rebuilds_from_its_files():
    """What ``--only`` keeps: every CSV-backed section of ``outputs/bench.md`` read back from
    its files gives the same text (numbers, NaN, inf and missing cells as they were)."""
    out = ROOT / "outputs"
    kept = partial.read_report(out)
    meta, exact = kept.pop("meta"), kept.pop("exact")
    md = build_report(Results(meta=meta, cfg=CONFIG[meta["mode"]], exact=exact, **kept))
    committed = (out / "bench.md").read_text()
    for heading in CSV_HEADINGS:
        assert _section(md, heading) == _section(committed, heading), heading
