"""The explorer's map (:func:`atlas.explore.compute_map`) against the atlas (:func:`atlas.data.engine.generate`)."""

from __future__ import annotations

import numpy as np
import pytest

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
