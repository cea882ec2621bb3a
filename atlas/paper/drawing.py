"""Drawing primitives of the beta1-beta2 maps (Fig. 1, the outcome map): pi axes, the straight class
boundaries, categorical layers coloured by an enumeration (``pcolormesh`` with ``ListedColormap`` +
``BoundaryNorm``), hatching, dashed zero contours of smooth margins, legend patches.

Every function draws on a given ``ax`` and returns what it drew; none makes a figure or saves one
(the ``plot_*`` wrappers of :mod:`atlas.paper.plots` and :mod:`atlas.paper.figures_dynamics` do,
through :func:`new_figure` and :func:`atlas.data.io.savefig`).  matplotlib is imported lazily.
"""

from __future__ import annotations

import functools

import numpy as np

from atlas.core import contact_modes
from atlas.core.verdicts import Verdict

__all__ = [
    "HATCH_STYLE",
    "NOTHING_COLOR",
    "boolean",
    "categorical",
    "class_labels",
    "class_lines",
    "dashed",
    "hatch",
    "hatch_style",
    "label_positions",
    "legend_patches",
    "near_change",
    "new_figure",
    "pi_axis",
    "ss_boundary_cells",
]

#: hatching of the maps (matplotlib reads it when a hatched artist is made)
HATCH_STYLE = {"hatch.color": "0.55", "hatch.linewidth": 0.5}


def hatch_style(draw):
    """Run ``draw`` under :data:`HATCH_STYLE` (a ``matplotlib.rc_context``: no global change)."""

    @functools.wraps(draw)
    def styled(*args, **kwargs):
        from matplotlib import rc_context

        with rc_context(HATCH_STYLE):
            return draw(*args, **kwargs)

    return styled


def new_figure(**kwargs):
    """A ``matplotlib.figure.Figure`` made without pyplot (no backend, no global figure list)."""
    from matplotlib.figure import Figure

    return Figure(**kwargs)


def pi_axis(ax, which="both"):
    """Axis limits ``[0, 2 pi]`` with ticks at multiples of ``pi / 2``, equal aspect (no artists)."""
    ticks = np.arange(5) * np.pi / 2
    labels = ["0", r"$\pi/2$", r"$\pi$", r"$3\pi/2$", r"$2\pi$"]
    if which in ("both", "x"):
        ax.set_xticks(ticks, labels)
    if which in ("both", "y"):
        ax.set_yticks(ticks, labels)
    ax.set_xlim(0, 2 * np.pi)
    ax.set_ylim(0, 2 * np.pi)
    ax.set_aspect("equal")


def class_lines(ax, lw=0.6):
    """Straight class boundaries: axis directions of b1, b2 and beta2 = beta1, beta1 +- pi."""
    kw = dict(color="k", lw=lw, zorder=5)
    lines = []
    for v in (np.pi / 2, np.pi, 1.5 * np.pi):
        lines.append(ax.axvline(v, **kw))
        lines.append(ax.axhline(v, **kw))
    t = np.array([0, 2 * np.pi])
    for shift in (0.0, np.pi, -np.pi):
        lines += ax.plot(t, t + shift, **kw)
    return lines


def label_positions(ds):
    """Most interior cell of each class (max distance to the class's complement)."""
    from scipy.ndimage import distance_transform_edt

    cls = ds["class_code"].values
    b1, b2 = ds["beta1"].values, ds["beta2"].values
    pos = {}
    for code in contact_modes.ALL_CLASSES:
        mask = cls == code
        if not mask.any():
            continue
        d = distance_transform_edt(np.pad(mask, 1))[1:-1, 1:-1]
        i, j = np.unravel_index(np.argmax(d), d.shape)
        pos[code] = (b1[i], b2[j])
    return pos


def class_labels(ax, pos, fs=6.5):
    """Class code ``ij`` at each position of :func:`label_positions`; returns the texts."""
    return [
        ax.text(
            x,
            y,
            str(code),
            ha="center",
            va="center",
            fontsize=fs,
            zorder=6,
            clip_on=True,
            bbox=dict(boxstyle="round,pad=0.1", fc="white", ec="none", alpha=0.75),
        )
        for code, (x, y) in pos.items()
    ]


def categorical(ax, ds, field, enum, mask=None):
    """``pcolormesh`` of a categorical field with colours from the verdict enumeration."""
    from matplotlib.colors import BoundaryNorm, ListedColormap

    members = list(enum)
    codes = [int(m) for m in members]
    cmap = ListedColormap([m.color for m in members])
    bounds = np.array(codes + [codes[-1] + 1], float) - 0.5
    norm = BoundaryNorm(bounds, cmap.N)
    vals = np.asarray(field, float)
    if mask is not None:
        vals = np.ma.masked_where(~mask, vals)
    edges = np.linspace(0, 2 * np.pi, ds.sizes["beta1"] + 1)
    return ax.pcolormesh(edges, edges, vals.T, cmap=cmap, norm=norm, rasterized=True)


NOTHING_COLOR = "#fdae6b"


def boolean(ax, ds, flag, color):
    """Two-colour ``pcolormesh`` of a boolean layer (white / ``color``)."""
    from matplotlib.colors import BoundaryNorm, ListedColormap

    edges = np.linspace(0, 2 * np.pi, ds.sizes["beta1"] + 1)
    return ax.pcolormesh(
        edges,
        edges,
        np.asarray(flag, float).T,
        cmap=ListedColormap(["white", color]),
        norm=BoundaryNorm([-0.5, 0.5, 1.5], 2),
        rasterized=True,
    )


def hatch(ax, ds, flag):
    """Light hatching over the cells where ``flag`` holds (fill only; boundaries are drawn apart)."""
    b = ds["beta1"].values
    return ax.contourf(
        b,
        b,
        np.where(flag, 1.0, np.nan).T,
        levels=[0.5, 1.5],
        colors="none",
        hatches=["///"],
        zorder=2,
    )


def near_change(field, cls, width=2):
    """Cells within ``width`` of a change of ``field`` between cells of the same class."""
    from scipy.ndimage import binary_dilation

    ch = np.zeros(field.shape, bool)
    for axis in (0, 1):
        d = np.diff(field, axis=axis) != 0
        same = np.diff(cls, axis=axis) == 0
        e = d & same
        sl_a = [slice(None)] * 2
        sl_b = [slice(None)] * 2
        sl_a[axis] = slice(0, -1)
        sl_b[axis] = slice(1, None)
        ch[tuple(sl_a)] |= e
        ch[tuple(sl_b)] |= e
    return binary_dilation(ch, iterations=width) if ch.any() else ch


def dashed(ax, ds, margin, where=None, color="k", lw=1.1, ls="--"):
    """Dashed zero contour of a smooth margin (optionally restricted to cells ``where``)."""
    m = np.array(ds[margin].values, float)
    m[ds["class_code"].values == 0] = np.nan  # degenerate cells (beta2 = beta1, b2 = -b1)
    if where is not None:
        m = np.where(where, m, np.nan)
    if not np.isfinite(m).any() or np.nanmin(m) >= 0 or np.nanmax(m) <= 0:
        return None
    b = ds["beta1"].values
    return ax.contour(b, b, m.T, levels=[0.0], colors=color, linewidths=lw, linestyles=ls, zorder=7)


def ss_boundary_cells(ds):
    """Cells next to a change of the SS verdict inside one class (neutral counted as stable)."""
    v = ds["stable_SS"].values.copy()
    v[v == Verdict.NEUTRAL] = Verdict.STABLE
    return near_change(v, ds["class_code"].values)


def legend_patches(enum, present=None, relabel=None):
    """Legend patches of the members of a verdict enumeration (only codes in ``present``)."""
    from matplotlib.patches import Patch

    out = []
    for m in enum:
        if present is not None and int(m) not in present:
            continue
        label = (relabel or {}).get(m, m.label)
        out.append(Patch(facecolor=m.color, edgecolor="0.4", lw=0.5, label=label))
    return out
