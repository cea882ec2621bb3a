"""Figures of the simulated contact dynamics: the paper's Fig. 2 and the outcome map.

Plots only; the numbers come from :mod:`atlas.dynamics`.  The ``draw_*`` functions draw on a given
``ax`` (or ``fig``) and return the artists; the ``plot_*`` wrappers make a figure and save it.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from atlas.core.verdicts import Consistency, Verdict
from atlas.data.io import atomic_write_text, savefig
from atlas.dynamics import (
    NO_STABLE_SUBCLASSES,
    Outcome,
    classify,
    fig2_cases,
    no_stable_subclass,
    outcome_grid,
    outcome_map,
    simulate,
)
from atlas.paper import drawing, runlog
from atlas.paper.figures import stability_map

__all__ = [
    "FIG2_T_END",
    "PAPER_MAP_N",
    "draw_trajectory",
    "draw_fig2",
    "draw_outcome",
    "draw_theory",
    "draw_outcome_map",
    "fig2_runs",
    "plot_fig2",
    "plot_outcome_map",
    "write_outcome_map",
    "outcome_map_files",
    "subclass_distribution",
    "draw_distribution",
    "outcome_distribution_files",
    "DISTRIBUTION_MODELS",
    "distribution_grid",
    "PAPER_DISTRIBUTION",
]

#: simulated horizon of each Fig. 2 panel (the paper does not state its time axes) [time]
FIG2_T_END = {"a": 400.0, "b": 20.0, "c": 400.0, "d": 40.0, "e": 100.0}

PAPER_SAYS = {
    "a": "paper: inverse chattering (growing)",
    "b": "paper: SS stable, settles",
    "c": "paper: inverse chattering (growing)",
    "d": "caption: sustained small oscillation; text: growing, simultaneous impacts",
    "e": "caption: growing, simultaneous impacts; text: sustained micro-oscillation",
}
TIME_LABEL = "time [rescaled, paper eq. 6]"


# --------------------------------------------------------------------------- Fig. 2


def draw_trajectory(ax, res, p, name, note="", n_samples=6000, outcome=None) -> list:
    """Gaps ``d1(t)``, ``d2(t)`` of one simulation ``res`` (parameters ``p``) on ``ax``, titled
    ``(name) angles``, with its outcome (:func:`atlas.dynamics.classify` unless given) and
    ``note`` written on it.  Returns the artists drawn."""
    outcome = classify(res) if outcome is None else outcome
    t = np.union1d(np.linspace(0.0, res.t_final, n_samples), res.t_events)
    g = res.sample(t)
    art = ax.plot(t, g[:, 0], lw=0.7, label=r"$d_1$")
    art += ax.plot(t, g[:, 1], lw=0.7, label=r"$d_2$")
    art.append(ax.axhline(0.0, color="k", lw=0.4))
    ax.set_ylabel("gap [1]")
    art.append(
        ax.set_title(
            f"({name}) beta1={p['beta1'] / math.pi:.2f}pi, beta2={p['beta2'] / math.pi:.2f}pi, "
            f"alpha={p['alpha'] / math.pi:.2f}pi, q={p['q'][0]:g}",
            fontsize=9,
        )
    )
    text = f"simulated: {outcome.label} ({res.n_events} events, {res.status.value})"
    art.append(
        ax.text(
            0.01,
            0.97,
            text + (f"\n{note}" if note else ""),
            transform=ax.transAxes,
            va="top",
            fontsize=8,
            bbox={"facecolor": "white", "alpha": 0.8, "lw": 0},
        )
    )
    art.append(ax.legend(loc="upper right", fontsize=8))
    return art


def fig2_runs(t_end: dict | None = None) -> dict:
    """The simulations of Fig. 2: ``{panel: (parameters, SimulationResult, Outcome)}`` over the
    horizons ``t_end`` (default :data:`FIG2_T_END`) [time]."""
    horizons = dict(FIG2_T_END, **(t_end or {}))
    runs = {}
    for name, p in fig2_cases().items():
        p = dict(p, t_end=horizons[name])
        res = simulate(**p, max_events=100_000)
        runs[name] = (p, res, classify(res))
    return runs


def draw_fig2(fig, runs: dict, n_samples: int = 6000) -> list:
    """Fig. 2 (panels a-e, one per row) on ``fig`` from :func:`fig2_runs`."""
    axes = fig.subplots(len(runs), 1, squeeze=False)[:, 0]
    art = []
    for ax, (name, (p, res, outcome)) in zip(axes, runs.items(), strict=True):
        art += draw_trajectory(ax, res, p, name, PAPER_SAYS[name], n_samples, outcome)
    axes[-1].set_xlabel(TIME_LABEL)
    return art


def _fig2_table(runs) -> str:
    rows = [
        "| panel | beta1, beta2, alpha | k; q (physical) | simulated (horizon) | the paper says |",
        "|---|---|---|---|---|",
    ]
    for name, (p, res, outcome) in runs.items():
        ang = ", ".join(f"{p[k] / math.pi:.2f} pi" for k in ("beta1", "beta2", "alpha"))
        rows.append(
            f"| {name} | {ang} | {p['k'][0]:g}, {p['k'][1]:g}; {p['q'][0]:g}, {p['q'][1]:g} "
            f"| **{outcome.label}** "
            f"(t <= {p['t_end']:g}, {res.n_events} events) | {PAPER_SAYS[name]} |"
        )
    return (
        "Fig. 2, simulated outcome per panel (`atlas.paper.figures_dynamics.plot_fig2`; the "
        "caption and the text of Sec. 6.4-6.5 disagree on panels d and e: the simulation "
        "decides).\n\n" + "\n".join(rows) + "\n"
    )


def plot_fig2(outdir, t_end: dict | None = None, n_samples: int = 6000) -> list:
    """Regenerate the paper's Fig. 2 (panels a-e): gaps ``d1(t)``, ``d2(t)`` of eq. (1), (6).

    Parameters
    ----------
    outdir : path-like
        Output directory (created if missing).
    t_end : dict, optional
        Horizon per panel, default :data:`FIG2_T_END` [time].
    n_samples : int
        Samples of the exact dense output per panel (event times are added).

    Returns
    -------
    list of pathlib.Path
        ``[outdir / "fig2.png"]``; ``outdir / "fig2.md"`` (the outcomes beside what the paper
        says) is written too.
    """
    outdir = Path(outdir)
    outdir.mkdir(parents=True, exist_ok=True)
    runs = fig2_runs(t_end)
    fig = drawing.new_figure(figsize=(8, 13), constrained_layout=True)
    draw_fig2(fig, runs, n_samples)
    path = outdir / "fig2.png"
    savefig(fig, path)
    atomic_write_text(outdir / "fig2.md", _fig2_table(runs))
    return [path]


# --------------------------------------------------------------------------- outcome map


#: grid of the outcome map in ``atlas paper`` (quick mode, full) [cells per axis]
PAPER_MAP_N = (6, 256)


def write_outcome_map(ds, path, overwrite: bool = True) -> str:
    """Write an outcome atlas (:mod:`atlas.dynamics.outcomes`, CF attributes included) to
    netCDF4 through :func:`atlas.data.io.write_netcdf` (temporary file + ``os.replace``; no
    ``_FillValue`` on the int8 flags or the coordinates)."""
    from atlas.data.io import write_netcdf

    return write_netcdf(ds, path, overwrite=overwrite)


def draw_theory(ax, theory) -> list:
    """The Fig. 1 theory map (certified kernels, :func:`atlas.paper.figures.stability_map`) on
    ``ax``: SS stability as in Fig. 1, orange where SS is unstable and no impact without collision
    is stable (IF, FI consistent; II stable), the Fig. 1 overview layer, the dashed SS boundary and
    the class boundaries.  Returns the artists drawn."""
    from matplotlib.colors import ListedColormap

    n = theory.sizes["beta1"]
    ss = theory["stable_SS"].values
    iwc = (
        np.broadcast_to(theory["consistent_IF"].values[:, None], (n, n))
        | np.broadcast_to(theory["consistent_FI"].values[None, :], (n, n))
        | (
            (theory["consistent_II"].values == Consistency.CONSISTENT)
            & (theory["stable_II"].values == Verdict.STABLE)
        )
    )
    nothing = (ss != Verdict.STABLE) & (ss != Verdict.NEUTRAL) & ~iwc
    art = [drawing.categorical(ax, theory, ss, Verdict)]
    edges = np.linspace(0, 2 * np.pi, n + 1)
    art.append(
        ax.pcolormesh(
            edges,
            edges,
            np.ma.masked_where(~nothing, np.ones((n, n))).T,
            cmap=ListedColormap([drawing.NOTHING_COLOR]),
            rasterized=True,
        )
    )
    if "margin_SS" in theory:
        art.append(drawing.dashed(ax, theory, "margin_SS", where=drawing.ss_boundary_cells(theory)))
    art += drawing.class_lines(ax)
    return [a for a in art if a is not None]


def _theory_legend(ax, theory):
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    ss_codes = set(np.unique(theory["stable_SS"].values).tolist())
    h1 = drawing.legend_patches(Verdict, ss_codes, {Verdict.NEUTRAL: "SS neutral (q = 0)"})
    h1 = [Patch(facecolor=p.get_facecolor(), label=p.get_label()) for p in h1]
    for p in h1:
        if not p.get_label().startswith("SS"):
            p.set_label("SS " + p.get_label())
    h1.append(Patch(color=drawing.NOTHING_COLOR, label="SS unstable, no stable IWC"))
    h1.append(Line2D([], [], color="k", lw=1.1, ls="--", label="SS boundary (smooth margin)"))
    return ax.legend(
        handles=h1, loc="upper center", bbox_to_anchor=(0.5, -0.09), ncol=2, fontsize=8
    )


def draw_outcome(ax, ds) -> list:
    """The simulated outcome per cell of an :func:`atlas.dynamics.outcome_map` dataset on ``ax``
    (:class:`atlas.dynamics.Outcome` colours, ``pcolormesh`` + ``ListedColormap`` +
    ``BoundaryNorm``) and the class boundaries.  Returns the artists drawn."""
    from matplotlib.colors import BoundaryNorm, ListedColormap

    codes = [int(m) for m in Outcome]
    cmap = ListedColormap([Outcome(c).color for c in codes])
    norm = BoundaryNorm(np.arange(min(codes) - 0.5, max(codes) + 1.5), cmap.N)
    n1, n2 = ds.sizes["beta1"], ds.sizes["beta2"]
    mesh = ax.pcolormesh(
        np.linspace(0, 2 * np.pi, n1 + 1),
        np.linspace(0, 2 * np.pi, n2 + 1),
        ds["outcome"].values.T,
        cmap=cmap,
        norm=norm,
        rasterized=True,
    )
    return [mesh] + drawing.class_lines(ax)


def _outcome_legend(ax, ds):
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    present = sorted(set(np.unique(ds["outcome"].values).tolist()))
    h0 = [Patch(color=Outcome(c).color, label=Outcome(c).label) for c in present]
    h0.append(Line2D([], [], color="k", lw=1.6, label="subclasses 132/133/142/143 + duals"))
    return ax.legend(
        handles=h0, loc="upper center", bbox_to_anchor=(0.5, -0.09), ncol=3, fontsize=8
    )


def draw_no_stable_outline(ax, alpha, n_outline: int = 600) -> list:
    """Solid black outline of subclasses 132, 133, 142, 143 and their duals at ``alpha`` [rad]
    (paper Sec. 6.4-6.5; :func:`atlas.dynamics.no_stable_subclass` on an ``n_outline`` grid),
    with the ``pi`` axes and labels.  Returns the artists drawn."""
    f = (np.arange(n_outline) + 0.5) * (2 * np.pi / n_outline)
    F1, F2 = np.meshgrid(f, f, indexing="ij")
    region = no_stable_subclass(F1, F2, np.full(F1.shape, alpha)).astype(float)
    art = []
    if region.any():
        art.append(ax.contour(f, f, region.T, levels=[0.5], colors="k", linewidths=1.6, zorder=8))
    drawing.pi_axis(ax)
    art += [ax.set_xlabel(r"$\beta_1$"), ax.set_ylabel(r"$\beta_2$")]
    return art


def _check_theory(ds, theory):
    """The theory map of the outcome map's ``(kappa, q1, q2)`` (computed at 121^2 if None)."""
    kappa, q1, q2 = (float(ds.attrs[k]) for k in ("kappa", "q1", "q2"))
    if theory is None:
        return stability_map(121, kappa, q1, q2)
    if not all(
        math.isclose(float(theory[k]), v) for k, v in (("kappa", kappa), ("q1", q1), ("q2", q2))
    ):
        raise ValueError("theory: (kappa, q1, q2) differ from the outcome map's")
    return theory


def draw_outcome_map(fig, ds, theory=None, n_outline: int = 600) -> list:
    """Outcome map beside the Fig. 1 theory map of the same ``(kappa, q)`` on ``fig``.

    Left: :func:`draw_outcome`, one sample per cell of the uniform grid of ``[0, 2 pi)^2``.
    Right: :func:`draw_theory` of ``theory`` (an :func:`atlas.paper.figures.stability_map`
    dataset; computed at 121 x 121 if not given).  Both: :func:`draw_no_stable_outline` at the
    map's ``alpha``.  Returns the artists drawn.
    """
    kappa, q1, q2 = (float(ds.attrs[k]) for k in ("kappa", "q1", "q2"))
    alpha = float(ds.attrs["alpha"])
    theory = _check_theory(ds, theory)
    ax0, ax1 = fig.subplots(1, 2)
    art = draw_outcome(ax0, ds) + draw_theory(ax1, theory)
    for ax in (ax0, ax1):
        art += draw_no_stable_outline(ax, alpha, n_outline)
    art += [_outcome_legend(ax0, ds), _theory_legend(ax1, theory)]
    n1, n2 = ds.sizes["beta1"], ds.sizes["beta2"]
    und = int((ds["outcome"].values == int(Outcome.UNDETERMINED)).sum())
    art.append(
        ax0.set_title(
            f"simulated ({n1}x{n2} cells, {ds.attrs['n_perturb']} run(s) each, t <= "
            f"{ds.attrs['t_end']:g} x up to {ds.attrs.get('horizon_cap', 1):g}; "
            f"{und} undetermined)",
            fontsize=9,
        )
    )
    art.append(
        ax1.set_title(
            f"theory (Fig. 1, certified kernels, {theory.sizes['beta1']}$^2$ cells)", fontsize=9
        )
    )
    art.append(
        fig.suptitle(
            f"Outcome of a perturbed SS equilibrium vs theory: kappa = {kappa:g}, q = ({q1:g}, "
            f"{q2:g}), alpha = {alpha / math.pi:.3g} pi",
            fontsize=10,
        )
    )
    fig.subplots_adjust(left=0.06, right=0.98, top=0.9, bottom=0.22, wspace=0.2)
    return art


def plot_outcome_map(ds, path, theory=None, n_outline: int = 600) -> Path:
    """Write the outcome map beside the theory map (:func:`draw_outcome_map`) to ``path``.

    Returns
    -------
    pathlib.Path
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig = drawing.new_figure(figsize=(13.5, 6.8))
    draw_outcome_map(fig, ds, theory, n_outline)
    savefig(fig, path)
    return path


def outcome_map_files(out, n: int = 24, theory=None, **kwargs) -> list:
    """Compute an outcome map on :func:`atlas.dynamics.outcome_grid` ``(n)`` and write
    ``out/outcome_map.nc`` and ``out/outcome_map.png`` (beside ``theory``, see
    :func:`plot_outcome_map`; the netCDF holds the theory verdicts of the same cells too).
    ``kwargs`` go to :func:`atlas.dynamics.outcome_map`.  The netCDF holds no date or seconds
    (:func:`atlas.paper.runlog.fixed`)."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    b1, b2 = outcome_grid(n)
    ds = outcome_map(b1, b2, **{"theory": True, **kwargs})
    nc = Path(write_outcome_map(runlog.fixed(ds, "outcome_map.nc"), out / "outcome_map.nc"))
    png = plot_outcome_map(ds, out / "outcome_map.png", theory=theory)
    return [nc, png]


# --------------------------------------------------------------------------- outcome distribution

#: the model of each row of the outcome-distribution figure: Fig. 2 a-c and d-e (k = (100, 200),
#: |b| = 1: kappa = 0.5; q_hat = 20 / sqrt(200) for d-e; alpha as in the caption; subclasses 132,
#: 142), and alpha = 0.65 pi, where subclasses 133 and 143 lie
DISTRIBUTION_MODELS = (
    {"label": "Fig. 2 a-c", "kappa": 0.5, "q": 0.0, "alpha": 0.35 * math.pi},
    {"label": "Fig. 2 d-e", "kappa": 0.5, "q": 20.0 / math.sqrt(200.0), "alpha": 0.2 * math.pi},
    {"label": "alpha 0.65 pi", "kappa": 0.5, "q": 0.0, "alpha": 0.65 * math.pi},
)
#: grid (``m`` of :func:`distribution_grid`) and runs per cell of the outcome distribution in
#: ``atlas paper`` (quick mode, full)
PAPER_DISTRIBUTION = ((4, 4), (12, 12))


def distribution_grid(m: int) -> tuple[np.ndarray, np.ndarray]:
    """``beta1 = (i + 1/3) (pi/2) / m``, ``beta2 = pi/2 + (j + 2/3) (pi/2) / m`` [rad], ``i < m``,
    ``j < 2 m``: the box ``(0, pi/2) x (pi/2, 3 pi/2)`` that holds subclasses 132, 133, 142, 143
    (not their duals), offset from the degenerate directions like
    :func:`atlas.dynamics.outcome_grid`."""
    step = 0.5 * math.pi / int(m)
    return (np.arange(m) + 1 / 3) * step, 0.5 * math.pi + (np.arange(2 * m) + 2 / 3) * step


def subclass_distribution(ds) -> dict:
    """Runs per outcome class summed over the cells of each subclass 132, 133, 142, 143 of an
    outcome atlas with theory verdicts (one ``(kappa, q, alpha)``), split by the certified SS
    verdict of the cell: ``{(code, ss): (cells, mixed cells, counts per class)}`` for the groups
    present, ``ss`` = ``"SS stable"`` (stable or neutral) or ``"SS unstable"`` (unstable or SS
    inconsistent); *mixed*: the runs of the cell disagree."""
    code = ds["subclass_code"].values
    counts = ds["outcome_count"].values
    mixed = ds["agreement"].values < 1
    ss = np.isin(ds["stable_SS"].values, (Verdict.STABLE, Verdict.NEUTRAL))
    ss &= ds["consistent_SS"].values
    out = {}
    for c in NO_STABLE_SUBCLASSES:
        for name, flag in (("SS stable", True), ("SS unstable", False)):
            sel = (code == c) & (ss == flag)
            if sel.any():
                out[(c, name)] = (int(sel.sum()), int(mixed[sel].sum()), counts[sel].sum(axis=0))
    return out


def draw_distribution(ax, ds, title: str) -> list:
    """Stacked bars of :func:`subclass_distribution`: fraction of the runs per outcome class in
    each subclass without a stable mode (split by the theory's SS verdict), with the cells, runs
    and mixed cells written beside them."""
    dist = subclass_distribution(ds)
    art = []
    for y, (cells, mixed, counts) in enumerate(dist.values()):
        frac = counts / max(1, counts.sum())
        left = 0.0
        for o, f in zip(Outcome, frac, strict=True):
            if f > 0:
                art += ax.barh(y, f, left=left, color=o.color, edgecolor="k", lw=0.3).patches
                left += f
        text = f"{cells} cells, {int(counts.sum())} runs; {mixed} mixed"
        art.append(ax.text(1.01, y, text, va="center", fontsize=7))
    ax.set_yticks(range(len(dist)), [f"{c}, theory: {ss}" for c, ss in dist])
    ax.set_ylim(len(dist) - 0.5, -0.5)
    ax.set_xlim(0, 1)
    ax.set_xlabel("fraction of the perturbed runs")
    art.append(ax.set_title(title, fontsize=9))
    return art


def outcome_distribution_files(out, m: int = 16, n_perturb: int = 16, models=None) -> list:
    """The outcome distribution where the paper predicts no stable mode (Sec. 6.4-6.5): an
    outcome atlas with theory verdicts on :func:`distribution_grid` ``(m)`` with
    ``n_perturb`` runs per cell for each model of ``models`` (default
    :data:`DISTRIBUTION_MODELS`), summed per subclass 132, 133, 142, 143
    (:func:`subclass_distribution`).  Writes ``out/outcome_distribution.png`` and
    ``out/outcome_distribution.md`` (the counts)."""
    from matplotlib.patches import Patch

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    models = DISTRIBUTION_MODELS if models is None else models
    b1, b2 = distribution_grid(m)
    fig = drawing.new_figure(figsize=(10, 1.2 + 1.9 * len(models)), constrained_layout=True)
    axes = fig.subplots(len(models), 1, squeeze=False)[:, 0]
    rows = [
        "| model | subclass | theory | cells | cells mixed | runs | "
        + " | ".join(o.label for o in Outcome)
        + " |",
        "|---|---|---|---|---|---|" + "---|" * len(Outcome),
    ]
    for ax, p in zip(axes, models, strict=True):
        ds = outcome_map(b1, b2, p["kappa"], p["q"], p["alpha"], n_perturb=n_perturb, theory=True)
        title = (
            f"{p['label']}: kappa = {p['kappa']:g}, q = {p['q']:.4g}, alpha = "
            f"{p['alpha'] / math.pi:.3g} pi ({b1.size} x {b2.size} cells, {n_perturb} runs each)"
        )
        draw_distribution(ax, ds, title)
        for (c, ss), (cells, mixed, counts) in subclass_distribution(ds).items():
            rows.append(
                f"| {p['label']} | {c} | {ss} | {cells} | {mixed} | {int(counts.sum())} | "
                + " | ".join(str(int(x)) for x in counts)
                + " |"
            )
    fig.legend(
        handles=[Patch(color=o.color, label=o.label) for o in Outcome],
        loc="outside lower center",
        ncol=4,
        fontsize=8,
    )
    png = out / "outcome_distribution.png"
    savefig(fig, png)
    md = out / "outcome_distribution.md"
    atomic_write_text(
        md,
        "Outcome distribution in the subclasses without a stable mode (paper Sec. 6.4-6.5): "
        f"runs per outcome class summed over the cells of each subclass, {b1.size} x {b2.size} "
        f"offset grid of (0, pi/2) x (pi/2, 3 pi/2), {n_perturb} perturbed SS equilibria per cell "
        "(`atlas.paper.figures_dynamics.outcome_distribution_files`). *theory*: the certified SS "
        "verdict of the cell (stable: stable or neutral and SS consistent); *cells mixed*: cells "
        "whose runs do not all agree.\n\n" + "\n".join(rows) + "\n",
    )
    return [png, md]
