"""``atlas generate``'s scene: built-in or explicit ranges, the model from physical parameters.

Reference values: SPEC §1 in closed form (``kappa = k1 |b1| / (k2 |b2|)``,
``q_j = q_j |b_j| / sqrt(k2 |b2|)``) and the paper's Fig. 2 parameters
(``k = (100, 200)``, ``q = (20, 20)``: ``kappa = 0.5``, ``q = sqrt(2)``).
"""

import math

import pytest

from atlas.data.generate_cli import parse_physical, scene_from_options
from atlas.data.scene import BUILTIN_SCENES


def test_physical_model_on_a_builtin_scene_keeps_its_ranges_and_name():
    sc = scene_from_options("fig1", physical="k1=100,k2=200,q1=20,q2=20")
    assert sc.name == "fig1" and sc.beta1 == BUILTIN_SCENES["fig1"]["beta1"]
    assert float(sc.axes["kappa"].values) == 0.5
    assert float(sc.axes["q"].values) == pytest.approx(math.sqrt(2), rel=1e-15)
    # the same scene (and atlas attributes) as the model typed as numbers
    typed = scene_from_options("fig1", kappa="0.5", q=repr(float(sc.axes["q"].values)))
    assert sc.describe() == typed.describe()


def test_unequal_damping_gives_q1_q2_on_explicit_ranges():
    sc = scene_from_options(None, "k1=50,k2=200,q1=10,b2=2", None, "0:2pi:4", "0:2pi:4")
    assert sc.model_names == ("kappa", "q1", "q2") and sc.name == "custom"
    assert float(sc.axes["kappa"].values) == 50 / 400
    assert float(sc.axes["q1"].values) == pytest.approx(10 / 20, rel=1e-15)
    assert float(sc.axes["q2"].values) == 0.0


@pytest.mark.parametrize(
    "kw, name",
    [
        (dict(physical="k1=1,k2=1", kappa="2"), "physical"),
        (dict(q="0.1", q1="0.1", q2="0.2"), "q"),
        (dict(physical="k1=-1,k2=1"), "k1"),
    ],
)
def test_conflicts_and_bad_values_name_the_option(kw, name):
    with pytest.raises(ValueError, match=f"^{name}:"):
        scene_from_options(**kw)


def test_parse_physical():
    assert parse_physical("k1=100, k2=2e2,") == {"k1": 100.0, "k2": 200.0}
    for text, name in (("k1=1", "physical"), ("k1=1,k2=1,k1=2", "physical"), ("k1=x,k2=1", "k1")):
        with pytest.raises(ValueError, match=f"^{name}:"):
            parse_physical(text)


@pytest.mark.parametrize(
    "extra, where",
    [
        (["--store", "s.zarr"], dict(store="s.zarr")),
        (["--scheduler", "local:1"], dict(scheduler="local:1")),
        (["--resume", "--store", "s.zarr"], dict(resume=True, store="s.zarr")),
        (["--slab", "4"], dict(slab=4)),
        (["--block2", "4"], dict(block2=4)),
    ],
)
def test_model_box_with_a_store_runs_tile_by_tile(tmp_path, monkeypatch, extra, where):
    """``--model-box`` with a store option takes the store path, the box passed on (nothing
    computed here: the store path is replaced)."""
    from atlas import cli
    from atlas.data import generate_cli

    monkeypatch.chdir(tmp_path)
    ran = []
    monkeypatch.setattr(generate_cli, "_run_store", lambda *a, **k: ran.append(k) or 0)
    monkeypatch.setattr(generate_cli, "_run_over_models", lambda *a, **k: ran.append("memory") or 0)
    argv = ["generate", "--beta1", "0:1:2", "--beta2", "0:1:2", "--model-box", "q=0:1"]
    assert cli.main([*argv, *extra, "--out", "a.nc"]) == 0
    assert len(ran) == 1 and ran[0]["model_box"] == "q=0:1", ran
    assert {k: ran[0][k] for k in where} == where


@pytest.mark.parametrize("box", ["kappa=2:1", "q1=-1:1", "kappa=1:2,zeta=0:1"])
def test_a_bad_model_box_with_a_store_is_refused_in_one_line(tmp_path, capsys, box):
    """Refused before any work: one line naming model_box, exit 2, nothing written."""
    from atlas import cli

    argv = ["generate", "--beta1", "0:1:2", "--beta2", "0:1:2", "--model-box", box]
    store, out = tmp_path / "s.zarr", tmp_path / "a.nc"
    assert cli.main([*argv, "--store", str(store), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("atlas: error: model_box: ") and err.count("\n") == 1, err
    assert list(tmp_path.iterdir()) == []
