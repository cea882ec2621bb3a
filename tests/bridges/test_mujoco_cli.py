"""``atlas mujoco`` (atlas.bridges.mujoco_cli) on the worked example examples/ladder.xml: the JSON
object against the planar ladder's closed forms, the text report, one-line errors, the missing
extra."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import pytest

from atlas import cli
from atlas.core.contact_space import verdict_names
from atlas.core.rigid_body import Mechanism

EXAMPLE = str(Path(__file__).resolve().parents[2] / "examples" / "ladder.xml")
QVEL = "0.25,-0.0645497224368,0.129099444874"  # Mechanism.ladder(speed=0.5).twist


def _have_mujoco():
    try:
        import mujoco  # noqa: F401
    except ImportError:
        return False
    return True


needs_mujoco = pytest.mark.skipif(not _have_mujoco(), reason="the mujoco extra is not installed")


@needs_mujoco
def test_json_of_the_worked_example_is_the_planar_ladder(capsys):
    """examples/ladder.xml (written by hand: wall x = 0, floor z = 0, spheres of 0.02 m) at the
    sliding state gives the built-in ladder's B to rounding and a + rho omega^2; every verdict
    under its output name."""
    assert cli.main(["mujoco", EXAMPLE, "--qvel", QVEL, "--json"]) == 0
    rep = json.loads(capsys.readouterr().out)
    lad = Mechanism.ladder(speed=0.5)
    np.testing.assert_allclose(rep["B"], lad.B, rtol=0, atol=1e-12 * np.abs(lad.B).max())
    np.testing.assert_allclose(rep["a"], lad.a + 0.02 * lad.omega**2, rtol=0, atol=1e-8)
    assert set(verdict_names()) <= set(rep) and rep["approximate_model"] is True
    assert [c["name"] for c in rep["contacts"]] == ["floor/foot", "wall/top"]
    assert rep["consistent_SS"] == bool(lad.verdicts()["consistent_SS"])


@needs_mujoco
def test_text_report_and_single_contact(capsys):
    assert cli.main(["mujoco", EXAMPLE, "--qvel", QVEL, "--contacts", "top,foot"]) == 0
    out = capsys.readouterr().out
    assert "contact wall/top: mu 0.4" in out.splitlines()[1]
    assert "stable_SS = 1 (stable)" in out and "jam consistent: none" in out
    assert "lift-off consistent: none (a separation the engine shows here is an artefact" in out
    off_wall = ["--qpos", "0.1,0,0", "--qvel", QVEL]  # the top 0.1 m off the wall
    assert cli.main(["mujoco", EXAMPLE, *off_wall, "--contacts", "foot"]) == 0
    out = capsys.readouterr().out
    assert "consistent_S = True" in out and "B [1/kg] = [[0.0598017]]" in out
    args = ["mujoco", EXAMPLE, "--slip", "1,0,0;0,0,-1"]  # at rest: the directions given
    assert cli.main(args) == 0
    assert (
        "B [1/kg] = [[0.0598017, -0.0267456], [-7.89585e-05, 0.273532]]" in capsys.readouterr().out
    )


@needs_mujoco
@pytest.mark.parametrize(
    "extra, pattern",
    [
        (["--qvel", "1,x"], "atlas: error: qvel: expected comma-separated numbers"),
        (["--qvel", "1,2"], "atlas: error: qvel: expected 3 finite numbers, got 2"),
        (["--qpos", "0.3,0.5,0"], "atlas: error: contacts: no two geoms touch"),
        ([], "atlas: error: qvel: contact floor/foot does not slide"),
        (["--qvel", QVEL, "--contacts", "rails"], "atlas: error: contacts: 'rails' does not"),
        (["--slip", "1,0"], "atlas: error: slip: expected x,y,z per contact"),
    ],
)
def test_errors_are_one_line(extra, pattern, capsys):
    assert cli.main(["mujoco", EXAMPLE, *extra]) == 2
    err = capsys.readouterr().err
    assert err.startswith(pattern) and len(err.strip().splitlines()) == 1, err


def test_missing_extra_is_one_line_naming_the_install(monkeypatch, capsys):
    monkeypatch.setitem(sys.modules, "mujoco", None)
    assert cli.main(["mujoco", EXAMPLE]) == 2
    err = capsys.readouterr().err.strip()
    assert err == (
        "atlas: error: mujoco: the MuJoCo bridge needs the mujoco extra: "
        "pip install 'painleve-atlas[mujoco]'"
    )


@needs_mujoco
def test_rollout_reports_events(capsys):
    """--rollout: the example ladder (mu = 0.4) sliding at 0.5 m/s slows to a stop; the events
    name the state at the start and where a contact stops sliding; the text report ends with
    the engine's behaviour and the jam test."""
    args = ["mujoco", EXAMPLE, "--qvel", QVEL, "--rollout", "0.3", "--every", "20"]
    assert cli.main([*args, "--json"]) == 0
    rep = json.loads(capsys.readouterr().out)
    assert rep["contacts"] == ["floor/foot", "wall/top"] and len(rep["samples"]) == 31
    first = rep["events"][0]
    assert first["t"] == 0.0 and "consistent_SS = True" in first["event"]
    assert any("stuck" in e["event"] for e in rep["events"][1:])
    assert cli.main([*args, "--jam-test"]) == 0
    out = capsys.readouterr().out
    assert out.startswith("contacts: floor/foot, wall/top; 31 states judged")
    assert out.splitlines()[-1].startswith("stop: ") and "friction stop)" in out
    assert out.splitlines()[-2] == "engine: stop"  # the engine's behaviour, before the jam test
