"""The widget's map figure: the selected layer of an :class:`~atlas.explore.state.Explorer` on a
matplotlib axes, with its legend, the overlays and the marker of the inspected point (matplotlib is
imported when a view is made)."""

from __future__ import annotations

import math
import time

import numpy as np

from atlas.explore.colors import legend_entries
from atlas.explore.state import Explorer

__all__ = ["MapView", "class_lines"]

_PI_TICKS = ["0", "π/2", "π", "3π/2", "2π"]


def class_lines(ax) -> list:
    """The straight (model-independent) class boundaries: axes of beta1, beta2; beta2 = beta1
    (+ pi).  Returns the artists."""
    tp = 2 * math.pi
    kw = dict(color="k", lw=0.5, alpha=0.6)
    arts = []
    for a in (0.5 * math.pi, math.pi, 1.5 * math.pi):
        arts += [ax.axvline(a, **kw), ax.axhline(a, **kw)]
    x = np.array([0.0, tp])
    arts += ax.plot(x, x, **kw)
    arts += ax.plot([0, math.pi], [math.pi, tp], **kw)
    arts += ax.plot([math.pi, tp], [0, math.pi], **kw)
    return arts


class MapView:
    """The widget's map on a matplotlib axes: the selected layer as an image, its legend, the
    overlays and the marker of the inspected point.  :meth:`render` is the figure half of a
    redraw (the canvas draw is the caller's: ``draw_idle`` on ipympl, ``draw`` on Agg)."""

    def __init__(self, ax):
        from matplotlib.lines import Line2D

        self.ax, self.fig = ax, ax.figure
        pi = math.pi
        self.im = ax.imshow(
            np.zeros((1, 1, 4)),
            origin="lower",
            extent=(0, 2 * pi, 0, 2 * pi),
            interpolation="nearest",
        )
        self.lines = class_lines(ax)
        (self.marker,) = ax.plot([], [], "o", mfc="none", mec="C3", ms=10, mew=2)
        self.contour = None
        self._ss_handle = Line2D([], [], color="k", ls="--", lw=0.8, label="SS boundary")
        ax.set_xlabel(r"$\beta_1$")
        ax.set_ylabel(r"$\beta_2$")
        ticks = np.arange(5) * pi / 2
        ax.set_xticks(ticks, _PI_TICKS)
        ax.set_yticks(ticks, _PI_TICKS)
        ax.set_xlim(0, 2 * pi)
        ax.set_ylim(0, 2 * pi)

    def render(self, ex: Explorer):
        """Image, class boundaries, SS contour, legend, title and marker of ``ex``'s state."""
        ax, p = self.ax, ex.params
        self.im.set_data(ex.image())
        t = time.perf_counter()
        for a in self.lines:
            a.set_visible("class boundaries" in p["overlays"])
        handles = self._layer_handles(ex) + self._draw_ss_boundary(ex)
        if ax.get_legend() is not None:
            ax.get_legend().remove()
        if handles:
            ax.legend(handles=handles, loc="upper right", fontsize=7, framealpha=0.85)
        ax.set_title(p["layer"], fontsize=10)
        self.marker.set_data(
            [] if ex.point is None else [ex.point[0]], [] if ex.point is None else [ex.point[1]]
        )
        ex.timings["overlay_ms"] = 1e3 * (time.perf_counter() - t)

    def _layer_handles(self, ex: Explorer) -> list:
        from matplotlib.patches import Patch

        return [
            Patch(facecolor=c, edgecolor="0.5", label=lbl)
            for c, lbl in legend_entries(ex.params["layer"], ex.ds)
        ]

    def _draw_ss_boundary(self, ex: Explorer) -> list:
        """Replace the dashed zero contour of the smooth SS margin; returns its legend handle."""
        if self.contour is not None:
            self.contour.remove()
            self.contour = None
        if "SS boundary" not in ex.params["overlays"] or ex.margin is None:
            return []
        m = ex.margin.values
        if not np.nanmin(m) < 0 < np.nanmax(m):  # no zero contour (and a warning)
            return []
        self.contour = self.ax.contour(
            ex.margin.beta1,
            ex.margin.beta2,
            m.T,
            levels=[0.0],
            colors="k",
            linestyles="--",
            linewidths=0.8,
        )
        return [self._ss_handle]
