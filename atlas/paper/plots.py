"""Drawing the paper's map figures: Fig. 1 (class diagram, stability maps, variants) and Table 2.

The maps come from :mod:`atlas.paper.figures` (verdicts and smooth margins); this module only
arranges and draws them.  Colours and legends come from :class:`atlas.core.verdicts.Verdict` and
:class:`atlas.core.verdicts.Consistency`; categorical layers are ``pcolormesh`` with
``ListedColormap`` + ``BoundaryNorm``; model-dependent boundaries are dashed (certified curves of
:func:`atlas.boundaries` if given, else zero contours of the smooth margins).
"""

from __future__ import annotations

import math
from pathlib import Path

import jax.numpy as jnp
import numpy as np

from atlas.core import contact_modes
from atlas.core.verdicts import Consistency, Verdict
from atlas.data.io import savefig
from atlas.paper import drawing
from atlas.paper.figures import class_representatives

__all__ = [
    "plot_fig1_classes",
    "plot_fig1_stability",
    "plot_fig1_variants",
    "plot_table2",
    "draw_class_diagram",
    "draw_fig1_classes",
    "draw_fig1_layer",
    "draw_fig1_stability",
    "draw_fig1_variant",
    "draw_fig1_variants",
    "draw_table2",
    "FIG1_LAYERS",
    "LAYER_CURVES",
    "TABLE_SHADE",
    "DPI",
]

DPI = 110


def draw_class_diagram(ax, cls: int, rep: dict) -> list:
    """One class of Fig. 1 on ``ax``: ``b1``, ``b2`` (arrows), ``-b1`` (dotted) and ``a`` for each
    subclass ``k`` (dashed), at the representative point ``rep`` of :func:`class_representatives`.

    Returns the artists drawn.
    """
    t = np.linspace(0, 2 * np.pi, 200)
    art = ax.plot(np.cos(t), np.sin(t), color="0.85", lw=0.6)
    art += [ax.axhline(0, color="0.6", lw=0.5), ax.axvline(0, color="0.6", lw=0.5)]
    b1s = rep["beta1"] + np.pi
    art += ax.plot([0, np.cos(b1s)], [0, np.sin(b1s)], ls=":", color="C3", lw=0.9)
    for k, a in rep["alpha"].items():
        art += ax.plot([0, 0.78 * np.cos(a)], [0, 0.78 * np.sin(a)], ls="--", color="0.35", lw=0.8)
        art.append(
            ax.text(
                0.93 * np.cos(a),
                0.93 * np.sin(a),
                str(k),
                ha="center",
                va="center",
                fontsize=7,
                color="0.2",
            )
        )
    for j, (key, col) in enumerate((("beta1", "C3"), ("beta2", "C0"))):
        b = rep[key]
        art.append(
            ax.annotate(
                "",
                xy=(np.cos(b), np.sin(b)),
                xytext=(0, 0),
                arrowprops=dict(arrowstyle="-|>", color=col, lw=1.6, mutation_scale=9),
            )
        )
        art.append(
            ax.text(
                1.22 * np.cos(b),
                1.22 * np.sin(b),
                f"$b_{j + 1}$",
                color=col,
                fontsize=8,
                ha="center",
                va="center",
            )
        )
    ax.set_xlim(-1.4, 1.4)
    ax.set_ylim(-1.4, 1.4)
    ax.set_aspect("equal")
    ax.set_xticks([])
    ax.set_yticks([])
    dual = contact_modes.class_code(
        *(
            jnp.asarray(v)
            for v in contact_modes.dual_vectors(
                *contact_modes.direction(rep["beta1"]), *contact_modes.direction(rep["beta2"])
            )
        )
    )
    dual = int(dual)
    art.append(ax.set_title(f"class {cls} ({'same' if dual == cls else dual})", fontsize=9))
    return art


def draw_fig1_classes(fig, reps: dict | None = None) -> list:
    """Fig. 1 (class diagram) on ``fig``: a 4 x 6 grid of :func:`draw_class_diagram`."""
    reps = reps or class_representatives()
    axes = fig.subplots(4, 6)
    art = []
    for ax, cls in zip(axes.ravel(), contact_modes.ALL_CLASSES, strict=True):
        art += draw_class_diagram(ax, cls, reps[cls])
    art.append(
        fig.suptitle(
            "Fig. 1 (classes): directions of $b_1$, $b_2$ (solid) and of $a$ for subclasses "
            "k = 1..6 (dashed); dotted: $-b_1$; at representative points found by the kernels; "
            "(dual) in brackets",
            fontsize=10,
        )
    )
    fig.tight_layout(rect=(0, 0, 1, 0.97))
    return art


def plot_fig1_classes(path, reps: dict | None = None):
    """Write Fig. 1 (class diagram, :func:`draw_fig1_classes`) to ``path``."""
    fig = drawing.new_figure(figsize=(13, 9.2))
    draw_fig1_classes(fig, reps)
    return _save(fig, path)


def _save(fig, path) -> Path:
    savefig(fig, path, dpi=DPI)
    return Path(path)


# --------------------------------------------------------------------------- Fig. 1, stability

_NEUTRAL_LABEL = {Verdict.NEUTRAL: "neutral (drawn as stable in the paper)"}

#: the layers of Fig. 1 (stability map), in panel order
FIG1_LAYERS = ("SF", "FS", "SS", "IF", "FI", "II_consistency", "II_stability", "nothing_stable")

_LAYER_TITLES = {
    "SF": "SF stability ($b_{11} > 0$)",
    "FS": "FS stability ($b_{22} > 0$)",
    "SS": "SS stability",
    "IF": "IF consistent (then stable)",
    "FI": "FI consistent (then stable)",
    "II_consistency": "II consistency",
    "II_stability": "II stability (hatched: II inconsistent)",
    "nothing_stable": "SS unstable, no stable IWC (orange; Sec. 6.4)",
}


def _layer_fields(ds) -> dict:
    """The fields of the Fig. 1 layers on the full ``(beta1, beta2)`` grid."""
    n = ds.sizes["beta1"]
    IF = np.broadcast_to(ds["consistent_IF"].values[:, None], (n, n)).astype(np.int8)
    FI = np.broadcast_to(ds["consistent_FI"].values[None, :], (n, n)).astype(np.int8)
    ss, si = ds["stable_SS"].values, ds["stable_II"].values
    ss_ok = (ss == Verdict.STABLE) | (ss == Verdict.NEUTRAL)
    return {
        "SF": np.broadcast_to(ds["stable_SF"].values[:, None], (n, n)),
        "FS": np.broadcast_to(ds["stable_FS"].values[None, :], (n, n)),
        "SS": ss,
        "IF": IF,
        "FI": FI,
        "II_consistency": ds["consistent_II"].values,
        "II_stability": si,
        "nothing_stable": ~ss_ok & (IF == 0) & (FI == 0) & (si != Verdict.STABLE),
    }


def _layer_boundaries(ds, layer) -> list:
    """``(margin, cells)`` of the dashed model-dependent boundaries of a layer."""
    cls = ds["class_code"].values
    ci = ds["consistent_II"].values
    if layer in ("SS", "nothing_stable"):
        return [("margin_SS", drawing.ss_boundary_cells(ds))]
    if layer == "II_consistency":
        return [("margin_II_consistent", drawing.near_change(ci, cls))]
    if layer == "II_stability":
        si_cells = drawing.near_change(ds["stable_II"].values, cls) & (ci == Consistency.CONSISTENT)
        return [
            ("margin_II_stable", si_cells),
            ("margin_II_consistent", drawing.near_change(ci, cls)),
        ]
    return []


#: the boundary kinds (:mod:`atlas.data.boundaries`) drawn dashed on each Fig. 1 layer
LAYER_CURVES = {
    "SS": ("SS_stability",),
    "nothing_stable": ("SS_stability",),
    "II_consistency": ("II_consistency",),
    "II_stability": ("II_stability", "II_consistency"),
}


def _dashed_curves(ax, curves, layer) -> list:
    """The certified model-dependent boundaries of ``layer`` (pieces off the class lines) dashed."""
    kinds = LAYER_CURVES.get(layer, ())
    arts = []
    for c in curves.curves:
        if c.kind in kinds and not c.on_class_line:
            arts += ax.plot(*c.vertices.T, color="k", lw=1.1, ls="--", zorder=7)
    return arts


@drawing.hatch_style
def draw_fig1_layer(ax, ds, layer: str, pos: dict | None = None, curves=None) -> list:
    """One panel of Fig. 1 (stability map) on ``ax``: the layer (one of :data:`FIG1_LAYERS`) of a
    :func:`stability_map` dataset, its dashed model-dependent boundaries, the class boundaries and
    (if ``pos``, from :func:`atlas.paper.drawing.label_positions`) the class labels.

    The dashed boundaries are the certified curves ``curves`` (:func:`atlas.boundaries` of the
    same slice) if given, else the zero contours of the dataset's smooth margins.  Returns the
    artists drawn.
    """
    if layer not in FIG1_LAYERS:
        raise ValueError(f"layer: expected one of {FIG1_LAYERS}, got {layer!r}")
    field = _layer_fields(ds)[layer]
    ci = ds["consistent_II"].values
    ax.set_facecolor("white")
    if layer in ("SF", "FS", "SS"):
        art = [drawing.categorical(ax, ds, field, Verdict)]
    elif layer in ("IF", "FI", "II_consistency"):
        art = [drawing.categorical(ax, ds, field, Consistency)]
    elif layer == "II_stability":
        art = [
            drawing.categorical(ax, ds, field, Verdict, mask=ci == Consistency.CONSISTENT),
            drawing.hatch(ax, ds, ci != Consistency.CONSISTENT),
        ]
    else:
        art = [drawing.boolean(ax, ds, field, drawing.NOTHING_COLOR)]
    n = ds.sizes["beta1"]
    if curves is not None:
        art += _dashed_curves(ax, curves, layer)
    else:
        for m, cells in _layer_boundaries(ds, layer):
            if m in ds:
                art.append(drawing.dashed(ax, ds, m, where=cells & np.ones((n, n), bool)))
    art += drawing.class_lines(ax)
    if pos is not None:
        art += drawing.class_labels(ax, pos)
    drawing.pi_axis(ax)
    art.append(ax.set_title(_LAYER_TITLES[layer], fontsize=9))
    ax.tick_params(labelsize=7)
    return [a for a in art if a is not None]


def _param_text(kappa, q1, q2):
    q = f"q = {q1:g}" if q1 == q2 else f"q1 = {q1:g}, q2 = {q2:g}"
    return rf"$\kappa$ = {kappa:g}, {q}"


def _fig1_legend(fig, ds, certified: bool = False):
    from matplotlib.lines import Line2D

    present_v = (
        set(np.unique(ds["stable_SS"].values).tolist())
        | {0, 1}
        | set(np.unique(ds["stable_II"].values).tolist())
    )
    handles = drawing.legend_patches(Verdict, present_v, _NEUTRAL_LABEL)
    handles += drawing.legend_patches(
        Consistency, set(np.unique(ds["consistent_II"].values).tolist()) | {0, 1}
    )
    handles += [
        Line2D([], [], color="k", lw=0.6, label="class boundary (model-independent)"),
        Line2D(
            [],
            [],
            color="k",
            lw=1.1,
            ls="--",
            label="model-dependent boundary ("
            + (
                "certified curve, vertices within 1e-10 rad"
                if certified
                else "zero of smooth margin"
            )
            + ")",
        ),
    ]
    return fig.legend(handles=handles, loc="lower center", ncol=5, fontsize=8.5, frameon=False)


def draw_fig1_stability(fig, ds, curves=None) -> list:
    """Fig. 1 (stability map) on ``fig``: the 8 layers of :func:`draw_fig1_layer` in a 2 x 4 grid
    (dashed boundaries from the certified ``curves`` if given), legend from the verdict
    enumerations, title with the parameters and decision counts."""
    axes = fig.subplots(2, 4).ravel()
    pos = drawing.label_positions(ds)
    art = []
    for ax, layer in zip(axes, FIG1_LAYERS, strict=True):
        art += draw_fig1_layer(ax, ds, layer, pos, curves)
    for ax in axes[-4:]:
        ax.set_xlabel(r"$\beta_1$", fontsize=9)
    for ax in axes[::4]:
        ax.set_ylabel(r"$\beta_2$", fontsize=9)
    kappa, q1, q2 = (float(ds[k]) for k in ("kappa", "q1", "q2"))
    art.append(_fig1_legend(fig, ds, certified=curves is not None))
    und = int(ds.attrs.get("n_undecided", 0))
    art.append(
        fig.suptitle(
            f"Fig. 1 (stability map), {_param_text(kappa, q1, q2)}; grid "
            f"{ds.sizes['beta1']}$^2$, {ds.attrs.get('n_resolved', 0)} cells settled by the "
            f"exact reference, {und} undecided. FF (always stable when consistent) not shown.",
            fontsize=10,
        )
    )
    # explicit margins: tight_layout mis-sizes the equal-aspect panels, so the bottom row's titles
    # ran into the top row's tick labels; hspace leaves room for tick labels + title
    fig.subplots_adjust(left=0.045, right=0.99, bottom=0.13, top=0.92, wspace=0.2, hspace=0.34)
    return art


def plot_fig1_stability(path, ds, curves=None):
    """Write Fig. 1 (stability map, :func:`draw_fig1_stability`) to ``path``."""
    fig = drawing.new_figure(figsize=(15.5, 9.4))
    draw_fig1_stability(fig, ds, curves)
    return _save(fig, path)


@drawing.hatch_style
def draw_fig1_variant(ax, ds, ref, pos: dict | None = None) -> list:
    """SS stability and II consistency (hatched) of one :func:`stability_map` on ``ax``, with the
    reference map ``ref``'s SS boundary in red (how the model-dependent boundaries move)."""
    ss = ds["stable_SS"].values
    art = [drawing.categorical(ax, ds, ss, Verdict)]
    ci = ds["consistent_II"].values
    b = ds["beta1"].values
    hatch = np.where(ci == Consistency.CONSISTENT, 1.0, 0.0)
    art.append(
        ax.contourf(b, b, hatch.T, levels=[0.5, 1.5], colors="none", hatches=["////"], zorder=3)
    )
    art.append(
        ax.contourf(
            b,
            b,
            np.where(ci == Consistency.CONSISTENT, 1.0, np.nan).T,
            levels=[0.5, 1.5],
            colors=[Consistency.CONSISTENT.color],
            alpha=0.25,
            zorder=2,
        )
    )
    ref_cells = drawing.ss_boundary_cells(ref)
    art.append(drawing.dashed(ax, ref, "margin_SS", where=ref_cells, color="C3", lw=0.9, ls="-"))
    art.append(drawing.dashed(ax, ds, "margin_SS", where=drawing.ss_boundary_cells(ds)))
    art.append(
        drawing.dashed(
            ax,
            ds,
            "margin_II_consistent",
            where=drawing.near_change(ci, ds["class_code"].values),
            color=Consistency.CONSISTENT.color,
            lw=1.3,
        )
    )
    art += drawing.class_lines(ax, lw=0.5)
    if pos is not None:
        art += drawing.class_labels(ax, pos, fs=5.5)
    drawing.pi_axis(ax)
    ax.tick_params(labelsize=7)
    art.append(
        ax.set_title(_param_text(*(float(ds[k]) for k in ("kappa", "q1", "q2"))), fontsize=9)
    )
    return [a for a in art if a is not None]


@drawing.hatch_style
def _variants_legend(fig):
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    handles = drawing.legend_patches(
        Verdict,
        {0, 1, 2},
        {
            Verdict.STABLE: "SS stable",
            Verdict.UNSTABLE: "SS unstable",
            Verdict.NEUTRAL: "SS neutral (q = 0)",
        },
    )
    handles += [
        Patch(
            facecolor=Consistency.CONSISTENT.color, alpha=0.4, hatch="////", label="II consistent"
        ),
        Line2D([], [], color="k", ls="--", label="SS boundary (margin zero)"),
        Line2D(
            [], [], color=Consistency.CONSISTENT.color, ls="--", label="II consistency boundary"
        ),
        Line2D([], [], color="C3", label=r"SS boundary at $\kappa$=0.5, q=0 (reference)"),
    ]
    return fig.legend(handles=handles, loc="lower center", ncol=4, fontsize=8.5, frameon=False)


def draw_fig1_variants(fig, maps: list) -> list:
    """SS stability + II consistency at several (kappa, q1, q2) on ``fig``, 3 per row
    (:func:`draw_fig1_variant`); the reference (first map)'s SS boundary repeated in red."""
    ncol = 3
    nrow = math.ceil(len(maps) / ncol)
    axes = fig.subplots(nrow, ncol, squeeze=False).ravel()
    pos = drawing.label_positions(maps[0])
    art = []
    for ax, ds in zip(axes, maps, strict=False):
        art += draw_fig1_variant(ax, ds, maps[0], pos)
    for ax in axes[len(maps) :]:
        ax.axis("off")
    art.append(_variants_legend(fig))
    art.append(
        fig.suptitle(
            "Fig. 1 at other model parameters: the dashed (model-dependent) boundaries move; "
            "the straight class boundaries do not",
            fontsize=10,
        )
    )
    fig.subplots_adjust(left=0.05, right=0.99, bottom=0.1, top=0.93, wspace=0.18, hspace=0.3)
    return art


def plot_fig1_variants(path, maps: list):
    """Write the Fig. 1 variants (:func:`draw_fig1_variants`) to ``path``."""
    nrow = math.ceil(len(maps) / 3)
    fig = drawing.new_figure(figsize=(4.6 * 3, 4.7 * nrow + 0.8))
    draw_fig1_variants(fig, maps)
    return _save(fig, path)


# --------------------------------------------------------------------------- Table 2 figure

#: the paper's Table 2 shading (the reverse of the maps: there *stable* is dark)
TABLE_SHADE = {
    "unstable": "#4d4d4d",
    "model-dependent": "#c8c8c8",
    "stable": "#ffffff",
    "-": "#ffffff",
}


def _table2_cells(rows):
    """Cell texts, background colours and text colours of the Table 2 figure."""
    cells, colours, textc = [], [], []
    for r in rows:
        dual = "same" if r.dual == r.cls else str(r.dual)
        line = [f"{r.cls} ({dual})"]
        shade = ["#eeeeee"]
        for m in ("FF", "SS", "SF", "FS"):
            ks = " ".join(map(str, r.subclasses[m]))
            line.append(ks)
            shade.append(TABLE_SHADE[r.stability[m]] if ks else "#ffffff")
        line += [r.IF, r.FI, r.II, r.CC]
        shade += [
            "#ffffff",
            "#ffffff",
            TABLE_SHADE[r.II_stability] if r.II != "-" else "#ffffff",
            "#ffffff",
        ]
        cells.append(line)
        colours.append(shade)
        textc.append(["white" if c == TABLE_SHADE["unstable"] else "black" for c in shade])
    return cells, colours, textc


def draw_table2(ax, rows) -> list:
    """Table 2 on ``ax`` (axis off): unstable dark, model-dependent light, stable white (the
    paper's shading); ``rows`` from :func:`atlas.paper.tables.table2`.  Returns [table, title]."""
    cols = ["class (dual)", "FF", "SS", "SF", "FS", "IF", "FI", "II", "CC"]
    cells, colours, textc = _table2_cells(rows)
    ax.axis("off")
    tab = ax.table(
        cellText=cells,
        colLabels=cols,
        cellColours=colours,
        loc="upper center",
        cellLoc="center",
        colWidths=[0.16] + [0.105] * 8,
    )
    tab.auto_set_font_size(False)
    tab.set_fontsize(8.5)
    tab.scale(1, 1.25)
    for (i, j), cell in tab.get_celld().items():
        cell.set_edgecolor("0.6")
        if i == 0:
            cell.set_text_props(weight="bold")
        elif j > 0:
            cell.get_text().set_color(textc[i - 1][j])
    title = ax.set_title(
        "Table 2 (regenerated): subclasses k where a mode is consistent; background: "
        "dark = unstable,\nlight = model-dependent, white = stable. IWC markers: x "
        "consistent, (x) model-dependent, - never; CC: ? = necessary condition holds",
        fontsize=8.5,
    )
    return [tab, title]


def plot_table2(path, rows):
    """Write Table 2 as a figure (:func:`draw_table2`) to ``path``."""
    fig = drawing.new_figure(figsize=(8.4, 0.27 * len(rows) + 1.0))
    draw_table2(fig.subplots(), rows)
    fig.tight_layout()
    return _save(fig, path)
