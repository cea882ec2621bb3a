"""The steps of ``atlas paper``: :class:`Steps` times them, :func:`say_stderr` reports them, and
:func:`side_steps` are those that need no other step's result.

Light on purpose (no JAX, no xarray, no matplotlib at import; each step imports what it uses):
the second process of a run (:mod:`atlas.paper.side_process`) starts from here, so the calling
run can spawn it before it imports its own steps' modules, and both import at once.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

__all__ = ["Steps", "dynamics", "say_stderr", "side_steps", "sizes"]


def say_stderr(msg: str) -> None:
    """The default progress: ``[atlas paper] msg`` on standard error."""
    print(f"[atlas paper] {msg}", file=sys.stderr, flush=True)


class Steps:
    """The steps of :func:`atlas.paper.run.run`: ``step(name, fn)`` announces ``name``, calls
    ``fn`` and records its wall time [s] in ``timings`` (and in the active run log,
    :mod:`atlas.paper.runlog`)."""

    def __init__(self, say):
        self.say = say
        self.timings: dict[str, float] = {}

    def __call__(self, name, fn):
        from atlas.paper import runlog

        self.say(f"{name} ...")
        t = time.perf_counter()
        res = fn()
        self.timings[name] = time.perf_counter() - t
        runlog.record(f"step {name} seconds", self.timings[name])
        self.say(f"{name} done in {self.timings[name]:.1f} s")
        return res


def sizes(quick: bool, ci: bool) -> tuple[int, int]:
    """Cells per axis of the Fig. 1 map and of its variants (odd: no cell on beta1 = beta1*)."""
    return (41, 41) if ci else (121, 61) if quick else (361, 201)


def dynamics():
    """:mod:`atlas.paper.figures_dynamics` and no note, or ``None`` and the README note saying
    why it is missing (it is optional here)."""
    try:
        from atlas.paper import figures_dynamics
    except ImportError as e:  # another module of the package; optional here
        return None, [f"fig2.png not made: atlas.paper.figures_dynamics not importable ({e})."]
    return figures_dynamics, []


def side_steps(step: Steps, out: Path, quick: bool, ci: bool):
    """The steps that need no other step's result: Fig. 1 over every model and at other models,
    the boundary curves, Fig. 1's classes, the realisability search, the ladder, Fig. 2 and the
    outcome distribution.  Returns the curves of Fig. 1's slice, the model-dependence shares and
    the README notes."""
    from atlas.paper import figure_boundaries, figure_ladder, figure_models, figures, plots

    n_var = sizes(quick, ci)[1]
    (models,) = step(
        "fig1_models.png",
        lambda: figure_models.plot_model_dependence(
            out / "fig1_models.png",
            n=figure_models.N_MODELS[ci + quick],
            boxes=figure_models.BOXES[:1],
        ),
    )
    maps = step(
        "fig1 variants (compute)",
        lambda: [figures.stability_map(n_var, *v) for v in figures.VARIANTS],
    )
    step(
        "fig1_stability_variants.png",
        lambda: plots.plot_fig1_variants(out / "fig1_stability_variants.png", maps),
    )
    curves = step(
        "fig1_boundaries.png",
        lambda: figure_boundaries.write_boundaries(out, n=16 if ci else 32 if quick else 64),
    )
    step("fig1_classes.png", lambda: plots.plot_fig1_classes(out / "fig1_classes.png"))
    step("realisability.md", lambda: _write_realisability(out / "realisability.md"))
    step(
        "ladder.png", lambda: figure_ladder.write_ladder(out / "ladder.png", n=41 if quick else 181)
    )
    notes = _dynamics_steps(step, out, quick)
    return figure_boundaries.slice_of(curves, *figure_boundaries.SLICES[0]), models, notes


def _dynamics_steps(step: Steps, out: Path, quick: bool) -> list[str]:
    """Fig. 2 (not in quick mode) and the outcome distribution, if
    :mod:`atlas.paper.figures_dynamics` imports; returns the README notes."""
    dyn, notes = dynamics()
    if dyn is not None and quick:
        notes.append("fig2.png skipped in quick mode (simulation).")
    elif dyn is not None:
        step("fig2.png", lambda: dyn.plot_fig2(out))
    if dyn is not None:
        n, runs = dyn.PAPER_DISTRIBUTION[not quick]
        step(
            "outcome_distribution.png",
            lambda: dyn.outcome_distribution_files(out, n, runs),
        )
    return notes


def _write_realisability(path) -> None:
    """The 144 single-body realisations (:mod:`atlas.paper.realisability`) as Markdown."""
    from atlas.data.io import atomic_write_text
    from atlas.paper import realisability, runlog

    found, stats = realisability.search(1 << 19)
    for key in ("seconds_search", "seconds_verify"):
        runlog.record(f"realisability {key}", stats[key])
    atomic_write_text(path, realisability.markdown(found, stats))
