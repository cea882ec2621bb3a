"""The widget's map figure: the selected layer of an :class:`~atlas.explore.state.Explorer` on a
matplotlib axes, with its legend, the overlays and the marker of the inspected point (matplotlib is
imported when a view is made)."""

from __future__ import annotations

import math
import time

import numpy as np

from atlas.explore.colors import legend_entries, value_label
from atlas.explore.maps import box_layers, is_box_layer, needs_alpha
from atlas.explore.state import Explorer

__all__ = ["MapView", "class_lines", "FIGSIZE", "AXES_RECT"]

_PI_TICKS = ["0", "π/2", "π", "3π/2", "2π"]
_CURVE_COLORS = {"SS": "black", "II": "#0050ff"}
#: the certified boundaries between the regions of a box layer
_REGION_COLOR = "#6a3d9a"
#: the map figure [in]: 640 x 460 px at 100 dpi, beside the controls (400 px) in a ~1,070 px
#: notebook column
FIGSIZE = (6.4, 4.6)
#: the map's axes in figure fractions (left, bottom, width, height): a square map, the colour key
#: to its right
AXES_RECT = (0.09, 0.09, 0.82 * FIGSIZE[1] / FIGSIZE[0], 0.82)


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
        from matplotlib import patheffects
        from matplotlib.lines import Line2D

        self.ax, self.fig = ax, ax.figure
        ax.set_position(AXES_RECT)
        pi = math.pi
        self.im = ax.imshow(
            np.zeros((1, 1, 4)),
            origin="lower",
            extent=(0, 2 * pi, 0, 2 * pi),
            interpolation="nearest",
        )
        self.im.set_mouseover(False)  # the hover text is format_coord's, not the RGBA values
        self.lines = class_lines(ax)
        # white ring with a black edge: visible on every colour of every layer
        (self.marker,) = ax.plot(
            [],
            [],
            "o",
            mfc="none",
            mec="white",
            ms=11,
            mew=2,
            path_effects=[patheffects.withStroke(linewidth=4, foreground="black")],
        )
        self.explorer: Explorer | None = None
        self.certified: list = []  # the artists of the certified boundaries
        ax.format_coord = self.format_coord
        #: the pointer's last map point ``(beta1, beta2)`` [rad] (set by the widget), or None
        self.hover_at: tuple[float, float] | None = None
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
        self.explorer = ex
        self.im.set_data(ex.image())
        t = time.perf_counter()
        for a in self.lines:
            a.set_visible("class boundaries" in p["overlays"])
        handles = self._layer_handles(ex) + self._draw_ss_boundary(ex) + self._draw_certified(ex)
        if ax.get_legend() is not None:
            ax.get_legend().remove()
        if handles:  # the colour key, right of the map
            ax.legend(
                handles=handles,
                loc="upper left",
                bbox_to_anchor=(1.02, 1.0),
                borderaxespad=0.0,
                fontsize=7,
                ncol=1 + (len(handles) > 24),
                handlelength=1.2,
                columnspacing=0.8,
                frameon=False,
            )
        title = p["layer"]
        if is_box_layer(p["layer"]):
            title += f"  ({p['model_box'].replace(',', ', ')})"
        if needs_alpha(p["layer"]):
            title += f"  (alpha = {p['alpha'] / math.pi:.3f} π)"
        ax.set_title(title, fontsize=10)
        self.marker.set_data(
            [] if ex.point is None else [ex.point[0]], [] if ex.point is None else [ex.point[1]]
        )
        ex.timings["overlay_ms"] = 1e3 * (time.perf_counter() - t)

    def format_coord(self, x: float, y: float) -> str:
        """The hover text: ``(beta1, beta2)`` in units of pi and the layer's value there."""
        text = f"beta1 = {x / math.pi:.4f} pi, beta2 = {y / math.pi:.4f} pi"
        ex = self.explorer
        if ex is None or ex.ds is None or not (0 <= x < 2 * math.pi and 0 <= y < 2 * math.pi):
            return text
        name = ex.params["layer"]
        da = ex.ds[name]
        at = {}
        for dim, v in (("beta1", x), ("beta2", y)):
            if dim in da.dims:
                at[dim] = min(int(v / (2 * math.pi) * da.sizes[dim]), da.sizes[dim] - 1)
        return f"{text} | {name}: {value_label(name, da.isel(at).values, ex.ds)}"

    def hover_text(self) -> str | None:
        """:meth:`format_coord` at the pointer's last map point (``None`` if it is off the map)."""
        return None if self.hover_at is None else self.format_coord(*self.hover_at)

    def _layer_handles(self, ex: Explorer) -> list:
        from matplotlib.patches import Patch

        return [
            Patch(facecolor=c, edgecolor="0.5", label=lbl)
            for c, lbl in legend_entries(ex.params["layer"], ex.ds)
        ]

    def _draw_certified(self, ex: Explorer) -> list:
        """The certified boundary curves of the slice (SS black, II blue, on a white stroke) and
        the codimension-2 points (yellow diamonds), or a "computing" legend entry while they are
        computed; returns the legend handles."""
        from matplotlib import patheffects
        from matplotlib.lines import Line2D

        for a in self.certified:
            a.remove()
        self.certified = []
        if "certified boundaries" not in ex.params["overlays"]:
            return []
        b = ex.boundaries()
        if b is None:
            return [Line2D([], [], color="0.5", ls=":", label="certified boundaries: computing")]
        stroke = [patheffects.withStroke(linewidth=3, foreground="white")]
        colors = {**_CURVE_COLORS, **{f: _REGION_COLOR for f in box_layers()}}
        for c in b.curves:
            if c.field in colors and len(c.vertices):
                v = c.vertices
                self.certified += self.ax.plot(
                    v[:, 0], v[:, 1], color=colors[c.field], lw=1.3, path_effects=stroke
                )
        if is_box_layer(ex.params["layer"]):
            return [Line2D([], [], color=_REGION_COLOR, lw=1.3, label="certified region boundary")]
        pts = np.array([(p.beta1, p.beta2) for p in b.points]).reshape(-1, 2)
        if len(pts):
            self.certified.append(
                self.ax.scatter(
                    pts[:, 0], pts[:, 1], marker="D", s=22, fc="yellow", ec="k", lw=0.8, zorder=4
                )
            )
        return [
            Line2D([], [], color=col, lw=1.3, label=f"certified {f} boundary")
            for f, col in _CURVE_COLORS.items()
        ] + [Line2D([], [], ls="", marker="D", mfc="yellow", mec="k", label="codim-2 point")]

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
