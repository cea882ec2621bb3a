"""The boundaries' arguments: one check for the API and the command line, and the command line's
refusals before any heavy import (counted in ``sys.modules`` of a fresh process, no clock)."""

import json
import subprocess
import sys

import pytest

from atlas.core import brackets
from atlas.data import boundary_args as ba

#: bad ``atlas boundaries`` arguments and the parameter each refusal must name
BAD = [
    (["--tol", "5"], "tol"),
    (["--chord", "1"], "chord"),
    (["--check", "99"], "check"),
    (["--fields", "XX"], "fields"),
    (["--out", "x.txt"], "out"),
    (["--kappa", "-1"], "kappa"),
    (["--kappa", "nan"], "kappa"),
    (["--kappa", "0"], "kappa"),
    (["--q", "-0.1"], "q"),
    (["--q1", "0.1", "--q2", "inf"], "q2"),
]
HEAVY = ("jax", "xarray", "scipy", "shapely", "flint", "netCDF4")


def test_field_names_are_the_kernels_fields():
    assert ba.FIELD_NAMES == tuple(brackets.FIELDS)


@pytest.mark.parametrize(
    "name, value", [("tol", 5.0), ("chord", 1.0), ("check", 99), ("fields", "XX")]
)
def test_check_args_names_the_parameter(name, value):
    opts = dict(tol=ba.TOL, chord=ba.CHORD, check=2, max_levels=2, fields="SS,II") | {name: value}
    with pytest.raises(ValueError, match=rf"^{name}: "):
        ba.check_args(**opts)


_PROBE = """
import contextlib, io, json, sys
from atlas import cli
err = io.StringIO()
with contextlib.redirect_stderr(err):
    try:
        rc = cli.main(sys.argv[1:])
    except SystemExit as e:
        rc = e.code
print(json.dumps([rc, err.getvalue(), sorted(m for m in sys.modules if m.split(".")[0] in HEAVY)]))
"""


@pytest.mark.e2e
@pytest.mark.parametrize("args, name", BAD)
def test_cli_refuses_before_heavy_imports(args, name):
    """``atlas boundaries`` with a bad ``--tol``, ``--chord``, ``--check``, ``--fields``, output
    name, or ``--kappa``/``--q``/``--q2`` (-1, NaN, 0; -0.1; inf; these imported JAX before the
    refusal): exit 2, one line naming the parameter, and neither JAX nor xarray (nor scipy,
    shapely, flint, netCDF4) imported at the refusal (before: all of them, 3.7-6.1 s)."""
    argv = ["boundaries", "--beta1", "0:2pi:8", "--beta2", "0:2pi:8", "--kappa", "1", *args]
    code = f"HEAVY = {HEAVY!r}\n" + _PROBE
    out = subprocess.run([sys.executable, "-c", code, *argv], capture_output=True, text=True)
    rc, err, heavy = json.loads(out.stdout.splitlines()[-1])
    assert rc == 2 and err.count("\n") == 1 and err.startswith(f"atlas: error: {name}: ")
    assert heavy == []


@pytest.mark.parametrize(
    "name, text", [("kappa", "-1"), ("kappa", "nan"), ("kappa", "0"), ("q", "-0.1"), ("q2", "inf")]
)
def test_model_text_refused_with_the_scene_message(name, text):
    """The light check refuses a bad model value with the message the scene's parser gives
    (:class:`atlas.Scene`, which the command line used to reach first)."""
    from atlas.data.scene import Scene

    with pytest.raises(ValueError) as light:
        ba.check_model_text(name, text)
    axes = dict(beta1="0:2pi:8", beta2="0:2pi:8", kappa="1") | {name: text}
    if name == "q2":
        axes["q1"] = "0.1"
    with pytest.raises(ValueError) as scene:
        Scene(**axes)
    assert str(light.value) == str(scene.value)
    assert ba.check_model_text("kappa", "0.5:2:4") is None  # a range: left to the parser
