"""``bench.md``: the markdown report of one ``atlas bench`` run, section by section.

:func:`build_report` joins the sections of a :class:`Results`; each ``*_section`` function returns
the paragraphs of one section (a list of strings, joined by newlines), and the tables' columns
are the ``*_COLUMNS`` constants: ``(row key, header)`` pairs.
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass, field

import numpy as np

from atlas.bench import model_box_map, startup_programs
from atlas.data.io import atomic_path

__all__ = [
    "Results",
    "build_report",
    "fmt",
    "runs_section",
    "slope",
    "startup_section",
    "table",
    "write_csv",
]


@dataclass
class Results:
    """Everything a report is built from: the run's ``meta`` (mode, command, start, duration,
    machine, notes), its configuration and the rows of every section."""

    meta: dict
    cfg: dict
    head: list
    wp: list
    refs: dict
    suites: list
    scaling: list
    sim: list
    large: list = field(default_factory=list)
    atlases: list = field(default_factory=list)
    curves: list = field(default_factory=list)
    #: the fast outcome-map engine against the exact simulator
    maps: list = field(default_factory=list)
    #: both engines lane by lane (:func:`atlas.bench.simulation.engine_lanes`)
    lanes: list = field(default_factory=list)
    #: start-up figures, whole processes (:mod:`atlas.bench.startup`)
    startup: list = field(default_factory=list)
    #: 2-D and 5-D grids through the certified driver (:mod:`atlas.bench.model_axes`)
    model_grids: list = field(default_factory=list)
    #: the Fig. 1 plane over every contact model (:mod:`atlas.bench.model_box_map`)
    model_box_map: list = field(default_factory=list)
    #: the exact reference: distinct ``points`` evaluated, ``seconds``, ``failures``
    exact: dict = field(default_factory=lambda: dict(points=0, seconds=0.0, failures=0))


# --------------------------------------------------------------------------- formatting


def fmt(x, nd=3) -> str:
    """A table cell: strings as they are, NaN/None ``n/a``, inf ``mismatch``, integers exact,
    |x| >= 100 without decimals, else ``nd`` significant digits."""
    if isinstance(x, str):
        return x
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "n/a"
    if isinstance(x, float) and math.isinf(x):
        return "mismatch"
    if isinstance(x, (int, np.integer)):
        return str(int(x))
    if x == 0:
        return "0"
    if abs(x) >= 100:
        return f"{x:.0f}"
    return f"{x:.{nd}g}"


def table(rows, columns) -> str:
    """A markdown table of ``rows`` (dicts); ``columns`` = row keys or ``(key, header)`` pairs."""
    columns = [c if isinstance(c, tuple) else (c, c) for c in columns]
    lines = ["| " + " | ".join(h for _, h in columns) + " |", "|" + "---|" * len(columns)]
    for r in rows:
        lines.append("| " + " | ".join(fmt(r.get(k, "")) for k, _ in columns) + " |")
    return "\n".join(lines)


def write_csv(path, rows):
    """``rows`` (dicts) as CSV, columns in order of first appearance; nothing if no rows."""
    if not rows:
        return
    cols = list(dict.fromkeys(k for r in rows for k in r))
    with atomic_path(path) as tmp, open(tmp, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=cols)
        w.writeheader()
        w.writerows(rows)


def slope(xs, ys) -> float:
    """Least-squares slope of log y against log x over the finite positive ys (NaN if < 2)."""
    xs, ys = np.asarray(xs, float), np.asarray(ys, float)
    ok = np.isfinite(ys) & (ys > 0)
    if ok.sum() < 2:
        return math.nan
    return float(np.polyfit(np.log(xs[ok]), np.log(ys[ok]), 1)[0])


# --------------------------------------------------------------------------- columns

HEADLINE_COLUMNS = (
    ("case", "case"),
    ("dtype", "dtype"),
    ("method", "method"),
    ("ns_per_point", "ns/point"),
    ("eig_over_method", "eig / method"),
    ("method_over_floor", "method / floor"),
    ("misclassified_sample", "miscl. / random sample"),
    ("misclassified", "miscl. / all checked"),
    ("undecided", "undecided"),
    ("target_1000x", "1000x vs eig"),
)
MODEL_GRID_COLUMNS = (
    ("grid", "grid"),
    ("dtype", "dtype"),
    ("points", "points"),
    ("ns_per_point", "ns/point"),
    ("over_2d", "/ 2-D"),
    ("f32_over_f64", "f32 / f64"),
    ("first_pass", "first pass"),
    ("tier2", "tier 2"),
    ("enclosures", "enclosures"),
    ("exact", "exact"),
    ("left", "left undecided"),
)
LARGE_COLUMNS = (
    ("label", "case"),
    ("dtype", "dtype"),
    ("method", "method"),
    ("ns_per_point", "ns/point"),
    ("eig_over_method", "eig / method"),
    ("method_over_floor", "method / floor"),
    ("misclassified", "misclassified"),
    ("checked", "checked"),
    ("undecided", "undecided (before exact)"),
)
WORK_PRECISION_COLUMNS = (
    ("case", "case"),
    ("dtype", "dtype"),
    ("n", "n"),
    ("method", "method"),
    ("ns_per_point", "ns/pt"),
    ("misclassified_sample", "miscl. (sample)"),
    ("misclassified", "miscl."),
    ("checked", "checked"),
    ("undecided", "undecided"),
    ("hausdorff_SS_margin", "H(SS margin)"),
    ("hausdorff_SS_mask", "H(SS mask)"),
    ("hausdorff_II_mask", "H(II mask)"),
)
SUITE_COLUMNS = (
    "suite",
    "dtype",
    "method",
    "points",
    "misclassified",
    "undecided",
    "bad_stable_SS",
    "bad_consistent_II",
    "bad_stable_II",
)
SCALING_COLUMNS = (
    "driver",
    "q",
    "points",
    "seconds",
    "ns_per_point",
    "peak_rss_mb",
    "rss_after_warmup_mb",
    "undecided",
    "bytes_written",
)
ATLAS_COLUMNS = (
    "atlas",
    "command",
    "points",
    "wall_seconds",
    "points_per_second",
    "file_mb",
    "bytes_per_point",
    "peak_rss_mb",
    "undecided_before",
    "undecided_after",
)
KERNEL_SPEED_COLUMNS = ("case", "dtype", "ns_per_point", "eig_over_method", "method_over_floor")
SIMULATION_COLUMNS = ("case", "method", "rtol", "seconds", "events", "error", "nfev")
OUTCOME_MAP_COLUMNS = (
    "map", "trajectories", "workers", "fast_seconds", "fast_per_s", "core_seconds", "core_per_s",
    "identical", "ref_cells", "ref_per_s", "speedup", "early_settle", "early_iwc", "stepped",
    "fallback", "agreement", "jax_map", "jax_compile_s", "jax_per_s", "fast_per_s_again",
    "jax_same",
)  # fmt: skip
ENGINE_LANE_COLUMNS = (
    "set", "lanes", "disagreements", "fallback", "fast_cpu_s", "exact_cpu_s", "speedup",
    "ratio_median", "ratio_p99", "ratio_worst", "over_exact", "steps_median", "steps_max",
    "over_steps", "over_cost", "worst_over_median", "over_steps_per_event", "event_steps_worst",
    "event_cost_worst", "over_event", "over_exact_stepped", "fallback_worst", "met",
)  # fmt: skip

STARTUP_COLUMNS = (
    ("figure", "figure"),
    ("runs", "runs"),
    ("median_s", "median [s]"),
    ("min_s", "min [s]"),
    ("max_s", "max [s]"),
    ("in_run_s", "in the run [s]"),
    ("compared", "compared"),
    ("value", "value"),
    ("target", "target (<=)"),
    ("met", "met"),
)

# --------------------------------------------------------------------------- sections


def header_section(meta) -> list[str]:
    """Title, mode, command, start and duration, machine."""
    m = meta["machine"]
    return [
        "# atlas bench: speed against error\n",
        f"Mode: **{meta['mode']}**. Command: `{meta['command']}`. "
        f"Started {meta['start']}; total duration **{meta['duration']:.0f} s**.\n",
        f"Machine: {m['nproc']} CPUs available ({m['cpu']}), RAM {m['ram']}, load average at start "
        f"{m['load']} (shared machine: absolute times are noisy, ratios are measured in the same "
        f"run). Python {m['python']}, JAX {m['jax']} ({m['jax_backend']}), NumPy {m['numpy']}; "
        f"{m['platform']}.\n",
    ]


def _target_summary(head) -> str:
    parts = [
        f"{r['case'].split(',')[0]} {r['dtype']}: {fmt(r['eig_over_method'])}x"
        for r in head
        if r["method"] == "certified" and r["case"].startswith(("(b)", "(c)"))
    ]
    return "Certified full verdict set vs eig: " + ", ".join(parts) + "." if parts else ""


def headline_section(head, cfg) -> list[str]:
    """The headline table (largest work-precision grid) and its target."""
    n = cfg["res"][-1]
    met = sum(h["target_1000x"] == "met" for h in head)
    notmet = sum(h["target_1000x"] == "not met" for h in head)
    return [
        "## Headline\n",
        f"Beta grid {n + 1} x {n + 1} on [0, 2 pi] (`linspace(0, 2 pi, {n + 1})` in both angles), "
        "kappa = 0.5. ns per point = minimum of repeats after compilation, results on the host. "
        "`eig / method` = how many times cheaper than batched `eig` (target: >= 1000 for "
        "the full verdict set); `method / floor` = multiple of the memory-bound floor kernel "
        "(reads the same coordinates, writes 4 int8 outputs of the grid size). Misclassified = "
        "decided points whose verdict differs from the exact reference, over the checked points "
        "(seeded sample + every undecided point + points where methods disagree). Undecided = points "
        "with any verdict 3 on the whole grid (certified+exact: after exact settlement). 'all "
        "verdicts' = `stable_SS`, `consistent_II`, `stable_II` (no `spectral_abscissa`).\n",
        table(head, HEADLINE_COLUMNS),
        "",
        f"**Target (>= 1000x cheaper than eig)**: met in {met} of {met + notmet} "
        "rows. " + _target_summary(head) + "\n",
    ]


def model_grids_section(rows) -> list[str]:
    """The 2-D grids beside the 5-D grid over the model axes, with the points each tier
    received (empty if not measured)."""
    if not rows:
        return []
    return [
        "### 2-D and 5-D grids\n",
        "The three flag verdicts through `spectral_points` with exact settlement, as `atlas "
        "generate` computes them; the 5-D grid laid out `(beta1, beta2, kappa, q1, q2)` like a "
        "generated atlas (kappa `log:0.1:10:8`, q1 {0.05, 0.2}, q2 {0.1, 0.3}). ns per point = "
        "minimum of repeats after compilation, same run. `/ 2-D` = over the first 2-D row of the "
        "same dtype (target for the 5-D row: <= 1.3); `f32 / f64` = float32 over float64 on the "
        "same grid (target <= 0.7). Points each tier received, as the driver counts them "
        "(`Verdicts.stats`): first pass (every point), tier 2, root enclosures, exact tier "
        "(points with a verdict still undecided), left undecided after it.\n",
        table(rows, MODEL_GRID_COLUMNS),
        "",
    ]


def large_section(large, cfg) -> list[str]:
    """The 1e7-point grid (empty if not measured)."""
    if not large:
        return []
    n_l = cfg["large_n"] + 1
    return [
        f"### At 1e7 points ({n_l} x {n_l} = {n_l * n_l:,} points)\n",
        "Same definitions, on a beta grid of 1e7 points; each method called once after "
        "compilation (`eig` takes minutes here); `eig` is timed on the all-verdicts run and "
        "serves as the baseline of the SS-alone row of the same grid (it computes every "
        f"eigenpair either way). Checked points: a seeded sample of {cfg['large_check']}, up to "
        f"{cfg['large_check']} undecided points and up to {cfg['large_check']} points where "
        "`eig` disagrees, each by the exact reference.\n",
        table(large, LARGE_COLUMNS),
        "",
    ]


def _convergence_orders(wp, cfg) -> list[str]:
    """One bullet per case: log-log slopes of the boundary errors against h."""
    out = []
    for case in [c[0] for c in cfg["cases"]]:
        rs = sorted(
            (
                r
                for r in wp
                if (r["case"], r["outputs"], r["method"], r["dtype"])
                == (case, "all", "certified+exact", "float64")
            ),
            key=lambda r: r["n"],
        )
        hs = [r["h"] for r in rs]
        s = {
            c: fmt(slope(hs, [r[f"hausdorff_{c}"] for r in rs]), 2)
            for c in ("SS_margin", "SS_mask", "II_mask")
        }
        out.append(
            f"* {case}: SS margin {s['SS_margin']}, SS mask {s['SS_mask']}, II mask {s['II_mask']}"
        )
    return out


def work_precision_section(wp, refs, cfg) -> list[str]:
    """Every method x dtype x resolution x case; convergence orders; the floor kernel."""
    vjit = list(cfg["vjit_damped_res"]) or "none (quick mode: 10-30 s compile)"
    refline = (
        "; ".join(
            f"{k}: {v['settled']} points settled exactly, {v['left']} left undecided"
            for k, v in refs.items()
        )
        or "not stored in this report's files"
    )
    floor = ", ".join(
        f"{r['dtype']} n={r['n']}: {fmt(r['floor_ns'])}"
        for r in wp
        if r["method"] == "certified" and r["outputs"] == "all" and r["case"] == "q=0"
    )
    return [
        "## Work-precision\n",
        "Every method x dtype x grid resolution x case. `certified` = `atlas.core.points.spectral_points"
        "(..., resolve=False)`; `certified+exact` = the same plus exact settlement of the undecided "
        "points (time = min certified time + one measured `exact` run over those points, which is "
        "what `resolve=True` adds); `verdicts_jit` = `spectral.verdicts_jit` in one jit over the "
        "broadcast grid (`damped=False` for q = 0; root path on every point when damped -- measured "
        f"only at n in {vjit} for "
        "the equal-q damped case); `eig` = `method='eig'` (batched `jnp.linalg.eig`, uncertified).\n",
        "Boundary error: Hausdorff distance [rad] of the drawn boundary to the reference boundary. "
        f"Reference: float64 certified verdicts on the {cfg['res'][-1] * cfg['ref_factor']}-cell "
        f"grid ({cfg['ref_factor']}x the finest measured), every undecided point settled by "
        "`atlas.core.exact`, drawn the "
        "same way. `SS margin` = zero contour of `hurwitz.ss_margin` (smooth; the curved, "
        "model-dependent SS boundary; float64 reference margin on the fine grid); `SS mask` / "
        "`II mask` = 0.5 contour of the 0/1 masks (SS stable-or-neutral; II consistent; undecided "
        "drawn as 0). Contours by marching squares with linear interpolation (contourpy); distances "
        "point-to-segment via a k-d tree, coarse lines densified to h/4.\n",
        f"Reference grids: {refline}.\n",
        table([r for r in wp if r["outputs"] == "all"], WORK_PRECISION_COLUMNS),
        "",
        "Convergence orders (log-log slope of Hausdorff distance against h, float64, "
        "certified+exact):\n",
        *_convergence_orders(wp, cfg),
        "\n![work-precision](bench_work_precision.png)\n\n![convergence](bench_convergence.png)\n",
        f"Floor kernel per grid (ns/point): {floor}.\n",
    ]


def suites_section(suites, cfg) -> list[str]:
    """Misclassified / undecided per hard-case suite, method and dtype; totals."""
    if cfg["suite_points"]:
        which = (
            f", a seeded subsample of {cfg['suite_points']} points per suite (quick mode; "
            "`double_roots` left out: 10 s generation)"
        )
    else:
        which = ", every point"
    tot = {}
    for r in suites:
        t = tot.setdefault((r["method"], r["dtype"]), [0, 0, 0])
        t[0] += r["misclassified"]
        t[1] += r["undecided"]
        t[2] += r["points"]
    totals = "; ".join(
        f"{m} {d}: {v[0]} misclassified, {v[1]} undecided of {v[2]}" for (m, d), v in tot.items()
    )
    return [
        "## Hard-case suites\n",
        "Suites of `atlas.core.hardcases` (seed 0)"
        + which
        + ". Truth = `atlas.core.exact`. `bad_*` = misclassified per verdict.\n",
        table(suites, SUITE_COLUMNS),
        "",
        f"Totals: {totals}.\n",
    ]


def _scaling_note(scaling) -> str:
    """Time against points (slope), peak RSS, and the extrapolation to 1e9 points."""
    rs = [r for r in scaling if r["driver"] == "spectral_points tiles" and r["q"] == 0.0]
    if len(rs) < 2:
        return ""
    sl = slope([r["points"] for r in rs], [r["seconds"] for r in rs])
    rss = [r["peak_rss_mb"] for r in rs]
    txt = (
        f"Undamped: time ~ points^{fmt(sl, 3)} over {rs[0]['points']:.2g} .. "
        f"{rs[-1]['points']:.2g} points; peak RSS {min(rss):.0f} .. {max(rss):.0f} MB."
    )
    big = max(r["points"] for r in rs)
    if big < 10**9:
        per = rs[-1]["ns_per_point"]
        txt += (
            f" Largest size measured here: {big:.2g} points; EXTRAPOLATED (not measured) to "
            f"1e9 points at the measured {per:.0f} ns/point: ~{per:.0f} s."
        )
    rd = [r for r in scaling if r["driver"] == "spectral_points tiles" and r["q"] != 0.0]
    if rd:
        per = rd[-1]["ns_per_point"]
        txt += (
            f" Damped (q = 0.1) measured up to {rd[-1]['points']:.2g} points "
            f"({per:.0f} ns/point); EXTRAPOLATED to 1e9 points: ~{per:.0f} s."
        )
    g = [r for r in scaling if r["driver"] == "generate_to_file"]
    if g:
        txt += (
            f" End to end `io.generate_to_file` (Fig. 1 scene, {g[0]['points']:.2g} points, "
            f"resolve=False, includes compilation): {g[0]['seconds']:.0f} s = "
            f"{g[0]['ns_per_point']:.0f} ns/point."
        )
    return txt


def scaling_section(scaling) -> list[str]:
    """Time and peak RSS per atlas size (a subprocess per size)."""
    return [
        "## Scaling\n",
        "Each size in a fresh subprocess: the Fig. 1 scene family (kappa = 0.5, float64, all three "
        "flag verdicts) on a beta1 x 1024 grid streamed through `atlas.core.points.spectral_points` in tiles "
        "of 256 x 1024 points; the verdicts are written to a scratch file (3 bytes/point) and "
        "deleted. Time excludes the first (compiling) tile; peak RSS = `VmHWM` of the subprocess "
        "(includes the JAX runtime). Undecided = before exact settlement (settling costs ~20-100 ms "
        "per point and is not included).\n",
        table(scaling, SCALING_COLUMNS),
        "",
        _scaling_note(scaling),
        "\n![scaling](bench_scaling.png)\n",
    ]


def atlases_section(atlases) -> list[str]:
    """``atlas generate`` end to end (empty if not measured)."""
    if not atlases:
        return []
    return [
        "### End to end: `atlas generate`\n",
        "The real CLI in a fresh subprocess, netCDF write included: wall time includes interpreter "
        "start-up and JAX compilation (the persistent compilation cache of the CLI may be warm); "
        "points/s is the run's own summary line; peak RSS = `VmHWM` of the subprocess. Undecided = "
        "before / after exact settlement (`--no-resolve`: not settled).\n",
        table(atlases, ATLAS_COLUMNS),
        "",
    ]


#: points/s of ``atlas generate --scene atlas4d`` before the kernel-speed work, the baseline of
#: its ">= 20x" target (the figure and its run are in CHANGELOG.md and the git log)
ATLAS4D_BEFORE = 19_800


def _kernel_speed_atlases(atlases) -> list[str]:
    """The axis/shifted pair and ``atlas4d`` against their targets."""
    out = []
    by = {r["atlas"]: r for r in atlases}
    ax, sh = by.get("axis scene"), by.get("shifted scene")
    if ax and sh:
        ratio = sh["points_per_second"] / ax["points_per_second"]
        out.append(
            "Axis-including scene vs the same scene shifted off the axes (both q > 0), each after "
            "one untimed run that warms the persistent compilation cache: "
            f"{fmt(ax['points_per_second'])} vs {fmt(sh['points_per_second'])} points/s, "
            f"ratio **{fmt(ratio)}** (target <= 1.5; 6.5 before); undecided after settlement "
            f"{ax['undecided_after']} and {sh['undecided_after']}.\n"
        )
    if "atlas4d" in by:
        r = by["atlas4d"]
        out.append(
            f"`atlas4d`: {fmt(r['points_per_second'])} points/s = "
            f"**{fmt(r['points_per_second'] / ATLAS4D_BEFORE)}x** the {ATLAS4D_BEFORE} points/s "
            f"before (target >= 20x); undecided after settlement **{r['undecided_after']}** "
            "(target 0).\n"
        )
    return out


def kernel_speed_section(head, suites, atlases) -> list[str]:
    """Targets of exact verdicts at kernel speed, from rows measured in this run."""
    rows = [r for r in head if r["method"] == "certified" and r["case"].startswith("(c")]
    out = [
        "### Exact at kernel speed\n",
        "Damped, all three flag verdicts, results on the host, no exact settlement (`certified`: "
        "root-free first pass, tier 2, enclosures for what is left); targets <= 25 ns/point f64, "
        "<= 15 f32, >= 150x `eig`.\n",
        table(rows, KERNEL_SPEED_COLUMNS),
    ]
    ex = [r for r in suites if r["method"] == "certified" and "exact_us_per_point" in r]
    if ex:
        worst = max(ex, key=lambda r: r["exact_us_per_point"])
        out.append(
            f"\nExact tier (`exact.resolve`, every flag verdict): worst hard suite "
            f"**{fmt(worst['exact_us_per_point'])} us/point** ({worst['suite']}, {worst['dtype']}; "
            "target <= 200); per suite in `bench_suites.csv` (`exact_us_per_point`).\n"
        )
    out += _kernel_speed_atlases(atlases)
    # the section is one paragraph block followed by an empty line
    return ["\n".join(out) + "\n"]


def curves_section(rows, chord: float) -> list[str]:
    """Certified boundary curves against the grid contours, their chords refined to a
    ``chord`` [rad] sagitta."""
    if not rows:
        return []
    sagitta = f"{chord:.0e}".replace("e-0", "e-")
    cols = [
        "case", "n", "field", "curves", "vertices", "points", "seconds",
        "hausdorff_curves", "hausdorff_grid", "p99_curves", "p99_grid", "hidden_cells",
        "unrefined", "tips_attached", "tips_unreached", "reference_tips_unreached", "max_bracket",
    ]  # fmt: skip
    return [
        "## Boundary curves (`atlas boundaries`)",
        "",
        "Certified curves of one slice on an n x n grid (both fields; vertices bisected to a "
        f"bracket <= 1e-10 rad, chords refined to a {sagitta} rad sagitta) against the curves of the "
        "4n x 4n grid: torus Hausdorff distance [rad] of the curves (`hausdorff_curves`) and of "
        "the grid's marching-squares contours (`hausdorff_grid`, what a plot of the atlas draws), "
        "and the 99th percentile of the point-to-curve distances (`p99_*`). Where a boundary "
        "meets a class line at a shallow angle, the tip of the wedge it leaves is found by a "
        "scan just off the line and attached to the curve (`tips_attached`); a tip no curve "
        "comes near marks a band or wedge along the line thinner than the grid, lost by the "
        "tracing (`tips_unreached`, of the n grid and of the reference). Two certified sets "
        "each within the chord tolerance of the boundary are within twice that of each other. "
        "`seconds`: both fields, the lost-branch check and the codimension-2 points included.",
        "",
        table(rows, cols),
        "",
    ]


def simulation_section(sim) -> list[str]:
    """``simulate`` against ``solve_ivp`` on the Fig. 2 cases."""
    return [
        "## Simulation\n",
        "Fig. 2 cases (`simulate.fig2_cases`). Error = max |event time - reference| over the "
        "impact/lift-off events (force on/off events are bookkeeping of the simulator only). "
        "`solve_ivp` runs are compared with `simulate`; `simulate` is compared with `solve_ivp` "
        "DOP853 at rtol = 1e-13, atol = 1e-16 (so its error is bounded by the agreement of two "
        "independent methods). `mismatch` = a different sequence of events. Time = min of repeats "
        "per run (atol = 1e-3 rtol).\n",
        table(sim, SIMULATION_COLUMNS),
        "\n![simulation](bench_simulation.png)\n",
    ]


def outcome_maps_section(maps) -> list[str]:
    """The fast outcome-map engine against the exact simulator on the same cells."""
    if not maps:
        return []
    lines = [
        "## Outcome maps: fast engine against the exact simulator\n",
        "`atlas simulate --map` with the fast engine (`atlas.dynamics.fast_engine`: event to event "
        "in the modal form of each contact configuration, certified early decisions) over the whole "
        "map on the machine's usable cores (`workers` processes, the default of the command; "
        "`fast_seconds`: wall time of the simulation, the start of the processes included; "
        "`fast_per_s`: trajectories per second of the machine) and on one core (`core_seconds`, "
        "`core_per_s`); `identical`: the two maps are equal cell by cell. `simulate_outcome` "
        "(exact event-driven simulator, one core) on a seeded sample of the same cells from the "
        "same initial states, in the same run (`ref_per_s`); `speedup` = `core_per_s` / "
        "`ref_per_s`, one core against one core. "
        "`early_settle` / `early_iwc`: fraction of runs decided by a certificate that no event can "
        "follow; `stepped`: run to a stop and classified; `fallback`: run by the exact simulator. "
        "`agreement`: same outcome on the sampled cells; every disagreement listed below. "
        "The same engine as a JAX kernel (`atlas.dynamics.jax_engine`; full runs only), on a "
        "smaller map (`jax_map`) with the first map's parameters, one initial state per cell: "
        "`jax_compile_s`: its first call less its second (compilation, or the persistent cache), "
        "`jax_per_s`: the second call, `fast_per_s_again`: the NumPy engine on that map (one core), "
        "`jax_same`: fraction of its cells with the NumPy engine's outcome.\n",
        table(maps, OUTCOME_MAP_COLUMNS),
        "",
    ]
    for row in maps:
        if row["disagreements"]:
            lines.append(f"* {row['map']}: {row['disagreements']}")
    return [*lines, ""]


def engine_lanes_section(lanes) -> list[str]:
    """Both engines lane by lane: disagreements, fallbacks, per-lane cost (empty if none)."""
    if not lanes:
        return []
    lines = [
        "### Lane by lane: fast engine against the exact simulator\n",
        "Seeded lanes over the whole parameter space (`atlas.dynamics.engine_check.random_lanes`: "
        "a quarter of the angles on the axes and diagonals, where the modal forms are degenerate) "
        "and the runs of the `0:2pi:8` degenerate-direction grid, each lane by both engines (one "
        "core each, CPU seconds: `fast_cpu_s`, `exact_cpu_s`, `speedup` their ratio). "
        "`disagreements`: lanes of different outcomes (each listed below); `fallback`: share of "
        "lanes the fast engine hands to the exact simulator. A lane's fast cost is its share of "
        "the batch's CPU in proportion to its steps (plus its exact run if it falls back); "
        "`ratio_*`: that cost over the exact simulator's CPU for the same lane (median, 99th "
        "percentile, worst); `over_exact`: lanes where it is over 1. `steps_median`, "
        "`steps_max`: steps of a lane in the fast engine; "
        "`over_steps`, `over_cost`: lanes over 10 times the median lane in steps, in fast cost; "
        "`worst_over_median`: the costliest lane over the median lane; `over_steps_per_event`: "
        "the most steps per event of a lane over 10 times the median (near 1: such a lane is "
        "stepped event to event).\n",
        'The target "no lane costs more than 10x the median lane" is read as: no lane\'s cost '
        "is out of proportion to the work its physics needs (a lane with 100 contact events "
        "cannot cost 10 events' worth).  `met` is 1 when (a) no lane costs over 10 times the median "
        "lane per event (`event_steps_worst`, `event_cost_worst`: the worst lane's steps and "
        "fast cost per event over the median lane's, events counted at least 1; `over_event`: "
        "lanes over 10 times in either) and (b) no lane costs more than the exact simulator's "
        "run of it (`over_exact_stepped`), fallbacks aside: a fallback lane pays the fast attempt "
        "and the exact run (`fallback_worst`: the costliest over its exact run).\n",
        table(lanes, ENGINE_LANE_COLUMNS),
        "",
    ]
    lines += [f"* {row['set']}: {row['disagree_lanes']}" for row in lanes if row["disagree_lanes"]]
    return [*lines, ""]


def startup_section(rows) -> list[str]:
    """Start-up figures, whole processes, against their targets (empty if not measured)."""
    if not rows:
        return []
    targeted = [r for r in rows if r["target"] != ""]
    met = sum(r["met"] == "met" for r in targeted)
    shown = [{k: "-" if v == "" else v for k, v in r.items()} for r in rows]
    commands = dict.fromkeys(f"`{r['command']}`" for r in rows if r["command"])
    notes = [f"* {r['figure']}: {r['note']}" for r in rows if r["note"]]
    return [
        "## Start-up\n",
        "Each figure is the wall time of a fresh process of this environment, from its start to "
        "its exit (median, min and max over `runs`; `atlas` is the environment's entry point), "
        "with one temporary, initially empty `ATLAS_JAX_CACHE` created for this section (never "
        "the user's) and the files written into a temporary directory. `generate 512 points` = "
        "the 16 x 16 x 2 damped atlas with every output: `cold` in the empty cache, then an "
        "untimed round (each layer's own programs cached) and timed rounds of `warm` (exported programs and their compiled executables, compilation cache), "
        "`exported programs only` (`ATLAS_KERNEL_EXECUTABLES=0`) and `compilation cache only` "
        "(`ATLAS_KERNEL_CACHE=0`), each as a multiple of the warm median (`x warm`). The "
        "8.4-million-point atlas: after a first run that compiles its shapes into the cache, the "
        "warm runs' wall time over the seconds of their own summary line (`in the run`). "
        "`atlas selftest`: the most disagreements of any run (each run's first in the cache "
        "compiles its kernels). Explorer: `make_widget()` with its default map built headless "
        "(matplotlib Agg, the map drawn to the widget's PNG), seconds from the script's first "
        "statement (imports included) to the drawn map; then a click on the map delivered "
        "through the canvas's `button_press_event` callbacks, as ipympl delivers one, timed "
        "until the inspector shows the point, and a second click elsewhere. `met` compares "
        "`value` with the target.\n",
        table(shown, STARTUP_COLUMNS),
        "",
        f"**Targets**: met in {met} of {len(targeted)} figures.\n",
        "Commands: " + "; ".join(commands) + ".\n",
        *([*notes, ""] if notes else []),
        *startup_programs.program_tables(rows),
    ]


def notes_section(notes, exact) -> list[str]:
    """The run's notes and the cost of the exact reference (``None``: not stored)."""
    if exact is None:
        line = "* Exact reference: its cost is not stored in this report's files."
    else:
        which = exact.get("sections")
        line = (
            f"* Exact reference: {exact['points']} distinct points evaluated in "
            f"{exact['seconds']:.0f} s; {exact['failures']} failed (counted as undecided)"
            + (f"; for the sections {', '.join(which)}." if which else ".")
        )
    return ["## Notes, omissions\n", *(f"* {note}" for note in notes), line]


def runs_section(meta) -> list[str]:
    """Which run measured each section, when the report joins several (``atlas bench --only``)."""
    runs = meta.get("sections", {})
    if len({(v["start"], v["command"]) for v in runs.values()}) < 2:
        return []
    rows = [dict(section=k, start=v["start"], command=f"`{v['command']}`") for k, v in runs.items()]
    return [
        "**This report joins several runs** (`atlas bench --only` re-measured some sections and "
        "kept the others): each section names the run that measured it. Ratios inside a section "
        "are of one run; do not compare figures across sections of different runs.\n",
        table(rows, ("section", "start", "command")),
        "",
    ]


def _stamp(parts, names, meta) -> list[str]:
    """``parts`` (one section's paragraphs) with, under its heading, the run(s) that measured
    ``names``, when the report joins several runs."""
    runs = meta.get("sections", {})
    if not parts or len({(v["start"], v["command"]) for v in runs.values()}) < 2:
        return parts
    seen = dict.fromkeys((runs[n]["start"], runs[n]["command"]) for n in names if n in runs)
    line = "; ".join(f"run started {start} (`{command}`)" for start, command in seen)
    head, _, rest = parts[0].partition("\n")
    return [f"{head}\n\n*Measured by the {line}.*\n{rest}", *parts[1:]]


def build_report(r: Results) -> str:
    """The markdown of ``bench.md``: every section in order, each under the run that measured it
    where the report joins several."""
    m = r.meta
    sections = [
        (("work_precision",), headline_section(r.head, r.cfg)),
        (("model_grids",), model_grids_section(r.model_grids)),
        (("model_box_map",), model_box_map.section(r.model_box_map)),
        (("large",), large_section(r.large, r.cfg)),
        (("work_precision",), work_precision_section(r.wp, r.refs, r.cfg)),
        (("suites",), suites_section(r.suites, r.cfg)),
        (("scaling",), scaling_section(r.scaling)),
        (("atlases",), atlases_section(r.atlases)),
        (
            ("work_precision", "suites", "atlases"),
            kernel_speed_section(r.head, r.suites, r.atlases),
        ),
        (("curves",), curves_section(r.curves, r.cfg["curve_chord"])),
        (("simulation",), simulation_section(r.sim)),
        (("outcome_maps",), [*outcome_maps_section(r.maps), *engine_lanes_section(r.lanes)]),
        (("startup",), startup_section(r.startup)),
    ]
    parts = [*header_section(m), *runs_section(m)]
    for names, section in sections:
        parts += _stamp(section, names, m)
    parts += notes_section(m["notes"], r.exact)
    return "\n".join(parts) + "\n"
