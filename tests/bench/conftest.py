"""Fixtures of tests/bench: a small made-up result set of an ``atlas bench`` run (no
measurement), rows of every section with the keys the measuring code writes, numbers by hand;
and one real ``tiny`` run per test session."""

import contextlib
import io
import json
import math

import pytest
from shared_run import shared_run

from atlas.bench.config import CONFIG, METHODS
from atlas.bench.report import Results
from atlas.bench.suites import headline

#: speed of each method [ns/point]; eig is 2000x the certified driver (target met)
NS = {"certified": 10.0, "certified+exact": 12.0, "verdicts_jit": 20.0, "eig": 20000.0}


def _wp_row(case, dtype, n, method, outputs="all"):
    pts = (n + 1) ** 2
    return dict(
        case=case, dtype=dtype, n=n, h=2 * math.pi / n, points=pts, outputs=outputs,
        method=method, seconds=NS[method] * pts * 1e-9, ns_per_point=NS[method],
        floor_ns=0.5, checked=20, misclassified=1 if method == "eig" else 0, sample=15,
        misclassified_sample=0, undecided=3 if method == "certified" else 0,
        undecided_before=3, settle_capped=False, roots_points="",
        # first-order convergence: H = h / 2
        hausdorff_SS_mask=math.pi / n, hausdorff_II_mask=math.pi / n,
        hausdorff_SS_margin=(2 * math.pi / n) ** 2,
    )  # fmt: skip


def fake_results(mode="full") -> Results:
    """Rows of every section for the configuration ``mode`` (large grid and atlases included)."""
    cfg = CONFIG[mode]
    wp = [
        _wp_row(c[0], dt, n, m) for c in cfg["cases"] for dt in ("float32", "float64")
        for n in cfg["res"] for m in METHODS
    ]  # fmt: skip
    wp += [
        _wp_row("q=0.1", dt, cfg["res"][-1], m, "SS")
        for dt in ("float32", "float64")
        for m in METHODS
    ]
    large = [
        dict(_wp_row("q=0", "float64", 3162, m), label="all verdicts, q=0", eig_over_method=2.0,
             method_over_floor=20.0)
        for m in ("certified", "eig")
    ]  # fmt: skip
    suites = [
        dict(suite=s, dtype="float64", method=m, points=10, misclassified=0, undecided=1,
             exact_us_per_point=40.0 + i, bad_stable_SS=0, bad_consistent_II=0, bad_stable_II=0)
        for i, s in enumerate(("near_hurwitz", "class_boundaries")) for m in METHODS
    ]  # fmt: skip
    scaling = [
        dict(driver="spectral_points tiles", q=0.0, dtype="float64", points=p, seconds=p * 1e-8,
             ns_per_point=10.0, peak_rss_mb=500.0, rss_after_warmup_mb=400.0, undecided=0,
             bytes_written=3 * p, wall_seconds=p * 1e-8 + 2)
        for p in (10**6, 10**7)
    ]  # fmt: skip
    atlases = [
        dict(atlas=label, command="atlas generate --scene x", points=1000, wall_seconds=2.0,
             points_per_second=pps, file_mb=0.1, bytes_per_point=100.0, peak_rss_mb=600.0,
             undecided_before=5, undecided_after=0)
        for label, pps in (("axis scene", 1e5), ("shifted scene", 1.2e5),
                           ("atlas4d", 19_800 * 25))
    ]  # fmt: skip
    sim = [
        dict(case="d", method="simulate (exact)", rtol="", seconds=0.02, events=21, error=1e-13,
             reference="solve_ivp DOP853 rtol=1e-13", nfev=""),
        dict(case="d", method="solve_ivp DOP853", rtol=1e-3, seconds=0.05, events=20,
             error=math.inf, reference="simulate", nfev=1500),
    ]  # fmt: skip
    curves = [
        dict(case="Fig. 1", n=n, field=f, curves=12, vertices=8000, points=14, seconds=3.0,
             hausdorff_curves=0.1, hausdorff_grid=0.2, p99_curves=1e-7, p99_grid=0.05,
             hidden_cells=0, unrefined=4, max_bracket=9e-11)
        for n in cfg["curve_res"] for f in ("SS", "II")
    ]  # fmt: skip
    maps = [
        dict(map="256x256, kappa=0.5, q=0, alpha=0.35pi", trajectories=65536, workers=2,
             fast_seconds=50.0, fast_per_s=1300.0, core_seconds=90.0, core_per_s=730.0,
             identical=True, ref_cells=500, ref_per_s=50.0, speedup=14.6, early_settle=0.13,
             early_iwc=0.62, stepped=0.25, fallback=0.0, agreement=1.0, disagreements="")
    ]  # fmt: skip
    startup = [
        dict(figure=f, command=f, runs=5, median_s=m, min_s=m, max_s=m, in_run_s=i,
             compared=c, value=v, target=t, met=met, note="")
        for f, m, i, c, v, t, met in (
            ("import atlas", 0.1, "", "median s", 0.1, 0.5, "met"),
            ("generate 512 points, warm", 2.5, "", "median s", 2.5, 2.0, "missed"),
            ("generate 512 points, cold", 20.0, "", "x warm", 8.0, "", ""),
        )
    ]  # fmt: skip
    model_grids = [
        dict(grid=g, dtype=dt, points=n, seconds=n * ns * 1e-9, ns_per_point=ns, over_2d=o,
             f32_over_f64=f, first_pass=n, tier2=500, enclosures=6, exact=0, left=0)
        for g, n, o in (("2-D 513^2", 263_169, 1.0), ("5-D 512^2 x 8 x 2 x 2", 8_388_608, 1.2))
        for dt, ns, f in (("float32", 40.0, 0.6), ("float64", 66.0, ""))
    ]  # fmt: skip
    model_box = [
        dict(field=f, points=129_600, seconds=s, ns_per_point=s / 129_600 * 1e9,
             one_model_ns_per_point=12.0, over_one_model=s / 129_600 * 1e9 / 12.0,
             undecided_before=u, undecided_after=u, stable=0.06, unstable=0.69, depends=0.25,
             undecided=u / 129_600)
        for f, s, u in (("SS", 1.2, 0), ("II", 60.0, 300))
    ]  # fmt: skip
    program = dict(name="rootfree._tier2_decide", shapes="f64[256]", compiles=1, trace_s=0.4,
                   lower_s=0.3, compile_s=2.5)  # fmt: skip
    startup += [
        dict(figure=f"cold, programs compiled: {c}", command=c, runs=1, median_s=85.0,
             min_s=85.0, max_s=85.0, in_run_s="", compared="programs", value=1, target="",
             met="", note="tracing 6.4 s", programs=json.dumps([program]))
        for c in ("atlas paper --quick", "atlas generate 16 x 16 x 2",
                  "explorer: first 513^2 map", "explorer: first certified boundary overlay",
                  "explorer: first certified boundary overlay after the warm-up")
    ]  # fmt: skip
    refs = {c[0]: dict(settled=4, left=0) for c in cfg["cases"]}
    meta = dict(
        mode=mode, quick=mode != "full", start="2024-06-01T12:00:00+0000",
        command="atlas bench", duration=1234.0, notes=["a note"],
        machine=dict(nproc=2, cpu="cpu", ram="8.0 GiB", load="1.00 1.00 1.00", python="3.11",
                     jax="0.4", numpy="2.0", platform="Linux", jax_backend="cpu"),
    )  # fmt: skip
    return Results(
        meta=meta, cfg=cfg, head=headline(wp, cfg), model_grids=model_grids, wp=wp, refs=refs,
        suites=suites,
        scaling=scaling, sim=sim, large=large, atlases=atlases, curves=curves, maps=maps,
        startup=startup, exact=dict(points=42, seconds=3.0, failures=0), model_box_map=model_box,
        lanes=[dict(set=name, lanes=100, disagreements=0, fallback=0.0, fast_cpu_s=1.0,
                    exact_cpu_s=20.0, speedup=20.0, ratio_median=0.1, ratio_p99=0.3,
                    ratio_worst=0.5, over_exact=0, steps_median=8.0, steps_max=90, over_steps=2,
                    over_cost=2, worst_over_median=11.0, over_steps_per_event=1.1,
                    event_steps_worst=6.0, event_cost_worst=6.0, over_event=0,
                    over_exact_stepped=0, fallback_worst=0.0, met=True,
                    disagree_lanes="") for name in ("random lanes", "grid")],
    )  # fmt: skip


@pytest.fixture
def results():
    """The made-up results of a full run."""
    return fake_results("full")


@pytest.fixture(scope="session")
def tiny_bench(tmp_path_factory):
    """One whole ``tiny`` run (``atlas.bench.run(config="tiny")``), measured for real, per test
    session (and xdist workers: :func:`shared_run`), started in an empty directory with the
    default output directory: ``(that directory, its exit code, what it printed)``."""

    def compute(cwd):
        from atlas.bench import run

        printed = io.StringIO()
        with pytest.MonkeyPatch.context() as mp, contextlib.redirect_stdout(printed):
            mp.chdir(cwd)
            code = run(config="tiny")
        return {"code": code, "printed": printed.getvalue()}

    cwd, got = shared_run(tmp_path_factory, "tiny_bench", compute)
    return cwd, got["code"], got["printed"]
