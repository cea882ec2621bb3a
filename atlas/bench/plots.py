"""The figures of ``bench.md``: work-precision, convergence in h, scaling, simulation error.

Each ``plot_*`` draws from the rows of one section and writes ``OUT/bench_*.png`` (atomically).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from atlas.bench.config import METHODS
from atlas.data.io import savefig

__all__ = [
    "NAMES",
    "plot_all",
    "plot_convergence",
    "plot_scaling",
    "plot_simulation",
    "plot_work_precision",
]

#: the figures of a run (``bench_<name>.png``)
NAMES = ("work_precision", "convergence", "scaling", "simulation")
_COLORS = {"certified": "C0", "certified+exact": "C1", "verdicts_jit": "C2", "eig": "C3"}
_MARKS = {"float32": "s", "float64": "o"}
_DPI = 110


def _subplots(*args, figsize, **kwargs):
    """``plt.subplots`` without pyplot (no backend selection, no global state, nothing to close)."""
    fig = Figure(figsize=figsize)
    return fig, fig.subplots(*args, **kwargs)


def _save(fig, out, name) -> Path:
    fig.tight_layout()
    path = Path(out) / name
    savefig(fig, path, dpi=_DPI)
    return path


def _series(rows, case, method, dtype):
    """The all-verdict rows of one (case, method, dtype), coarse to fine."""
    return sorted(
        (
            r
            for r in rows
            if (r["outputs"], r["case"], r["method"], r["dtype"]) == ("all", case, method, dtype)
        ),
        key=lambda r: r["n"],
    )


def _work_precision_panel(ax, wp, case, col, with_margin):
    for m in METHODS:
        for dt in ("float32", "float64"):
            rs = _series(wp, case, m, dt)
            if rs:
                ax.loglog(
                    [r["seconds"] for r in rs],
                    [r[col] for r in rs],
                    marker=_MARKS[dt],
                    color=_COLORS[m],
                    ls="-" if dt == "float64" else ":",
                    label=f"{m} {dt} (0/1 mask)",
                )
    if with_margin:
        for dt in ("float32", "float64"):
            rs = _series(wp, case, "certified", dt)
            if not rs:
                continue
            ax.loglog(
                [r["seconds"] for r in rs],
                [r["hausdorff_SS_margin"] for r in rs],
                marker=_MARKS[dt],
                color="k",
                ls="--",
                label=f"certified {dt} (smooth margin)",
            )
    ax.set_xlabel("time per grid [s]")
    ax.set_ylabel("Hausdorff distance [rad]")
    ax.grid(True, which="both", alpha=0.3)


def plot_work_precision(out, wp, cases) -> Path:
    """Boundary error (Hausdorff distance [rad]) against time per grid, SS and II, per case."""
    fig, axes = _subplots(2, len(cases), figsize=(4.2 * len(cases), 7.5), squeeze=False)
    for j, case in enumerate(cases):
        for i, (col, lab) in enumerate(
            (("hausdorff_SS_mask", "SS boundary"), ("hausdorff_II_mask", "II boundary"))
        ):
            _work_precision_panel(axes[i, j], wp, case, col, with_margin=i == 0)
            axes[i, j].set_title(f"{case}: {lab}")
    axes[0, 0].legend(fontsize=6)
    return _save(fig, out, "bench_work_precision.png")


def plot_convergence(out, wp, cases) -> Path:
    """Boundary error against grid spacing h (float64, certified+exact), with h/2 and h^2."""
    fig, axes = _subplots(1, len(cases), figsize=(4.2 * len(cases), 3.8), squeeze=False)
    for j, case in enumerate(cases):
        ax = axes[0, j]
        rs = _series(wp, case, "certified+exact", "float64")
        h = np.array([r["h"] for r in rs])
        for col, lab, st in (
            ("hausdorff_SS_margin", "SS, smooth-margin contour", "k-o"),
            ("hausdorff_SS_mask", "SS, 0/1 mask contour", "C0-s"),
            ("hausdorff_II_mask", "II, 0/1 mask contour", "C1-^"),
        ):
            ax.loglog(h, [r[col] for r in rs], st, label=lab)
        if len(h):
            ax.loglog(h, h / 2, "C7:", label="h/2")
            ax.loglog(h, h**2, "C7--", label="h^2")
        ax.set_title(f"{case} (float64, certified+exact)")
        ax.set_xlabel("grid spacing h [rad]")
        ax.set_ylabel("Hausdorff distance [rad]")
        ax.grid(True, which="both", alpha=0.3)
    axes[0, 0].legend(fontsize=7)
    return _save(fig, out, "bench_convergence.png")


def plot_scaling(out, scaling) -> Path:
    """Time [s] and peak RSS [MB] against atlas points, per driver and q."""
    fig, (a1, a2) = _subplots(1, 2, figsize=(9, 3.8))
    for q in sorted({r["q"] for r in scaling}):
        for drv in sorted({r["driver"] for r in scaling}):
            rs = [r for r in scaling if r["q"] == q and r["driver"] == drv]
            if not rs:
                continue
            lab = f"{drv}, q={q}"
            a1.loglog([r["points"] for r in rs], [r["seconds"] for r in rs], "o-", label=lab)
            a2.semilogx([r["points"] for r in rs], [r["peak_rss_mb"] for r in rs], "o-", label=lab)
    a1.set_xlabel("atlas points")
    a1.set_ylabel("time [s]")
    a2.set_xlabel("atlas points")
    a2.set_ylabel("peak RSS [MB]")
    a2.set_ylim(bottom=0)
    for a in (a1, a2):
        a.grid(True, which="both", alpha=0.3)
        a.legend(fontsize=7)
    return _save(fig, out, "bench_scaling.png")


def plot_simulation(out, sim) -> Path:
    """Max event-time error against time per run, per method (cases annotated)."""
    fig, ax = _subplots(figsize=(6, 4.2))
    for k, m in enumerate(sorted({r["method"] for r in sim})):
        rs = [r for r in sim if r["method"] == m and np.isfinite(r["error"]) and r["error"] > 0]
        ax.loglog([r["seconds"] for r in rs], [r["error"] for r in rs], "os^v"[k % 4], label=m)
        for r in rs:
            ax.annotate(r["case"], (r["seconds"], r["error"]), fontsize=6)
    ax.set_xlabel("time per run [s]")
    ax.set_ylabel("max event-time error")
    ax.set_title("Fig. 2 cases: event-time error against cost")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7)
    return _save(fig, out, "bench_simulation.png")


def plot_all(out, wp, scaling, sim, cfg) -> list[Path]:
    """The four figures of the report; their paths."""
    cases = [c[0] for c in cfg["cases"]]
    return [
        plot_work_precision(out, wp, cases),
        plot_convergence(out, wp, cases),
        plot_scaling(out, scaling),
        plot_simulation(out, sim),
    ]
