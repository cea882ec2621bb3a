"""Figures of the simulated contact dynamics: the paper's Fig. 2 and the outcome map.

Plots only; the numbers come from :mod:`atlas.dynamics`.
"""

from __future__ import annotations

import math
import os
from pathlib import Path

import numpy as np

from .dynamics import Outcome, classify, fig2_cases, in_no_stable_subclass, simulate

__all__ = ["FIG2_T_END", "plot_fig2", "plot_outcome_map"]

#: simulated horizon of each Fig. 2 panel (the paper does not state its time axes) [time]
FIG2_T_END = {"a": 400.0, "b": 20.0, "c": 400.0, "d": 40.0, "e": 100.0}

_PAPER_SAYS = {
    "a": "paper: inverse chattering (growing)",
    "b": "paper: SS stable, settles",
    "c": "paper: inverse chattering (growing)",
    "d": "caption: sustained small oscillation; text: growing, simultaneous impacts",
    "e": "caption: growing, simultaneous impacts; text: sustained micro-oscillation",
}


def _atomic_savefig(fig, path: Path) -> None:
    tmp = path.with_name(path.name + ".tmp.png")
    fig.savefig(tmp, dpi=120)
    os.replace(tmp, path)


def _plot_trajectory(ax, res, p, name, note, n_samples=6000):
    """Gaps ``d1(t)``, ``d2(t)`` of one simulation on ``ax``, with its outcome written on it."""
    outcome = classify(res)
    t = np.union1d(np.linspace(0.0, res.t_final, n_samples), res.t_events)
    g = res.sample(t)
    ax.plot(t, g[:, 0], lw=0.7, label=r"$d_1$")
    ax.plot(t, g[:, 1], lw=0.7, label=r"$d_2$")
    ax.axhline(0.0, color="k", lw=0.4)
    ax.set_ylabel("gap [1]")
    ax.set_title(
        f"({name}) beta1={p['beta1'] / math.pi:.2f}pi, beta2={p['beta2'] / math.pi:.2f}pi, "
        f"alpha={p['alpha'] / math.pi:.2f}pi, q={p['q'][0]:g}",
        fontsize=9,
    )
    text = f"simulated: {outcome.label} ({res.n_events} events, {res.status.value})"
    ax.text(
        0.01,
        0.97,
        text + (f"\n{note}" if note else ""),
        transform=ax.transAxes,
        va="top",
        fontsize=8,
        bbox={"facecolor": "white", "alpha": 0.8, "lw": 0},
    )
    ax.legend(loc="upper right", fontsize=8)
    return outcome


def run_cli(
    case=None,
    beta1=None,
    beta2=None,
    alpha=None,
    k1=None,
    k2=None,
    q1=None,
    q2=None,
    t_end=None,
    out=None,
    **_,
) -> int:
    """``atlas simulate``: one trajectory (a Fig. 2 case, optionally overridden), its outcome
    printed; ``--out`` writes a figure (``.png``/``.pdf``) or the events (``.csv``)."""
    case = case[len("fig2") :] if case and case.startswith("fig2") else case
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
    if not case and None in (beta1, beta2, alpha):
        raise ValueError("case: give --case or all of --beta1, --beta2, --alpha")
    for key, v in (("beta1", beta1), ("beta2", beta2), ("alpha", alpha), ("t_end", t_end)):
        if v is not None:
            p[key] = v
    k = list(p["k"])
    q = list(p["q"])
    for i, v in ((0, k1), (1, k2)):
        if v is not None:
            k[i] = v
    for i, v in ((0, q1), (1, q2)):
        if v is not None:
            q[i] = v
    p["k"], p["q"] = tuple(k), tuple(q)
    res = simulate(**p, max_events=100_000)
    outcome = classify(res)
    print(
        f"{case or 'custom'}: {outcome.label}; {res.n_events} events, status {res.status.value}, "
        f"t = {res.t_final:g}"
    )
    if out:
        out = Path(out)
        if out.suffix.lower() == ".csv":
            rows = ["t,kind,contact,d1,d2,d1dot,d2dot,mode_after"]
            for t, kind, c, g, m in zip(
                res.t_events, res.kinds, res.contacts, res.states, res.modes, strict=True
            ):
                rows.append(
                    ",".join(
                        [repr(float(t)), kind, str(int(c))] + [repr(float(x)) for x in g] + [m]
                    )
                )
            from .io import atomic_write_text

            atomic_write_text(out, "\n".join(rows) + "\n")
        else:
            import matplotlib

            matplotlib.use("Agg")
            import matplotlib.pyplot as plt

            fig, ax = plt.subplots(figsize=(8, 3), constrained_layout=True)
            _plot_trajectory(ax, res, p, case or "custom", _PAPER_SAYS.get(case, ""))
            ax.set_xlabel("time [rescaled, paper eq. 6]")
            _atomic_savefig(fig, out)
            plt.close(fig)
        print(f"wrote {out}")
    return 0


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
        ``[outdir / "fig2.png"]``.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    horizons = dict(FIG2_T_END, **(t_end or {}))
    outdir = Path(outdir)
    outdir.mkdir(parents=True, exist_ok=True)
    fig, axes = plt.subplots(5, 1, figsize=(8, 13), constrained_layout=True)
    for ax, (name, p) in zip(axes, fig2_cases().items(), strict=True):
        p = dict(p, t_end=horizons[name])
        res = simulate(**p, max_events=100_000)
        _plot_trajectory(ax, res, p, name, _PAPER_SAYS[name], n_samples)
    axes[-1].set_xlabel("time [rescaled, paper eq. 6]")
    path = outdir / "fig2.png"
    _atomic_savefig(fig, path)
    plt.close(fig)
    return [path]


def plot_outcome_map(ds, path) -> Path:
    """Plot an :func:`atlas.dynamics.outcome_map` dataset.

    Categories via ``pcolormesh`` + ``ListedColormap`` + ``BoundaryNorm`` from :class:`Outcome`;
    solid outline: subclasses 132, 133, 142, 143 and duals (drawn on a fine grid of the exact
    subclass test); dashed: zero level of the SS spectral abscissa (smooth margin; eig-based).

    Returns
    -------
    pathlib.Path
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import BoundaryNorm, ListedColormap
    from matplotlib.patches import Patch

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    codes = [int(m) for m in Outcome]
    cmap = ListedColormap([Outcome(c).color for c in codes])
    norm = BoundaryNorm(np.arange(min(codes) - 0.5, max(codes) + 1.5), cmap.N)
    b1 = ds["beta1"].values
    b2 = ds["beta2"].values
    fig, ax = plt.subplots(figsize=(7.5, 6), constrained_layout=True)
    ax.pcolormesh(
        b1 / math.pi, b2 / math.pi, ds["outcome"].values.T, cmap=cmap, norm=norm, shading="nearest"
    )
    alpha = float(ds.attrs["alpha"])
    f1 = np.linspace(b1.min(), b1.max(), 300)
    f2 = np.linspace(b2.min(), b2.max(), 300)
    region = np.array([[in_no_stable_subclass(x, y, alpha) for x in f1] for y in f2], float)
    if region.any() and not region.all():
        ax.contour(f1 / math.pi, f2 / math.pi, region, levels=[0.5], colors="k", linewidths=1.2)
    absc = ds["ss_spectral_abscissa"].values.T
    level = 1e-6 * max(1.0, float(np.nanmax(np.abs(absc))))
    if np.nanmin(absc) < level < np.nanmax(absc):
        ax.contour(
            b1 / math.pi,
            b2 / math.pi,
            absc,
            levels=[level],
            colors="k",
            linestyles="--",
            linewidths=0.8,
        )
    present = sorted(set(np.unique(ds["outcome"].values).tolist()))
    handles = [Patch(color=Outcome(c).color, label=Outcome(c).label) for c in present]
    handles.append(Patch(facecolor="none", edgecolor="k", label="subclass 132/133/142/143 + duals"))
    ax.legend(handles=handles, loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8)
    ax.set_xlabel(r"$\beta_1$ [$\pi$ rad]")
    ax.set_ylabel(r"$\beta_2$ [$\pi$ rad]")
    ax.set_title(
        f"simulated outcome, kappa={ds.attrs['kappa']:g}, q=({ds.attrs['q1']:g}, "
        f"{ds.attrs['q2']:g}), alpha={alpha / math.pi:.2f}pi; dashed: SS spectral abscissa = 0",
        fontsize=9,
    )
    _atomic_savefig(fig, path)
    plt.close(fig)
    return path
