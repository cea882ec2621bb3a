"""``atlas boundaries`` at its defaults (no --fields, --tol, --chord, --check) with every output:
the same curves, CSV and GeoJSON as :func:`atlas.boundaries` at its own defaults, and the three
files hold the same curves, labels and points."""

import csv
import inspect
import json

import numpy as np
import xarray as xr

from atlas.cli import main
from atlas.core.brackets import FIELD_LABELS
from atlas.data.boundaries import boundaries, slice_boundaries
from atlas.data.scene import Scene

AXES = dict(beta1="0:2pi:12", beta2="0:2pi:12", kappa="2", q="0.1")


def _api_defaults() -> str:
    """The options of :func:`slice_boundaries` at their defaults, as ``history`` writes them."""
    sig = inspect.signature(slice_boundaries).parameters
    names = ("check", "chord", "dtype", "fields", "tol")
    return ", ".join(f"{k}={sig[k].default!r}" for k in names)


def _same_run(x):
    """A GeoJSON object without what differs between two runs of the same curves: the durations
    and the call in ``history`` (the CLI's options written out, the API's not)."""
    if isinstance(x, dict):
        return {k: _same_run(v) for k, v in x.items() if k != "history" and "seconds" not in k}
    if isinstance(x, list):
        return [_same_run(v) for v in x]
    return x


def test_defaults_with_csv_and_geojson_are_the_apis(tmp_path, capsys, traced_once):
    """The slice is traced once if the command line calls :func:`slice_boundaries` with the
    API's defaults (``traced_once``), twice otherwise."""
    argv = ["boundaries", *(x for k, v in AXES.items() for x in (f"--{k}", v))]
    cli = {end: tmp_path / f"cli.{end}" for end in ("nc", "csv", "json")}
    argv += ["--out", str(cli["nc"]), "--csv", str(cli["csv"]), "--geojson", str(cli["json"])]
    assert main(argv) == 0, capsys.readouterr().err
    bd = boundaries(Scene(**AXES))
    api = {end: tmp_path / f"api.{end}" for end in ("nc", "csv", "json")}
    bd.to_netcdf(api["nc"])
    bd.to_csv(api["csv"])
    bd.to_geojson(api["json"])
    with xr.open_dataset(cli["nc"]) as a, xr.open_dataset(api["nc"]) as b:
        # the options of the run, as the file records them, are the API's defaults
        assert f"atlas.boundaries({_api_defaults()}) over 1 slice(s)" in a.attrs["history"]
        xr.testing.assert_identical(a.drop_attrs(), b.drop_attrs())
    assert cli["csv"].read_text() == api["csv"].read_text()
    assert _same_run(json.loads(cli["json"].read_text())) == _same_run(
        json.loads(api["json"].read_text())
    )
    fields = {r.split(",")[2] for r in cli["csv"].read_text().splitlines()[1:]}
    assert {"SS", "II"} <= fields
    _three_files_agree(*cli.values())


def _three_files_agree(nc, cs, gj):
    """The netCDF nodes, the CSV vertex rows and the GeoJSON line coordinates are the same
    vertices in the same order, curve by curve with the same field and side labels; the points
    likewise; the slice is ``complete``."""
    with xr.open_dataset(nc) as ds:
        assert int(ds.attrs["complete"]) == 1
        nodes = np.stack([ds.node_beta1.values, ds.node_beta2.values], 1)
        counts = ds.node_count.values.tolist()
        fields = [str(f) for f in ds.curve_field.values]
        pts = np.stack([ds.point_beta1.values, ds.point_beta2.values], 1)
    assert len(pts) > 0
    rows = list(csv.DictReader(cs.read_text().splitlines()))
    vert = [r for r in rows if r["record"] == "vertex"]
    np.testing.assert_array_equal([(float(r["beta1"]), float(r["beta2"])) for r in vert], nodes)
    per_curve = np.bincount([int(r["curve"]) for r in vert], minlength=len(counts))
    assert per_curve.tolist() == counts
    csv_pts = [(float(r["beta1"]), float(r["beta2"])) for r in rows if r["record"] == "point"]
    np.testing.assert_array_equal(csv_pts, pts)
    feats = json.loads(gj.read_text())["features"]
    lines = [f for f in feats if f["geometry"]["type"] == "LineString"]
    assert [len(f["geometry"]["coordinates"]) for f in lines] == counts
    coords = np.concatenate([np.array(f["geometry"]["coordinates"]) for f in lines])
    np.testing.assert_array_equal(coords, nodes)
    points = [f["geometry"]["coordinates"] for f in feats if f["geometry"]["type"] == "Point"]
    np.testing.assert_array_equal(points, pts)
    first = {}
    for r in vert:
        first.setdefault(int(r["curve"]), (r["field"], r["side_left"], r["side_right"]))
    for i, f in enumerate(lines):
        field, left, right = first[i]
        assert f["properties"]["field"] == field == fields[i]
        labels = FIELD_LABELS.get(field, {})
        assert f["properties"]["side_left"] == labels.get(int(left), "")
        assert f["properties"]["side_right"] == labels.get(int(right), "")
