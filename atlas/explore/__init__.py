"""Layer 4, interactive exploration: maps at any resolution, point inspection, the notebook widget.

The logic behind ``notebooks/explore.ipynb`` as plain, testable functions, one module per idea:

* :mod:`atlas.explore.maps` -- :func:`compute_map`, the Fig. 1 layers on an ``n x n`` grid for one
  ``(kappa, q1, q2)`` (and optionally one ``alpha``), equal to the slice of an atlas, and the box
  layers (:func:`box_layers`: verdicts over a box of models, ``ss_over_models``).
* :mod:`atlas.explore.inspector` -- :func:`inspect_point`, everything the theory says about one
  point, and :func:`format_inspection`.
* :mod:`atlas.explore.colors` -- :func:`layer_rgba`, :func:`legend_entries`.
* :mod:`atlas.explore.state` -- :class:`Explorer`, the state and callbacks of the widget (no
  ipywidgets needed).  Redraws are bounded: undecided cells beyond :data:`LIVE_MAX_RESOLVE` exact
  settlements are drawn as undecided until settled on request.  :func:`keep_kernels` keeps the
  compiled kernels for the session (an :class:`Explorer` turns it on).
* :mod:`atlas.explore.map_view` -- the widget's map figure (matplotlib).
* :mod:`atlas.explore.widget` -- :func:`make_widget`, ipywidgets controls wired to an
  :class:`Explorer` (clicking the map needs ipympl, the ``notebook`` extra).
* :mod:`atlas.explore.redraw` -- :func:`measure_redraw` times a slider move.

Grid: cell centres ``beta = (i + 1/2) 2 pi / n`` [rad].  The widget offers odd ``n`` only: for even
``n`` the centres ``beta`` and ``beta + pi`` are both on the grid, i.e. a whole line of cells lies on
``det B = 0`` (``beta2 = beta1 + pi``) up to the rounding of the directions (decided, with the
exact sign of ``det B``, but a line of near-ties nobody asked for).
"""

from atlas.explore.colors import layer_rgba, legend_entries
from atlas.explore.inspector import format_inspection, inspect_point, over_models_at
from atlas.explore.maps import (
    DEFAULT_LAYERS,
    beta_grid,
    box_layers,
    compute_map,
    layer_groups,
    layers,
    map_layers,
)
from atlas.explore.redraw import format_redraw, measure_redraw
from atlas.explore.state import LIVE_MAX_RESOLVE, OVERLAYS, Explorer, keep_kernels
from atlas.explore.widget import RESOLUTIONS, make_widget

__all__ = [
    "DEFAULT_LAYERS",
    "LIVE_MAX_RESOLVE",
    "OVERLAYS",
    "RESOLUTIONS",
    "Explorer",
    "beta_grid",
    "box_layers",
    "compute_map",
    "format_inspection",
    "format_redraw",
    "inspect_point",
    "keep_kernels",
    "layer_groups",
    "layers",
    "map_layers",
    "over_models_at",
    "layer_rgba",
    "legend_entries",
    "make_widget",
    "measure_redraw",
]
