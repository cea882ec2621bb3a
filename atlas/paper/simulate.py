"""``atlas simulate``: one trajectory (a Fig. 2 case or given parameters), or with ``--map`` an
outcome atlas over the axes of ``atlas generate`` (:mod:`atlas.dynamics.outcomes`), written
as CF netCDF or drawn beside the theory map (:mod:`atlas.paper.figures_dynamics`)."""

from __future__ import annotations

import functools
import os
import shlex
import sys
from pathlib import Path

import numpy as np

from atlas.core.config import use_compile_cache
from atlas.data import store_guard
from atlas.data.engine import progress_bar
from atlas.data.io import atomic_write_text, savefig
from atlas.data.scene import parse_values
from atlas.dynamics import Outcome, classify, fig2_cases, outcome_grid, simulate
from atlas.dynamics.lane_pool import check_workers, usable_cores
from atlas.dynamics.outcome_tiles import default_slab, outcome_atlas_tiles
from atlas.dynamics.outcomes import MAX_T_END, Dynamics, outcome_atlas, outcome_scene
from atlas.paper import drawing
from atlas.paper.figures_dynamics import (
    PAPER_SAYS,
    TIME_LABEL,
    draw_trajectory,
    plot_outcome_map,
    write_outcome_map,
)

__all__ = ["run_cli", "map_scene", "map_dynamics", "DEFAULT_MAP_N"]

#: cells per axis of ``atlas simulate --map`` when neither ``--beta1`` nor ``--beta2`` is given
DEFAULT_MAP_N = 24
_AXES = ("beta1", "beta2", "alpha", "kappa", "q", "q1", "q2")


def run_cli(case=None, t_end=None, out=None, outcome_map=False, k1=None, k2=None, argv=None,
            **kw) -> int:  # fmt: skip
    """``atlas simulate``: one trajectory (a Fig. 2 case, optionally overridden), its outcome
    printed; ``--out`` writes a figure (``.png``/``.pdf``/``.svg``) or the events (``.csv``).

    With ``--map``: the outcome atlas of :func:`map_scene` (``--t-end`` default 150,
    ``--n-perturb`` runs per cell, default 1), the outcome counts printed; ``--out`` writes it as
    netCDF (``.nc``) or as the figure beside the Fig. 1 theory map (``.png``/``.pdf``; one
    ``(kappa, q, alpha)``); ``--store DIR`` computes it tile by tile into a resumable store
    (``--resume``, ``--slab N``).  ``--workers N``: processes of the fast engine (default the
    usable cores, 1 with ``--scheduler``; the map does not depend on it)."""
    if outcome_map:
        if case:
            raise ValueError("case: --case and --map exclude each other")
        for name, v in (("k1", k1), ("k2", k2)):
            if v is not None:
                raise ValueError(f"{name}: not an option of --map (its model is --kappa, --q)")
        return _run_map(t_end, out, argv=argv, **kw)
    for name in ("n", "kappa", "q", "n_perturb", "seed", "store", "slab", "resume", "no_theory",
                 "scheduler", "workers"):  # fmt: skip
        if kw.get(name) not in (None, False):
            raise ValueError(f"{name.replace('_', '-')}: only with --map")
    case = case[len("fig2") :] if case and case.startswith("fig2") else case
    angles = {k: _scalar(kw.get(k), k) for k in ("beta1", "beta2", "alpha")}
    p = _case_params(case, angles, t_end, (k1, k2), (_scalar(kw.get("q1"), "q1"),
                                                      _scalar(kw.get("q2"), "q2")))  # fmt: skip
    res = simulate(**p, max_events=100_000)
    outcome = classify(res)
    print(
        f"{case or 'custom'}: {outcome.label}; {res.n_events} events, status {res.status.value}, "
        f"t = {res.t_final:g}"
    )
    if out:
        out = Path(out)
        if out.suffix.lower() == ".csv":
            atomic_write_text(out, _events_csv(res))
        else:
            fig = drawing.new_figure(figsize=(8, 3), constrained_layout=True)
            ax = fig.subplots()
            draw_trajectory(ax, res, p, case or "custom", PAPER_SAYS.get(case, ""), outcome=outcome)
            ax.set_xlabel(TIME_LABEL)
            savefig(fig, out)
        print(f"wrote {out}")
    return 0


def _scalar(spec, name):
    """A single number (``pi`` suffix allowed) or None."""
    if spec is None:
        return None
    vals, is_dim = parse_values(spec, name)
    if is_dim:
        raise ValueError(f"{name}: expected a single number without --map, got {spec!r}")
    return float(vals)


def _case_params(case, angles, t_end, k, q) -> dict:
    """Keyword arguments of :func:`atlas.dynamics.simulate`: a Fig. 2 case (or the default
    physical parameters) with the given values overriding."""
    p = (
        dict(fig2_cases()[case])
        if case
        else {
            "k": (100.0, 200.0),
            "q": (0.0, 0.0),
            "b_norm": (1.0, 1.0),
            "a_norm": 1.0,
            "g0": (0.0, 0.0, 0.0, 0.0),
            "t_end": 10.0,
        }
    )
    if not case and None in angles.values():
        raise ValueError("case: give --case or all of --beta1, --beta2, --alpha")
    if t_end is not None and not 0 < t_end <= MAX_T_END:
        raise ValueError(f"t-end: must be > 0 and <= {MAX_T_END:g}, got {t_end!r}")
    for key, v in (*angles.items(), ("t_end", t_end)):
        if v is not None:
            p[key] = v
    p["k"] = tuple(old if new is None else new for old, new in zip(p["k"], k, strict=True))
    p["q"] = tuple(old if new is None else new for old, new in zip(p["q"], q, strict=True))
    return p


def _events_csv(res) -> str:
    rows = ["t,kind,contact,d1,d2,d1dot,d2dot,mode_after"]
    for t, kind, c, g, m in zip(
        res.t_events, res.kinds, res.contacts, res.states, res.modes, strict=True
    ):
        rows.append(
            ",".join([repr(float(t)), kind, str(int(c))] + [repr(float(x)) for x in g] + [m])
        )
    return "\n".join(rows) + "\n"


def map_scene(n=None, beta1=None, beta2=None, alpha=None, kappa=None, q=None, q1=None, q2=None):
    """The scene of ``atlas simulate --map``: axes in the syntax of ``atlas generate``;
    ``beta1``/``beta2`` not given: :func:`atlas.dynamics.outcome_grid` ``(n)`` (default
    :data:`DEFAULT_MAP_N`), one sample per cell, offset from the degenerate directions; ``kappa``
    default 0.5, ``q`` 0, ``alpha`` :data:`atlas.dynamics.outcomes.DEFAULT_ALPHA`."""
    if n is not None and int(n) < 1:
        raise ValueError(f"n: must be >= 1, got {n}")
    grid = outcome_grid(DEFAULT_MAP_N if n is None else int(n))
    b1 = grid[0] if beta1 is None else beta1
    b2 = grid[1] if beta2 is None else beta2
    return outcome_scene(
        b1, b2, alpha=alpha, kappa=0.5 if kappa is None else kappa, q=q, q1=q1, q2=q2
    )


def scene_options(options: dict) -> dict:
    """The options of :func:`map_scene` among the command's ``options``."""
    return {k: options[k] for k in ("n", *_AXES) if k in options}


def _advance(bar, done, total):
    """A progress callback ``(done, total)`` on a tqdm ``bar``."""
    bar.total = total
    bar.n = done
    bar.refresh()


def map_dynamics(n_perturb=None, seed=None, engine="fast", t_end=None) -> Dynamics:
    """The :class:`~atlas.dynamics.outcomes.Dynamics` of ``atlas simulate --map``."""
    kw = {"engine": engine}
    for name, v in (("n_perturb", n_perturb), ("seed", seed), ("t_end", t_end)):
        if v is not None:
            kw[name] = v
    return Dynamics(**kw)


def _tiles_into(scene, store, **kw) -> dict:
    """:func:`outcome_atlas_tiles`, a failed write into the store (full disk, read-only place)
    said in one line naming the store and how to continue (:func:`store_guard.write_failure`)."""
    try:
        return outcome_atlas_tiles(scene, store, **kw)
    except OSError as e:
        err = store_guard.write_failure(os.path.abspath(store), e)
        if err is None:
            raise
        raise err from None


def _run_map(t_end, out, engine="fast", store=None, resume=False, slab=None, overwrite=False,
             no_theory=False, argv=None, scheduler=None, workers=None, **kw) -> int:  # fmt: skip
    if workers is None:
        workers = 1 if scheduler is not None else usable_cores()
    workers = check_workers(workers)
    scene = map_scene(**scene_options(kw))
    dyn = map_dynamics(kw.get("n_perturb"), kw.get("seed"), engine, t_end)
    suffix = Path(out).suffix.lower() if out else ""
    if out and suffix not in (".nc", ".png", ".pdf"):
        raise ValueError(f"out: expected FILE.nc, FILE.png or FILE.pdf, got {out!r}")
    if suffix in (".png", ".pdf") and len(scene.dims) > 2:
        raise ValueError(
            f"out: a figure shows one (kappa, q, alpha); the map varies {', '.join(scene.dims[2:])}"
            " (write FILE.nc)"
        )
    for name, v in (("resume", resume), ("scheduler", scheduler)):
        if v and store is None:
            raise ValueError(f"{name}: needs --store")
    history = "atlas " + " ".join(shlex.quote(a) for a in argv) if argv else None
    theory = not no_theory or suffix in (".png", ".pdf")
    use_compile_cache()  # the theory kernels and --engine jax's kernel compile once per machine
    bar = progress_bar(sys.stderr.isatty(), 1, "outcome atlas", unit="run")
    try:
        progress = None if bar is None else functools.partial(_advance, bar)
        if store is not None:
            s = _tiles_into(
                scene, store, dynamics=dyn, slab=slab, resume=resume, overwrite=overwrite,
                theory=theory, history=history, scheduler=scheduler, progress=progress,
                workers=workers,
            )  # fmt: skip
            ds = s["dataset"]
            print(
                f"store {s['store']}: {s['tiles']} tiles, {len(s['computed'])} computed, "
                f"{len(s['verified'])} verified",
                file=sys.stderr,
            )
        else:
            slab = default_slab(scene, dyn.n_perturb) if slab is None else slab
            ds = outcome_atlas(
                scene, theory=theory, slab=slab, history=history, progress=progress,
                workers=workers, **dyn.attrs(),
            )  # fmt: skip
    finally:
        if bar is not None:
            bar.close()
    vals, counts = np.unique(ds["outcome"].values, return_counts=True)
    summary = ", ".join(f"{Outcome(int(v)).label} {c}" for v, c in zip(vals, counts, strict=True))
    shape = "x".join(str(ds.sizes[d]) for d in scene.dims)
    print(
        f"outcome map {shape}: {summary}; {ds.attrs['trajectories']} trajectories in "
        f"{ds.attrs['seconds']:.1f} s ({ds.attrs['trajectories_per_second']:.0f}/s, {engine}"
        + (f", {workers} worker{'s' * (workers > 1)})" if engine == "fast" else ")")
    )
    if out:
        if suffix == ".nc":
            write_outcome_map(ds, out, overwrite=overwrite)
        else:
            plot_outcome_map(ds, out)
        print(f"wrote {out}")
    return 0
