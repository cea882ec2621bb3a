"""The notebook widget (:func:`atlas.explore.make_widget`): its redraw callback computes exactly the
arrays :func:`atlas.data.engine.generate` stores for the same parameters; clicks inspect points;
redraws are capped and "settle undecided" settles; overlays draw the SS boundary."""

from __future__ import annotations

import html
import json
import math
import re
import subprocess
import sys
import time
from concurrent.futures import Future

import numpy as np
import pytest
from matplotlib.backend_bases import MouseEvent
from matplotlib.colors import to_rgba
from scipy.interpolate import RegularGridInterpolator

from atlas.core import exact
from atlas.core.brackets import FIELD_LABELS
from atlas.core.contact_modes import direction
from atlas.core.verdicts import Verdict
from atlas.data.engine import generate
from atlas.data.scene import Scene
from atlas.explore import inspector, maps, state, widget

N = 65
ALPHA = 0.35 * math.pi


@pytest.fixture(autouse=True)
def no_warm_up(request, monkeypatch):
    """The widget's background warm-up (one inspection, compiling the inspector's kernels once
    the first map is drawn) left out of this module's in-process tests, as if it had ended: none
    is about it, and one still running when its test ends ran on through the next tests or the
    worker's exit (~7 s CPU over the module).  Its claims keep it: the order against a first
    overlay (test_state) and a first session's click that does not compile (the e2e tests here,
    in fresh processes)."""
    if request.node.get_closest_marker("e2e"):
        return

    def warm_up(self):
        if self._warm is None:
            self._warm = Future()
            self._warm.set_result(None)
            self._inspector_ready.set()
        return self._warm

    monkeypatch.setattr(state.Explorer, "warm_up", warm_up)


@pytest.fixture
def drawn(monkeypatch):
    """The layers the widget's PNG draws showed, one per draw, the PNG itself not made (most
    of a redraw's seconds): for the tests of what a redraw computes, shows in its controls and
    status, or answers to a click; the overlay, title, legend and witness tests draw it."""
    layers = []
    draw = widget._Callbacks.draw

    def counted(cb):
        if cb.image is None:  # the interactive canvas's path: as it is
            return draw(cb)
        layers.append(cb.ex.params["layer"])

    monkeypatch.setattr(widget._Callbacks, "draw", counted)
    return layers


@pytest.mark.parametrize(
    "kappa, q1, q2",
    [(0.5, 0.0, 0.0), (2.0, 0.3, 0.3), (0.5, 1.0, 0.01)],
    ids=["fig1", "damped", "q1-neq-q2"],
)
def test_widget_map_equals_generate(kappa, q1, q2, need, drawn):
    """Every control change reaches the map through the redraw callback, which then draws."""
    need("ipywidgets")
    box = widget.make_widget(n=N, layer="class_code", alpha=ALPHA)
    c, ex = box.controls, box.explorer
    c["kappa"].value = kappa
    if q1 == q2:
        c["q"].value = q1
    else:
        c["separate"].value = True
        c["q1"].value, c["q2"].value = q1, q2
    c["alpha"].value = ALPHA / math.pi
    assert (ex.params["kappa"], ex.params["q1"], ex.params["q2"]) == (kappa, q1, q2)

    beta = maps.beta_grid(N)
    model = dict(q=q1) if q1 == q2 else dict(q1=q1, q2=q2)
    layers = [k for k in maps.layers() if k != "margin_SS"]
    ref = generate(
        Scene(
            beta1=beta, beta2=beta, alpha=ex.params["alpha"], kappa=kappa, outputs=layers, **model
        )
    )
    for layer in layers:
        c["layer"].value = layer  # the redraw callback
        got = ex.ds[layer]
        want = ref[layer]
        assert got.dims == want.dims, layer
        assert got.dtype == want.dtype, layer
        np.testing.assert_array_equal(got["beta1" if "beta1" in got.dims else "beta2"].values, beta)
        if layer == "spectral_abscissa":  # float, not certified: different root finders agree
            np.testing.assert_allclose(got.values, want.values, rtol=1e-9, atol=1e-12)
        else:
            np.testing.assert_array_equal(got.values, want.values, err_msg=layer)
        assert drawn[-1] == layer, layer  # the callback drew the new layer
    assert ex.ds.attrs["n_undecided"] == 0


def _click(box, beta1, beta2, button=1):
    """Deliver a synthetic left click at data point ``(beta1, beta2)`` through the canvas's
    ``button_press_event`` callbacks (what ipympl does for a click in the browser)."""

    fig = box.figure
    ax = fig.axes[0]
    x, y = ax.transData.transform((beta1, beta2))
    event = MouseEvent("button_press_event", fig.canvas, x, y, button=button)
    fig.canvas.callbacks.process("button_press_event", event)
    return event


def test_click_on_map_inspects_that_point(need, drawn):
    need("ipywidgets")
    kappa, q = 0.5, 2**0.5
    box = widget.make_widget(n=N, layer="stable_II", kappa=kappa, q1=q, alpha=ALPHA)
    ex, c = box.explorer, box.controls
    assert ex.point is None
    # a click outside the axes (in the figure margin) does nothing
    _click(box, -0.5, 1.0)
    assert ex.point is None and ex.last_inspection is None

    seen = set()
    for b1, b2 in ((0.15 * math.pi, 1.07 * math.pi), (0.6, 4.0), (5.5, 2.2), (3.0, 0.4)):
        event = _click(box, b1, b2)
        assert event.inaxes is box.figure.axes[0]
        info = ex.last_inspection
        assert info is not None
        np.testing.assert_allclose(ex.point, (b1, b2), atol=1e-9)
        assert (info["beta1"], info["beta2"]) == ex.point
        np.testing.assert_allclose(
            (c["beta1"].value, c["beta2"].value), (b1 / math.pi, b2 / math.pi), atol=1e-6
        )
        assert inspector.format_inspection(info) in box.inspector.value
        # truth: the exact reference at the clicked point, directions from numpy
        d = [np.cos(ex.point[0]), np.sin(ex.point[0]), np.cos(ex.point[1]), np.sin(ex.point[1])]
        ref = exact.point_spectral(*d, kappa, q, q)
        codes = exact.point_codes(*d, np.cos(ALPHA), np.sin(ALPHA))
        for k in ("stable_SS", "consistent_II", "stable_II"):
            assert info["spectral"][k] == int(ref[k]), (b1, b2, k)
        assert info["class_code"] == codes["class_code"]
        assert info["subclass_code"] == codes["subclass_code"]
        np.testing.assert_allclose(
            np.sort_complex(info["eigenvalues"]),
            np.sort_complex(np.asarray(ref["roots"], complex)),
            atol=1e-9,
        )
        seen.add(codes["class_code"])
        # the marker sits on the clicked point
        np.testing.assert_allclose(np.ravel(box.figure.axes[0].lines[-1].get_data()), ex.point)
    assert len(seen) >= 3  # the clicks landed in different classes


def test_redraw_capped_then_settle_undecided(need, bounded_det_b, drawn):
    """An even grid puts cells on det B = 0 (undecided with a float-bounded ``sign det B``,
    :func:`bounded_det_b`): a redraw settles at most
    ``max_resolve`` of them and draws the rest in the undecided colour; the "settle undecided"
    button settles all, giving the atlas's map."""
    need("ipywidgets")
    n, cap, kappa, q = 64, 5, 0.5, 0.3
    box = widget.make_widget(n=n, layer="stable_SS", kappa=kappa, q1=q, max_resolve=cap)
    ex = box.explorer
    fast = ex.ds.attrs["n_undecided_fast"]
    assert fast > cap
    assert ex.ds.attrs["n_undecided"] == fast - cap
    undecided = ex.ds["stable_SS"].values == int(Verdict.UNDECIDED)
    assert undecided.sum() == fast - cap
    img = ex.image()
    red = np.all(np.isclose(img, to_rgba(Verdict.UNDECIDED.color)), axis=-1)
    np.testing.assert_array_equal(red, undecided.T)  # image is (beta2, beta1)
    labels = [t.get_text() for t in box.figure.axes[0].get_legend().get_texts()]
    assert Verdict.UNDECIDED.label in labels
    assert "settle undecided" in ex.status()

    box.callbacks["settle"]()
    assert ex.ds.attrs["n_undecided"] == 0
    assert ex.ds.attrs["n_undecided_fast"] == fast
    beta = maps.beta_grid(n)
    ref = generate(Scene(beta1=beta, beta2=beta, kappa=kappa, q=q, outputs=["stable_SS"]))
    np.testing.assert_array_equal(ex.ds["stable_SS"].values, ref["stable_SS"].values)
    labels = [t.get_text() for t in box.figure.axes[0].get_legend().get_texts()]
    assert Verdict.UNDECIDED.label not in labels
    # the next slider move is capped again
    box.controls["kappa"].value = 0.6
    assert ex.ds.attrs["n_undecided"] == max(0, ex.ds.attrs["n_undecided_fast"] - cap)


def test_overlays(need):
    need("ipywidgets")
    box = widget.make_widget(n=N, layer="consistent_II", kappa=0.5, q1=0.3)
    c, ax = box.controls, box.figure.axes[0]
    c["overlays"].value = ("SS boundary",)
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert "SS boundary" in labels
    assert not any(a.get_visible() for a in ax.lines[:-1])  # class boundaries hidden
    # the dashed contour is the zero set of the smooth margin (values at its vertices ~ 0)
    m = maps.compute_map(0.5, 0.3, n=N, layers=("margin_SS",))["margin_SS"]
    f = RegularGridInterpolator((m.beta1.values, m.beta2.values), m.values)
    paths = [p for p in ax.collections[-1].get_paths() if len(p.vertices)]
    assert paths
    v = np.concatenate([p.vertices for p in paths])
    inside = np.all((v > m.beta1.values[0]) & (v < m.beta1.values[-1]), axis=1)
    assert np.abs(f(v[inside])).max() < 1e-9 + 0.05 * np.abs(m.values).max()
    c["overlays"].value = ("class boundaries",)
    assert all(a.get_visible() for a in ax.lines[:-1])
    assert "SS boundary" not in [t.get_text() for t in ax.get_legend().get_texts()]
    with pytest.raises(ValueError, match="overlays"):
        box.explorer.update(overlays=("nope",))


def test_separately_starts_q1_q2_from_q(need, drawn):
    """Ticking "q1, q2 separately" keeps the model: q1 = q2 = the current q; unticking gives q
    the value of q1."""
    need("ipywidgets")
    box = widget.make_widget(n=N, layer="stable_II", kappa=0.5, q1=0.0)
    c, ex = box.controls, box.explorer
    c["q"].value = 1.2
    drawn = ex.ds["stable_II"].values.copy()
    c["separate"].value = True
    assert c["q1"].value == c["q2"].value == 1.2
    assert ex.params["q1"] == ex.params["q2"] == 1.2
    np.testing.assert_array_equal(ex.ds["stable_II"].values, drawn)
    c["q1"].value, c["q2"].value = 0.4, 2.0
    assert (ex.params["q1"], ex.params["q2"]) == (0.4, 2.0)
    c["separate"].value = False
    assert c["q"].value == 0.4 and ex.params["q1"] == ex.params["q2"] == 0.4


def test_kappa_log10_slider_and_text_box(need):
    """The slider moves log10 kappa in steps of 0.01 (x 1.023) over 1e-3 .. 1e3; the text box
    holds kappa exactly; a bad kappa is a one-line message in the status line."""
    need("ipywidgets")
    box = widget.make_widget(n=N, layer="stable_SS", kappa=0.5)
    c, ex = box.controls, box.explorer
    s = c["log10_kappa"]
    assert (s.min, s.max, s.step) == (-3.0, 3.0, 0.01)
    assert s.value == pytest.approx(math.log10(0.5), abs=0.005)
    c["kappa"].value = 2.0
    assert ex.params["kappa"] == 2.0  # exactly the typed value
    assert s.value == pytest.approx(math.log10(2.0), abs=0.005)
    s.value = round(s.value - s.step, 2)  # one step left, as the arrow key moves it
    assert c["kappa"].value == pytest.approx(10**0.29, rel=1e-3)
    assert ex.params["kappa"] == c["kappa"].value
    c["kappa"].value = -1.0
    assert "kappa: must be &gt; 0" in box.status.value and "Traceback" not in box.status.value
    assert ex.params["kappa"] == pytest.approx(10**0.29, rel=1e-3)  # unchanged


def test_status_times_the_repaint_not_the_request(need):
    """On a canvas that draws later (ipympl draws when the browser asks), the status line says
    "drawing in the browser" until the canvas has drawn; the first draw (which waits until the
    browser shows the widget) reads "drawn", later ones the time from the request to the draw."""
    need("ipywidgets")
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    box = widget.make_widget(n=N, layer="stable_SS", kappa=0.5)
    canvas, status = FigureCanvasAgg(box.figure), box.status
    cb = box.callbacks["change"].__self__
    cb.image = None  # the interactive path: draw_idle requests, the canvas draws later
    requested = []
    canvas.draw_idle = lambda: requested.append(1)
    box.controls["kappa"].value = 0.7
    assert requested and "drawing in the browser" in status.value
    canvas.draw()
    assert status.value.endswith(", drawn</tt>") and "repaint" not in status.value
    box.controls["kappa"].value = 0.8
    assert "drawing in the browser" in status.value
    time.sleep(0.05)
    canvas.draw()
    ms = float(re.search(r"repaint (\d+) ms", status.value).group(1))
    assert ms >= 50


def test_status_says_what_the_session_is_doing_before_the_map_arrives(need, drawn):
    """Every value the status line takes during a move to 513^2 cells (with the SS boundary
    overlay): first what is being computed, step by step, then the new map's summary."""
    need("ipywidgets")
    box = widget.make_widget(n=N, layer="stable_SS", kappa=0.5, q1=0.3, overlays=())
    seen = []
    box.status.observe(lambda ch: seen.append(html.unescape(ch["new"])), names="value")
    box.controls["overlays"].value = ("SS boundary",)
    box.controls["n"].value = 513
    assert box.explorer.ds.sizes["beta1"] == 513
    done = next(i for i, s in enumerate(seen) if "513^2 cells: compute" in s)
    before = seen[:done]
    margin = [s for s in before if "step 1 of 2: computing the SS margin on 513^2 cells" in s]
    layer = [s for s in before if "step 2 of 2: " in s and "computing stable_SS on 513^2" in s]
    assert margin and layer, seen
    assert seen.index(margin[0]) < seen.index(layer[0])
    assert all(s.startswith("<tt>working -- ") for s in margin + layer)
    assert not any("513^2 cells: compute" in s for s in before)


def test_hover_text_follows_the_layer(need, drawn):
    """After a layer change the hover readout is rewritten at the pointer's last point (not
    left on the previous layer's value until the mouse moves): the exact class code there."""
    need("ipywidgets")
    from matplotlib.backend_bases import MouseEvent as Event

    box = widget.make_widget(n=N, layer="stable_SS", kappa=0.5)
    fig, messages = box.figure, []
    fig.canvas.toolbar = type("Toolbar", (), {"mode": "", "set_message": messages.append})()
    b1, b2 = 0.4 * math.pi, 1.3 * math.pi
    x, y = fig.axes[0].transData.transform((b1, b2))
    fig.canvas.callbacks.process(
        "motion_notify_event", Event("motion_notify_event", fig.canvas, x, y)
    )
    box.controls["layer"].value = "class_code"
    d = [np.cos(b1), np.sin(b1), np.cos(b2), np.sin(b2)]
    cls = exact.point_codes(*d, np.cos(ALPHA), np.sin(ALPHA))["class_code"]
    assert messages and messages[-1].endswith(f"class_code: class {cls}"), messages


def test_alpha_in_status_and_title_for_the_layers_that_depend_on_it(need):
    need("ipywidgets")
    box = widget.make_widget(n=N, layer="stable_SS", kappa=0.5, alpha=0.35 * math.pi)
    title = box.figure.axes[0].get_title
    assert "alpha" not in box.status.value and "alpha" not in title()
    box.controls["layer"].value = "subclass_code"
    assert "alpha = 0.350 pi" in box.status.value and "alpha = 0.350 π" in title()
    box.controls["alpha"].value = 0.6
    assert "alpha = 0.600 pi" in box.status.value and "alpha = 0.600 π" in title()


def _wait_boundaries(ex):
    """The slice's curves once the background thread has them (a hang is ended by
    pytest-timeout, not by a clock in the test)."""
    while ex.boundaries() is None:
        time.sleep(0.2)
    time.sleep(0.5)  # the worker's redraw
    return ex.boundaries()


def _exact_code(field, point, kappa, q):
    """The field's code at ``point`` from the exact reference (numpy directions)."""
    d = [np.cos(point[0]), np.sin(point[0]), np.cos(point[1]), np.sin(point[1])]
    ref = exact.point_spectral(*d, kappa, q, q)
    if field == "SS":
        return int(ref["stable_SS"])
    return 0 if not ref["consistent_II"] else {1: 2, 0: 1, 2: 3}[int(ref["stable_II"])]


@pytest.mark.slow
def test_certified_boundaries_overlay_and_clicks_near_each_kind(need):
    """The "certified boundaries" overlay: computed in the background (the map shows
    "computing" until then), then drawn as the curves of
    :func:`atlas.data.boundaries.slice_boundaries`.  A click next to a curve of each kind names
    the kind, its vertex's bracket and the codes on its two sides, and the exact code at the
    clicked point is one of them; a click on a codimension-2 point names the point."""
    need("ipywidgets")
    kappa, q = 0.5, 0.3
    box = widget.make_widget(n=N, layer="stable_SS", kappa=kappa, q1=q)
    ex, ax = box.explorer, box.figure.axes[0]
    box.controls["overlays"].value = ("certified boundaries",)
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert "certified boundaries: computing" in labels
    b = _wait_boundaries(ex)
    drawn = [np.column_stack(a.get_data()) for a in ax.lines]
    curves = [c for c in b.curves if c.field != "class"]
    for c in curves:
        assert any(d.shape == c.vertices.shape and np.array_equal(d, c.vertices) for d in drawn)
    kinds = ("SS_stability", "II_consistency", "II_stability")
    for kind in kinds:
        c = max((c for c in curves if c.kind == kind), key=lambda c: len(c.vertices))
        i = len(c.vertices) // 2
        v = c.vertices[i]
        _click(box, v[0] + 1e-6, v[1] - 1e-6)
        text = html.unescape(box.inspector.value)
        lab = FIELD_LABELS[c.field]
        assert f"near the certified {kind} boundary" in text, text
        assert f"bracketed within {c.bracket[i]:.2g} rad" in text
        assert f"{lab[c.side_left]} | {lab[c.side_right]}" in text
        assert lab[_exact_code(c.field, ex.point, kappa, q)] in (
            lab[c.side_left],
            lab[c.side_right],
        )
        assert inspector.format_inspection(ex.last_inspection) in text
        np.testing.assert_allclose(ex.point, (v[0] + 1e-6, v[1] - 1e-6), atol=1e-9)
    p = b.points[0]
    _click(box, p.beta1, p.beta2)
    text = html.unescape(box.inspector.value)
    assert f"on the codimension-2 point '{p.kind}'" in text, text
    assert ("proven within" if p.proven else "no bound claimed") in text
    assert "near the certified" in text  # a point lies on a curve


def test_failed_inspection_leaves_the_widget_on_the_previous_point(need, monkeypatch):
    """An error in the click callback shows in the status line and the inspector says the
    inspection failed; marker, beta fields and inspector text stay on the previous point."""
    need("ipywidgets")
    box = widget.make_widget(n=N, layer="stable_SS", kappa=0.5)
    ex, c, ax = box.explorer, box.controls, box.figure.axes[0]
    _click(box, 1.0, 2.0)
    before = (ex.point, c["beta1"].value, c["beta2"].value, box.inspector.value)
    marker = np.ravel(ax.lines[-1].get_data()).copy()

    def boom(*a, **k):
        raise RuntimeError("inspection failed on purpose")

    monkeypatch.setattr(state, "inspect_point", boom)
    with pytest.raises(RuntimeError):
        _click(box, 4.0, 5.0)
    assert (ex.point, c["beta1"].value, c["beta2"].value) == before[:3]
    np.testing.assert_array_equal(np.ravel(ax.lines[-1].get_data()), marker)
    assert "the last inspection failed" in box.inspector.value
    assert before[3].replace("<pre>", "") in box.inspector.value
    assert "inspection failed on purpose" in box.status.value
    assert any("inspection failed on purpose" in o.get("text", "") for o in box.errors.outputs)


#: a widget in a fresh process: XLA compilations by thread (the main thread: the map while it is
#: made, then a click made at once, during the inspector's warm-up; the warm-up's own thread),
#: counted by jax.monitoring once the warm-up has ended
_START_PROBE = """
import json, threading
import jax
from atlas.core import warm
from atlas.explore import state
from atlas.explore.widget import make_widget

compiles = []
def count(event, seconds, **kw):
    if event.endswith("backend_compile_duration"):
        compiles.append(threading.current_thread() is threading.main_thread())
jax.monitoring.register_event_duration_secs_listener(count)
box = make_widget(n=9, layer="stable_SS", kappa=0.5, q1=0.3)
made, started = sum(compiles), box.explorer._warm is not None
during = started and not box.explorer._warm.done()
box.controls["beta1"].value, box.controls["beta2"].value = 1.3, 0.2
box.callbacks["inspect"]()
assert box.explorer.last_inspection is not None
box.explorer.warm_up().result()  # a click waits for its inspection only: the rest counts here
main = sum(compiles)
out = dict(started=started, during=during, made=made, click=main - made,
           warm_up=len(compiles) - main, used=len(warm._STATE["used"]),
           kept=state.keep_kernels(), cache=jax.config.jax_compilation_cache_dir)
print(json.dumps(out))
"""


@pytest.mark.e2e
def test_widget_keeps_kernels_and_the_first_click_does_not_compile(tmp_path, need, probe_env):
    """A first session (empty cache) compiles the map's kernels and, in the background warm-up,
    the inspector's; a click made at once, during the warm-up, waits for its inspection and
    compiles nothing itself, and no program is compiled twice (as many compilations as kept
    programs); a second session compiles nothing at all (kept kernels).  The sessions keep
    kernels in ``<cache>/kernels`` and use the compilation cache (the explorer's switches with
    none set; the others: tests/explore/test_state.py)."""
    need("ipywidgets")

    def session(cache):
        cmd = [sys.executable, "-c", _START_PROBE]
        p = subprocess.run(cmd, env=probe_env(cache), cwd=tmp_path, stdout=subprocess.PIPE,
                           text=True, timeout=600)  # fmt: skip
        assert p.returncode == 0
        return json.loads(p.stdout.strip().splitlines()[-1])

    first = session(tmp_path / "a")
    assert (first["kept"], first["cache"]) == (str(tmp_path / "a" / "kernels"), str(tmp_path / "a"))
    assert first["started"] and first["during"], first  # the click came before the warm-up ended
    assert first["made"] > 0 and first["warm_up"] > 0 and first["click"] == 0, first
    kept = [p.suffix for p in (tmp_path / "a" / "kernels").iterdir()]
    assert ".txt" in kept  # the session's list
    assert first["made"] + first["warm_up"] == kept.count(".jaxexport"), (first, sorted(kept))
    second = session(tmp_path / "a")
    assert (second["made"], second["warm_up"], second["click"]) == (0, 0, 0), second
    assert second["used"] > 0  # kept executables served it


def test_box_layer_key_model_box_and_witnesses_on_click(need):
    """The ``ss_over_models`` layer in the widget: its colour key names the verdicts over the box
    present on the map (each in its colour), the title and status name the box, the "model box"
    text changes it (a bad one says so in one line and keeps the map), and a click where the
    verdict depends on the model shows the two witness models in the inspector, each on its side
    by the exact reference."""
    need("ipywidgets")
    from atlas.core.verdicts import OverModels

    box = widget.make_widget(n=33, layer="ss_over_models")
    ex, c, ax = box.explorer, box.controls, box.figure.axes[0]
    key = {
        t.get_text(): h.get_facecolor()
        for t, h in zip(ax.get_legend().texts, ax.get_legend().legend_handles)
    }
    want = [
        OverModels.UNSTABLE,
        OverModels.STABLE,
        OverModels.DEPENDS,
    ]  # all on the map, none undecided
    assert list(key) == [v.label for v in want]
    for v in want:
        assert key[v.label] == to_rgba(v.color)
    assert maps.WHOLE_BOX.replace(",", ", ") in ax.get_title()
    assert "over the model box" in box.status.value
    c["model_box"].value = "kappa=0.5:2,q=0:1"
    assert ex.ds.attrs["model_box"] == "kappa=0.5:2,q=0:1" and "q=0:1" in ax.get_title()
    ds = ex.ds
    c["model_box"].value = "kappa=2:1"
    assert "model_box: kappa: reversed range 2:1" in html.unescape(box.status.value)
    assert ex.ds is ds
    c["model_box"].value = maps.WHOLE_BOX
    c["overlays"].value = ("certified boundaries",)  # the region curves over the box
    curves = _wait_boundaries(ex).curves
    assert curves and {cv.field for cv in curves} == {"ss_over_models"}
    labels = [t.get_text() for t in ax.get_legend().texts]
    assert labels[-1] == "certified region boundary", labels
    drawn = [ln for ln in ax.lines if ln.get_color() == "#6a3d9a"]
    assert len(drawn) == sum(1 for cv in curves if len(cv.vertices))
    b1, b2 = 0.25 * math.pi, 0.6 * math.pi  # class 13: depends
    _click(box, b1, b2)
    text = html.unescape(box.inspector.value)
    assert "ss_over_models over the model box" in text and ": depends on the model" in text
    d = [float(x) for angle in ex.point[:2] for x in direction(angle)]
    for side in ("stable", "unstable"):
        m = re.search(rf"{side} witness: kappa = (\S+), q1 = (\S+), q2 = (\S+) \(", text)
        assert m, text
        model = ex.last_inspection["over_models"]["verdicts"]["ss_over_models"]["witnesses"][side]
        np.testing.assert_allclose([float(x) for x in m.groups()], model["model"], rtol=1e-5)
        v = exact.point_spectral(*d, *model["model"])["stable_SS"]
        assert (v in (Verdict.STABLE, Verdict.NEUTRAL)) == (side == "stable"), (side, model, v)


def test_ii_box_layers_show_witnesses_on_click(need):
    """The two II layers over the whole model space: a click on a map cell where the verdict
    depends on the model shows two witness models in the inspector, the ones the dataset holds,
    each on its side by the exact tier (``consistent_II`` true / false, ``stable_II`` stable /
    not)."""
    need("ipywidgets")
    from atlas.core.verdicts import OverModels

    box = widget.make_widget(n=17, layer="ii_consistent_over_models")
    ex = box.explorer
    for layer, sides, output in (
        ("ii_consistent_over_models", ("consistent", "inconsistent"), "consistent_II"),
        ("ii_stable_over_models", ("stable", "unstable"), "stable_II"),
    ):
        box.controls["layer"].value = layer
        dep = np.argwhere(ex.ds[layer].values == int(OverModels.DEPENDS))
        assert len(dep), layer
        i, j = dep[len(dep) // 2]
        _click(box, float(ex.ds.beta1[i]), float(ex.ds.beta2[j]))
        text = html.unescape(box.inspector.value)
        assert f"{layer} over the model box" in text and ": depends on the model" in text, text
        text = text.split(f"{layer} over the model box")[1].split("over the model box")[0]
        p = ex.point
        # the package's directions: the float nearest k pi / 2 is the exact axis vector
        d = [float(x) for angle in p[:2] for x in direction(angle)]
        for side in sides:
            m = re.search(rf"\b{side} witness: kappa = (\S+), q1 = (\S+), q2 = (\S+) \(", text)
            assert m, (side, text)
            model = ex.last_inspection["over_models"]["verdicts"][layer]["witnesses"][side]
            np.testing.assert_allclose([float(x) for x in m.groups()], model["model"], rtol=1e-5)
            v = exact.point_spectral(*d, *model["model"])[output]
            good = bool(v) if output == "consistent_II" else v == Verdict.STABLE
            assert good == (side == sides[0]), (layer, side, model, v)


def test_status_counts_the_certified_boundaries_seconds_until_they_are_drawn(need, monkeypatch):
    """The first certified boundaries take seconds in the background (their kernels compile):
    the status line says so and refreshes itself while they are computed, then gives their
    time (a hang is ended by pytest-timeout, not by a clock in the test).  On a 16 x 16 start
    grid (the status does not depend on it; the 64 x 64 default's curves are the slow overlay
    test's)."""
    need("ipywidgets")
    import threading

    from atlas.data import boundaries

    monkeypatch.setattr(state, "BOUNDARY_GRID", 16)
    release, real = threading.Event(), boundaries.slice_boundaries
    monkeypatch.setattr(
        boundaries, "slice_boundaries", lambda *a, **k: release.wait() and real(*a, **k)
    )
    box = widget.make_widget(n=N, layer="stable_SS", kappa=0.5, q1=0.3)
    seen = []
    box.status.observe(lambda ch: seen.append(html.unescape(ch["new"])), names="value")
    box.controls["overlays"].value = ("certified boundaries",)
    working = "working -- certified boundaries (the first: compiling or loading its kernels): "
    assert working in seen[-1] and seen[-1].startswith("<tt>stable_SS at kappa = 0.5"), seen
    shown = len(seen)
    while len(seen) == shown:  # refreshed by its timer while the worker runs
        time.sleep(0.1)
    assert working in seen[-1], seen
    release.set()
    _wait_boundaries(box.explorer)
    while not re.search(r", certified boundaries \d+ ms</tt>$", seen[-1]):  # the worker's redraw
        time.sleep(0.1)
    assert box.explorer.boundaries_pending() is None
    assert not any("working" in s for s in seen[seen.index(seen[-1]) :])
