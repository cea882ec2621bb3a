"""Layer 4, interactive exploration: maps at any resolution, point inspection, the notebook widget."""

from atlas.explore.colors import layer_rgba, legend_entries
from atlas.explore.inspector import format_inspection, inspect_point
from atlas.explore.maps import (
    DEFAULT_LAYERS,
    beta_grid,
    compute_map,
    layer_groups,
    layers,
)
from atlas.explore.redraw import format_redraw, measure_redraw
from atlas.explore.state import LIVE_MAX_RESOLVE, OVERLAYS, Explorer
from atlas.explore.widget import RESOLUTIONS, make_widget

__all__ = [
    "DEFAULT_LAYERS",
    "LIVE_MAX_RESOLVE",
    "OVERLAYS",
    "RESOLUTIONS",
    "Explorer",
    "beta_grid",
    "compute_map",
    "format_inspection",
    "format_redraw",
    "inspect_point",
    "layer_groups",
    "layers",
    "layer_rgba",
    "legend_entries",
    "make_widget",
    "measure_redraw",
]
