"""Outcome atlases tile by tile (atlas.dynamics.outcome_tiles): bit-identical to one process,
resumable after lost or damaged tiles, refusing a store of another atlas."""

import os

import numpy as np
import pytest

from atlas.dynamics import outcome_tiles as T
from atlas.dynamics import outcomes as O

SCENE = O.outcome_scene("0.1:3:5", "0.2pi,0.7pi,1.3pi", kappa="0.5,2", q=0.3)
DYN = O.Dynamics(n_perturb=2, t_end=60.0)


@pytest.fixture(scope="module")
def single():
    return O.outcome_atlas(SCENE, theory=False, **DYN.attrs())


def _same(a, b):
    assert set(a.data_vars) == set(b.data_vars)
    for k in list(a.data_vars) + list(a.coords):
        assert a[k].dtype == b[k].dtype and a[k].dims == b[k].dims, k
        assert a[k].values.tobytes() == b[k].values.tobytes(), k


def test_tiles_bit_identical_and_resumable(tmp_path, single):
    store = tmp_path / "m.tiles"
    s = T.outcome_atlas_tiles(SCENE, store, dynamics=DYN, slab=2, theory=False)
    assert s["tiles"] == 3 and s["computed"] == [0, 1, 2] and s["verified"] == []
    _same(s["dataset"], single)
    # a lost tile and a damaged one: the resume recomputes exactly those, same bytes again
    os.remove(store / "t000000.npy")
    data = bytearray((store / "t000002.npy").read_bytes())
    data[-1] ^= 1
    (store / "t000002.npy").write_bytes(bytes(data))
    nc = tmp_path / "m.nc"
    s = T.outcome_atlas_tiles(
        SCENE, store, dynamics=DYN, slab=2, theory=False, resume=True, to_netcdf=nc
    )
    assert s["computed"] == [0, 2] and s["verified"] == [1]
    _same(s["dataset"], single)
    assert "resumed: 2 of 3 tiles computed" in s["dataset"].attrs["history"]
    import xarray as xr

    with xr.open_dataset(nc) as back:
        np.testing.assert_array_equal(back["outcome_count"].values, single["outcome_count"])
    # complete: a second resume computes nothing
    s = T.outcome_atlas_tiles(SCENE, store, dynamics=DYN, slab=2, theory=False, resume=True)
    assert s["computed"] == [] and s["verified"] == [0, 1, 2]


def test_store_of_another_atlas_is_refused(tmp_path):
    with pytest.raises(ValueError, match="^scheduler: "):
        T.outcome_atlas_tiles(SCENE, tmp_path / "e.tiles", dynamics=DYN, scheduler="local:0")
    assert not (tmp_path / "e.tiles").exists()
    store = tmp_path / "m.tiles"
    T.outcome_atlas_tiles(SCENE.replace(beta1="0.1,0.2"), store, dynamics=DYN, theory=False)
    with pytest.raises(FileExistsError, match="^store: "):
        T.outcome_atlas_tiles(SCENE, store, dynamics=DYN)
    with pytest.raises(ValueError, match="^store: .*differs in .*scene"):
        T.outcome_atlas_tiles(SCENE, store, dynamics=DYN, resume=True)
    with pytest.raises(ValueError, match="^store: .*dynamics"):
        T.outcome_atlas_tiles(
            SCENE.replace(beta1="0.1,0.2"), store, dynamics=O.Dynamics(n_perturb=3), resume=True
        )


@pytest.mark.slow
def test_tiles_on_dask_workers_bit_identical(tmp_path, single):
    pytest.importorskip("distributed")
    s = T.outcome_atlas_tiles(
        SCENE, tmp_path / "d.tiles", dynamics=DYN, slab=1, theory=False, scheduler="local:2"
    )
    assert s["computed"] == list(range(5))
    _same(s["dataset"], single)
