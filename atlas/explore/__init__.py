"""Layer 4, interactive exploration: maps at any resolution, point inspection, the notebook widget."""

from atlas.explore.explorer import (
    ALPHA_LAYERS,
    BETA_LAYERS,
    DEFAULT_LAYERS,
    LAYER_GROUPS,
    LAYERS,
    LIVE_MAX_RESOLVE,
    OVERLAYS,
    RESOLUTIONS,
    SPECTRAL_LAYERS,
    Explorer,
    beta_grid,
    compute_map,
    format_inspection,
    format_redraw,
    inspect_point,
    layer_rgba,
    legend_entries,
    make_widget,
    measure_redraw,
)

__all__ = [
    "ALPHA_LAYERS", "BETA_LAYERS", "DEFAULT_LAYERS", "LAYER_GROUPS", "LAYERS", "LIVE_MAX_RESOLVE",
    "OVERLAYS", "RESOLUTIONS", "SPECTRAL_LAYERS", "Explorer", "beta_grid", "compute_map",
    "format_inspection", "format_redraw", "inspect_point", "layer_rgba", "legend_entries",
    "make_widget", "measure_redraw",
]
