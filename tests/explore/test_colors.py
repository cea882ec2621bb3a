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


#: simulated colour vision on linear sRGB (Machado, Oliveira & Fernandes 2009, severity 1)
_VISION = {
    "normal": np.eye(3),
    "deutan": [[0.367322, 0.860646, -0.227968], [0.280085, 0.672501, 0.047413],
               [-0.011820, 0.042940, 0.968881]],
    "protan": [[0.152286, 1.052583, -0.204868], [0.114503, 0.786281, 0.099216],
               [-0.003882, -0.048116, 1.051998]],
    "tritan": [[1.255528, -0.076749, -0.178779], [-0.078411, 0.930809, 0.147602],
               [0.004733, 0.691367, 0.303900]],
}  # fmt: skip


def _lab(hex_colour: str, vision) -> np.ndarray:
    """CIE L*a*b* (D65) of an sRGB colour as seen with ``vision``."""
    c = np.array(to_rgba(hex_colour)[:3])
    lin = np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)
    lin = np.clip(np.asarray(vision) @ lin, 0, 1)
    xyz = np.array([[0.4124, 0.3576, 0.1805], [0.2126, 0.7152, 0.0722], [0.0193, 0.1192, 0.9505]])
    t = xyz @ lin / np.array([0.95047, 1.0, 1.08883])
    f = np.where(t > 0.008856, np.cbrt(t), 7.787 * t + 16 / 116)
    return np.array([116 * f[1] - 16, 500 * (f[0] - f[1]), 200 * (f[1] - f[2])])


def test_neighbouring_classes_are_distinguishable_also_colour_blind():
    """Classes that share an edge on the plane (read off a 257^2 class map, 4- and
    8-neighbours on the torus) differ by CIE76 Delta E >= 20 in normal, deutan, protan and
    tritan vision; any two classes by >= 8 (the key stays readable)."""
    from atlas.explore import maps

    v = maps.compute_map(0.5, 0.0, n=257, layers=("class_code",))["class_code"].values
    pairs = set()
    for shift in ((1, 0), (0, 1), (1, 1), (1, -1)):
        w = np.roll(v, shift, axis=(0, 1))
        m = (v != w) & (v > 0) & (w > 0)
        pairs |= {tuple(sorted(p)) for p in zip(v[m].tolist(), w[m].tolist())}
    assert len(pairs) > 40  # the 24 classes tile the plane
    cols = colors._category_colors("class_code")
    codes = sorted({c for p in pairs for c in p})

    def delta(a, b):
        return min(np.linalg.norm(_lab(cols[a], m) - _lab(cols[b], m)) for m in _VISION.values())

    worst = min((delta(a, b), a, b) for a, b in pairs)
    assert worst[0] >= 20, worst
    worst = min((delta(a, b), a, b) for i, a in enumerate(codes) for b in codes[i + 1 :])
    assert worst[0] >= 8, worst


def test_neutral_key_names_q_zero_only_on_an_undamped_map():
    """A damped map's neutral cells (an eigenvalue on the imaginary axis, e.g. det B = 0 on
    beta1 = beta2) are not labelled as the q = 0 case."""
    codes = np.array([[1, 2], [0, 1], [2, 0]], np.int8)
    for q, label in ((1.2, "neutral (Re = 0)"), (0.0, Verdict.NEUTRAL.label)):
        ds = _ds(stable_SS=(("beta1", "beta2"), codes)).assign_coords(q1=q, q2=q)
        labels = [lbl for _, lbl in colors.legend_entries("stable_SS", ds)]
        assert labels == ["unstable", "stable", label]
        assert colors.value_label("stable_SS", 2, ds) == label
