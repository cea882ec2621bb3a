"""Layer 4, interactive exploration: maps at any resolution, point inspection, the notebook widget."""

from atlas.explore.colors import layer_rgba, legend_entries
from atlas.explore.inspector import format_inspection, inspect_point
from atlas.explore.maps import (
    ALPHA_LAYERS,
    BETA_LAYERS,
    DEFAULT_LAYERS,
    LAYERS,
    SPECTRAL_LAYERS,
    beta_grid,
    compute_map,
)
from atlas.explore.redraw import format_redraw, measure_redraw
from atlas.explore.state import LAYER_GROUPS, LIVE_MAX_RESOLVE, OVERLAYS, Explorer
from atlas.explore.widget import RESOLUTIONS, make_widget

__all__ = [
    "ALPHA_LAYERS",
    "BETA_LAYERS",
    "DEFAULT_LAYERS",
    "LAYER_GROUPS",
    "LAYERS",
    "LIVE_MAX_RESOLVE",
    "OVERLAYS",
    "RESOLUTIONS",
    "SPECTRAL_LAYERS",
    "Explorer",
    "beta_grid",
    "compute_map",
    "format_inspection",
    "format_redraw",
    "inspect_point",
    "layer_rgba",
    "legend_entries",
    "make_widget",
    "measure_redraw",
]
