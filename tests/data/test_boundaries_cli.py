"""``atlas boundaries`` as the README runs it: the default fields, check and chord, one damped
slice, written as netCDF, CSV and GeoJSON in one call; the three files hold the same curves,
labels and points."""

import csv
import inspect
import json

import numpy as np
import xarray as xr

from atlas.cli import main
from atlas.core.brackets import FIELD_LABELS
from atlas.data import boundaries as bd

GRID = "0:2pi:12"
MODEL = {"kappa": 2.0, "q1": 0.1, "q2": 0.3}


def test_the_readme_command_writes_three_agreeing_files(tmp_path, capsys):
    """Defaults (``SS,II``, ``check = 2``, the default chord): SS and II curves present,
    ``complete``; the netCDF nodes, the CSV vertex rows and the GeoJSON line coordinates are the
    same vertices in the same order, curve by curve with the same field and side labels; the
    points likewise."""
    nc, cs, gj = (tmp_path / f"b.{e}" for e in ("nc", "csv", "json"))
    args = ["boundaries", "--beta1", GRID, "--beta2", GRID]
    args += [f"--{k}={v}" for k, v in MODEL.items()]
    rc = main([*args, "--out", str(nc), "--csv", str(cs), "--geojson", str(gj)])
    assert rc == 0, capsys.readouterr().err
    with xr.open_dataset(nc) as ds:
        assert int(ds.attrs["complete"]) == 1
        chord = inspect.signature(bd.slice_boundaries).parameters["chord"].default
        assert ds.attrs["chord_tolerance"] == chord
        nodes = np.stack([ds.node_beta1.values, ds.node_beta2.values], 1)
        counts = ds.node_count.values.tolist()
        fields = [str(f) for f in ds.curve_field.values]
        pts = np.stack([ds.point_beta1.values, ds.point_beta2.values], 1)
    assert {"SS", "II"} <= set(fields) and len(pts) > 0
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
