"""``atlas generate --method eig``, ``--dtype float32`` and ``--scene`` through the command line:
the file holds what :func:`atlas.generate` returns for the same scene and options."""

import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from atlas.cli import main
from atlas.data.cluster import worker_env
from atlas.data.engine import generate
from atlas.data.scene import Scene

GRID = dict(beta1="0:2pi:8", beta2="0:2pi:8")
#: the Fig. 1 plane of the paper: kappa = 0.5, no damping
FIG1 = dict(kappa=0.5, q=0.0)


def _argv(axes: dict) -> list[str]:
    return [x for k, v in axes.items() for x in (f"--{k}", str(v))]


@pytest.mark.parametrize(
    "extra, axes, options",
    [
        (["--method", "eig"], dict(GRID, kappa=0.5, q=0.1), dict(method="eig")),
        (["--dtype", "float32"], dict(GRID, kappa=0.5, q=0.1), dict(dtype="float32")),
        (["--scene", "fig1"], dict(GRID), dict()),
    ],
    ids=["method-eig", "dtype-float32", "scene-fig1"],
)
def test_the_file_is_the_apis_result(tmp_path, capsys, extra, axes, options):
    out = tmp_path / "a.nc"
    assert main(["generate", *extra, *_argv(axes), "--out", str(out)]) == 0, capsys.readouterr()
    scene = Scene(**(dict(axes, **FIG1) if "--scene" in extra else axes))
    api = generate(scene, **options)
    with xr.open_dataset(out) as ds:
        assert set(ds.data_vars) == set(api.data_vars)
        for name, var in api.data_vars.items():
            assert ds[name].dims == var.dims, name
            assert ds[name].dtype == var.dtype, name
            np.testing.assert_array_equal(ds[name].values, var.values, err_msg=name)
        for c in api.coords:
            np.testing.assert_array_equal(ds[c].values, api[c].values, err_msg=c)
        for key in ("method", "dtype", "kappa", "q", "undecided_fast", "undecided_after_resolve"):
            assert ds.attrs[key] == api.attrs[key], key
        assert ds.attrs["scene"] == ("fig1" if "--scene" in extra else "custom")


#: a dashboard port held by another process is only a warning (the cluster takes another port)
BUSY_PORT = "ignore:Port .* is already in use:UserWarning"


@pytest.mark.e2e
@pytest.mark.filterwarnings(BUSY_PORT)
def test_scheduler_local_n_through_the_command_line(tmp_path, capsys):
    pytest.importorskip("distributed")
    axes = dict(GRID, kappa="0.5,2", q="0,0.1")
    out = tmp_path / "a.nc"
    argv = ["generate", *_argv(axes), "--scheduler", "local:2", "--slab", "2", "--out", str(out)]
    # two single-thread workers writing tiles of one store at the same time
    assert main(argv) == 0, capsys.readouterr().err
    summary = capsys.readouterr().err.strip().splitlines()[-1]
    assert "on local:2 with 2 worker(s); 4 tiles: 4 computed" in summary, summary
    assert (tmp_path / "a.zarr").is_dir()  # the resumable store beside the file
    api = generate(Scene(**axes))
    with xr.open_dataset(out) as ds:
        for name, var in api.data_vars.items():
            assert ds[name].dtype == var.dtype, name
            np.testing.assert_array_equal(ds[name].values, var.values, err_msg=name)
        assert ds.attrs["undecided_after_resolve"] == api.attrs["undecided_after_resolve"]


def _running_cluster(tmp_path):
    """A dask scheduler and one single-thread worker in their own processes, started as the
    README starts a cluster (``dask scheduler``, ``dask worker``); their processes and address."""
    dask = Path(sys.executable).with_name("dask")
    info = tmp_path / "scheduler.json"
    env = dict(os.environ, **worker_env())
    procs = [
        subprocess.Popen(
            [
                dask,
                "scheduler",
                "--port",
                "0",
                "--dashboard-address",
                ":0",
                "--scheduler-file",
                info,
            ],
            env=env,
            stderr=subprocess.DEVNULL,
        )
    ]
    while not info.exists() and procs[0].poll() is None:
        time.sleep(0.2)
    procs.append(subprocess.Popen([dask, "worker", "--scheduler-file", info, "--nthreads", "1",
                                   "--nworkers", "1", "--dashboard-address", ":0"], env=env,
                                  stderr=subprocess.DEVNULL))  # fmt: skip
    return procs, json.loads(info.read_text())["address"]


@pytest.mark.e2e
def test_scheduler_address_of_a_running_cluster_through_the_command_line(tmp_path, capsys):
    pytest.importorskip("distributed")
    axes = dict(GRID, kappa="0.5,2", q="0,0.1")
    out = tmp_path / "a.nc"
    procs, address = _running_cluster(tmp_path)
    try:
        assert address.startswith("tcp://")
        argv = ["generate", *_argv(axes), "--scheduler", address, "--slab", "4", "--out", str(out)]
        assert main(argv) == 0, capsys.readouterr().err
        summary = capsys.readouterr().err.strip().splitlines()[-1]
        assert f"on {address} with 1 worker(s); 2 tiles: 2 computed" in summary, summary
        assert procs[0].poll() is None  # the cluster is left running
    finally:
        for p in procs[::-1]:
            p.terminate()
            p.wait(timeout=60)
    api = generate(Scene(**axes))
    with xr.open_dataset(out) as ds:
        for name, var in api.data_vars.items():
            np.testing.assert_array_equal(ds[name].values, var.values, err_msg=name)
