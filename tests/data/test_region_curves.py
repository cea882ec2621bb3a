"""The certified curves between the regions of ``ss_over_models`` (:mod:`atlas.data.region_curves`)
against independent references: the closed form of the whole model space decided in exact
rational arithmetic on both ends of every bracket, and over a bounded box the exact tier on a
sample of models at both ends."""

from __future__ import annotations

import itertools
import math
from fractions import Fraction

import numpy as np
import pytest
import xarray as xr

from atlas.core import contact_modes as mech
from atlas.core import exact
from atlas.core.model_box import ModelBox, parse_model_box
from atlas.core.verdicts import OverModels, Verdict
from atlas.data import region_curves as rc

#: a grid offset from every class line (no node within 0.15 rad of one)
N = 12
GRID = (np.arange(N) + 0.3) * (2 * np.pi / N)


def _directions(p):
    c1, s1 = mech.direction(p[0])
    c2, s2 = mech.direction(p[1])
    return tuple(float(v) for v in (c1, s1, c2, s2))


def _closed_form(p) -> int:
    """``ss_over_models`` over the whole model space at point ``p`` (closed form of
    :mod:`atlas.core.model_box`'s docstring), decided exactly on the rounded directions."""
    c1, s1, c2, s2 = (Fraction(v) for v in _directions(p))
    D = c1 * s2 - s1 * c2
    if D < 0 or (c1 <= 0 and s2 <= 0):
        return int(OverModels.UNSTABLE)
    if c1 > 0 and s2 > 0 and s1 * c2 >= 0:
        return int(OverModels.STABLE)
    return int(OverModels.DEPENDS)


def _line_distance(v) -> float:
    """Distance [rad] of ``v`` to the lines where the closed form's signs change: ``beta_j = k
    pi/2`` and ``beta2 = beta1 + k pi`` (``det B = 0``)."""
    q = lambda x, p: abs((x + p / 2) % p - p / 2)  # noqa: E731
    return min(q(v[0], np.pi / 2), q(v[1], np.pi / 2), q(v[1] - v[0], np.pi) / math.sqrt(2))


def test_whole_model_space_curves_against_the_exact_closed_form():
    """Every vertex's bracket ends carry the curve's two side codes by the exact closed form
    (so the true boundary runs between them), and every vertex lies within half its bracket of
    a line the closed form changes on (``<= tol`` but for the brackets stopped on an undecided
    or third-code midpoint, counted, a minority); all three interfaces are traced."""
    tol = 1e-6
    bd = rc.region_curves(GRID, GRID, ModelBox(), tol=tol)
    seen = set()
    for c in bd.curves:
        assert c.kind == "ss_over_models_region" and c.side_left > c.side_right
        seen.add((c.side_left, c.side_right))
        for v, (lo, hi), br in zip(c.vertices, c.ends, c.bracket):
            assert (_closed_form(lo), _closed_form(hi)) == (c.side_right, c.side_left), (c, v)
            assert _line_distance(v) <= 0.5 * br + 1e-15, (v, br)
    assert seen == {(1, 0), (2, 0), (2, 1)}
    assert bd.attrs["grid_undecided"] == 0
    brackets = np.concatenate([c.bracket for c in bd.curves])
    assert np.sum(brackets > tol) == bd.attrs["stopped"] < 0.25 * len(brackets)


def _good(p, model) -> bool:
    return exact.ss_hurwitz(*_directions(p), *model) in (Verdict.STABLE, Verdict.NEUTRAL)


def test_bounded_box_curves_against_the_exact_tier_on_sampled_models():
    """Over ``kappa in [0.5, 2], q1 = q2 in [0.1, 1]``: at the end of a bracket claimed
    'stable for every model' (resp. 'unstable') no sampled model is unstable (resp. stable) by
    the exact tier, and at a 'depends' end the two ends of the curve differ; brackets closed to
    ``tol`` for the most part."""
    box = parse_model_box("kappa=0.5:2,q=0.1:1")
    tol = 1e-5
    g = GRID[::2]
    bd = rc.region_curves(g, g, box, tol=tol)
    assert bd.curves and bd.attrs["model_box"] == "kappa=0.5:2,q=0.1:1"
    models = [(k, q, q) for k, q in itertools.product((0.5, 0.9, 1.4, 2.0), (0.1, 0.5, 1.0))]
    ends = 0
    for c in bd.curves:
        for lo, hi in c.ends:
            for p, code in ((lo, c.side_right), (hi, c.side_left)):
                if code == OverModels.DEPENDS:
                    continue
                want = code == OverModels.STABLE
                assert all(_good(p, m) == want for m in models), (p, code)
                ends += 1
    assert ends > 10
    closed = sum(int(np.sum(c.bracket <= tol)) for c in bd.curves)
    assert closed > bd.attrs["stopped"]


def test_cli_fields_pick_the_verdicts(tmp_path, capsys):
    """``--fields SS`` traces ``ss_over_models`` alone (every verdict was traced before), and
    ``II`` names the two II verdicts of SPEC §2."""
    from atlas.cli import main

    out = tmp_path / "r.nc"
    axes = ["--beta1", "0.1:6.2:6", "--beta2", "0.1:6.2:6", "--tol", "1e-3"]
    argv = ["boundaries", "--model-box", "kappa=0.5:2,q=0.1:1", *axes, "--fields", "SS"]
    assert main([*argv, "--out", str(out)]) == 0, capsys.readouterr().err
    with xr.open_dataset(out) as ds:
        assert set(ds["curve_kind"].values) == {"ss_over_models_region"}
    assert rc._fields("II") == ("ii_consistent_over_models", "ii_stable_over_models")
    assert rc._fields("SS,ii_stable_over_models") == ("ss_over_models", "ii_stable_over_models")
    assert len(rc._fields(None)) == 3


def test_cli_writes_the_curves_and_refuses_bad_input(tmp_path, capsys):
    """``atlas boundaries --model-box`` writes the curves (netCDF with the box and the codes'
    meanings, CSV); the model axes, a bad box and an unknown field are one-line refusals (exit
    2, nothing written)."""
    from atlas.cli import main

    out, csv = tmp_path / "r.nc", tmp_path / "r.csv"
    axes = ["--beta1", "0.1:6.2:6", "--beta2", "0.1:6.2:6", "--tol", "1e-4"]
    argv = ["boundaries", "--model-box", "kappa=0.5:2,q=0.1:1", *axes]
    assert main([*argv, "--out", str(out), "--csv", str(csv)]) == 0
    with xr.open_dataset(out) as ds:
        assert ds.attrs["model_box"] == "kappa=0.5:2,q=0.1:1"
        assert "depends on the model" in ds.attrs["region_labels"]
        kinds = set(ds["curve_kind"].values)
        assert "ss_over_models_region" in kinds
        assert kinds <= {f"{n}_over_models_region" for n in ("ss", "ii_consistent", "ii_stable")}
        assert "consistent for every model" in ds.attrs["region_labels"]
        assert ds.sizes["node"] == sum(1 for line in csv.read_text().splitlines()[1:])
    capsys.readouterr()
    for extra, name in (
        (["--kappa", "1"], "kappa"),
        (["--model-box", "kappa=2:1"], "model_box"),
        (["--fields", "stable_SS"], "fields"),
        (["--chord", "1e-3"], "chord"),  # were ignored: region curves are not refined
        (["--check", "1"], "check"),
    ):
        bad = tmp_path / "bad.nc"
        args = ["boundaries", "--model-box", "q=0:1", *axes, *extra, "--out", str(bad)]
        assert main(args) == 2
        err = capsys.readouterr().err
        assert err.startswith(f"atlas: error: {name}: ") and err.count("\n") == 1, err
        assert not bad.exists()


@pytest.mark.parametrize(
    "kw, name",
    [(dict(tol=0.0), "tol"), (dict(tol=float("nan")), "tol"), (dict(settle=-1), "settle")],
)
def test_bad_options(kw, name):
    with pytest.raises(ValueError, match=f"^{name}: "):
        rc.region_curves(GRID, GRID, ModelBox(), **kw)
