"""Bad model boxes on every entry point (the CLI's ``--model-box``, the Python functions, a
``ModelBox`` made directly, dicts with numpy scalars, a Dataset): one check
(:func:`atlas.core.model_box.checked`), a one-line ``ValueError`` naming the parameter, the same
message as the CLI (exit code 2, no traceback)."""

import math

import numpy as np
import pytest
import xarray as xr

from atlas import cli
from atlas.core import ii_over_models as iim
from atlas.core import model_box as mb
from atlas.data.box_points import point_values
from atlas.data.over_models import as_model_box, over_models

#: bad box texts and the parameter each message must name
BAD_TEXTS = [
    ("kappa=nan:1", "kappa"),
    ("kappa=2:1", "kappa"),
    ("q1=-1:1", "q1"),
    ("q2=0:-inf", "q2"),
    ("kappa=0:0", "kappa"),
    ("q=inf:inf", "q"),
    ("q=0:1,q2=0:1", "q"),
]

ENTRY_POINTS = {
    "parse_model_box": mb.parse_model_box,
    "as_model_box": as_model_box,
    "ss_over_models": lambda box: mb.ss_over_models(1.0, 0.0, 0.0, 1.0, box),
    "ii_over_models": lambda box: iim.ii_over_models(1.0, 0.0, 0.0, 1.0, box),
    "over_models": lambda box: over_models([0.5], [2.0], box, ii=True),
    "point_values": lambda box: point_values(0.5, 2.0, box),
}


def _message(fn, box) -> str:
    with pytest.raises(ValueError) as e:
        fn(box)
    text = str(e.value)
    assert "\n" not in text and text.startswith("model_box: "), text
    return text


def _cli_message(text, capsys) -> str:
    rc = cli.main(["boundaries", "--model-box", text])
    err = capsys.readouterr().err.strip()
    assert rc == 2 and "Traceback" not in err and len(err.splitlines()) == 1, err
    return err.removeprefix("atlas: error: ")


@pytest.mark.parametrize("text, name", BAD_TEXTS)
def test_every_entry_point_gives_the_clis_message(text, name, capsys):
    want = _cli_message(text, capsys)
    assert want.startswith(f"model_box: {name}: ") or f"model_box: {name}" in want, want
    for fn in ENTRY_POINTS.values():
        assert _message(fn, text) == want


@pytest.mark.parametrize(
    "make, name",
    [
        (lambda: mb.ModelBox(kappa=(math.nan, 1.0)), "kappa"),
        (lambda: mb.ModelBox(q1=(2.0, 1.0)), "q1"),
        (lambda: mb.ModelBox(q2=(-1.0, 1.0)), "q2"),
        (lambda: mb.ModelBox(q1=(0.0, 1.0), q2=(0.0, 2.0), equal=True), "q"),
        (lambda: mb.model_box(kappa=(np.bool_(True), 2.0)), "kappa"),
        (lambda: mb.model_box(q=np.float32("nan")), "q"),
        (lambda: as_model_box({"kappa": (np.float64(3.0), np.int64(1))}), "kappa"),
        (lambda: as_model_box({"kappa": np.array([0.1, 2.0, 3.0])}), "kappa"),
        (lambda: as_model_box({"zeta": 1.0}), "zeta"),
        (lambda: as_model_box(xr.Dataset({"a": ("x", np.arange(3))})), "Dataset"),
        (lambda: iim.ii_over_models(1.0, 0.0, 0.0, 1.0, {"q1": (1.0, 0.0)}), "q1"),
        (lambda: mb.ss_over_models(1.0, 0.0, 0.0, 1.0, None), "model_box"),
    ],
)
def test_objects_that_are_no_box(make, name):
    """Made directly, with numpy scalars, a dict or something else: the same one-line check."""
    assert name in _message(lambda _: make(), None)


def test_numpy_numbers_make_the_same_box():
    """numpy scalars and a 1-D array are numbers like any other: the same box as the text."""
    want = mb.parse_model_box("kappa=0.5:2,q=0:1")
    assert mb.model_box(kappa=(np.float32(0.5), np.int64(2)), q=np.array([0.0, 1.0])) == want
    assert as_model_box({"kappa": np.array([0.5, 2.0]), "q": (np.float64(0), 1)}) == want
    assert mb.ModelBox((0.5, 2), (0, 1), (0, 1), np.bool_(True)) == want
