"""Tests for atlas.data.distributed: dask tiles == in-process atlas bit for bit, kill + resume, corruption.

The kernels compile once per tile shape; every test uses slabs of 2 beta1 values of the same 5-D
scene (and ``tile_points=128``), so the in-process runs share one set of compilations, and the
LocalCluster workers and the killed subprocess share the persistent JAX compilation cache.
The byte flip in every file of a store is ``slow``: ``python -m pytest -m slow
tests/data/test_distributed.py``.
"""

import os
import shutil
import signal
import subprocess
import sys
import textwrap
import time

import numpy as np
import pytest
import xarray as xr

pytest.importorskip("dask")
pytest.importorskip("distributed")
zarr = pytest.importorskip("zarr")

from atlas.data.cluster import worker_env  # noqa: E402
from atlas.data.distributed import generate_distributed, verify_store  # noqa: E402
from atlas.data.engine import generate  # noqa: E402
from atlas.data.io import write_netcdf  # noqa: E402
from atlas.data.scene import Scene  # noqa: E402
from atlas.data.tile_store import TILES, open_store, read_record  # noqa: E402

TP = 128  # kernel tile (points): one spectral compilation for the reference and the slabs
SCENE = dict(beta1="0:2pi:8", beta2="0:2pi:8", kappa="0.5,2", q1="0,1", q2="0,0.5")


def scene(**kw):
    return Scene(**{**SCENE, **kw})


def same_bytes(a: xr.Dataset, b: xr.Dataset, names=None):
    """Every variable and coordinate: same dims, dtype and raw bytes."""
    names = list(b.variables) if names is None else names
    assert set(a.variables) == set(b.variables)
    for k in names:
        va, vb = np.asarray(a[k].values), np.asarray(b[k].values)
        assert a[k].dims == b[k].dims, k
        assert va.dtype == vb.dtype, (k, va.dtype, vb.dtype)
        assert va.tobytes() == vb.tobytes(), k


def chunk_files(array_dir, first: int):
    """Chunk files of a zarr array (format 2 or 3) whose first chunk index is ``first``."""
    out = []
    for p in array_dir.rglob("*"):
        rel = p.relative_to(array_dir).parts
        if not p.is_file() or rel[0] in ("zarr.json", ".zarray", ".zattrs"):
            continue
        key = rel[1] if rel[0] == "c" else rel[0].split(".")[0]
        if key == str(first):
            out.append(p)
    assert out
    return out


@pytest.fixture(scope="module")
def reference():
    return generate(scene(), tile_points=TP)


@pytest.fixture(scope="module")
def inproc(tmp_path_factory, reference):
    d = tmp_path_factory.mktemp("inproc")
    summary = generate_distributed(
        scene(), d / "a.zarr", slab=2, tile_points=TP, to_netcdf=d / "a.nc"
    )
    return d, summary


def test_2d_blocks_equal_generate_and_resume(reference, tmp_path):
    """Uneven (beta1, beta2) blocks: same bytes as generate(); shared regions written once."""
    store = tmp_path / "b.zarr"
    summary = generate_distributed(
        scene(), store, slab=4, block2=3, tile_points=TP, to_netcdf=tmp_path / "b.nc"
    )
    assert summary["tiles"] == 6 and summary["block2"] == 3
    assert summary["undecided_fast"] == reference.attrs["undecided_fast"]
    got = open_store(store).load()
    same_bytes(got, reference)
    for k in reference.data_vars:
        for a in ("undecided", "undecided_fast"):
            if a in reference[k].attrs:
                assert got[k].attrs[a] == reference[k].attrs[a], (k, a)
    with xr.open_dataset(tmp_path / "b.nc") as nc:
        same_bytes(nc.load(), reference)
    rec = read_record(str(store), 4)  # beta1 [4, 8), beta2 [3, 6)
    assert (rec["start"], rec["stop"], rec["start2"], rec["stop2"]) == (4, 8, 3, 6)
    assert set(rec["shared"]) == {"stable_FS", "consistent_FI", "stable_SF", "consistent_IF"}
    # stable_SF (no beta2) belongs to the tiles at beta2 block 0: corrupt it for beta1 [4, 8)
    g = zarr.open_group(str(store), mode="r+")
    g["stable_SF"][4:8] = ~np.asarray(reference["stable_SF"].values[4:8])
    shutil.rmtree(store / TILES / "t000001")
    assert verify_store(store) == {"ok": [0, 2, 4, 5], "missing": [1], "corrupt": [3], "arrays": []}
    summary = generate_distributed(scene(), store, slab=4, block2=3, tile_points=TP, resume=True)
    assert summary["computed"] == [1, 3]
    same_bytes(open_store(store).load(), reference)


def test_in_process_equals_generate(inproc, reference, tmp_path):
    d, summary = inproc
    assert summary["tiles"] == 4 and summary["computed"] == [0, 1, 2, 3]
    assert summary["undecided_fast"] == reference.attrs["undecided_fast"]
    same_bytes(open_store(d / "a.zarr").load(), reference)
    # the netCDF conversion: same file content as write_netcdf(generate(...)) but the history time
    write_netcdf(reference, tmp_path / "ref.nc", tile_points=TP)
    with xr.open_dataset(tmp_path / "ref.nc") as ref, xr.open_dataset(d / "a.nc") as got:
        got, ref = got.load(), ref.load()
    same_bytes(got, ref)
    for k in ref.variables:
        assert got[k].attrs.keys() == ref[k].attrs.keys(), k
        for a, v in ref[k].attrs.items():
            np.testing.assert_array_equal(got[k].attrs[a], v)
            assert np.asarray(got[k].attrs[a]).dtype == np.asarray(v).dtype, (k, a)
        assert got[k].encoding.get("chunksizes") == ref[k].encoding.get("chunksizes"), k
    assert {k: v for k, v in got.attrs.items() if k != "history"} == {
        k: v for k, v in ref.attrs.items() if k != "history"
    }
    # the store: complete, every tile recorded, shared (beta1-free) variables equal in all tiles
    attrs = dict(zarr.open_group(str(d / "a.zarr"), mode="r").attrs)
    assert attrs["atlas_complete"] == 1
    recs = [
        dict(zarr.open_group(str(d / "a.zarr"), path=f"{TILES}/t{i:06d}").attrs) for i in range(4)
    ]
    assert {r["start"] for r in recs} == {0, 2, 4, 6}
    assert set(recs[0]["shared"]) == {"stable_FS", "consistent_FI"}
    assert all(r["shared"] == recs[0]["shared"] for r in recs)
    assert verify_store(d / "a.zarr") == {
        "ok": [0, 1, 2, 3],
        "missing": [],
        "corrupt": [],
        "arrays": [],
    }


_KILLED = textwrap.dedent(
    """
    import sys, time
    import atlas.data.distributed as d
    from atlas.data.scene import Scene

    compute = d.compute_tile

    def slow(*args):  # slow tiles, so the run is killed half-way
        out = compute(*args)
        time.sleep(0.5)
        return out

    d.compute_tile = slow
    scene = Scene(beta1="0:2pi:16", beta2="0:2pi:8", kappa="0.5,2", q1="0,1", q2="0,0.5")
    d.generate_distributed(scene, sys.argv[1], slab=2, tile_points=128)
    """
)


@pytest.mark.e2e
def test_killed_run_resumes(tmp_path):
    store = tmp_path / "k.zarr"
    script = tmp_path / "run.py"
    script.write_text(_KILLED)
    env = {**os.environ, **worker_env()}  # the workers' flags: shares their compilation cache
    proc = subprocess.Popen(
        [sys.executable, str(script), str(store)],
        env=env,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
    )
    deadline = time.monotonic() + 180
    try:
        while True:
            done = sum(read_record(str(store), i) is not None for i in range(8))
            if done >= 2 or proc.poll() is not None or time.monotonic() > deadline:
                break
            time.sleep(0.05)
        assert proc.poll() is None, proc.stderr.read().decode()[-2000:]
        os.kill(proc.pid, signal.SIGKILL)
    finally:
        if proc.poll() is None:
            os.kill(proc.pid, signal.SIGKILL)
        proc.wait()
        proc.stderr.close()
    report = verify_store(store)
    assert report["corrupt"] == [] and 2 <= len(report["ok"]) < 8
    assert report["missing"] == sorted(set(range(8)) - set(report["ok"]))
    assert dict(zarr.open_group(str(store), mode="r").attrs)["atlas_complete"] == 0

    big = Scene(beta1="0:2pi:16", beta2="0:2pi:8", kappa="0.5,2", q1="0,1", q2="0,0.5")
    summary = generate_distributed(big, store, slab=2, tile_points=TP, resume=True)
    assert summary["verified"] == report["ok"]
    assert summary["computed"] == report["missing"]
    assert verify_store(store)["ok"] == list(range(8))
    same_bytes(open_store(store).load(), generate(big, tile_points=TP))
    assert "resumed" in open_store(store).attrs["history"]


def test_corrupt_tiles_detected_and_recomputed(inproc, reference, tmp_path):
    store = tmp_path / "x.zarr"
    shutil.copytree(inproc[0] / "a.zarr", store)
    # tile 1: valid data, wrong values (a region rewritten behind the records' back)
    ds = open_store(store).load()
    bad = ds[["class_code"]].isel(beta1=slice(2, 4))
    bad = bad.drop_vars(list(bad.coords))
    bad["class_code"] = bad["class_code"] * 0 + 11
    bad.to_zarr(store, region={"beta1": slice(2, 4)}, consolidated=False)
    # tile 3: raw chunk bytes overwritten (undecodable)
    for chunk in chunk_files(store / "spectral_abscissa", 3):
        chunk.write_bytes(b"\x00garbage" * 8)
    # tile 2: record lost
    shutil.rmtree(store / TILES / "t000002")
    assert verify_store(store) == {"ok": [0], "missing": [2], "corrupt": [1, 3], "arrays": []}

    summary = generate_distributed(scene(), store, slab=2, tile_points=TP, resume=True)
    assert summary["corrupt"] == [1, 3] and summary["missing"] == [2]
    assert summary["computed"] == [1, 2, 3] and summary["verified"] == [0]
    same_bytes(open_store(store).load(), reference)
    assert verify_store(store)["ok"] == [0, 1, 2, 3]


def test_corrupt_shared_variable_recomputes_tile_0(inproc, reference, tmp_path):
    store = tmp_path / "s.zarr"
    shutil.copytree(inproc[0] / "a.zarr", store)
    g = zarr.open_group(str(store), mode="r+")
    g["stable_FS"][:] = ~np.asarray(reference["stable_FS"].values)
    assert verify_store(store)["corrupt"] == [0]
    summary = generate_distributed(scene(), store, slab=2, tile_points=TP, resume=True)
    assert summary["computed"] == [0]
    same_bytes(open_store(store).load(), reference)


def test_store_guards(inproc, tmp_path):
    d = inproc[0]
    with pytest.raises(FileExistsError, match="^store:"):
        generate_distributed(scene(), d / "a.zarr", slab=2, tile_points=TP)
    with pytest.raises(ValueError, match="^store: .*different atlas.*tiles"):
        generate_distributed(scene(), d / "a.zarr", slab=4, tile_points=TP, resume=True)
    with pytest.raises(ValueError, match="^store: .*different atlas"):
        generate_distributed(
            scene(kappa="0.5,3"), d / "a.zarr", slab=2, tile_points=TP, resume=True
        )
    with pytest.raises(ValueError, match="^scheduler:"):
        generate_distributed(scene(), tmp_path / "b.zarr", scheduler="nowhere", slab=2)
    with pytest.raises(ValueError, match="^store: .*not an atlas store"):
        (tmp_path / "empty").mkdir()
        generate_distributed(scene(), tmp_path / "empty", resume=True)
    with pytest.raises(FileNotFoundError, match="^store:"):
        generate_distributed(scene(), tmp_path / "no" / "b.zarr")
    # a complete store resumes without computing anything
    summary = generate_distributed(scene(), d / "a.zarr", slab=2, tile_points=TP, resume=True)
    assert summary["computed"] == [] and summary["verified"] == [0, 1, 2, 3]


def test_fixed_beta1_is_one_tile(tmp_path):
    sc = Scene(beta1=0.3, beta2="0:2pi:8", outputs="class_code,stable_FS")
    summary = generate_distributed(sc, tmp_path / "f.zarr")
    assert summary["tiles"] == 1
    same_bytes(open_store(tmp_path / "f.zarr").load(), generate(sc))


def _one_of_each_kind(files, store) -> list:
    """The first file of each kind: the group's attributes, the tile index and a tile record,
    and for coordinates and for variables of each rank (1-, 2- and 5-D chunk keys) the array
    metadata and a chunk."""
    kinds = {}
    for p in files:
        rel = p.relative_to(store).parts
        role = rel[0] if rel[0] in ("_tiles", "zarr.json") else "var"
        role = "coord" if rel[0] in ("beta1", "beta2", "kappa", "q1", "q2") else role
        kinds.setdefault((role, len(rel)), p)
    return list(kinds.values())


@pytest.mark.parametrize("every_file", [False, pytest.param(True, marks=pytest.mark.slow)])
def test_a_flipped_byte_anywhere_is_detected_and_repaired(inproc, reference, tmp_path, every_file):
    """One byte flipped in a file of each kind of a finished store (``slow``: in every file) -- a
    coordinate chunk, a variable chunk, array metadata, attributes, a tile record -- is found by
    verify_store (or the store refused with a one-line ``store:`` error), and a resume restores
    the store bit for bit."""
    store = tmp_path / "f.zarr"
    shutil.copytree(inproc[0] / "a.zarr", store)
    files = sorted(p for p in store.rglob("*") if p.is_file())
    if not every_file:
        files = _one_of_each_kind(files, store)
        assert len(files) == 9
    assert any(p.parent.name == "beta1" for p in files)
    rng = np.random.default_rng(28)
    missed = []
    for path in files:
        data = path.read_bytes()
        at = int(rng.integers(len(data)))
        path.write_bytes(data[:at] + bytes([data[at] ^ 1 << int(rng.integers(8))]) + data[at + 1 :])
        try:
            rep = verify_store(store)
            found = rep["missing"] or rep["corrupt"] or rep["arrays"]
        except ValueError as e:
            found = str(e).startswith("store:")
        if not found:
            missed.append((str(path.relative_to(store)), at))
        path.write_bytes(data)
    assert missed == []
    # a coordinate chunk and an attribute: a resume rewrites them and recomputes nothing
    coord = next(p for p in (store / "beta1").rglob("*") if p.is_file() and p.name != "zarr.json")
    raw = bytearray(coord.read_bytes())
    raw[-1] ^= 0x40
    coord.write_bytes(bytes(raw))
    zarr.open_group(str(store), mode="r+")["class_code"].attrs["long_name"] = "tampered"
    assert verify_store(store)["arrays"] == ["beta1", "attributes"]
    summary = generate_distributed(scene(), store, slab=2, tile_points=TP, resume=True)
    assert summary["repaired"] == ["beta1", "attributes"] and summary["computed"] == []
    same_bytes(open_store(store).load(), reference)
    assert verify_store(store)["arrays"] == []


def test_overwrite_replaces_only_an_atlas_store(inproc, tmp_path):
    """``overwrite`` refuses a zarr store the project did not write (no plan, no tile records)
    and a non-empty directory; an atlas store is replaced by renames (nothing left beside)."""
    small = Scene(beta1="0.1,0.2", beta2="0.3,0.4", outputs="class_code")
    foreign = tmp_path / "data.zarr"
    zarr.open_group(str(foreign), mode="w").create_array("x", shape=(3,), dtype="i4")
    (tmp_path / "d.zarr").mkdir()
    (tmp_path / "d.zarr" / "keep.txt").write_text("x")
    before = sorted(str(p) for p in tmp_path.rglob("*"))
    for place in (foreign, tmp_path / "d.zarr"):
        with pytest.raises(ValueError, match="^store: .*not an atlas store.*refusing"):
            generate_distributed(small, place, overwrite=True)
    with pytest.raises(ValueError, match="^store: "):
        generate_distributed(small, tmp_path, overwrite=True)  # a directory holding stores
    assert sorted(str(p) for p in tmp_path.rglob("*")) == before
    store = tmp_path / "a.zarr"
    shutil.copytree(inproc[0] / "a.zarr", store)
    summary = generate_distributed(small, store, overwrite=True)
    assert summary["computed"] == [0]
    assert sorted(os.listdir(tmp_path)) == ["a.zarr", "d.zarr", "data.zarr"]
    same_bytes(open_store(store).load(), generate(small))


def test_a_second_writer_is_refused_and_a_changed_store_gives_no_file(
    inproc, tmp_path, monkeypatch
):
    """A live writer's lock refuses a second one; a region changed under a run (by a writer that
    ignored the lock) is found when the file is assembled: no netCDF file."""
    import json
    import socket

    from atlas.data import store_guard, tile_store

    small = Scene(beta1="0.1,0.2", beta2="0.3,0.4", outputs="class_code")
    store = tmp_path / "a.zarr"
    with open(store_guard.lock_path(str(store)), "w") as fh:
        json.dump({"pid": os.getppid(), "host": socket.gethostname()}, fh)
    with pytest.raises(BlockingIOError, match="^store: .*being written by process"):
        generate_distributed(small, store)
    assert not store.exists()
    os.remove(store_guard.lock_path(str(store)))
    mark = tile_store.mark_complete

    def then_changed(path, *a):
        mark(path, *a)
        zarr.open_group(path, mode="r+")["class_code"][0, 0] = 99

    monkeypatch.setattr(tile_store, "mark_complete", then_changed)
    nc = tmp_path / "a.nc"
    with pytest.raises(RuntimeError, match="^store: .*changed under this run.*class_code"):
        generate_distributed(small, store, to_netcdf=nc)
    assert not nc.exists() and not os.path.exists(store_guard.lock_path(str(store)))


def _files(store):
    """Every file but the two a resume rewrites (its history: the root and the record)."""
    skip = {"zarr.json", f"{TILES}/zarr.json"}
    files = (p for p in sorted(store.rglob("*")) if p.is_file())
    return {
        p.relative_to(store): p.read_bytes() for p in files if str(p.relative_to(store)) not in skip
    }


def test_a_damaged_record_or_root_is_rebuilt_when_the_data_verify(inproc, reference, tmp_path):
    """The attribute record (its value), the root metadata (truncated) and the plan's hash (a
    flipped bit) are rebuilt by --resume from what verifies (the metadata against plan and schema,
    the root from the record's copy) without recomputing a tile; a damaged record whose attributes
    also differ is refused naming the variable; another atlas names what differs."""
    good = inproc[0] / "a.zarr"
    store = tmp_path / "f.zarr"
    record = store / TILES / "zarr.json"

    def damaged(edits):
        shutil.rmtree(store, ignore_errors=True)
        shutil.copytree(good, store)
        for path, edit in edits:
            path.write_bytes(edit(path.read_bytes()))
        return generate_distributed(scene(), store, slab=2, tile_points=TP, resume=True)

    flip = lambda at: lambda d: d[:at] + bytes([d[at] ^ 1]) + d[at + 1 :]  # noqa: E731
    root = (good / "zarr.json").read_bytes()
    cases = [
        [(record, flip(len((good / TILES / "zarr.json").read_bytes()) // 2))],
        [(store / "zarr.json", lambda d: d[: len(d) // 2])],
        [(store / "zarr.json", flip(root.index(b'\\"hash\\": \\"') + 12))],
    ]
    for edits in cases:
        summary = damaged(edits)
        assert summary["computed"] == [] and _files(store) == _files(good), edits
        assert verify_store(store) == {
            "ok": [0, 1, 2, 3],
            "missing": [],
            "corrupt": [],
            "arrays": [],
        }
        same_bytes(open_store(store).load(), reference)
    for name in ("beta1", "class_code"):  # array metadata: rebuilt from a fresh layout
        meta = store / name / "zarr.json"
        summary = damaged([(meta, lambda d: d.replace(b'"fill_value"', b'"fill_valuf"'))])
        assert summary["computed"] == [] and _files(store) == _files(good), name
    unit = store / "stable_SS" / "zarr.json"
    swap = lambda d: d.replace(b'"flag_meanings": "', b'"flag_meanings": "x', 1)  # noqa: E731
    with pytest.raises(ValueError, match="^store: .*record .*damaged.*differ .* in stable_SS"):
        damaged([(record, flip(len((good / TILES / "zarr.json").read_bytes()) // 2)), (unit, swap)])
