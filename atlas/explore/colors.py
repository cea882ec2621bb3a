"""Colours of the explorer's map: a layer as an RGBA image and its legend, chosen by what the
registry (:mod:`atlas.data.outputs`) declares of the layer: integer codes in the colours and labels
of their declared codes (:class:`atlas.core.verdicts.Codes`; a code declared without a colour takes
a palette), booleans in two colours, float layers on a diverging map; matplotlib only for the
continuous layers and the code palettes."""

from __future__ import annotations

import numpy as np
import xarray as xr

from atlas.core.verdicts import CONSISTENCY
from atlas.data.outputs import OUTPUTS

__all__ = ["layer_rgba", "legend_entries", "value_label", "raw_label"]


def _hex_rgba(h: str) -> tuple:
    h = h.lstrip("#")
    return tuple(int(h[i : i + 2], 16) / 255 for i in (0, 2, 4)) + (1.0,)


#: the colours of ``False`` and ``True`` of a boolean layer declared without colours
_BOOL_COLORS = (CONSISTENCY.code(0).color, CONSISTENCY.code(1).color)


def _code_palette(name: str) -> dict:
    """code -> colour of the codes of an integer layer declared without a colour, none repeated:
    hues 7/n of a turn apart (saturation 0.75, value 0.85), n the number of such codes."""
    import colorsys

    import matplotlib

    codes = [c.value for c in OUTPUTS[name].codes.codes if c.color is None]
    n = max(len(codes), 2)
    return {
        c: matplotlib.colors.to_hex(colorsys.hsv_to_rgb((7 * i % n) / n, 0.75, 0.85))
        for i, c in enumerate(codes)
    }


def _kind(name: str) -> str:
    """How a layer is drawn: ``"enum"`` (declared integer codes), ``"bool"`` or ``"float"``."""
    return {"bool": "bool", "float": "float"}.get(OUTPUTS[name].storage, "enum")


def _category_colors(name: str) -> dict:
    """code -> colour for the categorical layers (integer codes: their declared colours)."""
    codes = OUTPUTS[name].codes.codes
    if _kind(name) == "bool":
        return {c.value: c.color or _BOOL_COLORS[c.value] for c in codes}
    palette = _code_palette(name) if any(c.color is None for c in codes) else {}
    return {c.value: c.color or palette[c.value] for c in codes}


def _undamped(ds: xr.Dataset | None) -> bool:
    """Whether ``ds`` is a map of the undamped model (``q1 = q2 = 0``), or of no known model."""
    if ds is None or "q1" not in ds.coords or "q2" not in ds.coords:
        return True
    return float(ds.q1) == 0 and float(ds.q2) == 0


def value_label(name: str, value, ds: xr.Dataset | None = None) -> str:
    """A layer's value in words: the declared label of a code (``stable``, ``class 23``),
    true / false, or the number of a continuous layer.  On a damped map ``ds`` (q1 or q2 > 0) a
    code's declared ``damped_label`` (a neutral verdict: ``neutral (Re = 0)``, an eigenvalue on the
    imaginary axis, not the q = 0 case)."""
    kind = _kind(name)
    if kind == "float":
        return f"{float(value):+.4g}"
    if kind == "enum":
        return _code_label(OUTPUTS[name].codes, value, ds)
    return "true" if int(value) else "false"


def raw_label(name: str, raw, ds: xr.Dataset | None = None) -> str:
    """A kernel's raw value of output ``name`` in words: by the output's declared raw codes where
    it has them (a boolean stored from a verdict: ``neutral``, ``undecided``), else as stored
    (:func:`value_label`)."""
    raw_codes = OUTPUTS[name].raw
    return value_label(name, raw, ds) if raw_codes is None else _code_label(raw_codes, raw, ds)


def _code_label(codes, value, ds) -> str:
    try:
        code = codes.code(int(value))
    except ValueError:
        return f"code {int(value)}"
    return code.damped_label if code.damped_label and not _undamped(ds) else code.label


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
    in their declared colours, continuous ones on a diverging map centred at 0."""
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
