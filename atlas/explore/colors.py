"""Colours of the explorer's map: a layer as an RGBA image and its legend, in the colours of the
verdict enumerations (:mod:`atlas.core.verdicts`); matplotlib only for the continuous layers and
the class-code palette."""

from __future__ import annotations

import numpy as np
import xarray as xr

from atlas.core.verdicts import UNDECIDED_CODE, Consistency, Verdict
from atlas.data.outputs import variable_attrs

__all__ = ["layer_rgba", "legend_entries"]


def _hex_rgba(h: str) -> tuple:
    h = h.lstrip("#")
    return tuple(int(h[i : i + 2], 16) / 255 for i in (0, 2, 4)) + (1.0,)


_BOOL_COLORS = ("#f7f7f7", Consistency.CONSISTENT.color)


def _category_colors(name: str) -> dict:
    """code -> colour for the categorical layers (from the verdict enumerations)."""
    if name in ("stable_SS", "stable_II"):
        return {int(v): v.color for v in Verdict}
    if name == "consistent_II":
        return {int(v): v.color for v in Consistency}
    if name in ("class_code", "subclass_code"):
        import matplotlib

        codes = [int(c) for c in variable_attrs(name)["flag_values"] if c > 0]  # CF flags, SPEC §2
        cmap = matplotlib.colormaps["tab20"]
        cols = {c: matplotlib.colors.to_hex(cmap(i % 20)) for i, c in enumerate(codes)}
        cols[0] = "#ffffff"
        cols[UNDECIDED_CODE] = Verdict.UNDECIDED.color
        return cols
    return {0: _BOOL_COLORS[0], 1: _BOOL_COLORS[1]}


def _image_values(ds: xr.Dataset, name: str) -> np.ndarray:
    """Values of a layer on the plane as an image ``(beta2, beta1)`` (1-D layers broadcast)."""
    n1, n2 = ds.sizes["beta1"], ds.sizes["beta2"]
    dims = ds[name].dims
    v = (
        ds[name]
        .transpose(*[d for d in ("beta1", "beta2") if d in dims])
        .values.reshape([n1 if "beta1" in dims else 1, n2 if "beta2" in dims else 1])
    )
    return np.broadcast_to(v, (n1, n2)).T


def _diverging_rgba(v: np.ndarray) -> np.ndarray:
    """A continuous layer on ``RdBu_r`` centred at 0, scaled by its largest finite magnitude."""
    import matplotlib

    finite = np.isfinite(v)
    lim = float(np.max(np.abs(v[finite]))) if finite.any() else 1.0
    lim = lim if lim > 0 else 1.0
    return matplotlib.colormaps["RdBu_r"](0.5 + 0.5 * np.clip(v / lim, -1, 1))


def _category_rgba(v: np.ndarray, name: str) -> np.ndarray:
    cols = _category_colors(name)
    codes = np.array(sorted(cols))
    lut = np.array([_hex_rgba(cols[c]) for c in codes])
    iv = v.astype(np.int64)
    idx = np.clip(np.searchsorted(codes, iv), 0, len(codes) - 1)
    rgba = lut[idx]
    rgba[codes[idx] != iv] = (1.0, 0.0, 1.0, 1.0)  # a code without a colour: magenta
    return rgba


def layer_rgba(ds: xr.Dataset, name: str) -> np.ndarray:
    """RGBA image ``(beta2, beta1, 4)`` of a layer (``imshow(origin='lower')``): categorical layers
    in the colours of :mod:`atlas.core.verdicts`, continuous ones on a diverging map centred at 0."""
    v = _image_values(ds, name)
    return _diverging_rgba(v) if v.dtype.kind == "f" else _category_rgba(v, name)


def legend_entries(name: str, ds: xr.Dataset | None = None) -> list[tuple[str, str]]:
    """(colour, label) pairs of a categorical layer (only codes present in ``ds`` if given)."""
    present = None if ds is None else set(np.unique(ds[name].values.astype(np.int64)).tolist())
    if name in ("stable_SS", "stable_II"):
        items = [(v.color, v.label) for v in Verdict if present is None or int(v) in present]
    elif name == "consistent_II":
        items = [(v.color, v.label) for v in Consistency if present is None or int(v) in present]
    elif name in ("class_code", "subclass_code", "margin_SS", "spectral_abscissa"):
        items = []
    else:
        items = [(_BOOL_COLORS[0], "false"), (_BOOL_COLORS[1], "true")]
    return items


# --------------------------------------------------------------------------- widget state
