"""The explorer's map (:func:`atlas.explore.compute_map`) against the atlas (:func:`atlas.data.engine.generate`)."""

from __future__ import annotations

import numpy as np
import pytest

from atlas.core.verdicts import OverModels, Verdict
from atlas.data.engine import generate
from atlas.data.outputs import OUTPUTS
from atlas.data.scene import Scene
from atlas.explore import maps


def test_even_grid_class_codes_settle_like_generate(bounded_det_b):
    """An even grid puts cells on beta2 = beta1 + pi (det B = 0), where the class code of a kernel
    with a float-bounded ``sign det B`` is undecided and settled exactly; ``cc_possible`` (never
    undecided) computed with it."""
    n = 16
    beta = maps.beta_grid(n)
    layers = ("class_code", "cc_possible")
    ds = maps.compute_map(0.5, 0.0, n=n, layers=layers)
    ref = generate(Scene(beta1=beta, beta2=beta, kappa=0.5, q=0.0, outputs=list(layers)))
    for k in layers:
        assert ds[k].dtype == ref[k].dtype, k
        np.testing.assert_array_equal(ds[k].values, ref[k].values, err_msg=k)
    fast = maps.compute_map(0.5, 0.0, n=n, layers=layers, resolve=False)["class_code"].values
    assert (fast == OUTPUTS["class_code"].undecided).any()  # the settlement path was taken


def test_compute_map_rejects_bad_input():
    for kw, msg in (
        (dict(kappa=-1.0), "kappa"),
        (dict(q1=float("nan")), "q1"),
        (dict(layers=("nope",)), "layers"),
        (dict(layers=("subclass_code",)), "alpha"),
    ):
        with pytest.raises(ValueError, match=msg):
            maps.compute_map(**{"n": 9, **kw})


def _closed_form(beta):
    """``ss_over_models`` over the whole model space in closed form (``atlas.core.model_box``'s
    docstring, derived from the Hurwitz conditions): unstable for every model iff ``det B < 0`` or
    ``c1 <= 0`` and ``s2 <= 0``; stable for every model iff ``det B >= 0``, ``c1 > 0``,
    ``s2 > 0``, ``s1 c2 >= 0``; depends otherwise.  Rows beta1, columns beta2."""
    b1, b2 = np.meshgrid(beta, beta, indexing="ij")
    c1, s1, c2, s2 = np.cos(b1), np.sin(b1), np.cos(b2), np.sin(b2)
    D = c1 * s2 - s1 * c2
    code = np.full(b1.shape, int(OverModels.DEPENDS))
    code[(D >= 0) & (c1 > 0) & (s2 > 0) & (s1 * c2 >= 0)] = int(OverModels.STABLE)
    code[(D < 0) | ((c1 <= 0) & (s2 <= 0))] = int(OverModels.UNSTABLE)
    return code


def test_box_layer_is_the_closed_form_with_witnesses_on_their_sides():
    """``ss_over_models`` as a map layer over the whole model space (a grid with no point within
    0.009 rad of a class line, so the float closed form is exact) equals the closed form;
    the witness models are there exactly where it depends, and a sample of them is on its side
    by the independent sympy/mpmath reference.  A kernel layer in the same map is unchanged."""
    from reference_sympy import point_spectral

    n = 33
    beta = (np.arange(n) + 0.3) * (2 * np.pi / n)
    ds = maps.compute_map(0.5, 0.3, beta=beta, layers=("stable_SS", "ss_over_models"))
    want = _closed_form(beta)
    np.testing.assert_array_equal(ds["ss_over_models"].values, want)
    assert ds["ss_over_models"].dims == ("beta1", "beta2") and ds.attrs["n_undecided"] == 0
    assert ds.attrs["model_box"] == maps.WHOLE_BOX
    alone = maps.compute_map(0.5, 0.3, beta=beta, layers=("stable_SS",))
    np.testing.assert_array_equal(ds["stable_SS"].values, alone["stable_SS"].values)
    depends = want == int(OverModels.DEPENDS)
    assert 0 < depends.sum() < n * n
    sides = maps.witness_outputs("ss_over_models")
    assert set(sides) == {"stable", "unstable"}
    for names in sides.values():
        for name in names:
            np.testing.assert_array_equal(np.isfinite(ds[name].values), depends, err_msg=name)
    good = (int(Verdict.STABLE), int(Verdict.NEUTRAL))
    for i, j in np.argwhere(depends)[::25]:
        d = (np.cos(beta[i]), np.sin(beta[i]), np.cos(beta[j]), np.sin(beta[j]))
        for side, names in sides.items():
            model = [float(ds[v][i, j]) for v in names]
            verdict = int(point_spectral(*d, *model)["stable_SS"])
            assert (verdict in good) == (side == "stable"), (i, j, side, model, verdict)


def test_box_layer_over_a_bounded_box_and_bad_boxes():
    """A bounded box shrinks the 'depends' region of the whole model space (a box's verdict
    "for every model" holds on a sub-box); a bad box is refused in one line naming model_box."""
    n = 17
    whole = maps.compute_map(n=n, layers=("ss_over_models",))["ss_over_models"].values
    ds = maps.compute_map(n=n, layers=("ss_over_models",), model_box="kappa=0.5:2,q=0.1:1")
    box = ds["ss_over_models"].values
    assert ds.attrs["model_box"] == "kappa=0.5:2,q=0.1:1" and ds.attrs["n_undecided"] == 0
    decided = whole != int(OverModels.DEPENDS)
    np.testing.assert_array_equal(box[decided], whole[decided])
    assert (box[~decided] != int(OverModels.DEPENDS)).any()
    for bad in ("kappa=2:1", "kappa=-1:1", "q1=nan:1", "speed=1"):
        with pytest.raises(ValueError, match="model_box"):
            maps.compute_map(n=5, layers=("ss_over_models",), model_box=bad)
