"""A model box on every path that carries it as text: the explorer's "model box" field, the
netCDF attribute and ``history`` of ``atlas generate --model-box``, a tiled store's plan (a resume
over another box is refused).  The text must be the box typed, to the last bit: a box read back
from rounded text is another box, so a "for every model" verdict would be claimed for models it
never covered (``kappa=0.1234567:2.0000004`` was written ``kappa=0.123457:2``).

Reference: the box as parsed from the user's text (``float`` of each bound), nothing computed."""

import math

import pytest
import xarray as xr

import atlas
from atlas import cli
from atlas.core.model_box import model_box, parse_model_box
from atlas.data.over_models import as_model_box

#: bounds that six significant digits do not hold (and some they do)
TYPED = [
    "kappa=0.1234567:2.0000004,q=0:1",
    "kappa=0.01:100,q1=0:1,q2=0:1",
    "kappa=1e-320:3.0000000000000004,q1=0.3333333333333333:inf,q2=0:0.1",
    "kappa=12345678:inf,q=1.5e-7:0.30000000000000004",
]


@pytest.mark.parametrize("text", TYPED)
def test_the_box_text_reads_back_as_the_box(text):
    box = parse_model_box(text)
    assert parse_model_box(str(box)) == box
    assert as_model_box(str(box)) == as_model_box(text)


def test_nice_bounds_keep_their_short_text():
    """The text of bounds ``%g`` already writes exactly is unchanged (stored files keep it)."""
    assert str(model_box(kappa=(0.01, 100), q1=(0, 1), q2=(0, 1))) == "kappa=0.01:100,q1=0:1,q2=0:1"
    assert str(model_box(q=(0.1, math.inf))) == "kappa=0:inf,q=0.1:inf"


def test_a_reversed_range_names_its_bounds_exactly():
    with pytest.raises(ValueError, match=r"^model_box: kappa: reversed range 2.0000004:2$"):
        parse_model_box("kappa=2.0000004:2")


def test_the_explorers_box_is_the_box_typed():
    """The explorer keeps the box as its text (``maps.checked_box``) and computes from it."""
    from atlas.explore.maps import checked_box

    text = TYPED[0]
    assert as_model_box(checked_box(text)) == parse_model_box(text)


def test_generate_cli_records_the_box_typed(tmp_path, capsys):
    """``atlas generate --model-box`` (one geometry): the netCDF attribute is the box typed."""
    out = tmp_path / "m.nc"
    argv = ["generate", "--beta1", "0.3", "--beta2", "2.0", "--kappa", "1", "--q", "0.5"]
    assert cli.main([*argv, "--model-box", TYPED[0], "--out", str(out)]) == 0, capsys.readouterr()
    with xr.open_dataset(out) as ds:
        assert parse_model_box(ds.attrs["model_box"]) == parse_model_box(TYPED[0])
        assert TYPED[0] in ds.attrs["history"]


def test_a_resume_over_a_box_that_differs_in_the_seventh_digit_is_refused(tmp_path, monkeypatch):
    """A store laid out over one box (its first tile interrupted), resumed over a box 4e-7 wider:
    refused in one line naming model_box before any tile is computed."""
    pytest.importorskip("zarr")
    from atlas.data import distributed

    class Interrupted(Exception):
        pass

    def interrupted(*args):
        raise Interrupted

    monkeypatch.setattr(distributed, "compute_tile", interrupted)
    scene = atlas.Scene(beta1="0.1:6.2:4", beta2="0.1:6.2:4", kappa=1.0, q=0.5)
    store = tmp_path / "s.zarr"
    with pytest.raises(Interrupted):
        distributed.generate_distributed(scene, store, model_box="kappa=0.5:2,q=0.1:1", slab=2)
    wider = "kappa=0.5:2.0000004,q=0.1:1"
    with pytest.raises(ValueError, match=r"^model_box: store .* asks for kappa=0.5:2.0000004") as e:
        distributed.generate_distributed(scene, store, model_box=wider, resume=True, slab=2)
    assert "\n" not in str(e.value)


def test_a_mechanism_atlas_records_the_box_typed():
    """``atlas.mechanism_atlas(name, model_box=...)`` (one body): the attribute and the call in
    ``history`` give the box typed."""
    from atlas.data.body_atlas import mechanism_atlas

    ds = mechanism_atlas("ladder", theta="0.3", mu="0.5", model_box=TYPED[0])
    assert parse_model_box(ds.attrs["model_box"]) == parse_model_box(TYPED[0])
    assert f"model_box={TYPED[0]!r}" in ds.attrs["history"]
