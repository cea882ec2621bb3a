"""The ``atlas`` command line: the subcommands of :data:`HELP`, each with its one-line help there.

The parser and the dispatch, nothing else: each subcommand imports only the module that
implements it, when it runs (``atlas --help`` imports neither JAX nor xarray).

Every bad input (NaN, negative stiffness, empty or reversed ranges, unknown outputs, an unwritable or
existing output path) is reported as one line ``atlas: error: PARAMETER: reason`` on stderr with exit
code 2 -- never a traceback; so is a run that cannot fit (``size: ...``, see ``--dry-run``) and a
failed write (``out: cannot write PATH: no space left on device``).  SIGINT / SIGTERM end a run
with exit 130 / 143 and nothing committed after them (:mod:`atlas.cli_signals`).  JAX compilations are cached on disk (``$ATLAS_JAX_CACHE``, default
``~/.cache/painleve-atlas/jax``; ``ATLAS_JAX_CACHE=0`` disables it), so repeated runs skip the
kernels' compilation (its seconds: ``atlas bench``'s Start-up section).

With ``--scheduler`` (``inprocess``, ``local[:N]``, ``tcp://HOST:PORT``) or ``--store``,
``atlas generate`` runs the scene tile by tile into a resumable zarr store
(:func:`atlas.data.distributed.generate_distributed`); ``--resume`` continues a killed run and ``--out``
converts the finished store to netCDF.

Examples::

    atlas generate --scene fig1 --out fig1.nc
    atlas generate --scene fig1 --scheduler local:2 --out fig1.nc      # fig1.zarr, then fig1.nc
    atlas generate --scene fig1 --scheduler local:2 --out fig1.nc --resume   # after a kill
    atlas generate --beta1 0:2pi:256 --beta2 0:2pi:256 --kappa log:0.1:10:5 --q 0,0.5 --out a.nc
    atlas generate --scene fig1 --physical k1=100,k2=200,q1=20,q2=20 --out fig2model.nc
"""

from __future__ import annotations

import argparse
import importlib
import math
import os
import re
import shlex
import signal
import sys

from atlas import cli_signals as signals

__all__ = ["main", "build_parser"]

EXIT_USAGE = 2


#: argument strings that are negative numbers or ranges, never options (``-1``, ``-0.5pi:1:3``,
#: ``--mu -1:2:4``), so that the validators, not argparse, report them
_NEGATIVE_VALUE = re.compile(r"^-(\d|\.\d|pi|inf|nan)")


class _Parser(argparse.ArgumentParser):
    """argparse with one-line errors ``atlas: error: ...`` (no usage dump, one prefix for every
    subcommand) and exit code 2.  Values that start with ``-`` and then a digit, ``.`` or ``pi``
    are values, not options: ``--beta1 -0.5pi:0.5pi:9`` needs no ``=``."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self._negative_number_matcher = _NEGATIVE_VALUE

    def error(self, message):  # noqa: D401 - argparse API
        raise _UsageError(f"atlas: error: {message}")


class _UsageError(Exception):
    pass


def _one_line(msg: str) -> str:
    return " ".join(str(msg).split())


#: the subcommands and their one-line help; each imports its own layer only when it is run or
#: asked for its options (``atlas --help`` imports none of them)
HELP = {
    "generate": "compute a scene into a CF netCDF4 atlas",
    "mechanism": "atlas of a built-in rigid body over physical axes (the bodies: mechanism --help)",
    "boundaries": "certified boundary curves of (beta1, beta2) slices (CF geometry, CSV, GeoJSON)",
    "paper": "regenerate every figure and table of the paper",
    "simulate": "simulate the compliant-contact dynamics (Fig. 2), or an outcome atlas (--map)",
    "table": "Table 2 of the paper from the kernels",
    "bench": "work-precision benchmark of the kernels",
    "selftest": "check the certified kernels on this JAX backend against the exact tier",
    "mujoco": "B, a and every verdict of a MuJoCo model's contacts at a state (extra: mujoco)",
}


def build_parser(command: str | None = "*") -> argparse.ArgumentParser:
    """The parser; ``command`` names the one subcommand whose options are built (the others get
    a stub with their help line, so their layers are not imported); ``"*"``: all of them."""
    p = _Parser(
        prog="atlas",
        description="Atlases of contact-mode consistency and stability for two sliding contacts "
        "(Painleve's paradox).",
    )
    sub = p.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    sub.required = True
    adders = {
        "generate": _add_generate,
        "mechanism": _add_mechanism,
        "boundaries": _add_boundaries,
        "paper": _add_paper,
        "simulate": _add_simulate,
        "table": _add_table,
        "bench": _add_bench,
        "selftest": _add_selftest,
        "mujoco": _add_mujoco,
    }
    for name, add in adders.items():
        if command in ("*", name):
            add(sub)
        else:
            sub.add_parser(name, help=HELP[name], add_help=False)
    return p


def _command(argv) -> str | None:
    """The subcommand named in ``argv`` (its first word that is not an option), if any."""
    return next((a for a in argv if not a.startswith("-")), None)


def _add_generate(sub) -> None:
    from atlas.data.engine import DEFAULT_TILE_POINTS, DTYPES, METHODS
    from atlas.data.outputs import atlas_outputs
    from atlas.data.scene import BUILTIN_SCENES

    g = sub.add_parser(
        "generate",
        help=HELP["generate"],
        description="Compute a scene (built-in or explicit ranges) tile by tile into a CF-1.10 "
        "netCDF4 file.  Ranges: START:STOP:N (linear; angles over a full turn exclude STOP), "
        "log:START:STOP:N, V1,V2,... or a scalar; numbers may carry a pi suffix (0.2pi).",
        epilog=f"built-in scenes: {', '.join(BUILTIN_SCENES)}; outputs: {', '.join(atlas_outputs())}",
    )
    g.add_argument("--scene", help="built-in scene to start from (options below override it)")
    for name, what in (
        ("beta1", "direction angle of b1 [rad]"),
        ("beta2", "direction angle of b2 [rad]"),
        ("alpha", "direction angle of a [rad] (needed by subclass/consistency outputs)"),
        ("kappa", "stiffness ratio k1|b1|/(k2|b2|) [1]"),
        ("q", "dimensionless damping q1_hat = q2_hat [1]"),
        ("q1", "dimensionless damping of contact 1 (with --q2, instead of --q)"),
        ("q2", "dimensionless damping of contact 2"),
    ):
        g.add_argument(f"--{name}", metavar="RANGE", help=what)
    g.add_argument(
        "--physical",
        metavar="k1=..,k2=..[,q1=..,q2=..,b1=..,b2=..]",
        help="physical contact parameters, converted to kappa and q (|b| default 1, q default 0)",
    )
    g.add_argument("--outputs", metavar="NAMES", help="comma-separated variables (default: all)")
    g.add_argument("--out", metavar="FILE.nc", help="output file (default: SCENE.nc)")
    g.add_argument("--method", choices=METHODS, default="certified")
    g.add_argument("--dtype", choices=DTYPES, default="float64")
    g.add_argument("--overwrite", action="store_true", help="replace an existing output file")
    g.add_argument(
        "--tile-points",
        type=_positive_int("tile-points"),
        default=DEFAULT_TILE_POINTS,
        metavar="N",
        help=f"points per tile (memory bound; default {DEFAULT_TILE_POINTS})",
    )
    g.add_argument(
        "--no-resolve",
        dest="resolve",
        action="store_false",
        help="keep undecided points instead of resolving them exactly",
    )
    g.add_argument(
        "--no-progress",
        dest="progress",
        action="store_false",
        help="no progress bar (default: one on a terminal, or where ATLAS_PROGRESS=1)",
    )
    g.add_argument(
        "--model-box",
        metavar="kappa=LO:HI,q1=LO:HI,q2=LO:HI",
        help="add ss_over_models, ii_consistent_over_models, ii_stable_over_models and their "
        "witness models: SS stable (II consistent, stable) for every model of the box, the "
        "opposite for every model, or depends (q=LO:HI: equal damping; inf allowed; an axis not "
        "given: its whole range; with --store/--scheduler: in every tile)",
    )
    _add_limits(g)
    _add_distributed(g)


def _add_limits(p) -> None:
    """``--dry-run`` and ``--no-size-check`` (see :mod:`atlas.data.limits`)."""
    p.add_argument(
        "--dry-run",
        action="store_true",
        help="print the estimated points, output bytes, peak memory and time, then stop",
    )
    p.add_argument(
        "--no-size-check",
        action="store_true",
        help="run even when the estimate exceeds the free memory or disk space",
    )


def _add_distributed(g) -> None:
    d = g.add_argument_group(
        "distributed (dask)",
        "--scheduler, --store, --resume, --slab or --block2 run the scene tile by tile into a resumable zarr store "
        "(atlas.data.distributed.generate_distributed; needs the dask extra); --out then converts the "
        "finished store to netCDF.",
    )
    d.add_argument(
        "--scheduler",
        metavar="WHERE",
        help="inprocess, local (one worker per core), local:N (N workers) or the address of a "
        "running dask scheduler (tcp://HOST:PORT)",
    )
    d.add_argument(
        "--store", metavar="PATH.zarr", help="zarr store of the tiles (default: --out with .zarr)"
    )
    d.add_argument(
        "--resume",
        action="store_true",
        help="continue an existing store: keep verified tiles, recompute missing or corrupt ones",
    )
    d.add_argument(
        "--slab",
        type=_positive_int("slab"),
        metavar="N",
        help="beta1 values per tile (default: about 2**18 points per tile, and beta2 split too "
        "when one beta1 value holds more)",
    )
    d.add_argument(
        "--block2",
        type=_positive_int("block2"),
        metavar="N",
        help="beta2 values per tile: 2-D (beta1, beta2) tiles (default: see --slab)",
    )


def _add_mechanism(sub) -> None:
    from atlas.core.bodies import MODEL
    from atlas.data.body_atlas import MECHANISM_SCENES, stored_units

    def fixed(sc) -> str:
        sets = {p for ax in sc.axes.values() for p in ax.sets}
        units = stored_units(sc)
        names = [k for k in sc.params if k not in sets] + list(MODEL)
        return ", ".join(f"{k} [{units[k][0]}]" for k in names)

    pm = sub.add_parser(
        "mechanism",
        help=HELP["mechanism"],
        description="Sweep a built-in body over its physical axes into a CF netCDF4 file: the "
        "invariants, B and a of eq. (1), and every verdict.  Without --out, print a summary.",
        epilog="; ".join(
            f"{n} ({sc.description}): "
            + ", ".join(f"--{a} [{ax.units}] (default {ax.default})" for a, ax in sc.axes.items())
            + f"; --fixed {fixed(sc)}"
            for n, sc in MECHANISM_SCENES.items()
        ),
    )
    pm.add_argument("name", choices=sorted(MECHANISM_SCENES), help="built-in mechanism scene")
    pm.add_argument(
        "--model-box",
        metavar="kappa=LO:HI,q1=LO:HI,q2=LO:HI",
        help="add ss_over_models and its witness models per body: SS stable for every contact "
        "model of the box at the body's geometry, for none, or depends",
    )
    axes = sorted({a for sc in MECHANISM_SCENES.values() for a in sc.axes})
    for a in axes:
        pm.add_argument(
            f"--{a}", metavar="RANGE", help="physical axis (START:STOP:N, values, scalar)"
        )
    pm.add_argument(
        "--fixed",
        metavar="K=V,...",
        help="other parameters in SI units, e.g. L=3,m=10,k1=2e5,c1=20,speed=0.5 (each body's "
        "below)",
    )
    pm.add_argument("--out", metavar="FILE.nc", help="output file")
    pm.add_argument("--overwrite", action="store_true", help="replace an existing output file")
    pm.add_argument("--dtype", choices=["float64", "float32"], default="float64")
    _add_limits(pm)


def _add_mujoco(sub) -> None:
    pm = sub.add_parser(
        "mujoco",
        help=HELP["mujoco"],
        description="Read a MuJoCo model (MJCF) at a state, build B and a of eq. (1) from its "
        "mass matrix and contact Jacobians, and print every verdict (needs: pip install "
        "'painleve-atlas[mujoco]').",
    )
    pm.add_argument("model", metavar="MODEL.xml", help="MJCF (or MJB) file")
    pm.add_argument(
        "--contacts", metavar="A,B", help="the touching contacts in order, geom names or pairs "
        "g1/g2 (default: the touching ones; three or more touching, or one left out, is refused)",
    )  # fmt: skip
    pm.add_argument("--qpos", metavar="X,...", help="generalised positions (default: qpos0)")
    pm.add_argument("--qvel", metavar="V,...", help="generalised velocities (default: 0)")
    pm.add_argument(
        "--slip", metavar="X,Y,Z;...", help="slip directions (world) of the contacts, in order: "
        "needed only where a frictional contact does not slide",
    )  # fmt: skip
    pm.add_argument("--tol", type=float, default=1e-6, help="touching: distance <= TOL [m]")
    pm.add_argument("--json", dest="json_out", action="store_true", help="one JSON object")
    pm.add_argument(
        "--rollout", type=float, metavar="T", help="step the model T seconds and report the "
        "verdicts along the trajectory (where the mode or a verdict changes)",
    )  # fmt: skip
    pm.add_argument("--every", type=int, help="rollout: judge every N-th step (default: 10)")
    pm.add_argument(
        "--jam-test", action="store_true", help="rollout: run again with the constraint time "
        "constants halved (a jam's stop time halves, a friction stop's does not)",
    )  # fmt: skip


def _add_boundaries(sub) -> None:
    from atlas.data.boundary_args import (
        CHECK,
        CHORD,
        CODE_MEANINGS,
        CSV_COLUMNS,
        MAX_CHECK,
        MIN_CHORD,
        MIN_TOL,
        TOL,
    )

    pb = sub.add_parser(
        "boundaries",
        help=HELP["boundaries"],
        description="Every SS and II boundary of each (kappa, q1, q2) slice as polylines whose "
        "vertices are certified within --tol of the true boundary (bisection on certified "
        "verdicts), the closed-form class lines, and the codimension-2 points.  Ranges as for "
        "generate.  Without an output file, print a summary.",
        epilog=f"CSV columns: {', '.join(CSV_COLUMNS)} (record: vertex or point; side_left / "
        f"side_right: the codes left / right of the direction of travel, the higher on the "
        f"left; side_on: the code on a class-line piece where it differs from both; "
        f"uncertainty: a point's proven enclosure radius, empty when not proven).  "
        f"Codes: {CODE_MEANINGS}.",
    )
    for name in ("beta1", "beta2", "kappa", "q", "q1", "q2"):
        pb.add_argument(f"--{name}", metavar="RANGE", help=f"{name} (as for generate)")
    pb.add_argument(
        "--fields",
        default=None,
        help="SS, II or SS,II (default); with --model-box also the names of the verdicts over "
        "the box (ss_over_models, ii_consistent_over_models, ii_stable_over_models)",
    )
    pb.add_argument(
        "--tol",
        type=_number("tol"),
        default=TOL,
        help=f"vertex bracket [rad], >= {MIN_TOL:.3g} ({TOL})",
    )
    pb.add_argument(
        "--chord",
        type=_number("chord"),
        default=None,
        help=f"chord sagitta [rad], in [max(tol, {MIN_CHORD:g}), 0.1] ({CHORD})",
    )
    pb.add_argument(
        "--check",
        type=int,
        default=None,
        help=f"resample cells N x finer for hidden branches, 0..{MAX_CHECK}; 0 or 1: no check; "
        f"refused if the refined grids may need more than 4 GiB ({CHECK})",
    )
    pb.add_argument("--out", metavar="FILE.nc", help="CF-1.10 geometry container")
    pb.add_argument("--csv", metavar="FILE.csv", help="one row per vertex and per point")
    pb.add_argument("--geojson", metavar="FILE.json", help="GeoJSON FeatureCollection")
    pb.add_argument("--overwrite", action="store_true", help="replace existing output files")
    pb.add_argument("--dtype", choices=["float64", "float32"], default="float64")
    pb.add_argument(
        "--model-box",
        metavar="kappa=LO:HI,q1=LO:HI,q2=LO:HI",
        help="instead: the certified curves between the regions of the verdicts over this box "
        "(ss_over_models and the II ones: for every model / for none / depends; no --kappa/--q, "
        "--chord, --check; atlas.data.region_curves)",
    )
    _add_limits(pb)


def _add_paper(sub) -> None:
    pp = sub.add_parser("paper", help=HELP["paper"])
    pp.add_argument(
        "--out",
        default="outputs",
        metavar="DIR",
        help="output directory (created if its parent exists; the files atlas paper writes "
        "are replaced)",
    )
    pp.add_argument("--quick", action="store_true", help="low resolution (seconds, for CI)")
    pp.add_argument(
        "--jobs",
        type=int,
        default=None,
        metavar="N",
        help="processes: 1, or 2 to run the independent steps beside the others (default: 2 "
        "where two cores are idle); the files are the same bytes either way",
    )


def _add_simulate(sub) -> None:
    ps = sub.add_parser(
        "simulate",
        help=HELP["simulate"],
        description="One trajectory (a Fig. 2 case, or --beta1, --beta2, --alpha numbers with the "
        "physical --k1, --k2, --q1, --q2), or with --map an outcome atlas: the axes take the "
        "ranges of atlas generate (START:STOP:N, log:START:STOP:N, V1,V2,... or a scalar; pi "
        "suffix ok) and --q, --q1, --q2 are the dimensionless dampings there.",
    )
    ps.add_argument("--case", choices=["fig2a", "fig2b", "fig2c", "fig2d", "fig2e"])
    for name, what in (
        ("beta1", "direction angle of b1 [rad]"),
        ("beta2", "direction angle of b2 [rad]"),
        ("alpha", "direction angle of a [rad] (--map default 0.35pi)"),
        ("kappa", "--map: stiffness ratio k1|b1|/(k2|b2|) [1] (default 0.5)"),
        ("q", "--map: dimensionless damping q1_hat = q2_hat [1] (default 0)"),
        ("q1", "damping of contact 1 (--map: dimensionless, with --q2; else physical)"),
        ("q2", "damping of contact 2"),
    ):
        ps.add_argument(f"--{name}", metavar="RANGE", help=what)
    for name in ("k1", "k2", "t-end"):
        ps.add_argument(f"--{name}", type=_number(name), metavar="X")
    ps.add_argument(
        "--out", metavar="FILE", help="output file: .csv, .png, .pdf, .svg (--map: .nc, .png, .pdf)"
    )
    ps.add_argument("--overwrite", action="store_true", help="replace an existing output file")
    ps.add_argument(
        "--map",
        dest="outcome_map",
        action="store_true",
        help="outcome atlas over the given axes (--out FILE.nc, or FILE.png for one model)",
    )
    ps.add_argument(
        "--n",
        type=int,
        metavar="N",
        help="map: cells per axis when --beta1/--beta2 are not given (offset grid, default 24)",
    )
    ps.add_argument(
        "--n-perturb", type=int, metavar="M", help="map: initial conditions per cell (default 1)"
    )
    ps.add_argument("--seed", type=int, metavar="S", help="map: seed of the perturbations (0)")
    ps.add_argument(
        "--engine",
        choices=["fast", "numpy", "jax"],
        default="fast",
        help="map engine: fast (batched, certified early stops), numpy (exact reference), jax (the "
        "fast engine as a JAX kernel, for accelerators)",
    )
    ps.add_argument(
        "--no-theory", action="store_true", help="map: without the theory verdicts of the cells"
    )
    ps.add_argument(
        "--store", metavar="DIR", help="map: tile by tile into this resumable store directory"
    )
    ps.add_argument("--resume", action="store_true", help="map: continue the tiles in --store")
    ps.add_argument("--slab", type=int, metavar="N", help="map: beta1 values per tile")
    ps.add_argument(
        "--workers",
        type=int,
        metavar="N",
        help="map, fast engine: processes (default: the usable cores; 1 = this process only)",
    )
    ps.add_argument(
        "--scheduler",
        metavar="WHERE",
        help="map with --store: local, local:N (dask workers) or tcp://HOST:PORT (default: here)",
    )
    _add_limits(ps)


def _add_table(sub) -> None:
    pt = sub.add_parser("table", help=HELP["table"])
    pt.add_argument(
        "--format", choices=["markdown", "csv"], default=None,
        help="default: the ending of --out (.md, .csv), else markdown",
    )  # fmt: skip
    pt.add_argument("--out", metavar="FILE", help="output file .md, .csv or .txt (default: stdout)")
    pt.add_argument("--overwrite", action="store_true", help="replace an existing output file")


def _add_bench(sub) -> None:
    pb = sub.add_parser("bench", help=HELP["bench"])
    pb.add_argument("--quick", action="store_true", help="small grids (CI)")
    pb.add_argument(
        "--out",
        metavar="DIR",
        help="output directory (default: outputs, --quick: outputs/quick; created if its parent "
        "exists; the files atlas bench writes are replaced)",
    )
    pb.add_argument(
        "--only",
        metavar="SECTION[,SECTION]",
        help="re-measure only these sections of the report already in --out and keep the others "
        "(each section then names the run that measured it): work_precision, model_grids, "
        "model_box_map, large, suites, scaling, atlases, simulation, outcome_maps, curves, "
        "startup, distributed",
    )


#: the output options of each command and the file name endings they take
_EXTENSIONS = {
    "generate": {"out": (".nc",), "store": (".zarr",)},
    "mechanism": {"out": (".nc",)},
    "boundaries": {"out": (".nc",), "csv": (".csv",), "geojson": (".json", ".geojson")},
    "simulate": {"out": (".csv", ".png", ".pdf", ".svg")},
    "simulate --map": {"out": (".nc", ".png", ".pdf")},
    "table": {"out": (".md", ".csv", ".txt")},
}


def _output_rules(args) -> None:
    """The rules every writing command follows, checked before any work: an output file has a
    name with a known ending (``out: ...`` otherwise), its directory exists and is writable, and an
    existing file is replaced only with ``--overwrite``; ``paper`` and ``bench`` write into a
    directory that exists or whose parent does."""
    command = args.command
    if command == "simulate" and args.outcome_map:
        command = "simulate --map"
    for opt, endings in _EXTENSIONS.get(command, {}).items():
        path = getattr(args, opt, None)
        if path is None:
            continue
        if not path.strip():
            raise ValueError(f"{opt}: empty path")
        if not path.lower().endswith(endings):
            raise ValueError(
                f"{opt}: expected a file name ending in {', '.join(endings)}, got {path!r}"
            )
        if opt != "store" and command != "generate":  # generate checks after --resume/--store
            from atlas.data.io import check_output_path

            check_output_path(path, getattr(args, "overwrite", False))
    if command in ("paper", "bench") and args.out is not None:
        _check_output_dir(args.out)


def _refuse_early(args) -> None:
    """The checks that need no heavy import, before any (a refusal costs no JAX start-up):
    ``atlas boundaries``' ``--kappa``, ``--q``, ``--q1``, ``--q2`` written as numbers, ``--tol``,
    ``--chord``, ``--check`` and ``--fields`` (with ``--model-box`` the region curves check their
    own: chord and check do not apply there)."""
    if args.command == "boundaries" and getattr(args, "model_box", None) is None:
        from atlas.data.boundary_args import CLI_DEFAULTS, check_args, check_model_text

        # the defaults of a slice's curves (left unset on the parser: --model-box refuses them)
        for name, default in CLI_DEFAULTS.items():
            if getattr(args, name) is None:
                setattr(args, name, default)
        for name in ("kappa", "q", "q1", "q2"):
            check_model_text(name, getattr(args, name, None))
        check_args(args.tol, args.chord, args.check, 2, args.fields)


def _check_output_dir(path: str) -> None:
    """``out``: a directory that exists and is writable, or can be created (its parent exists)."""
    from atlas.data.io import check_output_path

    if not path.strip():
        raise ValueError("out: empty path")
    if os.path.exists(path) and not os.path.isdir(path):
        raise NotADirectoryError(f"out: {path} is not a directory")
    probe = os.path.join(path, ".atlas-probe") if os.path.isdir(path) else path.rstrip("/")
    check_output_path(probe, overwrite=True)


def _add_selftest(sub) -> None:
    pt = sub.add_parser(
        "selftest",
        help=HELP["selftest"],
        description="Run the hard-case suites (atlas.core.hardcases) through the certified "
        "kernels on the JAX device in use and compare every decided point with the exact tier; "
        "prints ns/point and the disagreements (exit 1 if any).  The result is recorded per "
        "backend beside the compilation cache; the certified kernels refuse to run on a backend "
        "whose last self-check failed.",
    )
    pt.add_argument("--suites", metavar="NAMES", help="comma-separated suite names (default: all)")
    pt.add_argument(
        "--dtypes", default="float64,float32", metavar="NAMES", help="float64,float32 (default)"
    )


def _positive_int(name):
    def conv(text):
        try:
            n = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"must be a positive integer, got {text!r}") from None
        if n < 1:
            raise argparse.ArgumentTypeError(f"must be a positive integer, got {text!r}")
        return n

    conv.__name__ = name
    return conv


def _number(name):
    def conv(text):
        try:  # a plain number needs no parser (nor its imports)
            value = float(text)
        except ValueError:
            value = math.nan
        if math.isfinite(value):
            return value
        from atlas.data.scene import parse_values

        try:
            vals, is_dim = parse_values(text, name)
        except ValueError as e:
            raise argparse.ArgumentTypeError(str(e)) from None
        if is_dim:
            raise argparse.ArgumentTypeError(f"{name}: expected a single number, got {text!r}")
        return float(vals)

    conv.__name__ = name
    return conv


def _dispatch_estimate(args):
    """The estimate of a dispatched command that holds its grid in memory, or ``None``."""
    from atlas.data import limits
    from atlas.data.scene import parse_values

    if args.command == "mechanism":
        from atlas.data.body_atlas import MECHANISM_SCENES

        sc = MECHANISM_SCENES.get(args.name)
        if sc is None:
            return None
        points = 1
        for axis, (default, *_r) in sc.axes.items():
            spec = getattr(args, axis, None)
            points *= parse_values(default if spec is None else spec, axis)[0].size
        outs = [args.out] if args.out else []
        return limits.grid_estimate("mechanism", points, outputs=outs, **limits.MECHANISM)
    if args.command == "boundaries":
        from atlas.data.boundary_args import MAX_CHECK
        from atlas.data.scene import Scene

        box = getattr(args, "model_box", None) is not None
        if not box and not 0 <= args.check <= MAX_CHECK:
            return None  # refused by the boundaries' own check, which names the limit

        axes = {k: getattr(args, k) for k in ("beta1", "beta2", "kappa", "q", "q1", "q2")}
        scene = Scene(
            **{k: v for k, v in axes.items() if v is not None and (k[0] == "b" or not box)}
        )
        # a box: one unchecked slice per verdict over it (rough: a vertex there costs more)
        slices = 3 if box else math.prod(scene.axes[m].size for m in scene.model_names)
        n1, n2 = scene.axes["beta1"].size, scene.axes["beta2"].size
        outs = [p for p in (args.out, args.csv, args.geojson) if p]
        return limits.boundaries_estimate(n1, n2, 0 if box else args.check, slices, outputs=outs)
    if args.command == "simulate" and not args.outcome_map:
        for name in ("dry_run", "no_size_check"):
            if getattr(args, name):  # one trajectory: no grid to estimate
                raise ValueError(f"{name.replace('_', '-')}: only with --map")
    if args.command == "simulate" and args.outcome_map:
        from atlas.paper.simulate import map_dynamics, map_scene, scene_options

        scene = map_scene(**scene_options(vars(args)))
        dyn = map_dynamics(args.n_perturb, args.seed, args.engine, args.t_end)
        outs = [p for p in (args.out, args.store) if p]
        tile = None
        if args.store:
            from atlas.dynamics.outcome_tiles import default_slab

            slab = args.slab or default_slab(scene, dyn.n_perturb)
            tile = slab * math.prod(a.size for k, a in scene.axes.items() if k != "beta1")
            tile *= dyn.n_perturb
        return limits.outcome_estimate(
            scene, dyn.n_perturb, engine=dyn.engine, theory=not args.no_theory, outputs=outs,
            tile_runs=tile, t_end=dyn.t_end,
        )  # fmt: skip
    return None


def _force_progress() -> bool:
    return os.environ.get("ATLAS_PROGRESS", "") not in ("", "0")


_DISPATCH = {
    "paper": ("atlas.paper", "run"),
    "mechanism": ("atlas.data.body_atlas", "run_cli"),
    "boundaries": ("atlas.data.boundaries", "run_cli"),
    "simulate": ("atlas.paper.simulate", "run_cli"),
    "table": ("atlas.paper.tables", "run_cli"),
    "bench": ("atlas.bench", "run"),
    "selftest": ("atlas.core.selftest", "run_cli"),
    "mujoco": ("atlas.bridges.mujoco_cli", "run_cli"),
}


def _cmd_generate(args, argv) -> int:
    """``atlas generate``: its options, the progress bar decided here (a terminal, or
    ``ATLAS_PROGRESS=1``; never with ``--no-progress``) and the command line as ``history``."""
    from atlas.data.generate_cli import run_cli

    opts = {k: v for k, v in vars(args).items() if k != "command"}
    opts["progress"] = args.progress and (sys.stderr.isatty() or _force_progress())
    return run_cli(history="atlas " + " ".join(shlex.quote(a) for a in argv), **opts)


def dispatch_call(args, argv=()) -> tuple:
    """The function a dispatched command runs and its keyword arguments, from the parsed
    ``args`` (the options that only screen the run, ``--dry-run`` and ``--no-size-check``,
    are not passed on)."""
    module, func = _DISPATCH[args.command]
    if args.command == "boundaries" and args.model_box is not None:
        module = "atlas.data.region_curves"  # the regions over a box of models
    fn = getattr(importlib.import_module(module), func)
    skip = ("command", "dry_run", "no_size_check")
    opts = {k: v for k, v in vars(args).items() if k not in skip}
    if args.command == "simulate":  # the command line, for the map's history attribute
        opts["argv"] = [args.command, *argv[1:]] if argv else None
    return fn, opts


def _cmd_dispatch(args, argv=()) -> int:
    estimate = _dispatch_estimate(args) if hasattr(args, "dry_run") else None
    if estimate is not None and estimate.screen(args.dry_run, args.no_size_check):
        return 0
    fn, opts = dispatch_call(args, argv)
    if args.command in _TOGETHER:
        from atlas.data.io import committed_together

        with committed_together(overwrite=getattr(args, "overwrite", False)):
            rc = fn(**opts)
    else:
        rc = fn(**opts)
    return rc if isinstance(rc, int) else 0


#: commands whose output files are committed together at the end, or none of them
#: (``paper`` and ``bench`` read back what they wrote and keep the files finished before a stop)
_TOGETHER = ("mechanism", "boundaries", "simulate", "table")


def main(argv=None) -> int:
    """Entry point of the ``atlas`` console script; returns the exit code (the console script
    itself ends the process with it, see :mod:`atlas.cli_signals`)."""
    console = argv is None
    argv = list(sys.argv[1:] if argv is None else argv)
    saved = signals.install()
    written = sys.modules.get("atlas.data.io")
    if written is not None:
        written.forget_commits()
    rc = 130
    try:
        try:
            rc = _main(argv)
        except KeyboardInterrupt as e:
            signals.arm(0)
            rc = _interrupted(e)
        rc = signals.signal_code(rc)
        signals.state["exit_now"] = console and saved is not None  # a signal now ends the process
    except KeyboardInterrupt:  # a signal while the first one was being reported
        signals.state["exit_now"] = console and saved is not None
        rc = signals.signal_code(130)
    finally:
        signals.state["exit_now"] = console and saved is not None
        if signals.state["exit_now"]:
            signals.arm(0)
        else:
            signals.restore(saved)
    if console:
        signals.hard_exit(rc)
    return rc


def _interrupted(e) -> int:
    from atlas.core import interrupts

    why = _one_line(e) or "no partial output file left"
    done = sys.modules.get("atlas.data.io")
    if done is not None and done.COMMITTED and not _one_line(e):
        why += f"; complete before it: {', '.join(done.COMMITTED)}"
    print(f"atlas: interrupted ({why})", file=sys.stderr)
    return 128 + (interrupts.requested() or signal.SIGINT)


#: options that name where a run writes, not what it computes
_WHERE = ("out", "store", "csv", "geojson", "overwrite", "resume", "progress", "no_progress")


def _run_name(args) -> str:
    """What a run computes (its options but the output paths): runs of one name use the same
    kernels, which :func:`atlas.core.warm.kernel_cache` then loads in the background."""
    return repr(sorted((k, repr(v)) for k, v in vars(args).items() if k not in _WHERE))


def _main(argv) -> int:
    try:
        args = build_parser(_command(argv)).parse_args(argv)
        _refuse_early(args)
        _output_rules(args)
        from atlas.core.warm import kernel_cache

        with kernel_cache(run=_run_name(args)):  # kernels kept on disk: the next run starts warm
            if args.command == "generate":
                return _cmd_generate(args, argv)
            return _cmd_dispatch(args, argv)
    except _UsageError as e:
        print(_one_line(e), file=sys.stderr)
        return EXIT_USAGE
    except (ValueError, OSError, MemoryError) as e:
        print(f"atlas: error: {_one_line(e)}", file=sys.stderr)
        return EXIT_USAGE
    except SystemExit as e:  # --help
        return e.code if isinstance(e.code, int) else 0
    except Exception as e:  # a bug, not bad input: still one line (ATLAS_DEBUG=1 re-raises)
        if os.environ.get("ATLAS_DEBUG", "") not in ("", "0"):
            raise
        msg = f"atlas: internal error: {type(e).__name__}: {_one_line(e)}"
        print(f"{msg} (set ATLAS_DEBUG=1 for the traceback)", file=sys.stderr)
        return 1


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
