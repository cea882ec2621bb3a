"""The ladder's atlas over (angle, friction) with the classical one-contact Painleve threshold:
``ladder.png`` of ``atlas paper``."""

from __future__ import annotations

import numpy as np
from matplotlib.colors import ListedColormap
from matplotlib.patches import Patch

from atlas.core.verdicts import Consistency, Verdict
from atlas.data.body_atlas import mechanism_atlas
from atlas.data.io import savefig

#: (label, colour) of the II categories drawn
CATEGORIES = (
    ("II inconsistent", "#f2f2f2"),
    ("II consistent, unstable", "#f4a582"),
    ("II consistent, stable", "#b2182b"),
    ("undecided", "#000000"),
)


def painleve_threshold(theta):
    """Friction coefficient above which the foot of a uniform ladder alone has Painleve's paradox
    (``b11 < 0``): ``(1 + 3 cos^2 theta) / (3 sin theta cos theta)``, minimum 4/3 at
    ``tan theta = 2`` (the classical rod; ``theta`` [rad] from the floor)."""
    c, s = np.cos(theta), np.sin(theta)
    return (1 + 3 * c * c) / (3 * s * c)


def ii_category(ds) -> np.ndarray:
    """0 no II, 1 II consistent and unstable, 2 consistent and stable, 3 undecided (per body)."""
    cons, stab = ds.consistent_II.values, ds.stable_II.values
    cat = np.where(cons == int(Consistency.CONSISTENT), 1, 0)
    cat = np.where((cat == 1) & (stab == int(Verdict.STABLE)), 2, cat)
    undecided = (cons == int(Consistency.UNDECIDED)) | (stab == int(Verdict.UNDECIDED))
    return np.where(undecided, 3, cat)


def plot_ladder(ds, ax):
    """Draw the II categories of a ladder atlas (dims ``theta``, ``mu``) on ``ax``, with the
    region ``b11 < 0`` outlined and the classical threshold; returns the artists."""
    theta_deg = np.degrees(ds.theta.values)
    mesh = ax.pcolormesh(
        theta_deg,
        ds.mu.values,
        ii_category(ds).T,
        cmap=ListedColormap([c for _, c in CATEGORIES]),
        vmin=-0.5,
        vmax=len(CATEGORIES) - 0.5,
        shading="nearest",
    )
    painleve = ax.contour(theta_deg, ds.mu.values, ds.b11.values.T, levels=[0.0], colors="k")
    th = np.linspace(ds.theta.values[0], ds.theta.values[-1], 400)
    (line,) = ax.plot(np.degrees(th), painleve_threshold(th), "b--", lw=1.2)
    ax.set_ylim(ds.mu.values[0], ds.mu.values[-1])
    ax.set_xlabel("ladder angle from the floor theta [deg]")
    ax.set_ylabel("friction coefficient mu (floor and wall) [1]")
    handles = [Patch(color=c, label=lab) for lab, c in CATEGORIES[:3]]
    handles.append(line)
    line.set_label("one-contact threshold (1 + 3cos^2) / (3 sin cos), min 4/3")
    ax.legend(handles=handles, loc="lower right", fontsize=7)
    return [mesh, painleve, line]


def write_ladder(path, n: int = 181):
    """The default ladder atlas on an ``n x n`` (theta, mu) grid, drawn into ``path`` (png)."""
    import matplotlib.pyplot as plt

    ds = mechanism_atlas("ladder", theta=f"0.02pi:0.48pi:{n}", mu=f"0:2:{n}")
    fig, ax = plt.subplots(figsize=(6.4, 4.6), constrained_layout=True)
    plot_ladder(ds, ax)
    ax.set_title(
        "Ladder on a floor and a wall, slipping down: II impact without collision\n"
        "(solid: b11 = 0 of the two-contact body; dashed: the classical rod)",
        fontsize=9,
    )
    savefig(fig, path, dpi=120)
    plt.close(fig)
    return ds
