"""netCDF files: round trip, encodings, streaming == in-memory, atomic and interrupted writes."""

import os
import subprocess
import sys
import textwrap

import netCDF4
import numpy as np
import pytest
import xarray as xr

from atlas.data import io as aio
from atlas.data.engine import block_shape, generate
from atlas.data.io import generate_to_file, write_netcdf
from atlas.data.scene import Scene

TILE = 1024


def small_scene(**kw):
    base = dict(
        beta1="0:2pi:16",
        beta2="0:2pi:16",
        alpha="0:2pi:4",
        kappa="0.5,2",
        q="0,0.5",
        outputs="class_code,subclass_code,consistent_SS,stable_SF,cc_possible,stable_SS,"
        "spectral_abscissa,model_dependent_SS",
    )
    base.update(kw)
    return Scene(name="small", **base)


@pytest.fixture(scope="module")
def ds():
    return generate(small_scene(), tile_points=TILE, resolve=False)


def _strip_history(x):
    x = x.copy()
    x.attrs = {k: v for k, v in x.attrs.items() if k != "history"}
    return x


def test_round_trip_identical(ds, tmp_path):
    path = tmp_path / "a.nc"
    write_netcdf(ds, path, tile_points=TILE)
    with xr.open_dataset(path) as back:
        back.load()
        xr.testing.assert_identical(back, ds)
        assert back.class_code.dtype == np.int8
        assert back.stable_SS.dtype == np.int8
        assert back.subclass_code.dtype == np.int16
        assert back.consistent_SS.dtype == bool
        assert back.stable_SS.encoding["chunksizes"] == block_shape((16, 16, 2, 2), TILE)
        assert back.stable_SS.encoding["zlib"]


def test_no_fill_values_in_file(ds, tmp_path):
    path = tmp_path / "a.nc"
    write_netcdf(ds, path)
    with netCDF4.Dataset(path) as nc:
        for name, var in nc.variables.items():
            assert "_FillValue" not in var.ncattrs(), name
        assert nc.variables["stable_SS"].dtype == np.int8
        assert nc.variables["beta1"].units == "rad"
        assert nc.Conventions == "CF-1.10"


def test_streaming_equals_in_memory(ds, tmp_path):
    a, b = tmp_path / "mem.nc", tmp_path / "stream.nc"
    write_netcdf(ds, a, tile_points=TILE)
    stats = generate_to_file(small_scene(), b, tile_points=TILE, resolve=False)
    assert stats["path"] == str(b) and stats["bytes"] == os.path.getsize(b)
    assert stats["points"] == 16 * 16 * 4
    with xr.open_dataset(a) as x, xr.open_dataset(b) as y:
        xr.testing.assert_identical(_strip_history(x.load()), _strip_history(y.load()))
        for n in x.data_vars:
            assert x[n].encoding.get("chunksizes") == y[n].encoding.get("chunksizes"), n


def test_scalar_coordinates_survive(tmp_path):
    s = Scene(beta1="0:2pi:8", beta2="0:2pi:8", kappa=0.5, q=0.0, outputs="stable_SS,class_code")
    path = tmp_path / "f.nc"
    generate_to_file(s, path, tile_points=TILE, resolve=False)
    with xr.open_dataset(path) as back:
        assert float(back.kappa) == 0.5 and back.kappa.ndim == 0
        assert back.stable_SS.dims == ("beta1", "beta2")
        mem = generate(s, tile_points=TILE, resolve=False)
        xr.testing.assert_identical(_strip_history(back.load()), _strip_history(mem))


def test_existing_file_untouched_without_overwrite(ds, tmp_path):
    path = tmp_path / "a.nc"
    path.write_bytes(b"precious")
    with pytest.raises(FileExistsError, match="^out:"):
        write_netcdf(ds, path)
    with pytest.raises(FileExistsError, match="^out:"):
        generate_to_file(small_scene(), path, tile_points=TILE)
    assert path.read_bytes() == b"precious"
    write_netcdf(ds, path, overwrite=True)
    with xr.open_dataset(path) as back:
        assert "stable_SS" in back
    assert sorted(os.listdir(tmp_path)) == ["a.nc"]


@pytest.mark.parametrize("exc", [RuntimeError, KeyboardInterrupt])
def test_interrupted_streaming_write_leaves_nothing(tmp_path, monkeypatch, exc):
    calls = {"n": 0}
    orig = aio.NetCDFSink.write

    def failing(self, name, index, block):
        calls["n"] += 1
        if calls["n"] == 3:
            raise exc("interrupted")
        return orig(self, name, index, block)

    monkeypatch.setattr(aio.NetCDFSink, "write", failing)
    path = tmp_path / "x.nc"
    with pytest.raises(exc):
        generate_to_file(small_scene(), path, tile_points=64, resolve=False)
    assert os.listdir(tmp_path) == []  # no final file, no temporary left over
    # an existing file is left untouched by an interrupted overwrite
    path.write_bytes(b"old")
    calls["n"] = 0
    with pytest.raises(exc):
        generate_to_file(small_scene(), path, tile_points=64, resolve=False, overwrite=True)
    assert path.read_bytes() == b"old" and os.listdir(tmp_path) == ["x.nc"]


@pytest.mark.parametrize("where", ["create", "header"])
def test_interrupt_while_the_header_is_written_leaves_nothing(tmp_path, monkeypatch, where):
    """A SIGTERM arriving right after the temporary file appears (the CLI's signal test) lands in
    ``NetCDFSink.begin``: the run still aborts and removes it."""

    def interrupted(self, *a, **k):
        raise KeyboardInterrupt

    name = "createVariable" if where == "header" else "set_auto_mask"
    monkeypatch.setattr(netCDF4.Dataset, name, interrupted)
    with pytest.raises(KeyboardInterrupt):
        generate_to_file(small_scene(), tmp_path / "x.nc", tile_points=64, resolve=False)
    assert os.listdir(tmp_path) == []


def test_interrupted_in_memory_write_leaves_nothing(ds, tmp_path, monkeypatch):
    def boom(self, *a, **k):
        with open(a[0], "wb") as fh:  # a half-written temporary file
            fh.write(b"CDF")
        raise OSError("disk full")

    monkeypatch.setattr(xr.Dataset, "to_netcdf", boom)
    with pytest.raises(OSError, match="disk full"):
        write_netcdf(ds, tmp_path / "y.nc")
    assert os.listdir(tmp_path) == []


@pytest.mark.parametrize(
    "path, exc",
    [("/nonexistent-dir/x.nc", FileNotFoundError), (".", IsADirectoryError)],
)
def test_bad_output_path(ds, path, exc):
    with pytest.raises(exc, match="^out:"):
        write_netcdf(ds, path)


def test_atomic_write_text(tmp_path):
    p = tmp_path / "t.md"
    aio.atomic_write_text(p, "hello\n")
    assert p.read_text() == "hello\n"
    aio.atomic_write_text(p, "again\n")
    assert p.read_text() == "again\n" and os.listdir(tmp_path) == ["t.md"]


RSS_SCRIPT = textwrap.dedent(
    """
    import resource, sys, time
    import atlas
    from atlas.data.io import generate_to_file
    from atlas.data.scene import Scene
    n_b, n_k, n_q = int(sys.argv[2]), int(sys.argv[3]), int(sys.argv[4])
    s = Scene(beta1=f"0:2pi:{n_b}", beta2=f"0:2pi:{n_b}", kappa=f"log:0.01:100:{n_k}",
              q=f"log:0.001:10:{n_q}", outputs=sys.argv[5])
    st = generate_to_file(s, sys.argv[1], tile_points=1 << 16, resolve=False, overwrite=True)
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(st["points"], st["seconds"], st["bytes"], rss)
    """
)


def _peak_rss(tmp_path, n_b, n_k, n_q, outputs):
    out = subprocess.run(
        [
            sys.executable,
            "-c",
            RSS_SCRIPT,
            str(tmp_path / "big.nc"),
            str(n_b),
            str(n_k),
            str(n_q),
            outputs,
        ],
        capture_output=True,
        text=True,
        check=True,
    )
    points, seconds, size, rss = out.stdout.split()
    return int(points), float(seconds), int(size), float(rss)


@pytest.mark.slow
def test_peak_rss_bounded_by_tile(tmp_path):
    """Peak RSS of the streaming path does not grow with the atlas (goal: 1e9 points < 2 GB).

    Measures a 1.7e7-point and a 1.05e8-point 4-D ``stable_SS`` atlas with the same tile and
    checks that the peak RSS is flat (the file is streamed; only the tile and the 2-D
    ``model_dependent_SS`` accumulator live in memory).
    """
    small = _peak_rss(tmp_path, 256, 16, 16, "stable_SS,model_dependent_SS")
    big = _peak_rss(tmp_path, 1024, 10, 10, "stable_SS,model_dependent_SS")
    print("small", small, "big", big)
    assert big[0] >= 1e8
    assert big[3] < 2048
    assert big[3] < small[3] * 1.5 + 100


@pytest.mark.skipif(not os.path.isdir("/proc/self"), reason="needs Linux /proc")
def test_unwritable_directory_is_refused_up_front():
    """A directory nobody can create files in (/proc, even for root) fails before any work."""
    from atlas.data.io import check_output_path

    with pytest.raises(OSError, match="^out: directory /proc is not writable"):
        check_output_path("/proc/atlas.nc")


@pytest.mark.parametrize("suffix", [".png", ".pdf", ".svg"])
def test_savefig_writes_the_same_bytes_at_another_time(suffix, tmp_path, monkeypatch):
    """A figure is a pure function of what is drawn: the date matplotlib writes into PDF and SVG
    (``SOURCE_DATE_EPOCH`` when set, else now), its version and SVG's random ids are left out."""
    from matplotlib.figure import Figure

    got = []
    for k, epoch in enumerate(("0", "1700000000")):
        monkeypatch.setenv("SOURCE_DATE_EPOCH", epoch)
        fig = Figure(figsize=(2, 2))
        ax = fig.subplots()
        ax.fill_between([0, 1], [0, 1], clip_on=True)
        ax.set_title("beta1")
        path = tmp_path / f"{k}{suffix}"
        aio.savefig(fig, path)
        got.append(path.read_bytes())
    assert got[0] == got[1]
    assert b"atplotlib version" not in got[0] and b"Matplotlib v" not in got[0]


def test_an_interrupt_just_after_the_rename_still_names_the_file(tmp_path, monkeypatch):
    """A KeyboardInterrupt raised as the rename returns (the file complete in place, not yet
    listed): the file is listed as complete all the same, and the interrupt goes on."""
    real = os.replace

    def replace_then_interrupt(a, b):
        real(a, b)
        raise KeyboardInterrupt

    monkeypatch.setattr(aio, "COMMITTED", [])
    monkeypatch.setattr(aio.os, "replace", replace_then_interrupt)
    out = tmp_path / "a.md"
    with pytest.raises(KeyboardInterrupt):
        aio.atomic_write_text(out, "done\n")
    assert out.read_text() == "done\n" and aio.COMMITTED == [str(out)]
