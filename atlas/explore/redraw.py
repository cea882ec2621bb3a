"""How long one slider move of the widget takes: :func:`measure_redraw` and its table."""

from __future__ import annotations

import time

from atlas.explore.map_view import FIGSIZE, MapView
from atlas.explore.state import LIVE_MAX_RESOLVE, Explorer
from atlas.explore.widget import KAPPA_LOG_STEP

__all__ = ["measure_redraw", "format_redraw"]


def _drawn_view(ex: Explorer) -> tuple:
    """The widget's map figure on an offscreen Agg canvas, computed and drawn once (compiling the
    kernels); returns ``(figure, view)``."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=FIGSIZE)
    FigureCanvasAgg(fig)
    view = MapView(fig.add_subplot())
    ex.update()
    view.render(ex)
    fig.canvas.draw()
    return fig, view


def _timed_redraw(ex: Explorer, fig, view: MapView, kappa: float, case: dict) -> dict:
    """One redraw after ``kappa`` moved: ``case`` with the times [ms] and undecided counts."""
    t0 = time.perf_counter()
    ex.update(kappa=kappa)
    t1 = time.perf_counter()
    view.render(ex)
    t2 = time.perf_counter()
    fig.canvas.draw()
    t3 = time.perf_counter()
    return dict(
        **case,
        kappa=ex.params["kappa"],
        total_ms=1e3 * (t3 - t0),
        compute_ms=1e3 * (t1 - t0),
        render_ms=1e3 * (t2 - t1),
        draw_ms=1e3 * (t3 - t2),
        n_undecided_fast=int(ex.ds.attrs["n_undecided_fast"]),
        n_undecided=int(ex.ds.attrs["n_undecided"]),
    )


def _fastest_redraw(ex: Explorer, kappa: float, repeats: int, case: dict) -> dict:
    """The fastest of ``repeats`` redraws, kappa moving one slider step each time."""
    fig, view = _drawn_view(ex)
    best = None
    for i in range(repeats):
        row = _timed_redraw(ex, fig, view, kappa * 10 ** (KAPPA_LOG_STEP * (i + 1)), case)
        if best is None or row["total_ms"] < best["total_ms"]:
            best = row
    return best


def measure_redraw(
    n: int = 513,
    kappa: float = 0.5,
    cases=((0.0, 0.0), (0.1, 0.1), (1.0, 0.01)),
    layers=("stable_SS", "stable_II"),
    repeats: int = 5,
    max_resolve: int | None = LIVE_MAX_RESOLVE,
    overlays=("class boundaries", "SS boundary"),
    dtype="float64",
) -> list[dict]:
    """Time one slider-move redraw of the widget's map at ``n x n`` cells.

    For each layer and each ``(q1, q2)`` in ``cases``: an :class:`Explorer` and the widget's map
    figure (:class:`MapView` on an offscreen Agg canvas) are set up and drawn once (compiling
    the kernels), then ``repeats`` times ``kappa`` moves one slider step (x 10^0.01) and the
    redraw runs: :meth:`Explorer.update` (map computation with at most ``max_resolve`` exact
    settlements, plus the margin for the SS-boundary overlay), :meth:`MapView.render` (RGBA
    image, legend, contour) and ``canvas.draw()``.  Not included: PNG encoding and transport to
    the browser (ipympl), which do not depend on the model.

    Returns one dict per (layer, case) with ``n``, ``layer``, ``q1``, ``q2``, the times [ms] of
    the fastest repeat (``total_ms``, ``compute_ms``, ``render_ms``, ``draw_ms``) and its
    undecided counts ``n_undecided_fast``, ``n_undecided`` (after the capped settlement).
    """
    if repeats < 1:
        raise ValueError(f"repeats: must be >= 1, got {repeats}")
    rows = []
    for layer in layers:
        for q1, q2 in cases:
            ex = Explorer(
                kappa=kappa,
                q1=q1,
                q2=q2,
                n=n,
                layer=layer,
                dtype=dtype,
                max_resolve=max_resolve,
                overlays=overlays,
            )
            case = dict(n=n, layer=layer, q1=float(q1), q2=float(q2))
            rows.append(_fastest_redraw(ex, kappa, repeats, case))
    return rows


def format_redraw(rows: list[dict]) -> str:
    """A table of :func:`measure_redraw` results."""
    lines = [
        f"{'layer':<12} {'q1':>5} {'q2':>5} {'total':>7} {'compute':>8} {'render':>7} "
        f"{'draw':>6}  undecided fast -> left   [ms, n = {rows[0]['n'] if rows else '-'}]"
    ]
    for r in rows:
        lines.append(
            f"{r['layer']:<12} {r['q1']:>5g} {r['q2']:>5g} {r['total_ms']:>7.0f} "
            f"{r['compute_ms']:>8.0f} {r['render_ms']:>7.0f} {r['draw_ms']:>6.0f}  "
            f"{r['n_undecided_fast']:>14d} -> {r['n_undecided']}"
        )
    return "\n".join(lines)
