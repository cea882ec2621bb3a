"""Region curves over a model box on each of their advertised outputs: the netCDF written by the
API (``region_curves(...).to_netcdf``) as by ``atlas boundaries --model-box``, and the GeoJSON.
Each file must say what its side codes mean, in the box verdicts' words (README "Verdicts over
every contact model": 0 unstable / 1 stable for every model, 2 depends on the model, 3
undecided), and not in field SS's (2 neutral): the GeoJSON's sides were empty and the API's
netCDF gave SS's meanings."""

import json

import numpy as np
import pytest
import xarray as xr

from atlas.data import region_curves as rc

#: the declared words of the SS box verdict's codes (README, SPEC §2)
SS_WORDS = {
    0: "unstable for every model",
    1: "stable for every model",
    2: "depends on the model",
    3: "undecided",
}
GRID = np.linspace(0.1, 6.2, 6)
WHOLE = "kappa=0:inf,q1=0:inf,q2=0:inf"


@pytest.fixture(scope="module")
def curves():
    """Over the whole model space (decided by signs and witnesses: no settlement)."""
    bd = rc.region_curves(GRID, GRID, "kappa=0:inf", tol=1e-3, settle=0)
    assert bd.curves
    return bd


def test_geojson_sides_are_the_box_verdicts_words(curves, tmp_path):
    curves.to_geojson(tmp_path / "r.json")
    doc = json.loads((tmp_path / "r.json").read_text())
    lines = [f for f in doc["features"] if f["geometry"]["type"] == "LineString"]
    assert len(lines) == len(curves.curves)
    for feat, c in zip(lines, curves.curves):
        props = feat["properties"]
        assert (props["side_left"], props["side_right"]) == (
            SS_WORDS[c.side_left],
            SS_WORDS[c.side_right],
        )
    assert doc["properties"]["model_box"] == WHOLE


def test_api_netcdf_gives_the_box_verdicts_meanings(curves, tmp_path):
    curves.to_netcdf(tmp_path / "r.nc")
    with xr.open_dataset(tmp_path / "r.nc") as ds:
        assert json.loads(ds.attrs["region_labels"])["ss_over_models"] == {
            str(k): v for k, v in SS_WORDS.items()
        }
        comment = ds["curve_side_left"].attrs["comment"]
        assert "depends on the model" in comment and "neutral" not in comment
        assert ds.attrs["model_box"] == WHOLE and ds.sizes["curve"] == len(curves.curves)


@pytest.mark.parametrize("box", ["kappa=2:1", {"kappa": (float("nan"), 1)}, "zeta=0:1"])
def test_a_bad_box_is_one_line_naming_model_box(box):
    """The API takes the box as every other entry does (a ModelBox, its text or a dict)."""
    with pytest.raises(ValueError, match=r"^model_box: ") as e:
        rc.region_curves(GRID, GRID, box)
    assert "\n" not in str(e.value)
