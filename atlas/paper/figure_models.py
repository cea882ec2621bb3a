"""A panel beside Fig. 1: where SS stability depends on the contact model, proven.

:func:`model_dependence_map` computes ``ss_over_models`` (:mod:`atlas.core.model_box`) on the
Fig. 1 plane (the offset grid of :func:`atlas.paper.figures.stability_map`) for model boxes;
:func:`plot_model_dependence` draws one panel per box: stable for every model, unstable for every
model, depends on the model (undecided, if any, in red), with the class lines.  The paper judged
"model-dependent" from samples of ``K`` and ``Q`` (Appendix C); here every region is a proof.
"""

from __future__ import annotations

import numpy as np

from atlas.core.verdicts import OverModels
from atlas.data.io import savefig
from atlas.data.over_models import over_models
from atlas.paper import drawing

__all__ = [
    "BOXES",
    "N_MODELS",
    "model_dependence_map",
    "draw_model_dependence",
    "plot_model_dependence",
    "save_model_dependence",
    "fractions",
    "fractions_markdown",
]

#: cells per axis of the ``atlas paper`` panel (full, quick, CI runs); divisible by 4, so no cell lies
#: on a class line ``beta = k pi / 2``
N_MODELS = (360, 120, 40)
#: the boxes of the panels: the whole model space, equal damping, and a bounded box
BOXES = ("kappa=0:inf", "q=0:inf", "kappa=0.01:100,q1=0:1,q2=0:1")


def model_dependence_map(n: int = 361, box="kappa=0:inf"):
    """``ss_over_models`` and its witnesses on the ``n x n`` offset grid of ``(beta1, beta2)``
    in ``[0, 2 pi)`` (an ``xarray.Dataset``; the box and the undecided counts as attributes)."""
    b = (np.arange(n) + 0.5) * (2 * np.pi / n)
    return over_models(b, b, box)


def draw_model_dependence(fig, maps: list) -> list:
    """One panel per map of :func:`model_dependence_map`; returns the artists."""
    axes = fig.subplots(1, len(maps), squeeze=False)[0]
    artists = []
    present: set = set()
    for ax, ds in zip(axes, maps):
        code = ds["ss_over_models"].values
        present |= set(np.unique(code).tolist())
        artists.append(drawing.categorical(ax, ds, code, OverModels))
        artists += drawing.class_lines(ax)
        drawing.pi_axis(ax)
        ax.set_xlabel(r"$\beta_1$")
        ax.set_title(ds.attrs["model_box"].replace(",", ", "), fontsize=8)
    axes[0].set_ylabel(r"$\beta_2$")
    fig.legend(
        handles=drawing.legend_patches(OverModels, present),
        loc="outside lower center",
        ncol=4 if len(maps) > 1 else 1,  # one narrow panel: one entry a row, none clipped
        fontsize=8,
    )
    return artists


def plot_model_dependence(path, n: int = 181, boxes=BOXES):
    """The panels of :data:`BOXES` (or ``boxes``) at ``n x n`` points into ``path``; returns the
    maps."""
    return save_model_dependence(path, [model_dependence_map(n, box) for box in boxes])


def save_model_dependence(path, maps: list) -> list:
    """The panels of ``maps`` (:func:`model_dependence_map`, computed already) into ``path``;
    returns the maps."""
    fig = drawing.new_figure(figsize=(3.2 * len(maps), 3.8), layout="constrained")
    draw_model_dependence(fig, maps)
    savefig(fig, path, dpi=150)
    return maps


def fractions(ds) -> dict:
    """``{OverModels code: (cells, fraction of the plane)}`` of a map of
    :func:`model_dependence_map` (every code, fractions summing to 1)."""
    code = ds["ss_over_models"].values
    return {
        v: (int(np.count_nonzero(code == int(v))), np.count_nonzero(code == int(v)) / code.size)
        for v in OverModels
    }


def fractions_markdown(ds) -> list[str]:
    """Markdown lines: the share of the ``(beta1, beta2)`` plane in each region of the map ``ds``."""
    n1, n2 = ds["ss_over_models"].shape
    rows = [f"| {v.label} | {k} | {100 * f:.2f} % |" for v, (k, f) in fractions(ds).items()]
    return [
        f"Model box `{ds.attrs['model_box']}`, {n1} x {n2} offset cells of the Fig. 1 plane "
        "(`ss_over_models`, every region proved; neutral counted as stable):",
        "",
        "| region | cells | share of the plane |",
        "|---|---|---|",
        *rows,
    ]
