"""Speed against error: ``atlas bench`` and its report ``bench.md`` (SPEC §4).

Everything is measured in one run on this machine and reported as ratios measured in that run:

* **work-precision** -- methods (certified driver, certified + exact settlement, the single-jit
  :func:`atlas.core.spectral.verdicts_jit`, batched ``eig``) x dtype x grid resolution on beta
  grids: ns per point (minimum of repeats after compilation, results on the host) against
  misclassified points, undecided points and the Hausdorff distance of the drawn SS and II
  boundaries to a reference boundary on a finer grid (:mod:`atlas.bench.grids`,
  :mod:`atlas.bench.boundaries`);
* **hard-case suites** of :mod:`atlas.core.hardcases`: misclassified / undecided per method;
* **scaling** and **end to end**: time and peak RSS per atlas size, ``atlas generate``
  (:mod:`atlas.bench.suites`, subprocesses of :mod:`atlas.bench.timing`);
* **simulation**: :func:`atlas.dynamics.simulate` against ``solve_ivp``
  (:mod:`atlas.bench.simulation`);
* **start-up**: ``import atlas``, ``atlas --help``, ``atlas generate`` cold and warm,
  ``atlas selftest`` and the explorer as whole processes (:mod:`atlas.bench.startup`).

The report is built by :mod:`atlas.bench.report`, the figures by :mod:`atlas.bench.plots`.
Nothing here is imported by the library; :func:`run` is called by ``atlas bench``.
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

import numpy as np

from atlas.bench import distributed, model_axes, model_box_map, partial, plots, startup, suites
from atlas.bench.config import CONFIG, default_out, mode_name
from atlas.bench.curves import curves
from atlas.bench.grids import ExactCache
from atlas.bench.report import Results, build_report, write_csv
from atlas.bench.simulation import engine_lanes, jax_outcome_columns, outcome_maps, simulation
from atlas.bench.timing import log, machine
from atlas.core.config import use_compile_cache
from atlas.data.io import atomic_write_text

__all__ = ["run", "CONFIG"]

#: what every report says about how it was measured
NOTES = (
    "`verdicts_jit` on the damped grids is measured only at the headline size for q1 = q2 "
    "(each grid shape costs 10-30 s of compilation); never for q1 != q2.",
    "The SS-alone rows (a) reuse the damped q = 0.1 grid; `eig` there still computes "
    "eigenvectors (`atlas.core.baseline.eig_verdicts`).",
    "II boundaries here are drawn from 0/1 masks (the figures' II margin comes from "
    "uncertified eigenvalues, so it is not used as a reference).",
    "Misclassification counts are exact-verified on the checked points only (not every grid "
    "point); undecided counts cover the whole grid.",
)


#: the CSV sections of a run (``bench_<name>.csv``)
SECTIONS = (
    "work_precision", "suites", "large", "scaling", "atlases", "simulation", "curves", "startup",
)  # fmt: skip
#: every file a run writes into its output directory (``distributed.md`` only where the
#: configuration measures distributed generation: the full run); a test compares ``outputs/``
FILES = (
    "bench.md",
    "bench_headline.json",
    *(f"bench_{name}.csv" for name in SECTIONS),
    *(f"bench_{name}.png" for name in plots.NAMES),
    "distributed.md",
)


def files(mode: str) -> tuple[str, ...]:
    """The files a run of ``mode`` writes (a section its configuration turns off writes none)."""
    cfg = CONFIG[mode]
    off = {
        "distributed.md": not cfg.get("distributed"),
        "bench_large.csv": not cfg.get("large_n"),
        "bench_curves.csv": not cfg.get("curve_res"),
    }
    return tuple(f for f in FILES if not off.get(f, False))


def _work_precision(cfg, cache):
    wp, refs = suites.work_precision(cfg, cache, np.random.default_rng(20240601))
    return dict(wp=wp, refs=refs, head=suites.headline(wp, cfg))


def _outcome_maps(cfg, cache):
    maps = outcome_maps(cfg)
    jax_outcome_columns(maps, cfg)
    return dict(maps=maps, lanes=engine_lanes(cfg))


#: how each section is measured: ``fn(cfg, cache) -> {field: rows}`` (seeded: the same points
#: are checked every run, whichever sections it measures)
_MEASURE = {
    "work_precision": _work_precision,
    "model_grids": lambda cfg, cache: dict(model_grids=model_axes.measure(cfg)),
    "model_box_map": lambda cfg, cache: dict(model_box_map=model_box_map.measure(cfg)),
    "large": lambda cfg, cache: dict(
        large=suites.large_grid(cfg, cache, np.random.default_rng(20240602))
    ),
    "suites": lambda cfg, cache: dict(
        suites=suites.hard_case_suites(cfg, cache, np.random.default_rng(20240603))
    ),
    "scaling": lambda cfg, cache: dict(scaling=suites.scaling(cfg)),
    "atlases": lambda cfg, cache: dict(atlases=suites.atlases(cfg)),
    "curves": lambda cfg, cache: dict(curves=curves(cfg)),
    "simulation": lambda cfg, cache: dict(sim=simulation(cfg)),
    "outcome_maps": _outcome_maps,
    "startup": lambda cfg, cache: dict(startup=startup.measure(cfg["startup"])),
}
#: the sections that evaluate the exact reference (``ExactCache``)
_EXACT = ("work_precision", "large", "suites")


def _measure(cfg, names) -> dict:
    """The fields of the sections ``names``, in report order, and the exact reference's cost."""
    cache = ExactCache()
    fields = {}
    with np.errstate(all="ignore"):
        for name in names:
            if name in _MEASURE:
                fields.update(_MEASURE[name](cfg, cache))
    fields["exact"] = dict(
        points=len(cache.store), seconds=cache.seconds, failures=cache.failures,
        sections=[n for n in names if n in _EXACT],
    )  # fmt: skip
    return fields


def _results(meta, cfg, names, out) -> Results:
    """The sections ``names`` measured now; with ``--only``, the others read back from ``out``
    and ``meta["sections"]`` saying which run measured each."""
    whole = set(names) == set(partial.SECTIONS)
    kept = None if whole else partial.read_report(out)  # read first: a bad file costs no work
    fields = _measure(cfg, names)
    this = dict(start=meta["start"], command=meta["command"])
    mine = {n: dict(this) for n in names if n != "distributed" or cfg.get("distributed")}
    if whole:
        meta["sections"] = mine
        return Results(meta=meta, cfg=cfg, **fields)
    meta["sections"] = {**partial.section_runs(kept["meta"]), **mine}
    measured = {f for n in names for f in partial.SECTIONS[n]}
    if not set(names) & set(_EXACT):
        fields["exact"] = kept["exact"]
    for f in Results.__dataclass_fields__:
        if f not in ("meta", "cfg", "exact") and f not in measured:
            fields[f] = kept[f]
    return Results(meta=meta, cfg=cfg, **fields)


def _write(out: Path, r: Results, t_start: float, names):
    """The CSVs and figures of the sections ``names``, ``bench_headline.json`` and ``bench.md``
    into ``out`` (a kept section's files are left as they are)."""
    rows = dict(zip(SECTIONS, (r.wp, r.suites, r.large, r.scaling, r.atlases, r.sim, r.curves,
                                r.startup)))  # fmt: skip
    for name, section in rows.items():
        if name in names:
            write_csv(out / f"bench_{name}.csv", section)
    if "work_precision" in names:
        cases = [c[0] for c in r.cfg["cases"]]
        plots.plot_work_precision(out, r.wp, cases)
        plots.plot_convergence(out, r.wp, cases)
    if "scaling" in names:
        plots.plot_scaling(out, r.scaling)
    if "simulation" in names:
        plots.plot_simulation(out, r.sim)
    r.meta["duration"] = time.perf_counter() - t_start
    js = dict(
        meta=r.meta, headline=r.head, refs=r.refs, exact=r.exact, model_grids=r.model_grids,
        model_box_map=r.model_box_map, large=r.large,
        atlases=r.atlases, outcome_maps=r.maps, engine_lanes=r.lanes, startup=r.startup,
    )  # fmt: skip
    atomic_write_text(out / "bench_headline.json", json.dumps(js, indent=1, default=_json_default))
    atomic_write_text(out / "bench.md", build_report(r))


def run(quick: bool = False, out: str | None = None, config: str | None = None, only=None) -> int:
    """Run the benchmark and write :func:`files` (``bench.md``, ``bench_*.png``, ``bench_*.csv``,
    ``bench_headline.json``, and in the full run ``distributed.md``) into ``out``; returns 0.

    Parameters
    ----------
    quick : bool
        Small grids and subsamples (CI, < 2 minutes); the full run aims at < 30 minutes.
    out : str, optional
        Output directory (created if missing); default ``outputs`` for the full run (the committed
        report), ``outputs/quick`` for a quick one (ignored by git).
    config : str, optional
        A key of :data:`~atlas.bench.config.CONFIG` in place of ``quick`` (``tiny``: the tests).
    only : str or sequence of str, optional
        Re-measure only these sections (:data:`atlas.bench.partial.SECTIONS`, ``"a,b"``) and keep
        the others of the report of the same mode already in ``out``, which the report then
        names, per section, with the run that measured it.
    """
    t_start = time.perf_counter()
    mode = mode_name(quick, config)
    cfg = CONFIG[mode]
    out = default_out(mode) if out is None else Path(out)
    whole = tuple(partial.SECTIONS)
    names = whole if only is None else partial.check_only(only, out, mode, cfg, files(mode))
    out.mkdir(parents=True, exist_ok=True)
    meta = dict(
        mode=mode,
        quick=mode != "full",
        start=time.strftime("%Y-%m-%dT%H:%M:%S%z"),
        command=_command(mode, out, only),
        machine=machine(),
        notes=list(NOTES),
    )
    log(f"{mode} run into {out}" + (f", only {', '.join(names)}" if only is not None else ""))
    # timings exclude compilation (a warm-up call first); the cache spares recompiling next time
    use_compile_cache()
    results = _results(meta, cfg, names, out)
    if cfg.get("distributed") and "distributed" in names:
        log("distributed generation (in process, LocalCluster 1 and 2 workers)")
        distributed.measure_throughput(out=str(out))
    _write(out, results, t_start, names)
    log(f"done in {meta['duration']:.0f} s")
    print(f"atlas bench: {mode} report in {out / 'bench.md'}")
    return 0


def _command(mode, out, only=None) -> str:
    """The command line of this run, and the call it made."""
    argv = sys.argv[:]
    if argv and argv[0] in ("-c", ""):
        head = "python " + " ".join(argv)
    elif argv:
        head = " ".join([Path(argv[0]).name] + argv[1:])
    else:
        head = "python"
    call = f"quick={mode == 'quick'}" if mode in ("quick", "full") else f"config={mode!r}"
    if only is not None:
        call += f", only={only!r}"
    return f"{head} (bench.run({call}, out={str(out)!r}))"


def _json_default(x):
    if isinstance(x, np.integer):
        return int(x)
    if isinstance(x, np.floating):
        return float(x)
    return str(x)
