"""Certified boundary curves of the Fig. 1 slice: ``fig1_boundaries.png`` and
``fig1_boundaries.nc`` of ``atlas paper``.

Two slices at ``kappa = 0.5``: Fig. 1's ``q1 = q2 = 0`` and vanishing damping ``q1 = q2 = 1e-6``
(audit claim Z: the SS boundary moves from the discriminant curve to its small-damping limit).
Every vertex is certified within ``1e-10`` rad (:mod:`atlas.data.boundaries`).
"""

from __future__ import annotations

from matplotlib.figure import Figure

from atlas.data.boundaries import Boundaries, boundaries
from atlas.data.io import atomic_path, savefig
from atlas.data.scene import Scene
from atlas.paper import runlog
from atlas.paper.drawing import pi_axis

__all__ = ["SLICES", "STYLE", "draw_boundaries", "slice_of", "write_boundaries"]

#: the (kappa, q) slices drawn
SLICES = ((0.5, 0.0), (0.5, 1e-6))
#: colour of each boundary kind; pieces on a class line are drawn thicker
STYLE = {
    "SS_stability": "C0",
    "II_consistency": "C1",
    "II_stability": "C2",
    "class_line": "0.8",
}
_MARKERS = {
    "junction": "ks",
    "leaves_class_line": "r.",
    "crosses_class_line": "g+",
    "touches_class_line": "b^",
    "SS_meets_II": "m*",
    "end": "kx",
    "uncovered_class_line": "co",  # a class-line stretch no curve covers (proven = 0)
    "unproven_class_line": "cx",  # a class-line interval whose side codes are not proven
    "undecided_line_root": "kd",  # an algebraic root on a class line not accounted for
    "dangling_curve_end": "ro",  # a curve end with nothing near it (proven = 0)
}


def slice_of(bd: Boundaries, kappa: float, q: float) -> Boundaries:
    """The curves and points of one slice ``(kappa, q1 = q2 = q)`` of ``bd``."""
    keep = lambda x: (x.kappa, x.q1) == (kappa, q)  # noqa: E731
    return Boundaries(
        [c for c in bd.curves if keep(c)], [p for p in bd.points if keep(p)], bd.attrs
    )


def draw_boundaries(bd, ax, kappa: float, q: float) -> list:
    """Draw the curves and codimension-2 points of one slice of ``bd`` on ``ax``; returns the
    artists."""
    arts = []
    for c in bd.curves:
        if c.field != "class" and (c.kappa, c.q1) != (kappa, q):
            continue
        lw = 0.5 if c.field == "class" else (2.2 if c.on_class_line else 1.1)
        arts += ax.plot(*c.vertices.T, color=STYLE[c.kind], lw=lw, label=c.kind)
    for p in bd.points:
        if (p.kappa, p.q1) == (kappa, q):
            arts += ax.plot(p.beta1, p.beta2, _MARKERS[p.kind], ms=4, label=p.kind)
    pi_axis(ax)
    ax.set_xlabel("beta1")
    ax.set_ylabel("beta2")
    ax.set_title(f"kappa = {kappa:g}, q1 = q2 = {q:g}", fontsize=9)
    return arts


def write_boundaries(out, n: int = 64, chord: float = 1e-5):
    """Compute the curves of :data:`SLICES` on an ``n x n`` grid; write ``fig1_boundaries.nc``
    (CF-1.10 geometry; the seconds and the date in the run log, :func:`atlas.paper.runlog.fixed`) and ``fig1_boundaries.png`` into ``out``; returns the curves."""
    grid = f"0:2pi:{n}"
    bd = boundaries(
        Scene(beta1=grid, beta2=grid, kappa=SLICES[0][0], q=",".join(str(q) for _, q in SLICES)),
        chord=chord,
    )
    with atomic_path(out / "fig1_boundaries.nc") as tmp:
        runlog.fixed(bd.to_dataset(), "fig1_boundaries.nc").to_netcdf(tmp)
    fig = Figure(figsize=(10, 5.2), constrained_layout=True)
    axes = fig.subplots(1, len(SLICES))
    for ax, (kappa, q) in zip(axes, SLICES):
        draw_boundaries(bd, ax, kappa, q)
    handles, labels = axes[0].get_legend_handles_labels()
    seen = dict(zip(labels, handles))
    fig.legend(seen.values(), seen.keys(), loc="outside lower center", ncols=5, fontsize=7)
    fig.suptitle(
        "Certified boundary curves (vertices within 1e-10 rad; thick: on a class line)", fontsize=10
    )
    savefig(fig, out / "fig1_boundaries.png", dpi=110)
    return bd
