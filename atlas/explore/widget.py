"""The notebook widget: ipywidgets controls wired to an :class:`~atlas.explore.state.Explorer`
(ipywidgets and matplotlib are imported by :func:`make_widget` only; clicking the map needs ipympl,
the ``notebook`` extra)."""

from __future__ import annotations

import io
import math
import time

from atlas.explore.inspector import format_inspection
from atlas.explore.map_view import MapView
from atlas.explore.maps import LAYERS
from atlas.explore.state import LIVE_MAX_RESOLVE, OVERLAYS, Explorer

__all__ = ["make_widget", "RESOLUTIONS"]

#: resolutions offered by the widget (odd: no cell centre on beta2 = beta1 + pi)
RESOLUTIONS = (65, 129, 257, 513, 1025)

_STYLE = {"description_width": "80px"}
#: controls whose change redraws the map, in the order shown
_WATCHED = ("kappa", "separate", "q", "q1", "q2", "alpha", "n", "layer", "overlays")
_HINT = "<pre>click the map or enter beta1, beta2 and press 'inspect point'</pre>"


def _slider(W, name, value, lo, hi, step, desc=None, fmt=".3g"):
    return W.FloatSlider(
        value=value,
        min=lo,
        max=hi,
        step=step,
        description=desc or name,
        readout_format=fmt,
        continuous_update=False,  # one redraw per move, not a queue of them while dragging
        style=_STYLE,
    )


def _model_controls(W, p: dict) -> dict:
    """kappa (log slider), q or q1 and q2, alpha / pi."""
    return {
        "kappa": W.FloatLogSlider(
            value=p["kappa"],
            base=10,
            min=-3,
            max=3,
            step=0.05,
            description="kappa",
            readout_format=".3g",
            continuous_update=False,
            style=_STYLE,
        ),
        "separate": W.Checkbox(value=p["q1"] != p["q2"], description="q1, q2 separately"),
        "q": _slider(W, "q", p["q1"], 0.0, 5.0, 0.01),
        "q1": _slider(W, "q1", p["q1"], 0.0, 5.0, 0.01),
        "q2": _slider(W, "q2", p["q2"], 0.0, 5.0, 0.01),
        "alpha": _slider(W, "alpha", p["alpha"] / math.pi, 0.0, 2.0, 0.005, "alpha / pi", ".3f"),
    }


def _map_controls(W, p: dict) -> dict:
    """Resolution, layer, overlays, exact settlements per redraw, "settle undecided"."""
    return {
        "n": W.Dropdown(
            options=sorted(set(RESOLUTIONS) | {p["n"]}),
            value=p["n"],
            description="resolution",
            style=_STYLE,
        ),
        "layer": W.Dropdown(
            options=list(LAYERS), value=p["layer"], description="layer", style=_STYLE
        ),
        "overlays": W.SelectMultiple(
            options=list(OVERLAYS),
            value=tuple(p["overlays"]),
            rows=len(OVERLAYS),
            description="overlays",
            style=_STYLE,
        ),
        "max_resolve": W.BoundedIntText(
            value=LIVE_MAX_RESOLVE if p["max_resolve"] is None else int(p["max_resolve"]),
            min=0,
            max=10**9,
            description="exact / redraw",
            style=_STYLE,
        ),
        "settle": W.Button(description="settle undecided"),
    }


def _point_controls(W) -> dict:
    """beta1 / pi, beta2 / pi and "inspect point"."""
    return {
        "beta1": W.FloatText(value=0.25, description="beta1 / pi", style=_STYLE),
        "beta2": W.FloatText(value=0.75, description="beta2 / pi", style=_STYLE),
        "inspect": W.Button(description="inspect point"),
    }


def _map_figure(W):
    """The map's figure and view, and the widget that shows it: the canvas itself on an
    interactive backend (ipympl), else a PNG image.  Returns ``(fig, view, shown, image)``."""
    import matplotlib
    import matplotlib.pyplot as plt

    backend = matplotlib.get_backend()
    interactive = "ipympl" in backend or "widget" in backend
    with plt.ioff():  # shown inside the box, not a second time at the end of the cell
        fig, ax = plt.subplots(figsize=(5.6, 5.6))
    view = MapView(ax)
    if interactive:
        fig.canvas.header_visible = False
        return fig, view, fig.canvas, None
    plt.close(fig)
    image = W.Image(format="png")
    return fig, view, image, image


class _Callbacks:
    """The widget's callbacks: a control moved, "settle undecided", "inspect point", a click."""

    def __init__(self, ex: Explorer, ctl: dict, view: MapView, image, status, inspector):
        self.ex, self.ctl, self.view = ex, ctl, view
        self.fig, self.ax = view.fig, view.ax
        self.image, self.status, self.inspector = image, status, inspector

    def draw(self):
        t = time.perf_counter()
        if self.image is None:
            self.fig.canvas.draw_idle()
        else:
            buf = io.BytesIO()
            self.fig.savefig(buf, format="png", dpi=80)
            self.image.value = buf.getvalue()
        self.ex.timings["draw_ms"] = 1e3 * (time.perf_counter() - t)

    def render(self):
        self.view.render(self.ex)
        self.draw()
        self.status.value = f"<tt>{self.ex.status()}, draw {self.ex.timings['draw_ms']:.0f} ms</tt>"

    def model_changes(self) -> dict:
        """The Explorer's parameters as the controls show them."""
        ctl = self.ctl
        sep = ctl["separate"].value
        q1 = ctl["q1"].value if sep else ctl["q"].value
        q2 = ctl["q2"].value if sep else ctl["q"].value
        return dict(
            kappa=float(ctl["kappa"].value),
            q1=float(q1),
            q2=float(q2),
            alpha=float(ctl["alpha"].value) * math.pi,
            n=int(ctl["n"].value),
            layer=ctl["layer"].value,
            overlays=tuple(ctl["overlays"].value),
            max_resolve=int(ctl["max_resolve"].value),
        )

    def on_change(self, _change=None):
        sep = self.ctl["separate"].value
        self.ctl["q"].layout.display = "none" if sep else None
        self.ctl["q1"].layout.display = None if sep else "none"
        self.ctl["q2"].layout.display = None if sep else "none"
        self.ex.update(**self.model_changes())
        self.render()
        if self.ex.point is not None:
            self.show_point(*self.ex.point)

    def on_settle(self, _b=None):
        self.ex.settle()
        self.render()

    def show_point(self, b1, b2):
        info = self.ex.inspect(b1, b2)
        self.inspector.value = "<pre>" + format_inspection(info) + "</pre>"
        self.view.marker.set_data([self.ex.point[0]], [self.ex.point[1]])
        self.draw()

    def on_inspect(self, _b=None):
        self.show_point(self.ctl["beta1"].value * math.pi, self.ctl["beta2"].value * math.pi)

    def on_click(self, event):
        """``button_press_event`` handler: inspect the clicked ``(beta1, beta2)``."""
        toolbar = getattr(self.fig.canvas, "toolbar", None)
        if getattr(toolbar, "mode", "") != "":  # pan / zoom in progress
            return
        if event.inaxes is not self.ax or event.xdata is None or event.ydata is None:
            return
        self.ctl["beta1"].value = round(event.xdata / math.pi, 6)
        self.ctl["beta2"].value = round(event.ydata / math.pi, 6)
        self.show_point(event.xdata, event.ydata)

    def connect(self) -> int:
        """Observe the controls and the canvas; returns the click handler's connection id."""
        for key in _WATCHED + ("max_resolve",):
            self.ctl[key].observe(self.on_change, names="value")
        self.ctl["inspect"].on_click(self.on_inspect)
        self.ctl["settle"].on_click(self.on_settle)
        # connected on every backend; only interactive canvases (ipympl) deliver clicks from a
        # browser.  A function, not the bound method: matplotlib holds bound methods weakly.
        return self.fig.canvas.mpl_connect("button_press_event", lambda e: self.on_click(e))


def make_widget(explorer: Explorer | None = None, **initial):
    """An ipywidgets UI over :class:`Explorer`: kappa (log slider), q or q1 and q2, alpha,
    resolution, layer, overlays, exact settlements per redraw and a "settle undecided" button;
    the map redraws on every change; clicking the map fills the point inspector (needs an
    interactive matplotlib backend: ``%matplotlib widget`` with ipympl, the ``notebook`` extra),
    as does entering beta1, beta2 and pressing "inspect point".

    Returns an ``ipywidgets.VBox``; its ``explorer`` attribute is the :class:`Explorer`,
    ``controls`` the dict of control widgets, ``figure`` the map's figure (its canvas has the
    click handler connected to ``button_press_event``) and ``callbacks`` the callbacks.
    """
    import ipywidgets as W

    ex = explorer or Explorer(**initial)
    ctl = {**_model_controls(W, ex.params), **_map_controls(W, ex.params), **_point_controls(W)}
    status, inspector = W.HTML(), W.HTML(_HINT)
    fig, view, shown, image = _map_figure(W)
    cb = _Callbacks(ex, ctl, view, image, status, inspector)
    cid = cb.connect()
    cb.on_change()
    controls = W.VBox([ctl[k] for k in _WATCHED + ("max_resolve", "settle")])
    point = W.HBox([ctl["beta1"], ctl["beta2"], ctl["inspect"]])
    box = W.VBox([W.HBox([controls, shown]), status, point, inspector])
    box.explorer = ex
    box.controls = ctl
    box.figure = fig
    box.inspector = inspector
    box.click_cid = cid
    box.callbacks = {
        "change": cb.on_change,
        "inspect": cb.on_inspect,
        "click": cb.on_click,
        "settle": cb.on_settle,
    }
    return box
