"""Mechanism scenes (atlas.data.mechanisms): physical axes, derived invariants, verdicts."""

import numpy as np
import pytest

from atlas.core.mechanism import Mechanism
from atlas.data.mechanisms import MECHANISM_SCENES, mechanism_atlas


@pytest.fixture(scope="module")
def ladder():
    return mechanism_atlas("ladder", theta="0.05pi:0.45pi:17", mu="0:2:21")


def test_ladder_foot_has_painleve_threshold_of_the_classical_rod(ladder):
    """b11 < 0 (Painleve's paradox at the foot alone) iff mu > (1 + 3 cos^2) / (3 sin cos)
    (the uniform rod, worked by hand in Mechanism.ladder's docstring; minimum 4/3)."""
    th, mu = np.meshgrid(ladder.theta.values, ladder.mu.values, indexing="ij")
    threshold = (1 + 3 * np.cos(th) ** 2) / (3 * np.sin(th) * np.cos(th))
    away = np.abs(mu - threshold) > 1e-9
    assert np.array_equal((ladder.b11.values < 0)[away], (mu > threshold)[away])
    assert threshold.min() >= 4 / 3 - 1e-12


def test_every_point_equals_the_single_mechanism(ladder):
    rng = np.random.default_rng(3)
    for i, j in zip(
        rng.integers(0, ladder.sizes["theta"], 6), rng.integers(0, ladder.sizes["mu"], 6)
    ):
        th, mu = float(ladder.theta[i]), float(ladder.mu[j])
        body = Mechanism.ladder(theta=th, mu_floor=mu, mu_wall=mu)
        point = ladder.isel(theta=i, mu=j)
        for k, v in body.invariants.items():
            assert float(point[k]) == pytest.approx(v, rel=1e-12, abs=1e-12), k
        for k, v in body.verdicts().items():
            if (
                point[k].dtype.kind == "f"
            ):  # the abscissa: approximate roots (compiled per batch size)
                assert float(point[k]) == pytest.approx(float(v), rel=1e-12, abs=1e-15), k
            else:
                assert np.asarray(point[k].values) == np.asarray(v).astype(point[k].dtype), (
                    k,
                    th,
                    mu,
                )


def test_physical_coordinates_carry_units_and_select(ladder):
    assert ladder.theta.attrs["units"] == "rad" and ladder.mu.attrs["units"] == "1"
    one = ladder.sel(mu=0.6, method="nearest")
    assert one.sizes == {"theta": 17} and float(one.mu) == pytest.approx(0.6)
    assert ladder.b11.attrs["units"] == "1/kg" and "long_name" in ladder.class_code.attrs


@pytest.mark.parametrize("name", sorted(MECHANISM_SCENES))
def test_every_builtin_scene_runs_small(name):
    axes = {a: f"{lo}" for a, (lo, *_r) in MECHANISM_SCENES[name].axes.items()}
    small = {a: spec.rsplit(":", 1)[0] + ":3" for a, spec in axes.items()}
    ds = mechanism_atlas(name, **small)
    assert all(ds.sizes[a] == 3 for a in small)
    assert int((ds.class_code < 0).sum()) == 0  # every class code decided (settled exactly)


def test_bad_axis_and_name_are_one_line_errors():
    with pytest.raises(ValueError, match=r"^alpha: not an axis of ladder"):
        mechanism_atlas("ladder", alpha="0:1:3")
    with pytest.raises(ValueError, match=r"^mechanism: unknown 'chair'"):
        mechanism_atlas("chair")
    with pytest.raises(ValueError, match=r"^mu: "):
        mechanism_atlas("ladder", mu="0:nan:3")


def test_cli_writes_the_mechanism_atlas(tmp_path, capsys):
    from atlas.cli import main

    out = tmp_path / "ladder.nc"
    assert (
        main(
            [
                "mechanism",
                "ladder",
                "--theta",
                "0.1pi:0.4pi:4",
                "--mu",
                "0.5,1.5",
                "--out",
                str(out),
            ]
        )
        == 0
    )
    import xarray as xr

    with xr.open_dataset(out) as ds:
        assert ds.sizes == {"theta": 4, "mu": 2} and ds.mu.attrs["units"] == "1"
    assert main(["mechanism", "ladder", "--h", "1"]) == 2
    assert "h: not an axis of ladder" in capsys.readouterr().err


def test_float16_refused():
    with pytest.raises(ValueError, match="^dtype: must be float32 or float64"):
        mechanism_atlas("ladder", theta="0.1:1:3", mu="0:1:3", dtype="float16")
