"""Colours of the explorer's map (:func:`atlas.explore.layer_rgba`, :func:`legend_entries`): a
layer's image is in the colours of the verdict enumerations, oriented for ``imshow(origin='lower')``."""

from __future__ import annotations

import matplotlib
import numpy as np
import xarray as xr
from matplotlib.colors import to_rgba

from atlas.core.verdicts import Consistency, Verdict
from atlas.explore import colors

B1 = np.array([0.5, 1.5, 2.5])
B2 = np.array([1.0, 4.0])


def _ds(**layers) -> xr.Dataset:
    return xr.Dataset(layers, coords={"beta1": B1, "beta2": B2})


def test_verdict_layer_in_enumeration_colours_image_is_beta2_by_beta1():
    codes = np.array([[0, 1], [2, 3], [1, 7]], np.int8)  # (beta1, beta2); 7 has no colour
    img = colors.layer_rgba(_ds(stable_SS=(("beta1", "beta2"), codes)), "stable_SS")
    assert img.shape == (B2.size, B1.size, 4)
    for i in range(B1.size):
        for j in range(B2.size):
            want = (1.0, 0.0, 1.0, 1.0) if codes[i, j] == 7 else to_rgba(Verdict(codes[i, j]).color)
            np.testing.assert_allclose(img[j, i], want, atol=1 / 255)


def test_one_dimensional_layer_spans_the_plane():
    flags = np.array([True, False, True])
    img = colors.layer_rgba(_ds(stable_SF=(("beta1",), flags)), "stable_SF")
    assert img.shape == (B2.size, B1.size, 4)
    for i, f in enumerate(flags):
        want = to_rgba(Consistency.CONSISTENT.color) if f else to_rgba("#f7f7f7")
        np.testing.assert_allclose(img[:, i], [want] * B2.size, atol=1 / 255)


def test_continuous_layer_diverges_about_zero():
    """Scaled by the largest finite magnitude: -2 -> blue end, 0 -> centre, 2 -> red end."""
    cmap = matplotlib.colormaps["RdBu_r"]
    m = np.array([[-2.0, 0.0], [1.0, 2.0], [np.nan, -1.0]])
    img = colors.layer_rgba(_ds(margin_SS=(("beta1", "beta2"), m)), "margin_SS")
    for (i, j), x in {(0, 0): 0.0, (0, 1): 0.5, (1, 0): 0.75, (1, 1): 1.0, (2, 1): 0.25}.items():
        np.testing.assert_allclose(img[j, i], cmap(x))
    assert img[0, 2, 3] == 0.0  # NaN: transparent


def test_legend_lists_the_codes_present():
    ds = _ds(consistent_II=(("beta1", "beta2"), np.array([[0, 3], [0, 3], [3, 0]], np.int8)))
    assert colors.legend_entries("consistent_II", ds) == [
        (Consistency.INCONSISTENT.color, "inconsistent"),
        (Consistency.UNDECIDED.color, "undecided"),
    ]
    assert [lbl for _, lbl in colors.legend_entries("stable_II")] == [v.label for v in Verdict]
    assert colors.legend_entries("margin_SS") == []  # continuous: no key


def test_class_and_subclass_codes_have_a_key_and_distinct_colours():
    """Every class (24) and subclass (144) code has its own colour (no two closer than 0.06 in
    RGB), and the legend names the codes present."""
    from atlas.data.outputs import variable_attrs

    for name, n in (("class_code", 24), ("subclass_code", 144)):
        codes = [int(c) for c in variable_attrs(name)["flag_values"] if c > 0]
        assert len(codes) == n
        cols = colors._category_colors(name)
        rgb = np.array([to_rgba(cols[c])[:3] for c in codes])
        d = np.linalg.norm(rgb[:, None] - rgb[None], axis=-1) + 10 * np.eye(n)
        assert d.min() > 0.06, name
    ds = _ds(class_code=(("beta1", "beta2"), np.array([[11, 11], [23, 0], [11, 23]], np.int8)))
    assert [lbl for _, lbl in colors.legend_entries("class_code", ds)] == [
        "degenerate",
        "class 11",
        "class 23",
    ]
    c = colors._category_colors("class_code")
    assert colors.legend_entries("class_code", ds)[1][0] == c[11]
