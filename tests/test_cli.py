"""The ``atlas`` CLI: one-line errors with exit code 2, existing files untouched, a tiny scene end to
end, ``--help`` on every subcommand.  Through ``cli.main`` in this process (the code path of the
console script, without an interpreter start-up each), except one subprocess smoke test and the
signal test (``e2e``)."""

import contextlib
import io
import os
import subprocess
import sys

import numpy as np
import pytest
import xarray as xr

from atlas import cli

TINY = ["--beta1", "0:2pi:8", "--beta2", "0:2pi:8"]


def _env():
    env = dict(os.environ)  # ATLAS_JAX_CACHE: the run's shared compilation cache (conftest.py)
    env.pop("ATLAS_PROGRESS", None)
    return env


def _spawn(args, env):
    return subprocess.Popen(
        [sys.executable, "-m", "atlas.cli", *args],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
    )


# bad inputs without --overwrite: (arguments, parameter)
BAD = [
    (["--kappa", "nan"], "kappa"),
    (["--q", "inf"], "q"),
    (["--physical", "k1=-100,k2=200"], "k1"),
    (["--physical", "k1=100,k2=200,b2=-1"], "b2"),
    (["--beta2", "0:1:0"], "beta2"),
    (["--beta1", "1:0:5"], "beta1"),
    (["--outputs", "class_code,no_such_var"], "outputs"),
    (["--out", "/nonexistent-dir/a.nc"], "out"),
    (["--out", "{existing}"], "out"),  # exists, no --overwrite
]
# more bad inputs, with --overwrite
BAD_OVERWRITE = [
    (["--kappa", "-1"], "kappa"),
    (["--kappa", "log:1:0.1:3"], "kappa"),
    (["--alpha", "0:2pi:x"], "alpha"),
    (["--q1", "0.1"], "q2"),
    (["--q", "0.1", "--q1", "0.1", "--q2", "0.2"], "q"),
    (["--physical", "k1=1"], "k2"),
    (["--physical", "k1=1,k2=1,z=3"], "physical"),
    (["--physical", "k1=1,k2=1", "--kappa", "2"], "physical"),
    (["--dtype", "float16"], "dtype"),
    (["--method", "magic"], "method"),
    (["--tile-points", "0"], "tile-points"),
    (["--scene", "fig9"], "scene"),
    (["--outputs", "subclass_code"], "outputs"),  # needs alpha
    (["--out", "{dir}"], "out"),  # a directory
]


def _check_one_line(err, name, extra):
    lines = err.strip().splitlines()
    assert len(lines) == 1, (extra, err)
    assert "Traceback" not in err
    assert name in lines[0], (extra, lines[0])


@pytest.mark.parametrize("extra, name", BAD)
def test_bad_inputs_exit_2_one_line(extra, name, tmp_path, capsys):
    existing = tmp_path / "existing.nc"
    existing.write_bytes(b"keep me")
    extra = [a.format(existing=existing) for a in extra]
    args = ["generate", *TINY, "--outputs", "class_code", "--out", str(existing), *extra]
    assert cli.main(args) == 2
    _check_one_line(capsys.readouterr().err, name, extra)
    assert existing.read_bytes() == b"keep me"
    assert sorted(os.listdir(tmp_path)) == ["existing.nc"]


@pytest.mark.parametrize("extra, name", BAD_OVERWRITE)
def test_bad_inputs_with_overwrite(extra, name, tmp_path, capsys):
    existing = tmp_path / "existing.nc"
    existing.write_bytes(b"keep me")
    extra = [a.format(dir=tmp_path) for a in extra]
    args = ["generate", *TINY, "--outputs", "class_code", "--out", str(existing), "--overwrite"]
    assert cli.main(args + extra) == 2
    _check_one_line(capsys.readouterr().err, name, extra)
    assert existing.read_bytes() == b"keep me"
    assert sorted(os.listdir(tmp_path)) == ["existing.nc"]


def test_generate_end_to_end(tmp_path, capsys):
    out = tmp_path / "tiny.nc"
    args = ["generate", *TINY, "--kappa", "0.5,2", "--q", "0,0.5", "--alpha", "0:2pi:4"]
    args += ["--outputs", "class_code,subclass_code,stable_SS,model_dependent_SS,stable_SF"]
    args += ["--out", str(out), "--tile-points", "256"]
    rc, err = cli.main(args), capsys.readouterr().err
    assert rc == 0, err
    summary = err.strip().splitlines()[-1]
    for word in ("points", " s ", "points/s", "undecided"):
        assert word in summary
    with xr.open_dataset(out) as ds:
        assert ds.stable_SS.dims == ("beta1", "beta2", "kappa", "q")
        assert ds.stable_SS.dtype == np.int8 and ds.class_code.dtype == np.int8
        assert ds.attrs["Conventions"] == "CF-1.10"
        assert "atlas generate" in ds.attrs["history"]
        assert ds.attrs["undecided_after_resolve"] == 0
    # an existing output is replaced only with --overwrite
    before = out.read_bytes()
    rc, err = cli.main(args), capsys.readouterr().err
    assert rc == 2 and "out:" in err and out.read_bytes() == before
    args2 = [a for a in args if a not in ("--kappa", "0.5,2", "--q", "0,0.5")]
    args2 = [a if a != "model_dependent_SS" else "cc_possible" for a in args2]
    args2 = [a.replace(",model_dependent_SS", "") for a in args2]
    rc = cli.main([*args2, "--overwrite", "--physical", "k1=100,k2=200,q1=20,q2=20"])
    assert rc == 0, capsys.readouterr().err
    with xr.open_dataset(out) as ds:
        assert float(ds.kappa) == pytest.approx(0.5) and float(ds.q) == pytest.approx(2**0.5)


@pytest.mark.e2e
def test_subprocess_smoke(tmp_path):
    """The console entry point in a fresh interpreter; ATLAS_PROGRESS=1 forces the bar (as on a
    terminal): the run completes and shows it."""
    env = _env()
    env["ATLAS_PROGRESS"] = "1"
    out = tmp_path / "p.nc"
    p = _spawn(["generate", *TINY, "--outputs", "class_code,stable_SS", "--out", str(out)], env)
    _, err = p.communicate(timeout=300)
    assert p.returncode == 0, err
    assert "atlas custom" in err and "pt" in err  # the tqdm bar, then the summary line
    assert out.exists()


@pytest.mark.parametrize("sub", list(cli.HELP))
def test_help(sub, capsys):
    assert cli.main([sub, "--help"]) == 0
    assert "usage: atlas " + sub in capsys.readouterr().out


def test_top_level_help_lists_every_subcommand(capsys):
    assert cli.main(["--help"]) == 0
    out = " ".join(capsys.readouterr().out.split())
    for sub, line in cli.HELP.items():
        assert f"{sub} {line}" in out, sub


def test_simulate_and_table_run(tmp_path, capsys):
    """The dispatched subcommands resolve to real functions (no placeholder path)."""
    csv = tmp_path / "d.csv"
    rc = cli.main(["simulate", "--case", "fig2b", "--t-end", "5", "--out", str(csv)])
    out, err = capsys.readouterr()
    assert rc == 0, err
    assert out.startswith("b: ") and csv.read_text().startswith("t,kind,contact")
    rc = cli.main(["table", "--format", "csv"])
    out, err = capsys.readouterr()
    assert rc == 0, err
    assert len(out.strip().splitlines()) == 25  # header + 24 classes


def test_dispatch_passes_options(monkeypatch):
    import types

    seen = {}
    fake = types.ModuleType("atlas._fake_table")
    fake.run_cli = lambda **kw: seen.update(kw) or 0
    monkeypatch.setitem(sys.modules, "atlas._fake_table", fake)
    monkeypatch.setitem(cli._DISPATCH, "table", ("atlas._fake_table", "run_cli"))
    assert cli.main(["table", "--format", "csv"]) == 0
    assert seen == {"format": "csv", "out": None}


def test_no_subcommand_is_usage_error(capsys):
    assert cli.main([]) == 2
    assert len(capsys.readouterr().err.strip().splitlines()) == 1


@pytest.mark.e2e
def test_sigterm_leaves_no_partial_file(tmp_path):
    import signal
    import time

    out = tmp_path / "big.nc"
    # ~1e9 points: minutes of work at 1e7 points/s, so the signal arrives mid-run
    args = ["generate", "--beta1", "0:2pi:4096", "--beta2", "0:2pi:4096", "--kappa", "log:1:4:8"]
    args += ["--q", "log:0.1:0.4:8", "--outputs", "stable_SS", "--out", str(out)]
    p = _spawn(args, _env())
    deadline = time.time() + 60
    while time.time() < deadline and not any(f.endswith(".tmp") for f in os.listdir(tmp_path)):
        time.sleep(0.1)  # wait until the temporary file is being written
    p.send_signal(signal.SIGTERM)
    _, err = p.communicate(timeout=60)
    assert p.returncode == 130, err
    assert "interrupted" in err and "Traceback" not in err
    assert os.listdir(tmp_path) == []


# --- atlas generate --scheduler/--store/--resume (atlas.data.distributed through the CLI) ---------------

SCENE5 = ["--beta1", "0:2pi:8", "--beta2", "0:2pi:8", "--kappa", "0.5,2"]
SCENE5 += ["--q1", "0,1", "--q2", "0,0.5", "--tile-points", "128", "--no-progress"]
# a beta1-free variable (stable_FS: shared by all tiles) and a reduction over the model dimensions
SCENE5 += ["--outputs", "class_code,stable_SS,model_dependent_SS,stable_SF,stable_FS"]


def _main(args) -> tuple[int, str]:
    """``cli.main(args)`` in this process: its exit code and what it wrote on stderr."""
    err = io.StringIO()
    with contextlib.redirect_stderr(err):
        rc = cli.main(args)
    return rc, err.getvalue()


def _same_netcdf(a, b):
    """Same variables, coordinates, dtypes, raw bytes, attributes (global ones but ``history``)."""
    with xr.open_dataset(a) as x, xr.open_dataset(b) as y:
        x, y = x.load(), y.load()
    assert set(x.variables) == set(y.variables)
    for k in y.variables:
        assert x[k].dims == y[k].dims and x[k].dtype == y[k].dtype, k
        assert x[k].values.tobytes() == y[k].values.tobytes(), k
        assert x[k].attrs.keys() == y[k].attrs.keys(), k
        for name, v in y[k].attrs.items():
            np.testing.assert_array_equal(x[k].attrs[name], v)
    drop = lambda attrs: {k: v for k, v in attrs.items() if k != "history"}  # noqa: E731
    assert drop(x.attrs) == drop(y.attrs)


@pytest.fixture(scope="module")
def distributed_run(tmp_path_factory):
    """The in-process ``atlas generate`` file and ``--scheduler inprocess --slab 2`` (4 tiles)."""
    pytest.importorskip("zarr")
    d = tmp_path_factory.mktemp("dist")
    rc, err = _main(["generate", *SCENE5, "--out", str(d / "ref.nc")])
    assert rc == 0, err
    args = ["generate", *SCENE5, "--scheduler", "inprocess", "--slab", "2"]
    rc, err = _main([*args, "--out", str(d / "a.nc")])
    assert rc == 0, err
    return d, err


def test_generate_scheduler_inprocess_then_resume(distributed_run):
    d, err = distributed_run
    summary = err.strip().splitlines()[-1]
    assert str(d / "a.zarr") in summary and "4 tiles: 4 computed, 0 verified" in summary
    assert "in-process" in summary and "points/s" in summary
    _same_netcdf(d / "a.nc", d / "ref.nc")
    # lose one tile's record, damage another's bytes: --resume recomputes exactly those two
    import shutil

    import zarr

    shutil.rmtree(d / "a.zarr" / "_tiles" / "t000001")
    g = zarr.open_group(str(d / "a.zarr"), mode="r+")
    g["class_code"][6:8] = 0
    args = ["generate", *SCENE5, "--scheduler", "inprocess", "--slab", "2"]
    args += ["--store", str(d / "a.zarr"), "--out", str(d / "b.nc"), "--resume"]
    rc, err = _main(args)
    assert rc == 0, err
    summary = err.strip().splitlines()[-1]
    assert "4 tiles: 2 computed, 2 verified, 1 missing and 1 corrupt before" in summary, summary
    _same_netcdf(d / "b.nc", d / "ref.nc")
    with xr.open_dataset(d / "b.nc") as ds:
        assert "resumed, 2 of 4 tiles recomputed" in ds.attrs["history"]


def test_generate_distributed_bad_inputs(distributed_run, tmp_path, capsys):
    """One line ``atlas: error: PARAMETER: ...``, exit code 2, existing files untouched."""
    d, _ = distributed_run
    store = d / "a.zarr"
    before = sorted(str(p) for p in store.rglob("*"))
    bad = [
        (["--scheduler", "nowhere"], "scheduler:"),
        (["--resume", "--store", str(tmp_path / "none.zarr")], "resume:"),
        (["--store", str(store), "--resume", "--kappa", "0.5,3"], "store:"),  # another scene
    ]
    base = ["generate", *SCENE5, "--scheduler", "inprocess", "--slab", "2"]
    more = [
        (["--scheduler", "local:0"], "scheduler:"),
        (["--scheduler", "tcp://"], "scheduler:"),
        (["--resume", "--overwrite", "--store", str(store)], "resume:"),
        (["--store", str(store)], "store:"),  # exists: neither --resume nor --overwrite
        (["--store", str(store), "--resume", "--slab", "4"], "store:"),  # another tiling
        (["--store", str(store), "--resume", "--method", "eig"], "store:"),  # other options
        (["--store", str(tmp_path / "no" / "x.zarr")], "store:"),
        (["--store", str(tmp_path / "x.zarr"), "--out", str(d / "ref.nc")], "out:"),
        (["--store", str(tmp_path / "x.zarr"), "--slab", "0"], "slab"),
        (["--store", str(tmp_path / "x.zarr"), "--block2", "0"], "block2"),
        (["--store", str(tmp_path / "x.zarr"), "--block2", "2", "--beta2", "1"], "block2:"),
    ]
    got = []
    for extra, _ in bad + more:
        rc = cli.main([*base, *extra])
        got.append((rc, capsys.readouterr().err))
    for (extra, name), (rc, err) in zip(bad + more, got, strict=True):
        assert rc == 2, (extra, err)
        lines = err.strip().splitlines()
        assert len(lines) == 1 and "Traceback" not in err, (extra, err)
        assert "error: " in lines[0] and name in lines[0], (extra, lines[0])
    assert sorted(str(p) for p in store.rglob("*")) == before
    assert os.listdir(tmp_path) == []


def test_swallowed_interrupt_is_not_reported_but_other_errors_are(capsys):
    """A KeyboardInterrupt lost in a gc callback is re-delivered, not printed; others print."""
    import sys
    import types

    from atlas import cli

    def info(exc):
        return types.SimpleNamespace(
            exc_type=type(exc), exc_value=exc, exc_traceback=None, err_msg=None, object=None
        )

    cli._unraisable(info(KeyboardInterrupt()))
    assert capsys.readouterr().err == ""
    forwarded = []
    default = sys.__unraisablehook__
    try:
        sys.__unraisablehook__ = forwarded.append
        cli._unraisable(info(RuntimeError("boom")))
    finally:
        sys.__unraisablehook__ = default
    assert [str(i.exc_value) for i in forwarded] == ["boom"]
