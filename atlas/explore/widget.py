"""The notebook widget: ipywidgets controls wired to an :class:`~atlas.explore.state.Explorer`
(ipywidgets and matplotlib are imported by :func:`make_widget` only; clicking the map needs ipympl,
the ``notebook`` extra)."""

from __future__ import annotations

import contextlib
import html
import io
import math
import threading
import time
import traceback

from atlas.explore.inspector import format_inspection
from atlas.explore.map_view import FIGSIZE, MapView
from atlas.explore.maps import map_layers
from atlas.explore.state import LIVE_MAX_RESOLVE, OVERLAYS, Explorer

__all__ = ["make_widget", "RESOLUTIONS"]

#: resolutions offered by the widget (odd: no cell centre on beta2 = beta1 + pi)
RESOLUTIONS = (65, 129, 257, 513, 1025)
#: one step of the kappa slider, in log10 kappa: kappa x 1.023 (the arrow keys move one step)
KAPPA_LOG_STEP = 0.01

_STYLE = {"description_width": "100px"}
#: the controls' column: sliders wide enough to aim (log10 kappa: ~0.025 decades a pixel)
_WIDTH = "400px"
#: controls whose change redraws the map through :meth:`_Callbacks.on_change`
_WATCHED = ("kappa", "q", "q1", "q2", "alpha", "n", "layer", "model_box", "overlays")
_WATCHED += ("max_resolve",)
#: the controls, in the order shown
_SHOWN = ("log10_kappa", "kappa", "separate", "q", "q1", "q2", "alpha", "n", "layer", "model_box")
_SHOWN += ("overlays", "max_resolve", "settle")
#: put before the inspector's text when an inspection failed: it still describes the last point
_FAILED = "<pre style='color:#b00020'>(the last inspection failed, see the status line; below: the point before)\n"
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
        layout={"width": _WIDTH},
    )


def _model_controls(W, p: dict) -> dict:
    """kappa (a slider in log10 kappa and a text box with the exact value), q or q1 and q2,
    alpha / pi."""
    return {
        "log10_kappa": _slider(
            W,
            "log10_kappa",
            math.log10(p["kappa"]),
            -3.0,
            3.0,
            KAPPA_LOG_STEP,
            "log10 kappa",
            ".2f",
        ),
        "kappa": W.FloatText(value=p["kappa"], description="kappa", style=_STYLE),
        "separate": W.Checkbox(
            value=p["q1"] != p["q2"], description="q1, q2 separately", indent=False
        ),
        "q": _slider(W, "q", p["q1"], 0.0, 5.0, 0.01),
        "q1": _slider(W, "q1", p["q1"], 0.0, 5.0, 0.01),
        "q2": _slider(W, "q2", p["q2"], 0.0, 5.0, 0.01),
        "alpha": _slider(W, "alpha", p["alpha"] / math.pi, 0.0, 2.0, 0.005, "alpha / pi", ".3f"),
    }


def _map_controls(W, p: dict) -> dict:
    """Resolution, layer, model box (of the box layers), overlays, exact settlements per redraw,
    "settle undecided"."""
    return {
        "n": W.Dropdown(
            options=sorted(set(RESOLUTIONS) | {p["n"]}),
            value=p["n"],
            description="resolution",
            style=_STYLE,
        ),
        "layer": W.Dropdown(
            options=list(map_layers()), value=p["layer"], description="layer", style=_STYLE
        ),
        "model_box": W.Text(
            value=p["model_box"],
            description="model box",
            continuous_update=False,  # applied on Enter, not at every key
            style=_STYLE,
            layout={"width": _WIDTH},
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
        fig, ax = plt.subplots(figsize=FIGSIZE)
    view = MapView(ax)
    if interactive:
        fig.canvas.header_visible = False
        fig.canvas.toolbar_position = "top"  # over the title margin, not over the tick labels
        return fig, view, fig.canvas, None
    plt.close(fig)
    image = W.Image(format="png")
    return fig, view, image, image


class _Callbacks:
    """The widget's callbacks: a control moved, "settle undecided", "inspect point", a click.

    A bad value (``ValueError``, e.g. kappa <= 0) shows its one-line message in the status line;
    any other error shows its traceback there and in the widget's output area ``log`` (and is
    re-raised: the kernel's log), not only in the kernel's log."""

    def __init__(self, ex: Explorer, ctl: dict, view: MapView, image, status, inspector):
        self.ex, self.ctl, self.view = ex, ctl, view
        self.fig, self.ax = view.fig, view.ax
        self.image, self.status, self.inspector = image, status, inspector
        self.log = None  # an ipywidgets Output: the tracebacks of the callbacks
        self._quiet = False  # set while a callback moves other controls
        self._requested = None  # perf_counter of a canvas draw requested and not yet done
        self._note = ""
        self._draws = 0  # canvas draws done (ipympl)
        self._lock = threading.RLock()  # the boundaries' worker thread redraws too
        self._busy = False  # the status line says what is being computed (busy)
        self._ticker = None  # the timer counting the certified boundaries' seconds

    @contextlib.contextmanager
    def quiet(self):
        """Move controls without their callbacks redrawing."""
        self._quiet = True
        try:
            yield
        finally:
            self._quiet = False

    def guarded(self, fn):
        """``fn`` with its errors shown in the status line."""

        def run(*args):
            try:
                return fn(*args)
            except ValueError as e:
                self.status.value = f"<tt style='color:#b00020'>{html.escape(str(e))}</tt>"
            except Exception:
                tb = traceback.format_exc()
                self.status.value = f"<pre style='color:#b00020'>{html.escape(tb)}</pre>"
                if self.log is not None:
                    self.log.append_stderr(tb)
                raise

        return run

    def draw(self):
        """Request the canvas draw (ipympl: drawn when the browser asks, see :meth:`on_drawn`) or
        draw the PNG image."""
        if self.image is None:
            self._requested = time.perf_counter()
            self.fig.canvas.draw_idle()
        else:
            t = time.perf_counter()
            buf = io.BytesIO()
            self.fig.savefig(buf, format="png", dpi=80)
            self.image.value = buf.getvalue()
            self.ex.timings["draw_ms"] = 1e3 * (time.perf_counter() - t)

    def on_drawn(self, _event=None):
        """``draw_event``: the requested canvas draw is done (ipympl sends the image next)."""
        if self._requested is None:
            return
        self.ex.timings["draw_ms"] = 1e3 * (time.perf_counter() - self._requested)
        self._requested = None
        self._draws += 1
        self.show_status()

    def busy(self, text: str):
        """Say what the session is doing now (sent to the browser at once)."""
        self._busy = True
        self.status.value = f"<tt>working -- {html.escape(text, quote=False)} ...</tt>"

    def boundaries_note(self) -> str:
        """While the certified boundaries are computed: what and for how long (else the note
        of the last map)."""
        pending = self.ex.boundaries_pending()
        if pending is None:
            return self._note
        seconds, first = pending
        what = " (the first: compiling or loading its kernels)" if first else ""
        return f", working -- certified boundaries{what}: {seconds:.0f} s ..."

    def tick(self):
        """While the certified boundaries are computed, refresh the status line every second
        (their seconds count up) unless a computation's step is shown."""
        if self.ex.boundaries_pending() is None or self._ticker is not None:
            return

        def tock():
            self._ticker = None
            with self._lock:
                if not self._busy and self.ex.boundaries_pending() is not None:
                    self.show_status()

        self._ticker = threading.Timer(1.0, tock)
        self._ticker.daemon = True
        self._ticker.start()

    def show_status(self):
        if self._requested is not None:
            drawn = "drawing in the browser"
        elif self._draws <= 1 and self.image is None:
            # the first draw waits until the browser shows the widget (after Run All: until the
            # notebook's later cells ran), its time says nothing about drawing
            drawn = "drawn"
        else:
            drawn = f"repaint {self.ex.timings.get('draw_ms', float('nan')):.0f} ms"
        self._busy = False
        note = html.escape(self.boundaries_note(), quote=False)
        self.status.value = f"<tt>{html.escape(self.ex.status(), quote=False)}, {drawn}{note}</tt>"
        self.tick()

    def render(self):
        with self._lock:
            self.view.render(self.ex)
            self.draw()
            self.refresh_hover()
            self.show_status()

    def on_move(self, event):
        """``motion_notify_event``: remember the pointer's map point for :meth:`refresh_hover`."""
        inside = getattr(event, "inaxes", None) is self.ax and event.xdata is not None
        self.view.hover_at = (event.xdata, event.ydata) if inside else None

    def refresh_hover(self):
        """The hover text for the new layer at the pointer's last map point (ipympl shows the
        toolbar's message only on mouse moves otherwise)."""
        toolbar = getattr(self.fig.canvas, "toolbar", None)
        text = self.view.hover_text()
        if text is not None and hasattr(toolbar, "set_message"):
            toolbar.set_message(text)

    def on_boundaries(self, key):
        """The certified boundaries of ``key`` (a slice, or a box layer's box) are ready (worker
        thread): redraw if they are still the ones shown."""
        if key == self.ex.boundary_key():
            self._note = f", certified boundaries {self.ex.timings['boundaries_ms']:.0f} ms"
            self.render()

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
            model_box=ctl["model_box"].value,
            overlays=tuple(ctl["overlays"].value),
            max_resolve=int(ctl["max_resolve"].value),
        )

    def show_q(self):
        sep = self.ctl["separate"].value
        self.ctl["q"].layout.display = "none" if sep else None
        self.ctl["q1"].layout.display = None if sep else "none"
        self.ctl["q2"].layout.display = None if sep else "none"

    def on_change(self, _change=None):
        if self._quiet:
            return
        self.show_q()
        kappa = float(self.ctl["kappa"].value)
        if kappa > 0 and math.isfinite(kappa):
            with self.quiet():
                self.ctl["log10_kappa"].value = math.log10(kappa)
        self.busy("updating the map")
        self.ex.update(**self.model_changes())
        self._note = ""
        self.render()
        if self.ex.point is not None:
            self.show_point(*self.ex.point)

    def on_log_kappa(self, change):
        """The log10 kappa slider moved: the text box shows kappa to 4 digits."""
        if self._quiet:
            return
        with self.quiet():
            self.ctl["kappa"].value = float(f"{10 ** change['new']:.4g}")
        self.on_change()

    def on_separate(self, change):
        """q1, q2 start from q (ticked); q takes q1 (unticked): the model does not jump."""
        c = self.ctl
        with self.quiet():
            if change["new"]:
                c["q1"].value = c["q2"].value = c["q"].value
            else:
                c["q"].value = c["q1"].value
        self.on_change()

    def on_settle(self, _b=None):
        self.ex.settle()
        self.view.render(self.ex)
        self.draw()
        self._note = f", settled in {self.ex.timings['settle_ms']:.0f} ms"
        self.show_status()

    def show_point(self, b1, b2):
        """Inspect ``(b1, b2)`` [rad] and show it: the inspector's text, the beta fields and the
        marker change together, after the inspection succeeded (an error leaves all three on the
        previous point and says so in the inspector)."""
        try:
            info = self.ex.inspect(b1, b2)
        except Exception:
            self.inspector.value = self.inspector.value.replace("<pre>", _FAILED, 1)
            raise
        text = "\n".join([format_inspection(info), *self.ex.last_near])
        self.inspector.value = "<pre>" + html.escape(text, quote=False) + "</pre>"
        b1, b2 = self.ex.point
        self.ctl["beta1"].value = round(b1 / math.pi, 6)
        self.ctl["beta2"].value = round(b2 / math.pi, 6)
        with self._lock:
            self.view.marker.set_data([b1], [b2])
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
        self.show_point(event.xdata, event.ydata)

    def connect(self) -> int:
        """Observe the controls and the canvas; returns the click handler's connection id."""
        g = self.guarded
        for key in _WATCHED:
            self.ctl[key].observe(g(self.on_change), names="value")
        self.ctl["log10_kappa"].observe(g(self.on_log_kappa), names="value")
        self.ctl["separate"].observe(g(self.on_separate), names="value")
        self.ctl["inspect"].on_click(g(self.on_inspect))
        self.ctl["settle"].on_click(g(self.on_settle))
        canvas = self.fig.canvas
        canvas.mpl_connect("draw_event", g(self.on_drawn))
        canvas.mpl_connect("motion_notify_event", g(self.on_move))
        canvas.mpl_connect("figure_leave_event", g(self.on_move))
        self.ex.on_progress = self.busy
        self.ex.on_boundaries = g(self.on_boundaries)
        # connected on every backend; only interactive canvases (ipympl) deliver clicks from a
        # browser.  A function, not the bound method: matplotlib holds bound methods weakly.
        return canvas.mpl_connect("button_press_event", g(self.on_click))


def make_widget(explorer: Explorer | None = None, **initial):
    """An ipywidgets UI over :class:`Explorer`: kappa (a log10 slider and a text box), q or q1 and q2, alpha,
    resolution, layer, overlays, exact settlements per redraw and a "settle undecided" button;
    the map redraws on every change; clicking the map fills the point inspector (needs an
    interactive matplotlib backend: ``%matplotlib widget`` with ipympl, the ``notebook`` extra),
    as does entering beta1, beta2 and pressing "inspect point".  The box layers
    (``ss_over_models`` ...) are drawn over the "model box" text (``kappa=0.01:100,q1=0:1,q2=0:1``,
    applied on Enter); a click on one shows the verdict there and its witness models.  The kernels are kept for the
    process (:func:`~atlas.explore.state.keep_kernels`); the inspector's compile in the
    background once the first map is drawn (:meth:`Explorer.warm_up`).

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
    cb.log = W.Output()
    cb.log.add_class("atlas-log")
    cid = cb.connect()
    cb.on_change()  # a bad initial value raises
    ex.warm_up()  # the inspector's kernels, in the background: the first click does not compile
    for key, c in ctl.items():  # names for the page's CSS and the browser test
        c.add_class(f"atlas-{key.replace('_', '-')}")
    status.add_class("atlas-status")
    inspector.add_class("atlas-inspector")
    controls = W.VBox([ctl[k] for k in _SHOWN], layout={"width": _WIDTH, "flex": "0 0 auto"})
    # controls beside the map in a wide column, above it in a narrow one (no sideways scroll)
    row = W.HBox([controls, shown], layout={"flex_flow": "row wrap", "max_width": "100%"})
    point = W.HBox([ctl["beta1"], ctl["beta2"], ctl["inspect"]], layout={"flex_flow": "row wrap"})
    box = W.VBox([row, status, point, inspector, cb.log], layout={"max_width": "100%"})
    box.add_class("atlas-explorer")
    box.explorer = ex
    box.controls = ctl
    box.figure = fig
    box.inspector = inspector
    box.click_cid = cid
    box.status = status
    box.errors = cb.log  # the callbacks' tracebacks (an Output)
    box.callbacks = {
        "change": cb.on_change,
        "inspect": cb.on_inspect,
        "click": cb.on_click,
        "settle": cb.on_settle,
    }
    return box
