"""What ``atlas bench`` measures: the cases, the methods and the size of each run (:data:`CONFIG`).

``full`` writes the committed report ``outputs/bench.md`` (about 30 minutes); ``quick`` is the CI
run (small grids and subsamples, under 2 minutes); ``tiny`` is the end-to-end test's run (every
section, smallest sizes that still fill every table).
"""

from __future__ import annotations

import math
from pathlib import Path

from atlas.core.invariants import KEYS
from atlas.core.verdicts import UNDECIDED_FLAG

__all__ = [
    "CASES",
    "CONFIG",
    "FLAGS",
    "KEYS",
    "METHODS",
    "UNDECIDED",
    "default_out",
    "mode_name",
]

#: the flag verdicts measured (``spectral_abscissa`` is not)
FLAGS = ("stable_SS", "consistent_II", "stable_II")
#: the flag code of an undecided point (SPEC §2)
UNDECIDED = UNDECIDED_FLAG

#: (name, kappa, q1, q2) of the work-precision cases
CASES = (
    ("q=0", 0.5, 0.0, 0.0),
    ("q=0.1", 0.5, 0.1, 0.1),
    ("q1=0.05,q2=0.2", 0.5, 0.05, 0.2),
)

#: the methods compared on every grid, cheapest certified first, uncertified ``eig`` last
METHODS = ("certified", "certified+exact", "verdicts_jit", "eig")

#: a scene that includes the axes and the same scene shifted off them (compared in pairs)
AXIS_PAIR = (
    (
        "axis scene",
        ["--beta1", "0:2pi:64", "--beta2", "0:2pi:64", "--kappa", "0.5,2"]
        + ["--q1", "0,0.1", "--q2", "0,0.2", "--alpha", "0.35pi"],
    ),
    (
        "shifted scene",
        ["--beta1", "0.003pi:2.003pi:64", "--beta2", "0.003pi:2.003pi:64"]
        + ["--kappa", "0.5,2", "--q1", "0.05,0.1", "--q2", "0.05,0.2", "--alpha", "0.35pi"],
    ),
)

_SS_1E9 = (
    "4-D, 1e9 points, SS only",
    ["--beta1", "0:2pi:1024", "--beta2", "0:2pi:1024", "--kappa", "log:0.01:100:31"]
    + ["--q", "log:0.001:10:31", "--outputs", "stable_SS,model_dependent_SS", "--no-resolve"],
)

#: hard-case suites of the quick run (``double_roots`` left out: 10 s generation)
_QUICK_SUITES = (
    "q_to_zero",
    "near_hurwitz",
    "near_discriminant",
    "near_detB",
    "offdiag_to_zero",
    "extreme_ratios",
    "class_boundaries",
)

#: start-up of the quick and tiny runs: one ``import atlas`` and one ``atlas --help`` (~1 s)
_CHEAP_STARTUP = dict(
    runs=1, cold_runs=0, generate_runs=0, large_runs=0, selftest_runs=0, explorer_runs=0
)

CONFIG = {
    "full": dict(
        res=(64, 128, 256, 512),
        dtypes=("float32", "float64"),
        # 2-D grids at one model and a 5-D grid over the model axes (atlas.bench.model_axes)
        model_grids=dict(two_d=(513, 2048), five_d=512),
        # the Fig. 1 plane's verdicts over every contact model (atlas.bench.model_box_map)
        model_box_map=dict(n={"SS": 360, "II": 360}, fields=("SS", "II"), repeats=1),
        ref_factor=4,
        cases=CASES,
        sample=300,
        sample_small=100,
        disagree_cap=50,
        undecided_cap=3000,
        budget=2.0,
        vjit_damped_res=(512,),
        suites=None,  # all, full size
        suite_points=None,
        scale_undamped=(10**6, 10**7, 10**8, 10**9),
        scale_damped=(10**6, 10**7),
        generate_points=10**6,
        sim_cases=("a", "b", "c", "d", "e"),
        sim_methods=(("DOP853", (1e-3, 1e-6, 1e-9, 1e-12)), ("Radau", (1e-3, 1e-6, 1e-9))),
        sim_repeats=3,
        outcome_maps=((256, 0.5, 0.0, 0.35 * math.pi, 400), (256, 2.0, 0.5, 0.2 * math.pi, 300)),
        engine_random=(44, 2000),  # lanes of both engines over the whole space (~40 s CPU)
        engine_grid=4,  # runs a cell of the 0:2pi:8 degenerate-direction grid (~30 s CPU)
        jax_outcome_n=64,  # the JAX kernel of the outcome engine, first map's parameters (~2 min)
        large_n=3162,  # (3162 + 1)^2 = 1.0e7 points
        curve_res=(64, 128, 256),
        curve_chord=1e-6,  # sagitta the curves are refined to [rad] (`atlas boundaries`' default)
        curve_cases=3,
        distributed=True,  # distributed.md: in process vs LocalCluster (needs the dask extra)
        large_check=100,
        startup=dict(  # runs of each start-up figure (atlas.bench.startup; ~2.5 min)
            runs=5, cold_runs=1, generate_runs=3, large_runs=2, selftest_runs=1, explorer_runs=1
        ),
        atlases=(
            *AXIS_PAIR,
            ("fig1", ["--scene", "fig1"]),
            ("fig1-model", ["--scene", "fig1-model"]),
            ("atlas4d", ["--scene", "atlas4d"]),
            _SS_1E9,
        ),
    ),
    "quick": dict(
        res=(32, 64),
        dtypes=("float32", "float64"),
        model_grids=dict(two_d=(65,), five_d=16),
        model_box_map=dict(n=48, fields=("SS", "II"), repeats=1),
        ref_factor=2,
        cases=CASES[:2],
        sample=15,
        sample_small=15,
        disagree_cap=10,
        undecided_cap=300,
        budget=0.2,
        vjit_damped_res=(),
        suites=_QUICK_SUITES,
        suite_points=4,
        scale_undamped=(10**6, 10**7),
        scale_damped=(),
        generate_points=None,
        sim_cases=("d",),
        sim_methods=(("DOP853", (1e-4, 1e-8)), ("Radau", (1e-4,))),
        sim_repeats=1,
        outcome_maps=((48, 0.5, 0.0, 0.35 * math.pi, 64),),
        engine_random=(44, 200),
        engine_grid=1,
        jax_outcome_n=None,
        large_n=0,
        large_check=10,
        curve_res=(16,),
        curve_chord=1e-6,
        curve_cases=1,
        distributed=False,
        startup=_CHEAP_STARTUP,
        atlases=(
            (
                "tiny 4-D",
                ["--beta1", "0:2pi:16", "--beta2", "0:2pi:16", "--kappa", "0.5,2", "--q", "0,0.1"],
            ),
        ),
    ),
}

#: the end-to-end test's run: every section of the report filled, at the smallest sizes (one
#: grid per case, float64 only: each grid shape and dtype costs seconds of compilation)
CONFIG["tiny"] = dict(
    CONFIG["quick"],
    res=(16,),
    dtypes=("float64",),
    model_grids=dict(two_d=(9,), five_d=8),
    model_box_map=dict(n=8, fields=("SS",), repeats=1),
    sample=8,
    sample_small=8,
    disagree_cap=5,
    undecided_cap=40,
    budget=0.02,
    suites=("near_discriminant",),  # q = 0: verdicts_jit compiles its cheap undamped path
    suite_points=2,
    curve_res=(8,),
    curve_chord=1e-4,  # 1e-6 (the others): 4x the vertices, twice the section's seconds
    scale_undamped=(1 << 18,),
    sim_methods=(("DOP853", (1e-4,)), ("Radau", (1e-4,))),
    outcome_maps=((8, 0.5, 0.0, 0.35 * math.pi, 8),),
    engine_random=(44, 6),
    engine_grid=0,
    jax_outcome_n=None,
    atlases=(
        (
            "tiny 4-D",
            ["--beta1", "0:2pi:8", "--beta2", "0:2pi:8", "--kappa", "0.5,2", "--q", "0,0.1"]
            + ["--outputs", "stable_SS"],  # the other outputs cost 10 s of compilation
        ),
    ),
)


def mode_name(quick: bool = False, config: str | None = None) -> str:
    """The :data:`CONFIG` key of a run: ``config`` if given, else ``quick`` or ``full``."""
    name = config or ("quick" if quick else "full")
    if name not in CONFIG:
        raise ValueError(f"config: must be one of {', '.join(CONFIG)}, got {name!r}")
    return name


def default_out(mode: str) -> Path:
    """Where a run writes without ``--out``: ``outputs`` for the full run (the committed report),
    ``outputs/<mode>`` otherwise (ignored by git, so a quick run never overwrites the full one)."""
    return Path("outputs") if mode == "full" else Path("outputs") / mode
