"""The exploration widget's state and callbacks, independent of ipywidgets (:class:`Explorer`)."""

from __future__ import annotations

import functools
import math
import threading
import time
from concurrent.futures import Future, ThreadPoolExecutor

import numpy as np
import xarray as xr

from atlas.core import warm
from atlas.core.brackets import FIELD_LABELS
from atlas.data.boundary_curves import Boundaries, Curve, Point
from atlas.data.region_curves import labels
from atlas.explore.colors import layer_rgba
from atlas.explore.inspector import inspect_point
from atlas.explore.maps import (
    beta_grid,
    check_layer,
    check_model,
    checked_box,
    compute_map,
    is_box_layer,
    needs_alpha,
    needs_model,
)

__all__ = ["Explorer", "LIVE_MAX_RESOLVE", "OVERLAYS", "BOUNDARY_GRID", "RUN", "keep_kernels"]
__all__ += ["format_boundary", "format_point"]

#: exact settlements per redraw: at most this many undecided points of the spectral layers are
#: settled by :mod:`atlas.core.exact` when a control moves (up to ~20-100 ms each: the II verdicts need
#: the root reference); the rest are drawn as undecided until :meth:`Explorer.settle`
LIVE_MAX_RESOLVE = 16
#: overlays the widget can draw over the selected layer
OVERLAYS = ("class boundaries", "SS boundary", "certified boundaries")
#: cells a side of the grid :func:`atlas.data.boundaries.slice_boundaries` starts from for the
#: "certified boundaries" overlay (its vertices are certified within 1e-10 rad whatever the grid)
BOUNDARY_GRID = 64
#: cells a side of the grid the region curves of a box layer start from (each vertex a proven
#: bracket, bisected on proofs over the box: slower a vertex than the other curves)
BOX_BOUNDARY_GRID = 32
#: the name under which the explorer's kernels are kept (:func:`atlas.core.warm.keep_kernels`)
RUN = "atlas.explore"
#: open points per call the first overlay of a session settles exactly, without waiting for the
#: later-tier programs (:func:`atlas.core.points.host_first`)
HOST_POINTS = 128
#: the point ``(beta1, beta2)`` [rad] the background warm-up inspects (the widget's default point)
WARM_POINT = (0.25 * math.pi, 0.75 * math.pi)
#: a click closer than this to a codimension-2 point [rad] names the point (two cells of the
#: widget's 129^2 grid)
NEAR_POINT = 0.1


def keep_kernels() -> str | None:
    """The persistent compilation cache and the kept kernels on for the rest of this process
    (:func:`atlas.core.warm.keep_kernels`, named :data:`RUN`): from the second session on, the
    explorer's kernels load instead of compiling.  Off with ``$ATLAS_JAX_CACHE=0`` (both) or
    ``$ATLAS_KERNEL_CACHE=0`` (the kept kernels)."""
    return warm.keep_kernels(RUN)


def format_boundary(curve: Curve, i: int, distance: float) -> str:
    """The inspector's line for a click near a certified boundary: its kind, the certified
    bracket of the nearest vertex and the field's codes on its two sides (left | right of the
    direction of travel)."""
    lab = FIELD_LABELS.get(curve.field) or labels(curve.field)
    return (
        f"near the certified {curve.kind} boundary ({distance:.3g} rad away; its vertex is "
        f"bracketed within {curve.bracket[i]:.2g} rad): {lab.get(curve.side_left, curve.side_left)}"
        f" | {lab.get(curve.side_right, curve.side_right)}"
    )


def format_point(point: Point, distance: float) -> str:
    """The inspector's line for a click on a codimension-2 point: its kind, field and position
    bound (a proven enclosure radius, or none claimed)."""
    where = f" of the {point.field} boundary" if point.field else " of the SS and II boundaries"
    bound = (
        f"proven within {point.uncertainty:.2g} rad"
        if point.proven
        else "position estimated, no bound claimed"
    )
    return (
        f"on the codimension-2 point '{point.kind}'{where} ({distance:.3g} rad away; {bound}) "
        f"at beta1 = {point.beta1 / math.pi:.4f} pi, beta2 = {point.beta2 / math.pi:.4f} pi"
    )


class Explorer:
    """State and callbacks of the exploration widget, independent of ipywidgets.

    :meth:`update` sets parameters and recomputes the map (:func:`compute_map`) -- the widget's
    redraw callback; :meth:`settle` is its "settle undecided" button; :meth:`inspect` its click
    callback.  ``timings`` holds the last compute / render times [ms].

    Bounded interactivity (a design decision).  A slider move runs the certified fast path on the
    whole grid (milliseconds to a few hundred milliseconds at 513 x 513, see
    :func:`measure_redraw`) and settles at most ``max_resolve`` (default :data:`LIVE_MAX_RESOLVE`)
    of the points it leaves undecided with the exact reference (:mod:`atlas.core.exact`: tens of
    microseconds a point on the hard suites, more on degenerate ones).  Uncapped settlement of a
    scene with many undecided points could stall a slider move.  Cells that stay undecided are drawn in the ``undecided`` colour of
    :mod:`atlas.core.verdicts` (with its legend entry) and counted in :meth:`status`; every verdict
    drawn is certified.  :meth:`settle` settles all of them on request (``max_resolve=None``
    gives the old always-settle behaviour).  The angle-only layers (class and subclass codes,
    Table 1) are always settled in full: their exact reference is cheap rational arithmetic.

    One layer at a time (a design decision).  The layer dropdown chooses one categorical map;
    ``overlays`` adds what combines without ambiguity: the straight class boundaries and the
    curved SS boundary (dashed zero contour of the smooth ``margin_SS``, as in Fig. 1).  Stacking
    several categorical layers as translucent colours makes the colours unreadable, and contours
    of 0/1 labels are staircases of the grid, not boundaries; the point inspector gives every
    verdict at a point instead.

    Box layers.  A verdict over a box of contact models (``ss_over_models``:
    :func:`atlas.explore.maps.box_layers`) is drawn over ``model_box`` (text such as
    ``"kappa=0.01:100,q1=0:1,q2=0:1"``; default the whole model space): moving kappa, q or alpha
    recomputes nothing, changing the box does.  A click on such a layer adds its verdict at the
    point and, where it depends on the model, the two witness models to the inspector.

    Start-up.  An :class:`Explorer` turns on :func:`keep_kernels` for its process, and
    :meth:`warm_up` (called by the widget once its first map is drawn) compiles the point
    inspector's kernels and the programs of the certified boundaries' small point sets
    (:func:`atlas.core.points.compile_programs`: the shape buckets every caller shares) in a
    background thread; a click that arrives earlier waits for it.  A certified overlay does not:
    while the later tiers' programs are not compiled yet, its small open point sets (up to
    :data:`HOST_POINTS` a call) go to the exact tier (the same curves).

    The widget's sliders redraw when released (``continuous_update=False``): a redraw of the II
    layers with damping takes a few hundred milliseconds at 513 x 513, and a drag would otherwise
    queue one redraw per intermediate value.
    """

    def __init__(
        self,
        kappa=0.5,
        q1=0.0,
        q2=None,
        alpha=0.35 * math.pi,
        n=513,
        layer="stable_SS",
        dtype="float64",
        resolve=True,
        max_resolve=LIVE_MAX_RESOLVE,
        overlays=("class boundaries",),
        model_box=None,
    ):
        self.params = dict(
            kappa=float(kappa),
            q1=float(q1),
            q2=float(q1 if q2 is None else q2),
            alpha=float(alpha),
            n=int(n),
            layer=layer,
            dtype=dtype,
            resolve=bool(resolve),
            max_resolve=max_resolve,
            overlays=tuple(overlays),
            model_box=checked_box(model_box),
        )
        self.ds: xr.Dataset | None = None
        self.margin: xr.DataArray | None = None
        self._last_key = None
        self._margin_key = None
        self.timings: dict[str, float] = {}
        self.point: tuple[float, float] | None = None
        self.last_inspection: dict | None = None
        self.last_near: list[str] = []
        #: called (from the worker thread) with the slice ``(kappa, q1, q2)`` whose certified
        #: boundaries are ready
        self.on_boundaries = None
        #: called with a line saying what the explorer is doing (the widget's status line):
        #: ``"step 1 of 2: computing ..."`` before each computation of :meth:`update` /
        #: :meth:`settle`
        self.on_progress = None
        #: whether the last computed map was the first of its kind this session (its time
        #: includes compiling or loading the kernels)
        self.first_of_kind = False
        self._steps: tuple[list, int] = ([], 0)  # the steps of the running update, the next one
        self._curves: dict[tuple, Future] = {}
        self._pool: ThreadPoolExecutor | None = None
        self._warm: Future | None = None
        self._inspector_ready = threading.Event()  # the warm-up's inspection ended
        keep_kernels()

    def update(self, **changes) -> xr.Dataset:
        """Apply parameter changes and recompute the selected layer; returns the map."""
        unknown = set(changes) - set(self.params)
        if unknown:
            raise ValueError(f"unknown parameter(s) {sorted(unknown)}")
        p = {**self.params, **changes}
        p["overlays"] = tuple(p["overlays"])
        bad = [o for o in p["overlays"] if o not in OVERLAYS]
        if bad:
            raise ValueError(f"overlays: unknown overlay(s) {bad} (known: {', '.join(OVERLAYS)})")
        mr = p["max_resolve"]
        if mr is not None and (int(mr) != mr or mr < 0):
            raise ValueError(f"max_resolve: must be None or an integer >= 0, got {mr!r}")
        group = check_layer(p["layer"])
        check_model(float(p["kappa"]), float(p["q1"]), float(p["q2"]))
        p["model_box"] = checked_box(p["model_box"])
        self.params = p
        key = self._key(group)
        compute = self.ds is None or key != self._last_key
        steps = ["the map"] * compute
        if self._margin_due():
            steps.insert(0, "the SS margin")
        self._steps = (steps, 0)
        self._update_margin()
        if not compute:
            self.first_of_kind = False
            self.timings["compute_ms"] = 0.0  # only the displayed layer or the overlays changed
            return self.ds
        self._progress(self._compute_text(group))
        t = time.perf_counter()
        self.first_of_kind = _first_of_kind(key[:3])
        self.ds = self._compute(group, p["max_resolve"])
        self._last_key = key
        self.timings["compute_ms"] = 1e3 * (time.perf_counter() - t)
        return self.ds

    def _compute_text(self, group) -> str:
        """What computing ``group`` at the current parameters involves, in words."""
        p = self.params
        what = f"computing {p['layer']} on {p['n']}^2 cells"
        if _first_of_kind(self._key(group)[:3], peek=True):
            what = f"compiling (or loading) the kernels for {p['n']}^2 cells, then {what}"
        return what

    def _progress(self, text: str) -> None:
        """Report the next step of :meth:`update` (``step i of n: text``) to :attr:`on_progress`."""
        steps, i = self._steps
        self._steps = (steps, i + 1)
        if self.on_progress is not None:
            self.on_progress(f"step {i + 1} of {max(len(steps), i + 1)}: {text}")

    def _compute(self, group, max_resolve, resolve=None) -> xr.Dataset:
        p = self.params
        return compute_map(
            p["kappa"],
            p["q1"],
            p["q2"],
            n=p["n"],
            dtype=p["dtype"],
            layers=group,
            alpha=p["alpha"] if any(needs_alpha(k) for k in group) else None,
            resolve=p["resolve"] if resolve is None else resolve,
            max_resolve=max_resolve,
            model_box=p["model_box"] if is_box_layer(group[0]) else None,
        )

    def _margin_due(self) -> bool:
        p = self.params
        key = (p["n"], p["dtype"], p["kappa"], p["q1"], p["q2"])
        return "SS boundary" in p["overlays"] and key != self._margin_key

    def _update_margin(self):
        """The smooth SS margin for the "SS boundary" overlay (one jitted kernel, cached)."""
        if not self._margin_due():
            self.timings["margin_ms"] = 0.0
            return
        p = self.params
        self._progress(f"computing the SS margin on {p['n']}^2 cells (the SS boundary overlay)")
        key = (p["n"], p["dtype"], p["kappa"], p["q1"], p["q2"])
        t = time.perf_counter()
        m = compute_map(
            p["kappa"], p["q1"], p["q2"], n=p["n"], dtype=p["dtype"], layers=("margin_SS",)
        )
        self.margin, self._margin_key = m["margin_SS"], key
        self.timings["margin_ms"] = 1e3 * (time.perf_counter() - t)

    def settle(self) -> xr.Dataset:
        """Settle every undecided cell of the current layer group exactly (the "settle
        undecided" button).  Costs ~20-100 ms per undecided point; the settled map is kept until
        a parameter of the group changes."""
        if self.ds is None:
            self.update()
        t = time.perf_counter()
        if self.ds.attrs["n_undecided"] > 0 or not self.params["resolve"]:
            self._steps = (["settle"], 0)
            self._progress(f"settling {self.ds.attrs['n_undecided']} undecided cells exactly")
            n_fast = self.ds.attrs["n_undecided_fast"]
            self.ds = self._compute(check_layer(self.params["layer"]), None, resolve=True)
            self.ds.attrs["n_undecided_fast"] = n_fast
            self._last_key = self._key(check_layer(self.params["layer"]))
        self.timings["settle_ms"] = 1e3 * (time.perf_counter() - t)
        return self.ds

    def _key(self, group):
        p = self.params
        if is_box_layer(group[0]):  # the model box, not the model
            return (group, p["n"], p["dtype"], p["model_box"])
        model = (p["kappa"], p["q1"], p["q2"]) if any(needs_model(k) for k in group) else ()
        alpha = (p["alpha"],) if any(needs_alpha(k) for k in group) else ()
        return (group, p["n"], p["dtype"], p["resolve"], p["max_resolve"]) + model + alpha

    def image(self) -> np.ndarray:
        """RGBA image of the current layer (computing it first if needed)."""
        if self.ds is None:
            self.update()
        t = time.perf_counter()
        img = layer_rgba(self.ds, self.params["layer"])
        self.timings["render_ms"] = 1e3 * (time.perf_counter() - t)
        return img

    def warm_up(self) -> Future:
        """Compile the point inspector's kernels in a background thread: one inspection of
        :data:`WARM_POINT` at the current model, alpha and dtype, its result discarded (the kept
        kernels' list is then saved, :func:`atlas.core.warm.save_used`).  Started once; returns
        its future."""
        if self._warm is None:
            p = self.params
            pool = ThreadPoolExecutor(1, thread_name_prefix="atlas-warm-up")
            self._warm = pool.submit(
                _warm_up,
                ready=self._inspector_ready.set,
                alpha=p["alpha"],
                kappa=p["kappa"],
                q1=p["q1"],
                q2=p["q2"],
                dtype=p["dtype"],
            )
            pool.shutdown(wait=False)
        return self._warm

    def inspect(self, beta1, beta2) -> dict:
        """The point inspector at ``(beta1, beta2)`` [rad] with the current model and alpha
        (after the inspection of the :meth:`warm_up` if one is running: its kernels, not a second
        compilation; an error of the warm-up is not raised here, the inspection's own would be).

        All or nothing: ``point``, ``last_inspection`` and ``last_near`` (the lines of
        :meth:`near`) change together, or not at all when the inspection raises."""
        while self._warm is not None and not self._warm.done():  # its inspection part only
            if self._inspector_ready.wait(0.05):
                break
        p = self.params
        point = (float(beta1) % (2 * math.pi), float(beta2) % (2 * math.pi))
        info = inspect_point(
            *point,
            alpha=p["alpha"],
            kappa=p["kappa"],
            q1=p["q1"],
            q2=p["q2"],
            dtype=p["dtype"],
            model_box=p["model_box"] if is_box_layer(p["layer"]) else None,
        )
        near = self.near(*point)
        self.point, self.last_inspection, self.last_near = point, info, near
        return info

    def near(self, beta1, beta2) -> list[str]:
        """The inspector's lines for the certified boundaries near ``(beta1, beta2)`` [rad]: the
        codimension-2 point within :data:`NEAR_POINT` rad (:func:`format_point`) and the nearest
        curve vertex (:func:`format_boundary`); none while they are computed or off."""
        lines = []
        pt = self.nearest_point(beta1, beta2)
        if pt is not None:
            lines.append(format_point(*pt))
        cv = self.nearest_boundary(beta1, beta2)
        if cv is not None:
            lines.append(format_boundary(*cv))
        return lines

    def boundaries(self) -> Boundaries | None:
        """The certified boundary curves and codimension-2 points of the current slice, or
        ``None`` while they are computed (in a background thread, started by the first call
        for a slice with the "certified boundaries" overlay on; cached per slice).  The time
        from the request to the result is ``timings["boundaries_ms"]``."""
        p = self.params
        if "certified boundaries" not in p["overlays"]:
            return None
        key = self.boundary_key()
        fut = self._curves.get(key)
        if fut is None:
            if self._pool is None:
                self._pool = ThreadPoolExecutor(1, thread_name_prefix="atlas-boundaries")
            t0 = time.perf_counter()
            fut = self._pool.submit(_host_first, *_boundary_task(key, p["dtype"]))

            def done(f, key=key):
                self.timings["boundaries_ms"] = 1e3 * (time.perf_counter() - t0)
                if self.on_boundaries is not None:
                    self.on_boundaries(key)

            fut.t0, fut.first = t0, not self._curves  # read by boundaries_pending
            fut.add_done_callback(done)
            self._curves[key] = fut
        return fut.result() if fut.done() else None  # an error in the worker raises here

    def boundary_key(self) -> tuple:
        """What the certified boundaries shown depend on: the slice ``(kappa, q1, q2)``, or for
        a box layer ``(layer, model box)``."""
        p = self.params
        if is_box_layer(p["layer"]):
            return (p["layer"], p["model_box"])
        return (p["kappa"], p["q1"], p["q2"])

    def boundaries_pending(self) -> tuple[float, bool] | None:
        """While the certified boundaries of the current slice are computed: the seconds since
        they were requested and whether they are the session's first (their kernels compile or
        load first); else ``None``."""
        p = self.params
        fut = self._curves.get(self.boundary_key())
        if "certified boundaries" not in p["overlays"] or fut is None or fut.done():
            return None
        return time.perf_counter() - fut.t0, fut.first

    def nearest_boundary(self, beta1, beta2, within=2 * math.pi / BOUNDARY_GRID):
        """``(curve, vertex index, distance [rad])`` of the certified boundary vertex nearest to
        ``(beta1, beta2)`` (on the torus) if closer than ``within``, else ``None`` (class lines
        excluded)."""
        b = self.boundaries()
        best = None
        for c in [] if b is None else b.curves:
            if c.field == "class" or not len(c.vertices):
                continue
            d = _torus_distance(c.vertices, beta1, beta2)
            i = int(np.nanargmin(d))
            if d[i] < within and (best is None or d[i] < best[2]):
                best = (c, i, float(d[i]))
        return best

    def nearest_point(self, beta1, beta2, within=NEAR_POINT):
        """``(point, distance [rad])`` of the codimension-2 point nearest to ``(beta1, beta2)``
        (on the torus) if closer than ``within``, else ``None``."""
        b = self.boundaries()
        if b is None or not b.points:
            return None
        xy = np.array([(p.beta1, p.beta2) for p in b.points])
        d = _torus_distance(xy, beta1, beta2)
        i = int(np.argmin(d))
        return (b.points[i], float(d[i])) if d[i] < within else None

    def status(self) -> str:
        """The map's summary: layer, model (and alpha for the layers that depend on it) or the
        model box of a box layer, size, times, undecided counts."""
        p, ds = self.params, self.ds
        q = f"q = {p['q1']:g}" if p["q1"] == p["q2"] else f"q1 = {p['q1']:g}, q2 = {p['q2']:g}"
        if needs_alpha(p["layer"]):
            q += f", alpha = {p['alpha'] / math.pi:.3f} pi"
        und = ""
        box = is_box_layer(p["layer"])
        if ds is not None and box:
            und = (
                f"; undecided: {ds.attrs['n_undecided_fast']} before the settlement, "
                f"{ds.attrs['n_undecided']} after"
            )
        elif ds is not None:
            und = (
                f"; undecided: {ds.attrs['n_undecided_fast']} fast, "
                f"{ds.attrs['n_undecided']} after exact settlement"
                + ("" if p["max_resolve"] is None else f" (at most {p['max_resolve']} a redraw)")
            )
            if ds.attrs["n_undecided"]:
                und += " (drawn as undecided; 'settle undecided' settles them)"
        t = self.timings
        first = " (its kernels compiled or loaded first)" if self.first_of_kind else ""
        where = (
            f"over the model box {p['model_box']}" if box else f"at kappa = {p['kappa']:.4g}, {q}"
        )
        return (
            f"{p['layer']} {where}, {p['n']}^2 cells: "
            f"compute {t.get('compute_ms', float('nan')) + t.get('margin_ms', 0.0):.0f} ms{first}, "
            f"render {t.get('render_ms', float('nan')):.0f} ms{und}"
        )


#: ``(group, n, dtype)`` of the maps computed in this process
_SEEN: set = set()


def _first_of_kind(kind: tuple, peek: bool = False) -> bool:
    """Whether no map of this ``kind`` was computed in this process (recorded unless ``peek``)."""
    first = kind not in _SEEN
    if not peek:
        _SEEN.add(kind)
    return first


def _boundary_task(key: tuple, dtype) -> tuple:
    """``(function, *args)`` computing the certified boundaries of :meth:`Explorer.boundary_key`
    ``key``: :func:`atlas.data.boundaries.slice_boundaries` on a :data:`BOUNDARY_GRID` grid, or
    for a box layer :func:`atlas.data.region_curves.region_curves` on a
    :data:`BOX_BOUNDARY_GRID` grid (small proof budget only)."""
    if isinstance(key[0], str):
        from atlas.data.over_models import as_model_box  # noqa: PLC0415 - on use
        from atlas.data.region_curves import region_curves  # noqa: PLC0415

        grid = beta_grid(BOX_BOUNDARY_GRID)
        # without the settlement's budget: a bracket it would have to settle stops (its length
        # shown), the overlay stays interactive on a bounded box
        task = functools.partial(region_curves, settle=0)
        return task, grid, grid, as_model_box(key[1]), key[0]
    from atlas.data.boundaries import slice_boundaries  # noqa: PLC0415 - scipy: on use

    grid = beta_grid(BOUNDARY_GRID)
    return functools.partial(slice_boundaries, dtype=dtype), grid, grid, *key


def _torus_distance(xy: np.ndarray, beta1: float, beta2: float) -> np.ndarray:
    """Distances [rad] from the rows ``(beta1, beta2)`` of ``xy`` to a point, on the torus."""
    d = (xy - np.array([beta1, beta2]) + math.pi) % (2 * math.pi) - math.pi
    return np.hypot(d[:, 0], d[:, 1])


def _warm_up(ready=None, **model) -> None:
    """:meth:`Explorer.warm_up`'s work: one inspection (then ``ready()``, also on an error) and
    the shared point-set programs (:func:`atlas.core.points.compile_programs`; before each it
    waits while a certified overlay is computed, :data:`_NO_OVERLAY`), then the kept kernels'
    list saved."""
    from atlas.core import points  # noqa: PLC0415 - imported by the inspector already

    try:
        inspect_point(*WARM_POINT, **model)
    finally:
        if ready is not None:
            ready()
    points.compile_programs(model["dtype"], before_each=_NO_OVERLAY.wait)
    warm.save_used()


#: set while no certified overlay is computed: the warm-up's tracing holds the interpreter
#: lock, so it waits meanwhile (the overlay needs none of its later-tier programs)
_NO_OVERLAY = threading.Event()
_NO_OVERLAY.set()


def _host_first(fn, *args):
    """``fn(*args)`` with the small point sets of a first session settled by the exact tier
    (:func:`atlas.core.points.host_first`, :data:`HOST_POINTS`): the overlay needs none of the
    later-tier programs the warm-up compiles meanwhile (the curves are the same either way)."""
    from atlas.core import points  # noqa: PLC0415 - imported by the inspector already

    _NO_OVERLAY.clear()
    try:
        with points.host_first(HOST_POINTS):
            return fn(*args)
    finally:
        _NO_OVERLAY.set()
