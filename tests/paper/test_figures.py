"""Fig. 1 map: regions agree with the kernels (and the exact reference) at sampled pixels."""

import numpy as np
import pytest

from atlas.core import exact, mechanics
from atlas.core.verdicts import Verdict
from atlas.paper.figures import _offset_grid, stability_map


@pytest.fixture(scope="module")
def ds():
    return stability_map(41, 0.5, 0.0, 0.0)


def test_schema(ds):
    assert ds["stable_SS"].dims == ("beta1", "beta2")
    assert ds["stable_SF"].dims == ("beta1",)
    assert ds["stable_SS"].dtype == np.int8
    assert set(np.unique(ds["class_code"].values)) <= set(mechanics.ALL_CLASSES) | {
        0
    }  # 0: beta2 = beta1
    assert ds.attrs["n_undecided"] == 0


def test_regions_match_exact_reference(ds):
    rng = np.random.default_rng(0)
    b = _offset_grid(41)
    for i, j in rng.integers(0, 41, (25, 2)):
        c1, s1 = (float(v) for v in mechanics.direction(b[i]))
        c2, s2 = (float(v) for v in mechanics.direction(b[j]))
        r = exact.point_spectral(c1, s1, c2, s2, 0.5, 0.0, 0.0)
        for k in ("stable_SS", "consistent_II", "stable_II"):
            assert int(ds[k].values[i, j]) == r[k], (k, i, j)
        assert int(ds["class_code"].values[i, j]) == exact.point_codes(c1, s1, c2, s2)["class_code"]
        assert int(ds["stable_SF"].values[i]) == (Verdict.STABLE if c1 > 0 else Verdict.UNSTABLE)


def test_ss_margin_sign_matches_verdict_in_curved_classes(ds):
    # inside classes with curved boundaries, neutral <=> margin > 0 (q = 0)
    cls = ds["class_code"].values
    sel = np.isin(cls, (13, 23, 41, 46))
    ss = ds["stable_SS"].values[sel]
    m = ds["margin_SS"].values[sel]
    assert np.all((ss == Verdict.NEUTRAL) == (m > 0))


def test_damped_map_has_stable_cells():
    d = stability_map(21, 0.5, 1.0, 1.0, margins=False)
    assert (d["stable_SS"].values == Verdict.STABLE).any()
    interior = d["class_code"].values != 0  # det B = 0 on beta2 = beta1: double zero root, neutral
    assert not (d["stable_SS"].values[interior] == Verdict.NEUTRAL).any()
