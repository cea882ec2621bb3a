"""The measured sections of ``atlas bench``: work-precision grids, the 1e7-point grid, the hard-case
suites, scaling with atlas size and ``atlas generate`` end to end; the headline rows.

Each section takes the run's configuration (:data:`atlas.bench.config.CONFIG`) and returns rows
(dicts), the same rows that go to ``bench_*.csv`` and to the tables of ``bench.md``.
"""

from __future__ import annotations

import math
import tempfile
from pathlib import Path

import numpy as np

from atlas.bench.boundaries import contour_lines, hausdorff, masks, ss_margin
from atlas.bench.config import AXIS_PAIR, CASES, FLAGS, KEYS, METHODS
from atlas.bench.grids import ExactCache, measure_grid, misclassified, reference, run_method
from atlas.bench.timing import log, run_cli, run_worker, timeit
from atlas.core import exact, hardcases
from atlas.core.points import spectral_points

__all__ = [
    "atlases",
    "hard_case_suites",
    "headline",
    "large_grid",
    "scaling",
    "work_precision",
]

# --------------------------------------------------------------------------- work-precision


def _grid_methods(case, n, cfg) -> list[str]:
    """Methods measured on a grid: ``verdicts_jit`` on undamped grids, and on damped equal-q grids
    only at the sizes ``vjit_damped_res`` (each damped grid shape costs 10-30 s of compilation)."""
    damped = case[2] != 0 or case[3] != 0
    methods = [m for m in METHODS if m != "verdicts_jit" or not damped]
    if damped and n in cfg["vjit_damped_res"] and case[2] == case[3]:
        methods.insert(2, "verdicts_jit")
    return methods


def _with_boundary_errors(rows, res, beta, args, ref, damped, n):
    """Hausdorff distances [rad] of the drawn SS / II boundaries of each row's method (and of the
    SS margin) to the reference ``ref``; coarse lines densified to h/4."""
    step = 2 * np.pi / n / 4
    hm = hausdorff(contour_lines(beta, ss_margin(args), 0.0), ref["lines"]["SS_margin"], step)
    for row in rows:
        drawn = masks(res[row["method"]], damped)
        for b in ("SS", "II"):
            lines = contour_lines(beta, drawn[b], 0.5)
            row[f"hausdorff_{b}_mask"] = hausdorff(lines, ref["lines"][b], step)
        row["hausdorff_SS_margin"] = hm
    return hm


def work_precision(cfg, cache: ExactCache, rng):
    """Every method x dtype x resolution x case: rows with time, errors and boundary distances,
    plus the SS verdict alone on the damped equal-q grid at the headline size; and the reference
    grids per case."""
    rows, refs = [], {}
    head_n = cfg["res"][-1]
    for case in cfg["cases"]:
        log(f"reference boundary {case[0]} ({head_n * cfg['ref_factor']}^2 grid)")
        ref = refs[case[0]] = reference(case, cfg, cache)
        damped = case[2] != 0 or case[3] != 0
        for dtype in cfg["dtypes"]:
            for n in cfg["res"]:
                methods = _grid_methods(case, n, cfg)
                sample = cfg["sample"] if n == head_n else cfg["sample_small"]
                log(f"work-precision {case[0]} {dtype} n={n} ({', '.join(methods)})")
                r, res, beta, args = measure_grid(
                    case, dtype, n, FLAGS, methods, cfg, cache, rng, sample=sample
                )
                hm = _with_boundary_errors(r, res, beta, args, ref, damped, n)
                rows += r
                if n == head_n and case[0] == "q=0.1":  # headline (a): the SS verdict alone
                    r2, _, _, _ = measure_grid(
                        case,
                        dtype,
                        n,
                        ("stable_SS",),
                        list(METHODS),
                        cfg,
                        cache,
                        rng,
                        sample=sample,
                    )
                    for row in r2:
                        row.update(
                            hausdorff_SS_mask=math.nan,
                            hausdorff_II_mask=math.nan,
                            hausdorff_SS_margin=hm,
                        )
                    rows += r2
    return rows, refs


#: headline label -> (work-precision case, outputs)
HEADLINE_CASES = {
    "(a) SS verdict alone, q=0.1": ("q=0.1", "SS"),
    "(b) all verdicts, undamped (Fig. 1 scene, q=0)": ("q=0", "all"),
    "(c) all verdicts, damped q=0.1": ("q=0.1", "all"),
    "(c') all verdicts, damped q1=0.05, q2=0.2": ("q1=0.05,q2=0.2", "all"),
}


def _headline_row(label, r, eig) -> dict:
    speedup = eig["seconds"] / r["seconds"] if eig else math.nan
    if r["method"] == "eig":
        target = "baseline"
    else:
        target = "met" if speedup >= 1000 else "not met"
    return dict(
        case=label,
        dtype=r["dtype"],
        method=r["method"],
        points=r["points"],
        ns_per_point=r["ns_per_point"],
        eig_over_method=speedup,
        method_over_floor=r["ns_per_point"] / r["floor_ns"],
        misclassified_sample=f"{r['misclassified_sample']}/{r['sample']}",
        misclassified=f"{r['misclassified']}/{r['checked']}",
        undecided=r["undecided"],
        target_1000x=target,
    )


def headline(wp, cfg) -> list[dict]:
    """The headline rows: the largest work-precision grid of each :data:`HEADLINE_CASES` entry,
    with the speed-up over batched ``eig`` and its target (>= 1000x)."""
    n = cfg["res"][-1]
    out = []
    for label, (case, outputs) in HEADLINE_CASES.items():
        for dtype in cfg["dtypes"]:
            rs = [
                r
                for r in wp
                if (r["case"], r["outputs"], r["dtype"], r["n"]) == (case, outputs, dtype, n)
            ]
            eig = next((r for r in rs if r["method"] == "eig"), None)
            out += [_headline_row(label, r, eig) for r in rs]
    return out


# --------------------------------------------------------------------------- 1e7 points


def _large_case(case, dtype, cfg, lc, cache, rng):
    """The certified and ``eig`` rows of one large grid; for q=0.1 also the SS verdict alone
    (``eig``'s all-verdicts time is its baseline: eig computes every eigenpair either way)."""
    n, check = cfg["large_n"], cfg["large_check"]
    log(f"large grid {case[0]} {dtype}: {(n + 1) ** 2:.3g} points")
    rows, _, _, _ = measure_grid(
        case, dtype, n, FLAGS, ["certified", "eig"], lc, cache, rng, sample=check
    )
    for r in rows:
        r["label"] = f"all verdicts, {case[0]}"
    if case[0] == "q=0.1":
        eig = next(r for r in rows if r["method"] == "eig")
        r_ss, _, _, _ = measure_grid(
            case, dtype, n, ("stable_SS",), ["certified"], lc, cache, rng, sample=check
        )
        for r in r_ss:
            r["label"] = f"SS verdict alone, {case[0]}"
        rows += r_ss
        rows.append(dict(eig, label=f"SS verdict alone, {case[0]}", outputs="SS"))
    return rows


def large_grid(cfg, cache, rng) -> list[dict]:
    """The headline on a grid of >= 1e7 points (``large_n``; none if 0): each method called
    once after compilation, errors on a capped check (``large_check`` points per kind)."""
    if not cfg["large_n"]:
        return []
    lc = dict(cfg, budget=0.0, min_repeats=1)
    lc.update(undecided_cap=cfg["large_check"], disagree_cap=cfg["large_check"])
    rows = []
    for case in CASES[:2]:
        for dtype in cfg["dtypes"]:
            rows += _large_case(case, dtype, cfg, lc, cache, rng)
    for r in rows:
        eig = next(
            e
            for e in rows
            if e["method"] == "eig" and (e["case"], e["dtype"]) == (r["case"], r["dtype"])
        )
        r["eig_over_method"] = eig["seconds"] / r["seconds"]
        r["method_over_floor"] = r["ns_per_point"] / r["floor_ns"]
    return rows


# --------------------------------------------------------------------------- hard cases


def _exact_us_per_point(pts) -> float:
    """Microseconds a point of the exact tier (:func:`atlas.core.exact.resolve`, every flag)."""
    t = timeit(lambda: exact.resolve(pts, names=FLAGS), budget=1.0, max_repeats=3, min_repeats=1)
    return t / len(pts["c1"]) * 1e6


def _suite_points(sname, dtype, cfg, rng):
    """The inputs of suite ``sname`` (a seeded subsample of ``suite_points`` if set)."""
    s = hardcases.suite(sname, dtype)
    idx = np.arange(s["c1"].size)
    if cfg["suite_points"]:
        idx = np.sort(rng.choice(idx, min(cfg["suite_points"], idx.size), replace=False))
    return tuple(s[k][idx] for k in KEYS)


def _suite_verdicts(method, args, dtype, damped):
    if method == "certified+exact":
        return spectral_points(*args, names=FLAGS, dtype=dtype, resolve=True)
    return run_method(method, args, FLAGS, dtype, damped)


def hard_case_suites(cfg, cache, rng) -> list[dict]:
    """Misclassified and undecided points per method, suite (:mod:`atlas.core.hardcases`) and
    dtype against the exact verdicts; per verdict (``bad_*``) and the exact tier's us per point."""
    rows = []
    for sname in cfg["suites"] or tuple(hardcases.SUITES):
        for dtype in cfg["dtypes"]:
            args = _suite_points(sname, dtype, cfg, rng)
            pts = {k: a.astype(np.float64) for k, a in zip(KEYS, args)}
            log(f"suite {sname} {dtype}: {len(pts['c1'])} points")
            ref = cache.get(pts)
            exact_us = _exact_us_per_point(pts)
            damped = bool(np.any(pts["q1"] != 0) or np.any(pts["q2"] != 0))
            for m in METHODS:
                fast = _suite_verdicts(m, args, dtype, damped)
                bad, und = misclassified(fast, ref)
                per = {f"bad_{k}": misclassified({k: fast[k]}, ref, (k,))[0] for k in FLAGS}
                rows.append(
                    dict(
                        suite=sname,
                        dtype=dtype,
                        method=m,
                        points=len(pts["c1"]),
                        misclassified=bad,
                        undecided=und,
                        exact_us_per_point=exact_us,
                        **per,
                    )
                )
    return rows


# --------------------------------------------------------------------------- scaling, end to end


def scaling(cfg) -> list[dict]:
    """Time and peak RSS per atlas size, a fresh subprocess per size (:func:`scale_worker`), and
    ``io.generate_to_file`` end to end at ``generate_points`` (if set)."""
    rows = []
    for q, sizes in ((0.0, cfg["scale_undamped"]), (0.1, cfg["scale_damped"])):
        for n in sizes:
            log(f"scaling q={q} n={n:.0e} (subprocess)")
            d = run_worker("tiles", n, q, "float64")
            rows.append(dict(driver="spectral_points tiles", q=q, dtype="float64", **d))
    if cfg["generate_points"]:
        log(f"scaling generate_to_file n={cfg['generate_points']:.0e} (subprocess)")
        try:
            d = run_worker("generate", cfg["generate_points"], 0.0, "float64")
            rows.append(dict(driver="generate_to_file", q=0.0, dtype="float64", **d))
        except RuntimeError as e:
            log(f"generate_to_file failed: {e}")
    return rows


def parse_summary(line: str) -> dict:
    """Points, seconds, points/s and undecided before / after settlement from the summary line
    of ``atlas generate`` (``atlas generate: ...: P points in S s (R points/s) ...; undecided U
    before, V after exact resolution``)."""
    words = line.translate(str.maketrans(",();", "    ")).split()
    i = len(words) - 1 - words[::-1].index("undecided") if "undecided" in words else len(words)
    und = words[i + 1 : i + 4 : 2]  # "undecided U before V after"
    at = words.index("points")  # "P points in S s"
    return dict(
        points=int(words[at - 1]),
        seconds=float(words[at + 2]),
        points_per_second=float(words[words.index("points/s") - 1]),
        undecided_before=int(und[0]) if und else "",
        undecided_after=int(und[1]) if len(und) > 1 else "",
    )


#: the labels of the scenes timed in pairs, each after one untimed run
PAIRED = frozenset(label for label, _ in AXIS_PAIR)


def _generate_once(label, args):
    """One timed ``atlas generate ARGS``: (process, wall [s], peak RSS [MB], file size [bytes])."""
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "a.nc"
        cmd = ["generate", *args, "--out", str(out)]
        if label in PAIRED:  # compared in pairs: same (warm) compilation cache
            run_cli(cmd + ["--overwrite"])
            out.unlink(missing_ok=True)
        p, wall, peak = run_cli(cmd)
        size = out.stat().st_size if out.exists() else 0
    return p, wall, peak, size


def atlases(cfg) -> list[dict]:
    """End to end through the real CLI (``atlas generate`` in a subprocess, write included):
    wall time, points/s of the run's own summary, file size and the subprocess's peak RSS."""
    rows = []
    for label, args in cfg["atlases"]:
        log(f"atlas generate {label} (subprocess)")
        p, wall, peak, size = _generate_once(label, args)
        summary = [ln for ln in p.stderr.splitlines() if ln.startswith("atlas generate:")]
        if p.returncode or not summary or peak is None:
            log(f"atlas generate {label} failed: {p.stderr.strip().splitlines()[-1:]}")
            continue
        s = parse_summary(summary[-1])
        rows.append(
            dict(
                atlas=label,
                command="atlas generate " + " ".join(args),
                points=s["points"],
                wall_seconds=wall,
                points_per_second=s["points_per_second"],
                file_mb=size / 1e6,
                bytes_per_point=size / s["points"],
                peak_rss_mb=peak,
                undecided_before=s["undecided_before"],
                undecided_after=s["undecided_after"],
            )
        )
    return rows
