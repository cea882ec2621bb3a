"""Verdicts over a model box as atlas variables: on request only, from ``atlas.generate`` and
``atlas generate --model-box``; checked against the closed form of the whole model space and the
exact tier (witnesses)."""

import contextlib
import io

import numpy as np
import pytest
import xarray as xr

import atlas
from atlas import cli
from atlas.core import exact
from atlas.core.contact_modes import direction
from atlas.core.model_box import WITNESS_NAMES
from atlas.core.verdicts import OverModels, Verdict
from atlas.data import outputs, over_models

KQ = ("kappa", "q1", "q2")
# an offset grid: no point on a class line, so the closed form's float signs are exact
GRID = dict(beta1="0.1:6.2:9", beta2="0.05:6.25:9", kappa=0.5, q=0.0)


def _closed_form(b1, b2):
    (c1, s1), (c2, s2) = direction(b1[:, None]), direction(b2[None, :])
    D = c1 * s2 - s1 * c2
    U, S, DEP = int(OverModels.UNSTABLE), int(OverModels.STABLE), int(OverModels.DEPENDS)
    return np.where(
        (D < 0) | ((c1 <= 0) & (s2 <= 0)), U, np.where((c1 > 0) & (s2 > 0) & (s1 * c2 >= 0), S, DEP)
    )


def test_not_in_the_default_atlas():
    names = ("ss_over_models", *WITNESS_NAMES)
    assert not set(names) & set(outputs.atlas_outputs())
    assert all(n in outputs.OUTPUTS for n in names)
    ds = atlas.generate(atlas.Scene(**GRID))
    assert not set(names) & set(ds.data_vars)


def test_generate_with_the_whole_model_space():
    ds = atlas.generate(atlas.Scene(**GRID), model_box={})
    code = ds["ss_over_models"]
    assert code.dims == ("beta1", "beta2") and code.dtype == np.int8
    np.testing.assert_array_equal(code.values, _closed_form(ds.beta1.values, ds.beta2.values))
    assert ds.attrs["model_box"] == "kappa=0:inf,q1=0:inf,q2=0:inf"
    assert ds.attrs["over_models_undecided"] == 0
    assert "stable_SS" in ds  # the single-model atlas is still there
    _check_ii(ds)


def _check_ii(ds):
    """The II verdicts over the box: registered variables, witnesses on their side (exact)."""
    assert set(over_models.II_OVER_MODELS_OUTPUTS) <= set(ds.data_vars)
    cons = ds["ii_consistent_over_models"]
    assert cons.dtype == np.int8 and cons.dims == ("beta1", "beta2")
    assert cons.attrs["flag_meanings"] == "inconsistent consistent depends undecided"
    for name, key in (("ii_consistent", "consistent_II"), ("ii_stable", "stable_II")):
        code = ds[f"{name}_over_models"].values
        sides = over_models.iim.SIDES[f"{name}_over_models"]
        for i, j in np.argwhere(code == int(OverModels.DEPENDS)):
            (c1, s1), (c2, s2) = direction(ds.beta1.values[i]), direction(ds.beta2.values[j])
            for side, want in zip(sides, (1, 0)):
                m = [float(ds[f"{name}_witness_{side}_{v}"].values[i, j]) for v in KQ]
                got = exact.point_spectral(c1, s1, c2, s2, *m)[key]
                assert int(got == 1) == want, (name, side, m)
        assert np.isnan(ds[f"{name}_witness_{sides[0]}_kappa"].values[code != 2]).all()


def test_witnesses_hold_in_a_bounded_box():
    box = "kappa=0.01:100,q1=0:1,q2=0:1"
    ds = atlas.generate(atlas.Scene(**GRID), model_box=box)
    dep = np.argwhere(ds["ss_over_models"].values == int(OverModels.DEPENDS))
    assert len(dep) > 0
    good = (int(Verdict.STABLE), int(Verdict.NEUTRAL))
    for i, j in dep:
        (c1, s1), (c2, s2) = direction(ds.beta1.values[i]), direction(ds.beta2.values[j])
        w = [float(ds[n].values[i, j]) for n in WITNESS_NAMES]
        assert 0.01 <= w[0] <= 100 and 0.01 <= w[3] <= 100
        assert all(0 <= v <= 1 for v in (w[1], w[2], w[4], w[5]))
        assert exact.ss_hurwitz(c1, s1, c2, s2, *w[:3]) in good
        assert exact.ss_hurwitz(c1, s1, c2, s2, *w[3:]) == int(Verdict.UNSTABLE)
    other = ds["ss_over_models"].values != int(OverModels.DEPENDS)
    assert np.isnan(ds["ss_witness_stable_kappa"].values[other]).all()


def test_bad_box_refused_before_any_work():
    with pytest.raises(ValueError, match="^model_box: kappa: reversed"):
        atlas.generate(atlas.Scene(**GRID), model_box="kappa=3:1")
    with pytest.raises(ValueError, match="^model_box: unknown axes"):
        over_models.as_model_box({"zeta": 1})


def _main(args):
    err = io.StringIO()
    with contextlib.redirect_stderr(err):
        rc = cli.main(args)
    return rc, err.getvalue()


def test_cli_model_box(tmp_path):
    out = tmp_path / "a.nc"
    args = ["generate", "--beta1", "0.1:6.2:9", "--beta2", "0.05:6.25:9", "--out", str(out)]
    rc, err = _main([*args, "--model-box", "kappa=0.01:100,q1=0:1,q2=0:1"])
    assert rc == 0 and "undecided 0 before, 0 after settlement" in err
    with xr.open_dataset(out) as ds:
        assert ds["ss_over_models"].dtype == np.int8
        assert ds.attrs["model_box"] == "kappa=0.01:100,q1=0:1,q2=0:1"


@pytest.mark.parametrize(
    "box", ["kappa=2:1", "kappa=0:0", "q1=-1:1", "q2=nan:1", "q=1:0.5", "kappa=1:2,zeta=0:1"]
)
def test_cli_bad_boxes(tmp_path, box):
    out = tmp_path / "a.nc"
    rc, err = _main(["generate", "--beta1", "0:1:2", "--beta2", "0:1:2", "--out", str(out)] + [
        "--model-box", box,
    ])  # fmt: skip
    assert rc == 2 and err.count("\n") == 1 and "model_box" in err
    assert not out.exists()
