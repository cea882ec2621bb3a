"""The MuJoCo bridge on each advertised entry, as a user meets it: docs/mujoco.md's Python example
and first command copied from the page, an MJCF file of a free body with two contacts through
``atlas mujoco --qpos --qvel``, an MJB file, and models outside the supported form (a constraint
acting besides the contacts, whose force neither ``Q`` nor ``B`` holds) refused in one line
naming ``model`` on the API, the rollout and the CLI (they were accepted with the free body's
``B``).

References: the planar closed forms of :class:`atlas.core.rigid_body.Mechanism` (``B`` does not
depend on the speed; ``a`` gains the rounded vertex's ``rho omega^2``, tests/mjcf_bodies.py)."""

from __future__ import annotations

import json
import re
import shlex
from pathlib import Path

import numpy as np
import pytest

from atlas import cli
from atlas.core.rigid_body import Mechanism

mujoco = pytest.importorskip("mujoco", reason="the mujoco extra is not installed")

from mjcf_bodies import mjcf  # noqa: E402

from atlas.bridges import mujoco as bridge  # noqa: E402
from atlas.bridges.rollout import rollout  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
DOC = (ROOT / "docs" / "mujoco.md").read_text()
EXAMPLE = ROOT / "examples" / "ladder.xml"
QVEL = [0.25, -0.0645497224368, 0.129099444874]  # Mechanism.ladder(speed=0.5).twist
LADDER = Mechanism.ladder(speed=0.5)


def _block(lang: str) -> str:
    return re.search(rf"```{lang}\n(.*?)```", DOC, re.S).group(1)


def test_the_pages_python_example_runs_as_written(monkeypatch):
    """The page's code, run from the repository root as written: ``B`` is the planar ladder's
    (its ``qvel`` is rounded: ``B`` depends only on the slip directions)."""
    monkeypatch.chdir(ROOT)
    code = _block("python")
    last = code.strip().splitlines()[-1]
    space = {}
    exec(compile(code.replace(last, "out = " + last), "docs/mujoco.md", "exec"), space)
    B, a, k, c, verdicts = space["out"]
    np.testing.assert_allclose(B, LADDER.B, rtol=0, atol=1e-12 * np.abs(LADDER.B).max())
    assert (
        np.all(k > 0)
        and np.all(c > 0)
        and verdicts["consistent_SS"] == bool(LADDER.verdicts()["consistent_SS"])
    )


def test_the_pages_first_command_runs_as_written(monkeypatch, capsys):
    first = _block("bash").splitlines()[1]
    assert first.startswith("atlas mujoco examples/ladder.xml --qvel ")
    monkeypatch.chdir(ROOT)
    assert cli.main([*shlex.split(first)[1:], "--json"]) == 0
    rep = json.loads(capsys.readouterr().out)
    np.testing.assert_allclose(rep["B"], LADDER.B, rtol=0, atol=1e-12 * np.abs(LADDER.B).max())
    np.testing.assert_allclose(rep["a"], LADDER.a + 0.02 * LADDER.omega**2, rtol=0, atol=1e-8)


def test_a_free_body_file_with_two_contacts_through_the_cli(tmp_path, capsys):
    """A two-legged body on a free joint (quaternion: nq = 7, nv = 6), written to a file, its
    state given by ``--qpos`` and ``--qvel``."""
    body = Mechanism.two_legged(speed=0.5)
    text, qvel = mjcf(body, rho=0.01, free=True)
    path = tmp_path / "two_legged.xml"
    path.write_text(text)
    qpos = mujoco.MjModel.from_xml_string(text).qpos0
    fmt = lambda v: ",".join(repr(float(x)) for x in v)  # noqa: E731
    argv = ["mujoco", str(path), "--qpos", fmt(qpos), "--qvel", fmt(qvel), "--json"]
    assert cli.main(argv) == 0
    rep = json.loads(capsys.readouterr().out)
    np.testing.assert_allclose(rep["B"], body.B, rtol=0, atol=1e-13 * np.abs(body.B).max())
    a_ref = body.a + 0.01 * body.omega**2
    np.testing.assert_allclose(rep["a"], a_ref, rtol=0, atol=1e-9 * np.abs(a_ref).max())


def test_an_mjb_file_loads_like_its_mjcf(tmp_path, capsys):
    model, _ = bridge.load(EXAMPLE)
    mujoco.mj_saveModel(model, str(tmp_path / "ladder.mjb"), None)
    args = ["--qvel", ",".join(map(repr, QVEL)), "--json"]
    assert cli.main(["mujoco", str(tmp_path / "ladder.mjb"), *args]) == 0
    binary = json.loads(capsys.readouterr().out)
    assert cli.main(["mujoco", str(EXAMPLE), *args]) == 0
    assert binary["B"] == json.loads(capsys.readouterr().out)["B"]
    (tmp_path / "bad.mjb").write_bytes(b"not a model")
    assert cli.main(["mujoco", str(tmp_path / "bad.mjb")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("atlas: error: model: cannot load ") and err.count("\n") == 1, err


_HINGE = 'type="hinge" axis="0 -1 0"'
#: the example ladder with one constraint besides its contacts: (edit, element named)
UNSUPPORTED = {
    "equality": (("</worldbody>", '</worldbody><equality><joint name="lock" joint1="phi"/>'
                  "</equality>"), "equality constraint 'lock'"),
    "joint limit": ((_HINGE, _HINGE + ' range="1 30" limited="true"'), "limit of joint 'phi'"),
    "friction loss": ((_HINGE, _HINGE + ' frictionloss="5"'), "friction loss of joint 'phi'"),
    "tendon limit": (("</worldbody>", '</worldbody><tendon><fixed name="t" limited="true" '
                      'range="0.1 1"><joint joint="x" coef="1"/></fixed></tendon>'),
                     "limit of tendon 't'"),
}  # fmt: skip


def _ladder(old, new):
    text = EXAMPLE.read_text()
    assert old in text
    return text.replace(old, new, 1)


@pytest.mark.parametrize("kind", list(UNSUPPORTED))
def test_a_constraint_besides_the_contacts_is_refused(kind):
    (old, new), named = UNSUPPORTED[kind]
    model = mujoco.MjModel.from_xml_string(_ladder(old, new))
    for call in (
        lambda: bridge.contact_data(model, qvel=QVEL),
        lambda: rollout(model, None, 0.01, qvel=QVEL),
    ):
        with pytest.raises(ValueError, match=rf"^model: the {re.escape(named)} acts") as e:
            call()
        assert "\n" not in str(e.value)


def test_an_inactive_equality_is_no_constraint():
    """``active="false"``: MuJoCo adds no force, and ``B`` is the free ladder's."""
    text = _ladder("</worldbody>", '</worldbody><equality><joint joint1="phi" active="false"/>'
                   "</equality>")  # fmt: skip
    res = bridge.contact_data(mujoco.MjModel.from_xml_string(text), qvel=QVEL)
    np.testing.assert_allclose(res.space.B, LADDER.B, rtol=0, atol=1e-12 * np.abs(LADDER.B).max())


def test_the_cli_refuses_a_constrained_file_in_one_line(tmp_path, capsys):
    (old, new), named = UNSUPPORTED["equality"]
    path = tmp_path / "locked.xml"
    path.write_text(_ladder(old, new))
    assert cli.main(["mujoco", str(path), "--qvel", ",".join(map(repr, QVEL))]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"atlas: error: model: the {named} acts") and err.count("\n") == 1, err


@pytest.mark.parametrize(
    "extra, message",
    [
        (["--tol", "-1"], "tol: must be a finite distance >= 0 m, got -1.0"),
        (["--tol", "nan"], "tol: must be a finite distance >= 0 m, got nan"),
        (["--rollout", "0.01", "--tol", "-1"], "tol: must be a finite distance >= 0 m, got -1.0"),
        (["--rollout", "inf"], "rollout: must be > 0 s, got inf (and finite)"),
        (["--rollout", "1e9"], "rollout: 1e+09 s is 200,000,000,001 judged states of 0.0005 s "
                               "steps every 10, at most 1,000,000 (raise every)"),
        (["--every", "5"], "every: only with --rollout T (it applies to a rollout)"),
        (["--jam-test"], "jam_test: only with --rollout T (it applies to a rollout)"),
        (["--rollout", "0.01", "--slip", "1,0,0;0,0,-1"], "slip: not with --rollout"),
    ],
)  # fmt: skip
def test_bad_or_ignored_options_are_one_line(extra, message, capsys):
    """A bad tolerance was reported as "no two geoms touch", an infinite rollout was an internal
    error and a huge one ran out of memory; an option of the other mode was silently ignored."""
    argv = ["mujoco", str(EXAMPLE), "--qvel", ",".join(map(repr, QVEL)), *extra]
    assert cli.main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith("atlas: error: " + message) and err.count("\n") == 1, err


def test_the_api_refuses_a_bad_tolerance():
    model, data = bridge.load(EXAMPLE)
    for tol in (-1e-6, float("nan"), float("inf")):
        with pytest.raises(ValueError, match=r"^tol: must be a finite distance >= 0 m"):
            bridge.contact_data(model, data, qvel=QVEL, tol=tol)
