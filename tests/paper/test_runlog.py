"""Run-dependent attributes (dates, seconds) move from a Dataset into the run log."""

import json

import numpy as np
import xarray as xr

from atlas.paper import runlog


def _ds():
    slices = [{"kappa": 0.5, "SS_seconds": 0.39, "SS_grid": "9x9"}]
    attrs = {
        "history": "2026-11-27T21:13:23Z: atlas.boundaries(chord=1e-05) over 1 slice(s)",
        "seconds": 1.25,
        "trajectories_per_second": 800.0,
        "workers": 1,
        "slices": json.dumps(slices),
        "title": "{not json",
    }
    return xr.Dataset({"v": ("x", np.arange(3))}, attrs=attrs)


def test_fixed_moves_dates_and_seconds_into_the_log(tmp_path):
    ds = _ds()
    with runlog.RunLog(tmp_path):
        got = runlog.fixed(ds, "a.nc")
    assert got.attrs["history"] == "atlas.boundaries(chord=1e-05) over 1 slice(s)"
    assert "seconds" not in got.attrs and "trajectories_per_second" not in got.attrs
    assert json.loads(got.attrs["slices"]) == [{"kappa": 0.5, "SS_grid": "9x9"}]
    assert got.attrs["workers"] == 1 and got.attrs["title"] == "{not json"
    assert ds.attrs["seconds"] == 1.25  # the input is not changed
    log = (tmp_path / runlog.LOG).read_text()
    for line in (
        "a.nc history: 2026-11-27T21:13:23Z: atlas.boundaries",
        "a.nc seconds: 1.250",
        "a.nc trajectories_per_second: 800.000",
        "a.nc slices[0].SS_seconds: 0.390",
        "date: 20",
        "host: ",
    ):
        assert line in log, line


def test_without_a_run_log_nothing_is_recorded_nor_written(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    got = runlog.fixed(_ds(), "a.nc")
    runlog.record("x", 1.0)
    assert "seconds" not in got.attrs
    assert list(tmp_path.iterdir()) == []
