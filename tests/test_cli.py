"""The ``atlas`` CLI through real subprocesses: one-line errors with exit code 2, existing files
untouched, a tiny scene end to end, ``--help`` on every subcommand."""

import os
import subprocess
import sys

import numpy as np
import pytest
import xarray as xr

from atlas import cli

TINY = ["--beta1", "0:2pi:8", "--beta2", "0:2pi:8"]


def _env(tmp_path_factory):
    env = dict(os.environ)
    env["ATLAS_JAX_CACHE"] = str(tmp_path_factory.getbasetemp() / "jaxcache")
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


# the bad inputs of issue 3, each through the real CLI in a subprocess: (arguments, parameter)
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
# more bad inputs, through cli.main in-process (same code path, no interpreter start-up)
BAD_INPROCESS = [
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


def test_bad_inputs_exit_2_one_line(tmp_path, tmp_path_factory):
    existing = tmp_path / "existing.nc"
    existing.write_bytes(b"keep me")
    env = _env(tmp_path_factory)
    procs = []
    for extra, name in BAD:
        extra = [a.format(existing=existing) for a in extra]
        args = ["generate", *TINY, "--outputs", "class_code", "--out", str(existing), *extra]
        procs.append((extra, name, _spawn(args, env)))
    for extra, name, p in procs:
        _, err = p.communicate(timeout=120)
        assert p.returncode == 2, (extra, err)
        _check_one_line(err, name, extra)
    assert existing.read_bytes() == b"keep me"
    assert sorted(os.listdir(tmp_path)) == ["existing.nc"]


@pytest.mark.parametrize("extra, name", BAD_INPROCESS)
def test_more_bad_inputs_in_process(extra, name, tmp_path, capsys):
    existing = tmp_path / "existing.nc"
    existing.write_bytes(b"keep me")
    extra = [a.format(dir=tmp_path) for a in extra]
    args = ["generate", *TINY, "--outputs", "class_code", "--out", str(existing), "--overwrite"]
    assert cli.main(args + extra) == 2
    _check_one_line(capsys.readouterr().err, name, extra)
    assert existing.read_bytes() == b"keep me"
    assert sorted(os.listdir(tmp_path)) == ["existing.nc"]


def test_generate_end_to_end(tmp_path, tmp_path_factory):
    out = tmp_path / "tiny.nc"
    args = ["generate", *TINY, "--kappa", "0.5,2", "--q", "0,0.5", "--alpha", "0:2pi:4"]
    args += ["--outputs", "class_code,subclass_code,stable_SS,model_dependent_SS,stable_SF"]
    args += ["--out", str(out), "--tile-points", "256"]
    p = _spawn(args, _env(tmp_path_factory))
    _, err = p.communicate(timeout=300)
    assert p.returncode == 0, err
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
    p = _spawn(args, _env(tmp_path_factory))
    _, err = p.communicate(timeout=300)
    assert p.returncode == 2 and "out:" in err and out.read_bytes() == before
    args2 = [a for a in args if a not in ("--kappa", "0.5,2", "--q", "0,0.5")]
    args2 = [a if a != "model_dependent_SS" else "cc_possible" for a in args2]
    args2 = [a.replace(",model_dependent_SS", "") for a in args2]
    p = _spawn(
        [*args2, "--overwrite", "--physical", "k1=100,k2=200,q1=20,q2=20"], _env(tmp_path_factory)
    )
    _, err = p.communicate(timeout=300)
    assert p.returncode == 0, err
    with xr.open_dataset(out) as ds:
        assert float(ds.kappa) == pytest.approx(0.5) and float(ds.q) == pytest.approx(2**0.5)


def test_progress_bar_on(tmp_path, tmp_path_factory):
    """ATLAS_PROGRESS=1 forces the bar (as on a terminal): the run completes and shows it."""
    env = _env(tmp_path_factory)
    env["ATLAS_PROGRESS"] = "1"
    out = tmp_path / "p.nc"
    p = _spawn(["generate", *TINY, "--outputs", "class_code,stable_SS", "--out", str(out)], env)
    _, err = p.communicate(timeout=300)
    assert p.returncode == 0, err
    assert "atlas custom" in err and "pt" in err  # the tqdm bar, then the summary line
    assert out.exists()


@pytest.mark.parametrize("sub", ["generate", "paper", "simulate", "table", "bench"])
def test_help(sub, capsys):
    assert cli.main([sub, "--help"]) == 0
    assert "usage: atlas " + sub in capsys.readouterr().out


def test_simulate_and_table_run_in_subprocesses(tmp_path, tmp_path_factory):
    """The dispatched subcommands resolve to real functions (no placeholder path)."""
    env = _env(tmp_path_factory)
    csv = tmp_path / "d.csv"
    p = _spawn(["simulate", "--case", "fig2b", "--t-end", "5", "--out", str(csv)], env)
    out, err = p.communicate(timeout=600)
    assert p.returncode == 0, err
    assert out.startswith("b: ") and csv.read_text().startswith("t,kind,contact")
    p = _spawn(["table", "--format", "csv"], env)
    out, err = p.communicate(timeout=600)
    assert p.returncode == 0, err
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


def test_sigterm_leaves_no_partial_file(tmp_path, tmp_path_factory):
    import signal
    import time

    out = tmp_path / "big.nc"
    args = ["generate", "--beta1", "0:2pi:2048", "--beta2", "0:2pi:2048", "--kappa", "1,2,3,4"]
    args += ["--q", "0.1,0.2,0.3,0.4", "--outputs", "stable_SS", "--out", str(out)]
    p = _spawn(args, _env(tmp_path_factory))
    deadline = time.time() + 60
    while time.time() < deadline and not any(f.endswith(".tmp") for f in os.listdir(tmp_path)):
        time.sleep(0.1)  # wait until the temporary file is being written
    p.send_signal(signal.SIGTERM)
    _, err = p.communicate(timeout=60)
    assert p.returncode == 130, err
    assert "interrupted" in err and "Traceback" not in err
    assert os.listdir(tmp_path) == []
