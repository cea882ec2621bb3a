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


def test_overwrite_replaces_only_an_outcome_store(tmp_path, monkeypatch):
    """``overwrite`` never deletes a directory the project did not write: the working directory
    (with a file beside the would-be store), a non-empty directory without a plan; a store it
    wrote is replaced by renames."""
    work = tmp_path / "w"
    (work / "sub").mkdir(parents=True)
    (work / "keep.txt").write_text("x")
    monkeypatch.chdir(work)
    small = SCENE.replace(beta1="0.1,0.2")
    for place in (".", "", str(work), "sub/.."):
        with pytest.raises(ValueError, match="^store: "):
            T.outcome_atlas_tiles(small, place, dynamics=DYN, theory=False, overwrite=True)
    (work / "theirs").mkdir()
    (work / "theirs" / "notes.md").write_text("mine")
    with pytest.raises(ValueError, match="^store: .*not an outcome-atlas store"):
        T.outcome_atlas_tiles(small, "theirs", dynamics=DYN, theory=False, overwrite=True)
    assert (work / "keep.txt").read_text() == "x" and (work / "sub").is_dir()
    assert (work / "theirs" / "notes.md").read_text() == "mine"
    T.outcome_atlas_tiles(small, "m.tiles", dynamics=DYN, slab=1, theory=False)
    s = T.outcome_atlas_tiles(SCENE, "m.tiles", dynamics=DYN, slab=5, theory=False, overwrite=True)
    assert sorted(os.listdir("m.tiles")) == ["plan.json", "t000000.json", "t000000.npy"]
    assert s["computed"] == [0]
    assert sorted(os.listdir(work)) == ["keep.txt", "m.tiles", "sub", "theirs"]


def test_resume_after_a_killed_replacement(tmp_path, single, capsys):
    """A run killed between the renames of ``overwrite`` leaves the store only as
    ``.NAME.old.PID``: ``resume`` renames it back (one line) and computes nothing."""
    import subprocess
    import sys

    store = tmp_path / "m.tiles"
    T.outcome_atlas_tiles(SCENE, store, dynamics=DYN, slab=2, theory=False)
    gone = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True, check=True)  # fmt: skip
    os.rename(store, tmp_path / f".m.tiles.old.{int(gone.stdout)}")
    capsys.readouterr()
    s = T.outcome_atlas_tiles(SCENE, store, dynamics=DYN, slab=2, theory=False, resume=True)
    assert s["computed"] == [] and s["verified"] == [0, 1, 2]
    _same(s["dataset"], single)
    assert capsys.readouterr().err.startswith(f"store: restored {store} from ")
    assert sorted(os.listdir(tmp_path)) == ["m.tiles"]


def test_resume_of_no_store_is_refused(tmp_path):
    with pytest.raises(FileNotFoundError, match="^resume: store .* does not exist"):
        T.outcome_atlas_tiles(SCENE, tmp_path / "none", dynamics=DYN, resume=True)
    assert os.listdir(tmp_path) == []


def test_a_second_writer_is_refused(tmp_path):
    """A store held by a live writer (its lock file: pid and host) is refused, store untouched."""
    import json
    import socket

    from atlas.data import store_guard

    store = tmp_path / "m.tiles"
    T.outcome_atlas_tiles(SCENE, store, dynamics=DYN, slab=2, theory=False)
    before = {p: (store / p).read_bytes() for p in os.listdir(store)}
    with open(store_guard.lock_path(str(store)), "w") as fh:
        json.dump({"pid": os.getppid(), "host": socket.gethostname()}, fh)
    for kw in ({"overwrite": True}, {"resume": True}):
        with pytest.raises(BlockingIOError, match="^store: .*being written by process"):
            T.outcome_atlas_tiles(SCENE.replace(q=0.5), store, dynamics=DYN, theory=False, **kw)
    assert {p: (store / p).read_bytes() for p in os.listdir(store)} == before


@pytest.mark.parametrize("swap", ["tile", "plan"])
def test_a_store_changed_under_the_writer_gives_no_file(tmp_path, swap):
    """Another writer that ignores the lock replaces a tile or the plan while this one runs: the
    assembly checks every tile against this run's records and plan and refuses; no file."""
    store, other = tmp_path / "m.tiles", tmp_path / "o.tiles"
    T.outcome_atlas_tiles(SCENE.replace(q=0.5), other, dynamics=DYN, slab=2, theory=False)
    calls = []

    def progress(done, total):
        calls.append(done)
        if len(calls) == 2:  # after the first tile
            name = "t000000.npy" if swap == "tile" else "plan.json"
            (store / name).write_bytes((other / name).read_bytes())

    nc = tmp_path / "m.nc"
    with pytest.raises(RuntimeError, match="^store: .*changed under this run"):
        T.outcome_atlas_tiles(
            SCENE, store, dynamics=DYN, slab=2, theory=False, progress=progress, to_netcdf=nc
        )
    assert not nc.exists()


def _edit_json(path, edit):
    import json

    rec = json.loads(path.read_text())
    edit(rec)
    path.write_text(json.dumps(rec, sort_keys=True))


def test_every_record_is_checked(tmp_path, single):
    """A tile record with one number changed is recomputed (not "verified"); a plan with a
    flipped bit is rebuilt from the tile records made for it; a plan of another atlas (intact)
    or a damaged plan no record confirms is refused, naming what differs."""
    store = tmp_path / "m.tiles"
    T.outcome_atlas_tiles(SCENE, store, dynamics=DYN, slab=2, theory=False)
    more = lambda r: r["info"].update(trajectories=r["info"]["trajectories"] + 1)  # noqa: E731
    _edit_json(store / "t000001.json", more)
    s = T.outcome_atlas_tiles(SCENE, store, dynamics=DYN, slab=2, theory=False, resume=True)
    assert s["computed"] == [1] and s["trajectories"] == single.attrs["trajectories"]
    plan = (store / "plan.json").read_bytes()
    for at in (plan.index(b'"hash"') + 12, plan.index(b'"dynamics"') + 20):
        (store / "plan.json").write_bytes(plan[:at] + bytes([plan[at] ^ 1]) + plan[at + 1 :])
        s = T.outcome_atlas_tiles(SCENE, store, dynamics=DYN, slab=2, theory=False, resume=True)
        assert s["computed"] == [] and (store / "plan.json").read_bytes() == plan
    (store / "plan.json").write_bytes(plan[: len(plan) // 2])  # truncated: the records decide
    s = T.outcome_atlas_tiles(SCENE, store, dynamics=DYN, slab=2, theory=False, resume=True)
    assert s["computed"] == [] and (store / "plan.json").read_bytes() == plan
    for name in os.listdir(store):
        if name.endswith(".json") and name != "plan.json":
            os.remove(store / name)
    (store / "plan.json").write_bytes(plan[: len(plan) // 2])
    with pytest.raises(ValueError, match="^store: .*plan.json is damaged and no tile record"):
        T.outcome_atlas_tiles(SCENE, store, dynamics=DYN, slab=2, theory=False, resume=True)
