"""``atlas paper``: regenerate the paper's figures and tables, and the audit, into ``outputs/``.

Default resolution runs in a few minutes on 2 cores; ``quick=True`` (CI) in well under a minute
once the kernels are compiled.  Every file is written atomically (temporary file + ``os.replace``).
JAX compilations are cached on disk (``$ATLAS_JAX_CACHE``, default ``~/.cache/painleve-atlas/jax``;
set it to ``0`` to disable) so repeated runs skip the ~20 s compile of each kernel shape.
"""

from __future__ import annotations

import time
from pathlib import Path

from atlas.dynamics.lane_pool import check_workers
from atlas.paper import side_process
from atlas.paper.steps import (
    Shared,
    Steps,
    dynamics,
    notes,
    say_stderr,
    shared_steps,
    side_steps,
    sizes,
    write_realisability,
)

#: ``atomic_write_text``: from :mod:`atlas.data.io` on first use (module ``__getattr__``)
__all__ = ["FILES", "FIG2_FILES", "files", "run", "atomic_write_text", "write_netcdf"]  # noqa: F822

#: the files Fig. 2's simulations add (not in quick mode)
FIG2_FILES = ("fig2.md", "fig2.png")
#: every file ``atlas paper`` writes into its output directory (a test compares ``outputs/``)
FILES = (
    "README.md",
    "audit.md",
    "fig1_boundaries.nc",
    "fig1_boundaries.png",
    "fig1_classes.png",
    "fig1_map.nc",
    "fig1_models.png",
    "fig1_stability.png",
    "fig1_stability_variants.png",
    "ladder.png",
    "outcome_distribution.md",
    "outcome_distribution.png",
    "outcome_map.nc",
    "outcome_map.png",
    "realisability.md",
    "table2.csv",
    "table2.md",
    "table2.png",
    *FIG2_FILES,
)


def files(quick: bool = False) -> tuple[str, ...]:
    """The files a run writes (quick and CI runs leave out :data:`FIG2_FILES`)."""
    return tuple(f for f in FILES if not (quick and f in FIG2_FILES))


REFERENCE = (
    "P. L. Varkonyi, Dynamics of mechanical systems with multiple sliding contacts: new "
    "faces of Painleve's paradox"
)


def __getattr__(name: str):
    """``atomic_write_text`` (:mod:`atlas.data.io`), imported on first use: this module imports
    no JAX until :func:`run` has started its second process."""
    if name == "atomic_write_text":
        from atlas.data.io import atomic_write_text

        return atomic_write_text
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def write_netcdf(ds, path, call: str = "atlas.paper.run") -> Path:
    """Atomic netCDF4 write with the SPEC §2 encodings (no ``_FillValue`` on ints or coords);
    ``history`` is ``call`` (no time stamp: :mod:`atlas.paper.runlog`)."""
    import numpy as np

    from atlas.core import config
    from atlas.data.io import atomic_path
    from atlas.paper import runlog

    ds = runlog.fixed(ds, Path(path).name)
    ds.attrs.update(
        {
            "Conventions": "CF-1.10",
            "title": f"Fig. 1 map of the paper (kappa = {float(ds['kappa']):g}, q1 = "
            f"{float(ds['q1']):g}, q2 = {float(ds['q2']):g})",
            "source": config.source(),
            "history": call,
            "references": REFERENCE,
            "scene": "fig1: beta1 x beta2 offset grid over [0, 2 pi), certified fast kernels, float64, "
            "undecided cells settled by atlas.core.exact",
        }
    )
    enc = {}
    for name, var in ds.variables.items():
        if var.dtype.kind in "iub" or name in ds.coords:
            enc[name] = {"_FillValue": None}
        if name in ds.data_vars and var.ndim:
            enc.setdefault(name, {}).update(zlib=True, complevel=4)
            if var.dtype == np.float64 and name.startswith("margin"):
                enc[name]["dtype"] = "float32"
        if var.dtype == bool:
            ds[name] = var.astype(np.int8)
            ds[name].attrs.update(flag_values=np.array([0, 1], np.int8), flag_meanings="false true")
    with atomic_path(path, suffix=".tmp.nc") as tmp:
        ds.to_netcdf(tmp, format="NETCDF4", encoding=enc)
    return path


def run(
    out: str = "outputs", quick: bool = False, progress=None, ci: bool = False, jobs=None
) -> dict:
    """Regenerate Fig. 1 (classes, stability map, variants), Table 2 (md, csv, png), the audit,
    Fig. 2 (if :mod:`atlas.paper.figures_dynamics` is available) and ``fig1_map.nc`` into ``out``.

    ``jobs``: processes (1 or 2; default: 2 where two cores are idle,
    :func:`atlas.dynamics.lane_pool.usable_cores`).  With 2, the steps that need nothing from the
    others (:func:`atlas.paper.steps.side_steps`) run in a second process beside the rest
    (:mod:`atlas.paper.side_process`), started before this one imports its own steps' modules;
    the files are the same bytes either way.  Returns a dict ``{step: seconds}``; also writes
    ``out/README.md`` listing the files.  The files are a pure function of the code and
    ``quick`` / ``ci``: dates, seconds, host and command line go to ``out/run.log``
    (:mod:`atlas.paper.runlog`).
    """
    jobs = min(2, check_workers(jobs, "jobs"))
    say = progress or say_stderr
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    quick = quick or ci  # ci: the CI test's size (smallest grids)
    with Shared() as shared:
        total, step = _run_processes(out, quick, ci, jobs, shared, say)
    say(f"all done in {total:.1f} s -> {out}")
    return dict(step.timings, total=total)


def _run_processes(out: Path, quick: bool, ci: bool, jobs: int, shared: Shared, say):
    """:func:`_run_steps` under the run log, in ``jobs`` processes: the second one spawned
    before this one imports what its own steps use, so both import at once.  Returns the
    seconds and the :class:`Steps`."""
    t_all = time.perf_counter()
    side = (
        side_process.start(side_steps, out, quick, ci, say is say_stderr, shared)
        if jobs > 1
        else None
    )
    try:
        from atlas.core.config import use_compile_cache
        from atlas.paper import runlog

        use_compile_cache()
        with runlog.RunLog(out):
            step = Steps(say)
            runlog.record("processes", jobs)
            _run_steps(step, out, quick, ci, side, shared)
            total = time.perf_counter() - t_all
            runlog.record("total seconds", total)
    finally:
        side_process.stop(side)
    return total, step


def _run_steps(step: Steps, out: Path, quick: bool, ci: bool, side, shared: Shared) -> None:
    """The steps of :func:`run`, each file written into ``out``;
    :func:`atlas.paper.steps.side_steps` here, or in the second process ``side``
    (:func:`atlas.paper.side_process.start`) if not ``None``: then the steps of ``shared`` it
    has not claimed yet run here once this process's own steps are done."""
    from atlas.data.io import atomic_write_text
    from atlas.paper import audit, figures, plots, tables

    n_map, n_var = sizes(quick, ci)
    rows = step("table2", lambda: tables.table2(n=96, per_class=8 if quick else 24))
    step("table2.md", lambda: atomic_write_text(out / "table2.md", tables.to_markdown(rows)))
    step("table2.csv", lambda: atomic_write_text(out / "table2.csv", tables.to_csv(rows)))
    step("table2.png", lambda: plots.plot_table2(out / "table2.png", rows))
    ds = step("fig1 map (compute)", lambda: figures.stability_map(n_map, 0.5, 0.0, 0.0))
    fig1_map = ds[[v for v in ds.data_vars if v != "margin_II_stable"]]
    call = f"atlas.paper.run(quick={quick}, ci={ci})"
    step("fig1_map.nc", lambda: write_netcdf(fig1_map, out / "fig1_map.nc", call))
    ctx = audit.Context(quick, ci, step.say, rows)
    claims = step("audit (compute)", lambda: audit.run_audit(context=ctx))
    step("audit.md", lambda: audit.write_audit(claims, out / "audit.md"))
    models = _from_the_audit(step, out, ctx)
    _outcome_map_step(step, out, quick, ds)
    if side is None:
        fig1_curves = side_steps(step, out, quick, ci, shared)
    else:
        shared_steps(step, out, quick, ci, shared)
        fig1_curves = side_process.join(side, step)
    step(
        "fig1_stability.png",
        lambda: plots.plot_fig1_stability(out / "fig1_stability.png", ds, fig1_curves),
    )
    _write_readme(out, quick, n_map, n_var, _audit_counts(claims), notes(quick), ds, models)


def _from_the_audit(step: Steps, out: Path, ctx):
    """The files drawn from what the audit ``ctx`` computed (each computed once in the run):
    Fig. 1 over every model (its map, :attr:`atlas.paper.audit.Context.models_map`) and the
    realisations.  Returns the maps of ``fig1_models.png``."""
    from atlas.paper import figure_models

    path = out / "fig1_models.png"
    (models,) = step(
        "fig1_models.png", lambda: figure_models.save_model_dependence(path, [ctx.models_map])
    )
    path = out / "realisability.md"
    step("realisability.md", lambda: write_realisability(path, ctx.realisations))
    return models


def _outcome_map_step(step: Steps, out: Path, quick: bool, ds) -> None:
    """The outcome map beside the Fig. 1 map ``ds``, if :mod:`atlas.paper.figures_dynamics`
    imports (else nothing: :func:`atlas.paper.steps.side_steps` gives the note)."""
    dyn, _ = dynamics()
    if dyn is not None:
        step(
            "outcome_map.nc",
            lambda: dyn.outcome_map_files(out, dyn.PAPER_MAP_N[not quick], theory=ds),
        )


def _audit_counts(claims) -> dict:
    """Claims per audit status (the ``META`` claim not counted)."""
    return {
        s: sum(1 for c in claims if c.status == s and c.id != "META")
        for s in ("confirmed", "refuted", "imprecise")
    }


def _write_readme(out, quick, n_map, n_var, counts, notes, ds, models):
    """``out/README.md``: how the files were made, their sizes, the figures inline (no dates or
    seconds: those are in ``run.log``)."""
    from atlas.data.io import atomic_write_text
    from atlas.paper import runlog

    lines = [
        "# Regenerated figures and tables (`atlas paper`)",
        "",
        f"Made by `atlas.paper.run(quick={quick})` (Fig. 1 map {n_map}^2 cells, variants "
        f"{n_var}^2; {ds.attrs.get('n_resolved', 0)} map cells settled by the exact reference, "
        f"{ds.attrs.get('n_undecided', 0)} undecided).  The files are a pure function of the code "
        f"and these sizes; the date, seconds per step and host of the run are in `{runlog.LOG}` "
        "(not committed).",
        "",
        f"Audit of the paper's claims ([audit.md](audit.md)): {counts['confirmed']} confirmed, "
        f"{counts['refuted']} refuted, {counts['imprecise']} imprecise.",
        "",
        "| file | size |",
        "|---|---|",
        *_file_rows(out),
        "",
        *(f"* {n}" for n in notes),
        "",
        *_figure_sections(out),
        *_models_section(models),
    ]
    atomic_write_text(out / "README.md", "\n".join(lines))


def _models_section(models) -> list[str]:
    """README section: the model-dependence panel and the share of the plane in each region."""
    from atlas.paper import figure_models

    return [
        "## Fig. 1 plane over every contact model",
        "",
        "Where SS is stable for every model `kappa > 0, q1, q2 >= 0` (the whole model space, "
        "undamped models included), unstable for every model, or depends on the model: the "
        "paper's Appendix C judged this from sampled models, here each region is proved "
        "(`atlas.core.model_box`).",
        "",
        *figure_models.fractions_markdown(models),
        "",
        "![fig1 models](fig1_models.png)",
        "",
    ]


def _file_rows(out: Path) -> list[str]:
    """README table rows ``| file | size |`` of the files in ``out`` but the README, the run
    log and ``atlas bench``'s."""
    from atlas.paper.runlog import LOG

    files = sorted(
        p.name
        for p in out.iterdir()
        if p.is_file()
        and not p.name.startswith("bench")
        and p.name not in ("README.md", LOG)
        and ".tmp" not in p.name
    )
    return [f"| [{f}]({f}) | {(out / f).stat().st_size / 1024:.0f} kB |" for f in files]


def _figure_sections(out: Path) -> list[str]:
    """README sections showing the figures (Fig. 2 and the outcome map when they were made)."""
    from atlas.paper import figures

    lines = [
        "## Fig. 1: classes",
        "",
        "![fig1 classes](fig1_classes.png)",
        "",
        "## Fig. 1: stability map (kappa = 0.5, q = 0)",
        "",
        "Dashed: the certified boundary curves (model-dependent boundaries, vertices within "
        "1e-10 rad, from fig1_boundaries.nc); solid: class "
        "boundaries. Neutral (q = 0) is drawn in its own shade; the paper draws it as stable.",
        "",
        "![fig1 stability](fig1_stability.png)",
        "",
        "## Fig. 1 at other (kappa, q1, q2)",
        "",
        "Variants: " + ", ".join(f"({k:g}, {a:g}, {b:g})" for k, a, b in figures.VARIANTS),
        "",
        "![fig1 variants](fig1_stability_variants.png)",
        "",
        "## Fig. 1 boundaries as certified curves (q = 0 and q -> 0+)",
        "",
        "Every model-dependent boundary of the slice as polylines with vertices certified within "
        "1e-10 rad (`fig1_boundaries.nc`: CF-1.10 geometry; `atlas boundaries` for any slice). "
        "Right: vanishing damping moves the SS boundary off Fig. 1's curve (audit claim Z).",
        "",
        "![fig1 boundaries](fig1_boundaries.png)",
        "",
        "## The ladder",
        "",
        "![ladder](ladder.png)",
        "",
        "## Table 2",
        "",
        "![table 2](table2.png)",
        "",
    ]
    if (out / "fig2.png").exists():
        lines += ["## Fig. 2 (simulations)", "", "![fig2](fig2.png)", ""]
        if (out / "fig2.md").exists():
            lines += [(out / "fig2.md").read_text(), ""]
    if (out / "outcome_map.png").exists():
        lines += [
            "## Outcome map (simulated, beside the Fig. 1 theory map)",
            "",
            "[outcome_map.nc](outcome_map.nc): outcome of a perturbed SS equilibrium per "
            "cell (atlas.dynamics.outcome_map) and the certified theory verdicts of the same "
            "cells; outlined: subclasses 132/133/142/143 + duals.",
            "",
            "![outcome map](outcome_map.png)",
            "",
        ]
    if (out / "outcome_distribution.png").exists():
        lines += [
            "## Outcome distribution where the paper predicts no stable mode",
            "",
            "[outcome_distribution.md](outcome_distribution.md): runs per outcome class in the "
            "cells of subclasses 132, 133, 142, 143 (several perturbed SS equilibria per cell).",
            "",
            "![outcome distribution](outcome_distribution.png)",
            "",
        ]
    return lines
