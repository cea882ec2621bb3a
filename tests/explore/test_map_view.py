"""The widget's map figure (:class:`atlas.explore.map_view.MapView`) on an Agg canvas: the marker
is visible on every colour a layer can have; the hover text gives the point in units of pi and
the layer's value there."""

from __future__ import annotations

import math

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.colors import to_rgba
from matplotlib.figure import Figure

from atlas.explore import colors, maps
from atlas.explore.map_view import FIGSIZE, MapView
from atlas.explore.state import Explorer

POINT = (0.8 * math.pi, 1.1 * math.pi)


def _canvas(view: MapView) -> np.ndarray:
    view.fig.canvas.draw()
    return np.asarray(view.fig.canvas.buffer_rgba(), dtype=float)[..., :3] / 255


def _every_layer_colour() -> set:
    out = set()
    for name in maps.layers():
        if name in ("margin_SS", "spectral_abscissa"):
            out |= {to_rgba(c) for c in ("#053061", "#f7f7f7", "#67001f")}  # RdBu_r: ends, centre
        else:
            out |= {to_rgba(c) for c in colors._category_colors(name).values()}
    return out


def test_marker_visible_on_every_colour():
    """On a map of one colour, the marker changes >= 40 pixels by >= 0.5 in some channel (a
    marker of one colour vanishes on a cell of about that colour).  The figure is the widget's
    at a quarter of its size and the same dpi: the marker has the same size in pixels (sizes
    are in points), 16 times fewer pixels are drawn 352 times (at least 62 changed pixels at
    the full size, 69 here, where the marker falls at another sub-pixel offset)."""
    fig = Figure(figsize=(FIGSIZE[0] / 4, FIGSIZE[1] / 4))
    FigureCanvasAgg(fig)
    view = MapView(fig.add_subplot())
    for a in view.lines:
        a.set_visible(False)
    view.ax.set_axis_off()  # ticks and labels lie outside the map: the same marker pixels, half the drawing
    for rgba in sorted(_every_layer_colour()):
        view.im.set_data(np.tile(np.array(rgba), (4, 4, 1)))
        view.marker.set_data([], [])
        without = _canvas(view)
        view.marker.set_data([POINT[0]], [POINT[1]])
        with_marker = _canvas(view)
        changed = np.abs(with_marker - without).max(axis=-1) >= 0.5
        assert changed.sum() >= 40, (rgba, changed.sum())


def test_hover_text_in_units_of_pi_with_the_value():
    ex = Explorer(n=33, layer="class_code", kappa=0.5)
    ex.update()
    fig = Figure(figsize=FIGSIZE)
    FigureCanvasAgg(fig)
    view = MapView(fig.add_subplot())
    view.render(ex)
    x, y = POINT
    text = view.format_coord(x, y)
    i, j = int(x / (2 * math.pi / 33)), int(y / (2 * math.pi / 33))  # the cell holding (x, y)
    code = int(ex.ds["class_code"].values[i, j])
    assert text == f"beta1 = 0.8000 pi, beta2 = 1.1000 pi | class_code: class {code}"
    ex.update(layer="stable_SF")  # one-dimensional: beta1 only
    assert view.format_coord(x, y).endswith(
        "stable_SF: " + ("true" if ex.ds["stable_SF"].values[i] else "false")
    )
