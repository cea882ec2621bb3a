"""Verdicts over a model box in a tiled store (``atlas.data.box_tiles``): the store, its netCDF,
an interrupted-then-resumed run and ``atlas generate --model-box --store`` give the dataset of the
in-memory ``atlas.generate(scene, model_box=...)`` (an independent path: the whole grid in one
call), same values, attributes and witnesses; a store of another box is refused in one line.

The 12^2 geometry and the bounded box (``kappa=0.5:2, q=0.1:1``) leave SS and II each with
"depends" points (witnesses) and an II settlement to run, in a few seconds.
"""

import contextlib
import io

import numpy as np
import pytest
import xarray as xr

pytest.importorskip("dask")
zarr = pytest.importorskip("zarr")

import atlas  # noqa: E402
from atlas import cli  # noqa: E402
from atlas.core.verdicts import OverModels  # noqa: E402
from atlas.data import distributed  # noqa: E402
from atlas.data.box_tiles import BOX_COUNTS, BOX_OUTPUTS  # noqa: E402
from atlas.data.distributed import generate_distributed, verify_store  # noqa: E402
from atlas.data.io import write_netcdf  # noqa: E402
from atlas.data.tile_store import open_store, read_record  # noqa: E402

TP = 128
BOX = "kappa=0.5:2,q=0.1:1"
GRID = dict(beta1="0.1:6.2:12", beta2="0.05:6.25:12", kappa="0.5,2", q=0.0)
TILES = dict(slab=5, block2=7, tile_points=TP)  # 3 x 2 uneven blocks


def scene():
    return atlas.Scene(**GRID)


def _timeless(attrs) -> dict:
    """The attributes that do not measure time (``history``, ``*_seconds``) nor mark a store."""
    drop = ("history", "atlas_plan", "atlas_complete")
    return {k: v for k, v in attrs.items() if k not in drop and not k.endswith("_seconds")}


def same_dataset(got: xr.Dataset, ref: xr.Dataset):
    """Same variables (dims, dtype, raw bytes: NaN witnesses included), variable attributes and
    global attributes but the times."""
    assert set(got.data_vars) == set(ref.data_vars)
    for k in ref.variables:
        a, b = np.asarray(got[k].values), np.asarray(ref[k].values)
        assert got[k].dims == ref[k].dims and a.dtype == b.dtype, k
        assert a.tobytes() == b.tobytes(), k
        assert got[k].attrs.keys() == ref[k].attrs.keys(), k
        for name, v in ref[k].attrs.items():
            np.testing.assert_array_equal(got[k].attrs[name], v)
    assert _timeless(got.attrs) == _timeless(ref.attrs)


@pytest.fixture(scope="module")
def reference():
    return atlas.generate(scene(), model_box=BOX, tile_points=TP)


@pytest.fixture(scope="module")
def stored(tmp_path_factory):
    d = tmp_path_factory.mktemp("box")
    summary = generate_distributed(
        scene(), d / "a.zarr", model_box=BOX, to_netcdf=d / "a.nc", **TILES
    )
    return d, summary


def test_the_reference_exercises_every_part(reference):
    """SS and II each have "depends" points (so witnesses) and the II settlement ran."""
    for name in ("ss_over_models", "ii_consistent_over_models", "ii_stable_over_models"):
        assert (reference[name].values == int(OverModels.DEPENDS)).any(), name
    assert reference.attrs["ii_over_models_undecided_before_settlement"] > 0


def test_store_and_its_netcdf_equal_the_in_memory_atlas(stored, reference, tmp_path):
    d, summary = stored
    assert summary["tiles"] == 6 and summary["computed"] == list(range(6))
    assert _timeless(summary["over_models"]) == {
        k: reference.attrs[k] for k in ("model_box", *BOX_COUNTS) if not k.endswith("_seconds")
    }
    got = open_store(d / "a.zarr").load()
    assert set(BOX_OUTPUTS) <= set(got.data_vars)
    same_dataset(got, reference)
    assert got.attrs["atlas_complete"] == 1
    # the netCDF file: as write_netcdf of the in-memory atlas (attributes in the same order)
    write_netcdf(reference, tmp_path / "ref.nc", tile_points=TP)
    with xr.open_dataset(tmp_path / "ref.nc") as ref, xr.open_dataset(d / "a.nc") as nc:
        ref, nc = ref.load(), nc.load()
    same_dataset(nc, ref)
    assert list(_timeless(nc.attrs)) == list(_timeless(ref.attrs))
    for k in BOX_OUTPUTS:
        assert nc[k].encoding.get("chunksizes") == ref[k].encoding.get("chunksizes"), k
    # each tile owns its block of the box variables and records its counts
    rec = read_record(str(d / "a.zarr"), 3)  # beta1 [5, 10), beta2 [7, 12)
    assert set(BOX_OUTPUTS) <= set(rec["checksums"]) and set(rec["box_counts"]) == set(BOX_COUNTS)
    assert verify_store(d / "a.zarr")["ok"] == list(range(6))


def test_an_interrupted_run_resumes_to_the_same_store(stored, tmp_path, monkeypatch):
    store = tmp_path / "k.zarr"
    compute, calls = distributed.compute_tile, []

    def stopped(*args):  # the third tile is interrupted (Ctrl-C)
        calls.append(args[1])
        if len(calls) == 3:
            raise KeyboardInterrupt
        return compute(*args)

    monkeypatch.setattr(distributed, "compute_tile", stopped)
    with pytest.raises(KeyboardInterrupt):
        generate_distributed(scene(), store, model_box=BOX, **TILES)
    monkeypatch.setattr(distributed, "compute_tile", compute)
    report = verify_store(store)
    assert report["ok"] == [0, 1] and report["missing"] == [2, 3, 4, 5]
    assert dict(zarr.open_group(str(store), mode="r").attrs)["atlas_complete"] == 0

    summary = generate_distributed(scene(), store, model_box=BOX, resume=True, **TILES)
    assert summary["verified"] == [0, 1] and summary["computed"] == [2, 3, 4, 5]
    whole = open_store(stored[0] / "a.zarr").load()
    got = open_store(store).load()
    same_dataset(got, whole)
    for k in whole.data_vars:
        assert read_record(str(store), 0)["checksums"].get(k) == read_record(
            str(stored[0] / "a.zarr"), 0
        )["checksums"].get(k), k


def test_another_box_or_none_is_refused_on_resume(stored):
    store = stored[0] / "a.zarr"
    with pytest.raises(ValueError, match="^model_box: store .* over kappa=0.5:2,q=0.1:1, this run "
                       "asks for no model box") as e:  # fmt: skip
        generate_distributed(scene(), store, resume=True, **TILES)
    assert "\n" not in str(e.value)
    with pytest.raises(ValueError, match="^model_box: .* asks for kappa=0.5:3"):
        generate_distributed(scene(), store, model_box="kappa=0.5:3,q=0.1:1", resume=True, **TILES)
    with pytest.raises(ValueError, match="^model_box: kappa: reversed"):
        generate_distributed(scene(), stored[0] / "b.zarr", model_box="kappa=3:1", **TILES)
    assert not (stored[0] / "b.zarr").exists()


def _main(args):
    err = io.StringIO()
    with contextlib.redirect_stderr(err):
        rc = cli.main(args)
    return rc, err.getvalue()


def test_cli_store_with_a_model_box(stored, reference, tmp_path):
    """``atlas generate --model-box --store --scheduler inprocess`` (in this process): the same
    file; a resume over another box, or a bad box, is refused in one line naming model_box."""
    args = ["generate", "--beta1", GRID["beta1"], "--beta2", GRID["beta2"], "--kappa", "0.5,2"]
    args += ["--q", "0.0", "--tile-points", str(TP), "--slab", "5", "--block2", "7"]
    store, out = tmp_path / "s.zarr", tmp_path / "s.nc"
    rc, err = _main([*args, "--model-box", BOX, "--store", str(store), "--out", str(out)]
                    + ["--scheduler", "inprocess"])  # fmt: skip
    assert rc == 0, err
    n = reference.attrs
    assert (
        f"over the model box {BOX}: undecided {n['over_models_undecided_before_settlement']} "
        f"before, {n['over_models_undecided']} after settlement; II: undecided "
        f"{n['ii_over_models_undecided_before_settlement']} before, "
        f"{n['ii_over_models_undecided']} after"
    ) in err
    with xr.open_dataset(out) as nc:
        with xr.open_dataset(stored[0] / "a.nc") as api:
            same_dataset(nc.load(), api.load())
    for box in ("kappa=1:2,q=0.1:1", "kappa=2:1"):
        rc, err = _main([*args, "--model-box", box, "--store", str(store), "--resume"])
        assert rc == 2 and err.count("\n") == 1 and err.startswith("atlas: error: model_box: "), err


@pytest.mark.e2e
def test_a_local_cluster_gives_the_same_store(stored, tmp_path):
    """Tiles on a dask worker process (the box pickled to it): the in-process store's bytes."""
    pytest.importorskip("distributed")
    summary = generate_distributed(
        scene(), tmp_path / "c.zarr", scheduler="local:1", model_box=BOX, **TILES
    )
    assert summary["workers"] == 1 and summary["computed"] == list(range(6))
    same_dataset(open_store(tmp_path / "c.zarr").load(), open_store(stored[0] / "a.zarr").load())
