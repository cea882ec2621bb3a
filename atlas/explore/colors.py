"""Colours of the explorer's map: a layer as an RGBA image and its legend, chosen by what the
registry (:mod:`atlas.data.outputs`) declares of the layer: integer codes in the colours and labels
of their declared codes (:class:`atlas.core.verdicts.Codes`; a code declared without a colour takes
a palette), booleans in two colours, float layers on a diverging map; matplotlib only for the
continuous layers and the code palettes."""

from __future__ import annotations

import numpy as np
import xarray as xr

from atlas.core.verdicts import Consistency, Verdict
from atlas.data.outputs import OUTPUTS

__all__ = ["layer_rgba", "legend_entries", "value_label"]


def _hex_rgba(h: str) -> tuple:
    h = h.lstrip("#")
    return tuple(int(h[i : i + 2], 16) / 255 for i in (0, 2, 4)) + (1.0,)


_BOOL_COLORS = ("#f7f7f7", Consistency.CONSISTENT.color)


#: the 24 classes ``ij``: colours of matplotlib's tab20 / tab20b / tab20c, assigned so that classes
#: sharing an edge on the beta1-beta2 plane differ by CIE76 Delta E >= 23 and any two classes by
#: >= 10, in normal vision and for deutan, protan and tritan vision (Machado et al. 2009,
#: severity 1), chosen by a local search over the 60 colours
CLASS_COLORS = {
    11: "#c7e9c0", 12: "#a55194", 13: "#dbdb8d", 14: "#74c476", 15: "#843c39", 16: "#e7ba52",
    21: "#d62728", 22: "#7b4173", 23: "#e6550d", 24: "#393b79", 25: "#8c6d31", 26: "#6baed6",
    31: "#636363", 32: "#e7969c", 33: "#6b6ecf", 34: "#bdbdbd", 35: "#756bb1", 36: "#bcbd22",
    41: "#9edae5", 42: "#bd9e39", 43: "#a1d99b", 44: "#5254a3", 45: "#e377c2", 46: "#31a354",
}  # fmt: skip


def _code_palette(name: str) -> dict:
    """code -> colour of the codes of an integer layer declared without a colour, none repeated.

    The classes ``ij`` take :data:`CLASS_COLORS`; a code ``ijk`` whose ``ij`` is a class (the
    subclasses) is the ``ij``-th of 24 hues 105 degrees apart (saturation 0.75, value 0.85) shaded
    by ``k`` (k = 1..3 darker, 4..6 lighter), so the subclasses of one class read as one family;
    other codes take hues 7/n of a turn apart.
    """
    import colorsys

    import matplotlib

    hue = lambda i, n: np.array(colorsys.hsv_to_rgb((7 * i % n) / n, 0.75, 0.85))  # noqa: E731
    # the subclasses' families: 24 hues 105 degrees apart (144 shades pairwise distinct, which
    # shades of the tab20 colours are not)
    cls = {c: hue(i, 24) for i, c in enumerate(CLASS_COLORS)}
    codes = [c.value for c in OUTPUTS[name].codes.codes if c.color is None]
    if name == "class_code":
        cols = dict(CLASS_COLORS)
    elif codes and all(c // 10 in cls and 1 <= c % 10 <= len(_SHADES) for c in codes):
        cols = {}
        for c in codes:
            t = _SHADES[c % 10 - 1]
            rgb = cls[c // 10] * (1 - abs(t)) + (t > 0) * abs(t)  # towards white (t > 0) or black
            cols[c] = matplotlib.colors.to_hex(rgb)
    else:
        cols = {
            c: matplotlib.colors.to_hex(hue(i, max(len(codes), 2))) for i, c in enumerate(codes)
        }
    return cols


#: shade of subclass ``ijk`` by ``k`` (negative: mixed towards black, positive: towards white)
_SHADES = (-0.5, -0.32, -0.14, 0.14, 0.32, 0.5)


def _kind(name: str) -> str:
    """How a layer is drawn: ``"enum"`` (declared integer codes), ``"bool"`` or ``"float"``."""
    return {"bool": "bool", "float": "float"}.get(OUTPUTS[name].storage, "enum")


def _category_colors(name: str) -> dict:
    """code -> colour for the categorical layers (integer codes: their declared colours)."""
    if _kind(name) == "bool":
        return {0: _BOOL_COLORS[0], 1: _BOOL_COLORS[1]}
    codes = OUTPUTS[name].codes.codes
    palette = _code_palette(name) if any(c.color is None for c in codes) else {}
    return {c.value: c.color or palette[c.value] for c in codes}


def _undamped(ds: xr.Dataset | None) -> bool:
    """Whether ``ds`` is a map of the undamped model (``q1 = q2 = 0``), or of no known model."""
    if ds is None or "q1" not in ds.coords or "q2" not in ds.coords:
        return True
    return float(ds.q1) == 0 and float(ds.q2) == 0


def value_label(name: str, value, ds: xr.Dataset | None = None) -> str:
    """A layer's value in words: the declared label of a code (``stable``, ``class 23``),
    true / false, or the number of a continuous layer.  On a damped map ``ds`` (q1 or q2 > 0) a neutral
    verdict reads ``neutral (Re = 0)``: an eigenvalue on the imaginary axis, not the q = 0 case."""
    kind = _kind(name)
    if kind == "float":
        return f"{float(value):+.4g}"
    v = int(value)
    if kind == "enum":
        enum = OUTPUTS[name].enum
        if enum is Verdict and v == Verdict.NEUTRAL and not _undamped(ds):
            return "neutral (Re = 0)"
        try:
            return enum(v).label
        except ValueError:
            return f"code {v}"
    return "true" if v else "false"


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
    """(colour, label) pairs of a categorical layer (only codes present in ``ds`` if given, labelled
    for its model: :func:`value_label`); none for the continuous layers."""
    kind = _kind(name)
    if kind == "float":
        return []
    present = None if ds is None else set(np.unique(ds[name].values.astype(np.int64)).tolist())
    cols = _category_colors(name)
    codes = [int(v) for v in OUTPUTS[name].enum] if kind == "enum" else sorted(cols)
    return [(cols[c], value_label(name, c, ds)) for c in codes if present is None or c in present]
