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

from atlas.bench import distributed, model_axes, model_box_map, plots, startup, suites
from atlas.bench.config import CONFIG, default_out, mode_name
from atlas.bench.curves import curves
from atlas.bench.grids import ExactCache
from atlas.bench.report import Results, build_report, write_csv
from atlas.bench.simulation import jax_outcome_columns, outcome_maps, simulation
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


def _measure(cfg, meta) -> Results:
    """Every section of the run, in order (seeded: the same points are checked every run)."""
    rng = np.random.default_rng(20240601)
    cache = ExactCache()
    with np.errstate(all="ignore"):
        wp, refs = suites.work_precision(cfg, cache, rng)
        model_grids = model_axes.measure(cfg)
        box_map = model_box_map.measure(cfg)
        large = suites.large_grid(cfg, cache, rng)
        hard = suites.hard_case_suites(cfg, cache, rng)
        scaling = suites.scaling(cfg)
        atlases = suites.atlases(cfg)
        sim = simulation(cfg)
        maps = outcome_maps(cfg)
        jax_outcome_columns(maps, cfg)
        curve_rows = curves(cfg)
    startup_rows = startup.measure(cfg["startup"])
    exact = dict(points=len(cache.store), seconds=cache.seconds, failures=cache.failures)
    return Results(
        meta=meta,
        cfg=cfg,
        head=suites.headline(wp, cfg),
        wp=wp,
        refs=refs,
        suites=hard,
        scaling=scaling,
        sim=sim,
        large=large,
        model_grids=model_grids,
        model_box_map=box_map,
        atlases=atlases,
        curves=curve_rows,
        maps=maps,
        startup=startup_rows,
        exact=exact,
    )


def _write(out: Path, r: Results, t_start: float):
    """``bench_*.csv``, the figures, ``bench_headline.json`` and ``bench.md`` into ``out``."""
    rows = (r.wp, r.suites, r.large, r.scaling, r.atlases, r.sim, r.curves, r.startup)
    for name, section in zip(SECTIONS, rows):
        write_csv(out / f"bench_{name}.csv", section)
    plots.plot_all(out, r.wp, r.scaling, r.sim, r.cfg)
    r.meta["duration"] = time.perf_counter() - t_start
    js = dict(
        meta=r.meta, headline=r.head, model_grids=r.model_grids,
        model_box_map=r.model_box_map, large=r.large,
        atlases=r.atlases, outcome_maps=r.maps, startup=r.startup,
    )  # fmt: skip
    atomic_write_text(out / "bench_headline.json", json.dumps(js, indent=1, default=_json_default))
    atomic_write_text(out / "bench.md", build_report(r))


def run(quick: bool = False, out: str | None = None, config: str | None = None) -> int:
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
    """
    t_start = time.perf_counter()
    mode = mode_name(quick, config)
    out = default_out(mode) if out is None else Path(out)
    out.mkdir(parents=True, exist_ok=True)
    meta = dict(
        mode=mode,
        quick=mode != "full",
        start=time.strftime("%Y-%m-%dT%H:%M:%S%z"),
        command=_command(mode, out),
        machine=machine(),
        notes=list(NOTES),
    )
    log(f"{mode} run into {out}")
    # timings exclude compilation (a warm-up call first); the cache spares recompiling next time
    use_compile_cache()
    results = _measure(CONFIG[mode], meta)
    if CONFIG[mode].get("distributed"):
        log("distributed generation (in process, LocalCluster 1 and 2 workers)")
        distributed.measure_throughput(out=str(out))
    _write(out, results, t_start)
    log(f"done in {meta['duration']:.0f} s")
    print(f"atlas bench: {mode} report in {out / 'bench.md'}")
    return 0


def _command(mode, out) -> str:
    """The command line of this run, and the call it made."""
    argv = sys.argv[:]
    if argv and argv[0] in ("-c", ""):
        head = "python " + " ".join(argv)
    elif argv:
        head = " ".join([Path(argv[0]).name] + argv[1:])
    else:
        head = "python"
    call = f"quick={mode == 'quick'}" if mode in ("quick", "full") else f"config={mode!r}"
    return f"{head} (bench.run({call}, out={str(out)!r}))"


def _json_default(x):
    if isinstance(x, np.integer):
        return int(x)
    if isinstance(x, np.floating):
        return float(x)
    return str(x)
