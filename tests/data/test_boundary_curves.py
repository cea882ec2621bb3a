"""Storage of boundary curves: CF-1.10 geometry container, CSV, GeoJSON, summary."""

import json

import numpy as np
import xarray as xr

from atlas.data.boundary_curves import CSV_COLUMNS, Boundaries, Curve, Point, summary


def _boundaries() -> Boundaries:
    """Two hand-made curves (a 3-vertex SS curve, a 2-vertex II piece on a class line), one point."""
    ss = Curve(
        "SS", "SS_stability", 1, 0, np.array([[0.1, 0.2], [0.3, 0.4], [0.5, 0.7]]),
        np.array([1e-11, 2e-11, 5e-11]), kappa=2.0, q1=0.1, q2=0.1,
    )  # fmt: skip
    ii = Curve(
        "II", "II_consistency", 2, 0, np.array([[np.pi, 1.0], [np.pi, 2.0]]),
        np.array([0.0, 3e-11]), on_class_line=True, kappa=2.0, q1=0.1, q2=0.1,
    )  # fmt: skip
    pt = Point(np.pi, 1.0, "leaves_class_line", 3e-11, kappa=2.0, q1=0.1, q2=0.1)
    slices = [{"kappa": 2.0, "q1": 0.1, "q2": 0.1, "SS_hidden_cells": 0, "x": float("nan")}]
    return Boundaries([ss, ii], [pt], {"tolerance": 1e-10, "chord_tolerance": 1e-6,
                                         "seconds": 0.5, "slices": slices})  # fmt: skip


def test_netcdf_is_a_cf_geometry_container_that_round_trips(tmp_path):
    b = _boundaries()
    b.to_netcdf(tmp_path / "b.nc")
    with xr.open_dataset(tmp_path / "b.nc") as ds:
        assert ds.attrs["Conventions"] == "CF-1.10"
        geo = ds["boundary_geometry"].attrs
        assert geo["geometry_type"] == "line" and geo["node_count"] == "node_count"
        assert geo["node_coordinates"] == "node_beta1 node_beta2"
        assert ds["curve_kind"].attrs["geometry"] == "boundary_geometry"
        assert ds["node_count"].values.tolist() == [3, 2]
        nodes = np.stack([ds["node_beta1"].values, ds["node_beta2"].values], axis=1)
        np.testing.assert_array_equal(nodes, np.concatenate([c.vertices for c in b.curves]))
        assert ds["curve_kind"].values.tolist() == ["SS_stability", "II_consistency"]
        assert ds["curve_on_class_line"].values.tolist() == [0, 1]
        assert ds["point_kind"].values.tolist() == ["leaves_class_line"]
        assert ds["node_beta1"].attrs["units"] == "rad"
        assert json.loads(ds.attrs["slices"])[0]["x"] is None  # NaN is not JSON


def test_netcdf_holds_to_the_cf_rules(tmp_path):
    """What compliance-checker cf:1.10 asks of the file: a long_name on every variable, units on
    every float variable, no _FillValue on floats (NaN means "not proven", not missing),
    history and references; its remaining warnings are false positives documented in the
    README (beta1/beta2 are not longitude/latitude; the geometry's per-curve variables)."""
    _boundaries().to_netcdf(tmp_path / "b.nc")
    with xr.open_dataset(tmp_path / "b.nc", mask_and_scale=False) as ds:
        for name, v in ds.variables.items():
            assert "long_name" in v.attrs, name
            if v.dtype.kind == "f":
                assert "units" in v.attrs and "_FillValue" not in v.encoding, name
        assert ds.attrs["history"] and ds.attrs["references"]
        assert ds["curve_kappa"].attrs["units"] == "1"


def test_csv_has_one_row_per_vertex_and_point(tmp_path):
    b = _boundaries()
    b.to_csv(tmp_path / "b.csv")
    rows = (tmp_path / "b.csv").read_text().splitlines()
    head = rows[0].split(",")
    assert head == list(CSV_COLUMNS) and head[:4] == ["record", "curve", "field", "kind"]
    assert len(rows) == 1 + 5 + 1
    vertex = dict(zip(head, rows[-2].split(",")))
    assert vertex["curve"] == "1" and float(vertex["beta1"]) == np.pi
    assert float(vertex["bracket"]) == 3e-11
    point = dict(zip(head, rows[-1].split(",")))
    assert point["record"] == "point" and point["kind"] == "leaves_class_line"
    assert point["uncertainty"] == "" and point["proven"] == "0"  # no number without a proof


def test_geojson_lines_and_points(tmp_path):
    b = _boundaries()
    b.to_geojson(tmp_path / "b.json")
    doc = json.loads((tmp_path / "b.json").read_text())
    kinds = [f["geometry"]["type"] for f in doc["features"]]
    assert kinds == ["LineString", "LineString", "Point"]
    assert doc["features"][0]["geometry"]["coordinates"][2] == [0.5, 0.7]
    assert doc["features"][1]["properties"]["max_bracket"] == 3e-11
    assert doc["features"][0]["properties"]["side_left"] != ""  # the field's code label


def test_select_and_summary():
    b = _boundaries()
    assert [c.field for c in b.select(field="II")] == ["II"]
    assert b.select(kind="SS_stability")[0].vertices.shape == (3, 2)
    text = summary(b)
    assert text.startswith("boundaries: 2 curves, 5 vertices, 1 codimension-2 points")
    assert "II_consistency (on a class line): 1" in text and "point leaves_class_line: 1" in text


def test_spliced_points_are_marked_in_every_file(tmp_path):
    """A proven codimension-2 point spliced into a curve (vertex 1 of the SS curve) is marked as
    such in the netCDF (``node_spliced``), the CSV (``spliced``) and the GeoJSON (``spliced``:
    vertex indices); the other vertices are not."""
    b = _boundaries()
    b.curves[0].spliced = (1,)
    b.to_netcdf(tmp_path / "b.nc")
    with xr.open_dataset(tmp_path / "b.nc") as ds:
        assert ds["node_spliced"].values.tolist() == [0, 1, 0, 0, 0]
        assert ds["node_spliced"].attrs["flag_meanings"] == "no yes"
    b.to_csv(tmp_path / "b.csv")
    rows = [r.split(",") for r in (tmp_path / "b.csv").read_text().splitlines()]
    col = rows[0].index("spliced")
    assert [r[col] for r in rows[1:]] == ["0", "1", "0", "0", "0", ""]
    assert all(len(r) == len(CSV_COLUMNS) for r in rows)
    b.to_geojson(tmp_path / "b.json")
    feats = json.loads((tmp_path / "b.json").read_text())["features"]
    assert [f["properties"].get("spliced") for f in feats[:2]] == [[1], []]


def test_side_offset_is_stored_in_every_file(tmp_path):
    """A class-line piece labelled closer to the line than the side step (``side_offset``
    2^-43 rad on the II piece) says so in the netCDF (``curve_side_offset``, NaN: the side
    step), the CSV (``side_offset`` on each of its vertex rows, empty otherwise) and the GeoJSON
    (``side_offset``, null otherwise)."""
    b = _boundaries()
    b.curves[1].side_offset = 2.0**-43
    b.to_netcdf(tmp_path / "b.nc")
    with xr.open_dataset(tmp_path / "b.nc") as ds:
        got = ds["curve_side_offset"].values
        assert (
            np.isnan(got[0])
            and got[1] == 2.0**-43
            and ds["curve_side_offset"].attrs["units"] == "rad"
        )
    b.to_csv(tmp_path / "b.csv")
    rows = [r.split(",") for r in (tmp_path / "b.csv").read_text().splitlines()]
    col = rows[0].index("side_offset")
    assert [r[col] for r in rows[1:]] == ["", "", "", repr(2.0**-43), repr(2.0**-43), ""]
    assert all(len(r) == len(CSV_COLUMNS) for r in rows)
    b.to_geojson(tmp_path / "b.json")
    feats = json.loads((tmp_path / "b.json").read_text())["features"]
    assert [f["properties"].get("side_offset") for f in feats[:2]] == [None, 2.0**-43]
