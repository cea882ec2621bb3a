"""``atlas bench --only``: the sections of a report, which run measured each, and an existing
report read back from its files (``bench_headline.json`` and ``bench_*.csv``) so that a run can
re-measure some sections and keep the others.

A report then joins several runs; ``meta["sections"]`` names, per section, the run that measured
it (its start and command), and :mod:`atlas.bench.report` prints that under each section's
heading. Ratios stay inside one section, so each is still a ratio of one run.
"""

from __future__ import annotations

import csv
import json
from pathlib import Path

__all__ = ["CSV_FIELDS", "SECTIONS", "check_only", "read_report", "section_runs"]

#: every section ``--only`` can name, in report order, and the :class:`~atlas.bench.report.Results`
#: fields it fills (``distributed`` writes its own file, ``distributed.md``)
SECTIONS = {
    "work_precision": ("wp", "refs", "head"),
    "model_grids": ("model_grids",),
    "model_box_map": ("model_box_map",),
    "large": ("large",),
    "suites": ("suites",),
    "scaling": ("scaling",),
    "atlases": ("atlases",),
    "simulation": ("sim",),
    "outcome_maps": ("maps", "lanes"),
    "curves": ("curves",),
    "startup": ("startup",),
    "distributed": (),
}
#: the fields stored only as CSV (``bench_<name>.csv``); the others are in ``bench_headline.json``
CSV_FIELDS = {
    "wp": "work_precision",
    "suites": "suites",
    "scaling": "scaling",
    "sim": "simulation",
    "curves": "curves",
}
#: the ``bench_headline.json`` key of each field stored there
JSON_FIELDS = {
    "head": "headline",
    "refs": "refs",
    "model_grids": "model_grids",
    "model_box_map": "model_box_map",
    "large": "large",
    "atlases": "atlases",
    "maps": "outcome_maps",
    "lanes": "engine_lanes",
    "startup": "startup",
}


def check_only(only, out: Path, mode: str, cfg: dict, files=()) -> tuple[str, ...]:
    """The sections named by ``only`` (``"a,b"`` or a sequence); a :class:`ValueError` naming
    ``only`` for an unknown or off section, or without an existing report of ``mode`` in ``out``
    (every one of ``files``, the tables and texts a whole run writes there)."""
    names = only.split(",") if isinstance(only, str) else list(only)
    names = [n.strip() for n in names]
    bad = [n for n in names if n not in SECTIONS]
    if bad or not names:
        raise ValueError(
            f"only: unknown section {', '.join(map(repr, bad)) or repr('')}; "
            f"valid: {', '.join(SECTIONS)}"
        )
    if "distributed" in names and not cfg.get("distributed"):
        raise ValueError(f"only: the {mode} configuration does not measure distributed")
    stored = out / "bench_headline.json"
    if not stored.is_file() or not (out / "bench.md").is_file():
        raise ValueError(
            f"only: needs an existing full report in {str(out)!r} (bench_headline.json and "
            "bench.md); run atlas bench without --only first"
        )
    meta = json.loads(stored.read_text())["meta"]
    if meta.get("mode") != mode:
        raise ValueError(
            f"only: the report in {str(out)!r} is a {meta.get('mode')} run, this one {mode}: "
            "sections of different sizes are not joined"
        )
    lost = [f for f in files if f.endswith((".csv", ".md")) and not (out / f).is_file()]
    if lost:
        raise ValueError(
            f"only: the report in {str(out)!r} lacks {', '.join(lost)}; run atlas bench without "
            "--only first"
        )
    return tuple(dict.fromkeys(names))


def section_runs(meta: dict) -> dict:
    """Per section, the run that measured it: ``{"start", "command"}`` (a report written before
    runs were recorded per section: its own run for every section)."""
    run = dict(start=meta["start"], command=meta["command"])
    if "sections" in meta:
        return {name: dict(v) for name, v in meta["sections"].items()}
    return {name: dict(run) for name in SECTIONS if name != "distributed" or meta["mode"] == "full"}


def read_report(out: Path) -> dict:
    """An existing report's fields (the keys of :data:`SECTIONS`' tuples, ``meta`` and ``exact``),
    read back from ``bench_headline.json`` and ``bench_*.csv`` (a missing CSV: no rows)."""
    js = json.loads((out / "bench_headline.json").read_text())
    fields = {f: js.get(key, {} if f == "refs" else []) for f, key in JSON_FIELDS.items()}
    for f, name in CSV_FIELDS.items():
        fields[f] = _read_csv(out / f"bench_{name}.csv")
    fields["meta"] = js["meta"]
    fields["exact"] = js.get("exact")
    return fields


def _read_csv(path: Path) -> list[dict]:
    """Rows written by :func:`atlas.bench.report.write_csv`, numbers as numbers; an empty cell
    (a column the row did not have) is left out of the row."""
    if not path.is_file():
        return []
    with open(path, newline="") as fh:
        return [{k: _value(v) for k, v in r.items() if v != ""} for r in csv.DictReader(fh)]


def _value(text: str):
    """A CSV cell as the int, float (``nan``, ``inf`` included) or string it was written from."""
    try:
        return int(text)
    except ValueError:
        pass
    try:
        return float(text)
    except ValueError:
        return text
