"""The steps of ``atlas paper``: :class:`Steps` times them, :func:`say_stderr` reports them,
:func:`side_steps` and the :data:`SHARED` steps are those that need no other step's result.

Light on purpose (no JAX, no xarray, no matplotlib at import; each step imports what it uses):
the second process of a run (:mod:`atlas.paper.side_process`) starts from here, so the calling
run can spawn it before it imports its own steps' modules, and both import at once.
"""

from __future__ import annotations

import os
import shutil
import sys
import tempfile
import time
from pathlib import Path

__all__ = [
    "SHARED",
    "Shared",
    "Steps",
    "dynamics",
    "notes",
    "say_stderr",
    "shared_steps",
    "side_steps",
    "sizes",
    "write_realisability",
]


def say_stderr(msg: str) -> None:
    """The default progress: ``[atlas paper] msg`` on standard error."""
    print(f"[atlas paper] {msg}", file=sys.stderr, flush=True)


class Steps:
    """The steps of :func:`atlas.paper.run.run`: ``step(name, fn)`` announces ``name``, calls
    ``fn`` and records its wall time [s] in ``timings`` (and in the active run log,
    :mod:`atlas.paper.runlog`, with the CPU seconds of its process meanwhile, user + system:
    what a step costs on a loaded machine, where its wall time says little)."""

    def __init__(self, say):
        self.say = say
        self.timings: dict[str, float] = {}

    def __call__(self, name, fn):
        from atlas.paper import runlog

        self.say(f"{name} ...")
        t, cpu = time.perf_counter(), time.process_time()
        res = fn()
        self.timings[name] = time.perf_counter() - t
        runlog.record(f"step {name} seconds", self.timings[name])
        runlog.record(f"step {name} cpu seconds", time.process_time() - cpu)
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


class Shared:
    """The steps either process may run (:data:`SHARED`), each claimed once: ``claim()`` gives
    the index of the next unclaimed one (``len(SHARED)`` and beyond when none is left), so
    whichever process is free first takes the next step and the two halves end together.

    A claim is a file created exclusively (``O_EXCL``) in a private temporary directory: atomic
    between processes, no lock (a lock of a spawned process is a semaphore the interpreter
    reports as leaked at exit).  ``with Shared() as shared:`` removes the directory at the end.
    """

    def __init__(self):
        self.path = tempfile.mkdtemp(prefix="atlas-paper-steps-")
        self._next = 0

    def claim(self) -> int:
        while True:
            i, self._next = self._next, self._next + 1
            try:
                os.close(os.open(os.path.join(self.path, str(i)), os.O_CREAT | os.O_EXCL))
            except FileExistsError:  # the other process took it
                continue
            return i

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        shutil.rmtree(self.path, ignore_errors=True)


def side_steps(step: Steps, out: Path, quick: bool, ci: bool, shared: Shared):
    """The steps that need no other step's result and give one: the boundary curves, then the
    :data:`SHARED` steps ``shared`` leaves.  Returns the curves of Fig. 1's slice."""
    from atlas.paper import figure_boundaries

    # CI: segments within 1e-3 rad of their curve (1e-5 else; half the step's seconds), every
    # vertex still certified within 1e-10 rad
    n, chord = (16, 1e-3) if ci else (32 if quick else 64, 1e-5)
    curves = step(
        "fig1_boundaries.png", lambda: figure_boundaries.write_boundaries(out, n=n, chord=chord)
    )
    shared_steps(step, out, quick, ci, shared)
    return figure_boundaries.slice_of(curves, *figure_boundaries.SLICES[0])


def shared_steps(step: Steps, out: Path, quick: bool, ci: bool, shared: Shared) -> None:
    """The :data:`SHARED` steps left in ``shared``, one at a time until none is left."""
    while (i := shared.claim()) < len(SHARED):
        SHARED[i](step, out, quick, ci)


def notes(quick: bool) -> list[str]:
    """The README notes on Fig. 2 (skipped in quick mode, or not made)."""
    dyn, said = dynamics()
    return said + (["fig2.png skipped in quick mode (simulation)."] if dyn and quick else [])


def _variants(step: Steps, out: Path, quick: bool, ci: bool) -> None:
    """Fig. 1 at other models (:data:`atlas.paper.figures.VARIANTS`)."""
    from atlas.paper import figures, plots

    n_var = sizes(quick, ci)[1]
    maps = step(
        "fig1 variants (compute)",
        lambda: [figures.stability_map(n_var, *v) for v in figures.VARIANTS],
    )
    step(
        "fig1_stability_variants.png",
        lambda: plots.plot_fig1_variants(out / "fig1_stability_variants.png", maps),
    )


def _distribution(step: Steps, out: Path, quick: bool, ci: bool) -> None:
    """The outcome distribution (if :mod:`atlas.paper.figures_dynamics` imports)."""
    dyn, _ = dynamics()
    if dyn is not None:
        n, runs = dyn.PAPER_DISTRIBUTION[not quick]
        step("outcome_distribution.png", lambda: dyn.outcome_distribution_files(out, n, runs))


def _fig2(step: Steps, out: Path, quick: bool, ci: bool) -> None:
    """Fig. 2's simulations (not in quick mode)."""
    dyn, _ = dynamics()
    if dyn is not None and not quick:
        step("fig2.png", lambda: dyn.plot_fig2(out))


def _classes(step: Steps, out: Path, quick: bool, ci: bool) -> None:
    from atlas.paper import plots

    step("fig1_classes.png", lambda: plots.plot_fig1_classes(out / "fig1_classes.png"))


def _ladder(step: Steps, out: Path, quick: bool, ci: bool) -> None:
    from atlas.paper import figure_ladder

    n = 41 if quick else 181
    step("ladder.png", lambda: figure_ladder.write_ladder(out / "ladder.png", n=n))


def write_realisability(path, search) -> None:
    """The 144 single-body realisations ``search`` (:func:`atlas.paper.realisability.search`,
    2^19 bodies: the audit's, :attr:`atlas.paper.audit.Context.realisations`) as Markdown."""
    from atlas.data.io import atomic_write_text
    from atlas.paper import realisability, runlog

    found, stats = search
    for key in ("seconds_search", "seconds_verify"):
        runlog.record(f"realisability {key}", stats[key])
    atomic_write_text(path, realisability.markdown(found, stats))


#: the steps either process may run (each writes its files and gives nothing to another step),
#: the longest first so that the last one claimed is short
SHARED = (_distribution, _variants, _classes, _fig2, _ladder)
