"""Mechanism scenes (atlas.data.body_atlas): physical axes, derived invariants, verdicts."""

import numpy as np
import pytest

from atlas.core.rigid_body import Mechanism
from atlas.data.body_atlas import MECHANISM_SCENES, mechanism_atlas


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
    with pytest.raises(ValueError, match=r"^L: expected real numbers, got True"):
        mechanism_atlas("ladder", fixed={"L": True}, theta="0.1:0.4:3", mu="0:1:3")


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


@pytest.mark.parametrize(
    "argv, name",
    [
        (["ladder", "--mu", "-1:2:4"], "mu"),
        (["ladder", "--mu", "-0.5"], "mu"),
        (["ladder", "--theta", "0:0.4pi:3"], "theta"),
        (["ladder", "--theta", "0.1:0.6pi:3"], "theta"),
        (["ladder", "--theta", "-pi:1:3"], "theta"),
        (["two_legged", "--h", "-1:1:3"], "h"),
        (["leaning_rod", "--mu", "0,-2"], "mu"),
    ],
)
def test_cli_bad_physical_values(tmp_path, capsys, argv, name):
    """Out-of-range physical values (negative range starts included): exit 2, one line naming
    the axis, nothing written."""
    from atlas.cli import main

    out = tmp_path / "m.nc"
    assert main(["mechanism", *argv, "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"atlas: error: {name}: ") and err.count("\n") == 1, err
    assert not out.exists() and list(tmp_path.iterdir()) == []


@pytest.mark.parametrize(
    "body, kw, name",
    [
        ("ladder", dict(L=-1.0), "L"),
        ("ladder", dict(theta=np.array([0.3, np.pi / 2])), "theta"),
        ("ladder", dict(mu_wall=-0.1), "mu_wall"),
        ("two_legged", dict(d=-0.2), "d"),
        ("two_legged", dict(h=-0.5), "h"),
        ("two_legged", dict(I=0.0), "I"),
        ("leaning_rod", dict(e=0.6), "e"),
        ("leaning_rod", dict(e=-0.5), "e"),
        ("leaning_rod", dict(theta=0.0), "theta"),
    ],
)
def test_builtin_geometry_is_validated_on_every_path(body, kw, name):
    """The same one-line error from the geometry function, Mechanism and body_invariants."""
    from atlas.core.rigid_body import BODIES, body_invariants

    for build in (
        lambda: BODIES[body](**kw),
        lambda: getattr(Mechanism, body)(**kw),
        lambda: body_invariants(BODIES[body](**kw)),
    ):
        with pytest.raises(ValueError) as err:
            build()
        assert str(err.value).startswith(f"{name}: ") and "\n" not in str(err.value)


def test_fixed_parameters_are_stored_with_units(ladder):
    """Every non-axis parameter of the ladder is in the file with its units (the docstring's
    defaults: L = 4 m, m = 15 kg, I = m L^2 / 12 = 20 kg m^2, k = 1e5 N/m, c = 0, g = 9.81)."""
    want = {"L": (4.0, "m"), "m": (15.0, "kg"), "I": (20.0, "kg m2"), "k1": (1e5, "N m-1")}
    want.update({"k2": (1e5, "N m-1"), "c1": (0.0, "N s m-1"), "c2": (0.0, "N s m-1")})
    want.update({"g": (9.81, "m s-2"), "speed": (0.0, "m s-1"), "s1": (1, "1"), "s2": (1, "1")})
    for k, (value, units) in want.items():
        assert ladder[k].ndim == 0 and float(ladder[k]) == pytest.approx(value, rel=1e-15), k
        assert ladder[k].attrs["units"] == units, k
    assert (
        ladder.attrs["contact2_kind"] == "body_vertex" and "Varkonyi" in ladder.attrs["references"]
    )
    assert (
        "mechanism_atlas('ladder', theta='0.05pi:0.45pi:17', mu='0:2:21'" in ladder.attrs["history"]
    )
    legs = mechanism_atlas("two_legged", h="0.1,0.5", mu="0.3")
    np.testing.assert_allclose(legs.I.values[:, 0], 5.0 * (0.04 + np.array([0.01, 0.25])) / 3)


def test_fixed_values_reach_every_point():
    """``fixed`` (length, damping, a sliding speed: the edge's transport term) gives the
    Mechanism of the same parameters at every point."""
    ds = mechanism_atlas(
        "leaning_rod", theta="0.3,1.1", mu="0.2,1.4", fixed={"L": 2.0, "c1": 20.0, "speed": 0.5}
    )
    assert float(ds.L) == 2.0 and float(ds.speed) == 0.5 and float(ds.c1) == 20.0
    for i, th in enumerate(ds.theta.values):
        for j, mu in enumerate(ds.mu.values):
            body = Mechanism.leaning_rod(
                theta=th, mu_floor=mu, mu_edge=mu, L=2.0, c1=20.0, speed=0.5
            )
            point = ds.isel(theta=i, mu=j)
            assert float(point.omega) == pytest.approx(body.omega, rel=1e-13)
            for k, v in body.invariants.items():
                assert float(point[k]) == pytest.approx(v, rel=1e-12, abs=1e-12), k
            np.testing.assert_allclose([point.a1, point.a2], body.a, rtol=1e-13)


def test_cli_history_and_fixed_errors(tmp_path, capsys):
    """``history`` is the command line with every axis range; a bad fixed value is one line."""
    import xarray as xr

    from atlas.cli import main

    out = tmp_path / "legs.nc"
    argv = ["mechanism", "two_legged", "--mu", "0.5", "--fixed", "d=0.3,k1=2e5", "--out", str(out)]
    assert main(argv) == 0
    with xr.open_dataset(out) as ds:
        hist = ds.attrs["history"]
        assert float(ds.d) == 0.3 and float(ds.k1) == 2e5 and ds.d.attrs["units"] == "m"
    assert hist.endswith(
        f"atlas mechanism two_legged --h 0.05:2:196 --mu 0.5 --fixed d=0.3,k1=2e5 --out {out}"
    )
    for fixed, name in (("d=-0.1", "d"), ("q=1", "fixed"), ("speed=-1", "speed"), ("g=0", "g")):
        bad = tmp_path / "bad.nc"
        assert main(["mechanism", "two_legged", "--fixed", fixed, "--out", str(bad)]) == 2
        err = capsys.readouterr().err
        assert err.startswith(f"atlas: error: {name}: ") and err.count("\n") == 1, err
        assert not bad.exists()


def test_float16_refused():
    with pytest.raises(ValueError, match="^dtype: must be float32 or float64"):
        mechanism_atlas("ladder", theta="0.1:1:3", mu="0:1:3", dtype="float16")


def _over_models_closed_form(beta1, beta2) -> np.ndarray:
    """``ss_over_models`` over the whole model space (closed form of
    :mod:`atlas.core.model_box`), decided exactly on the rounded directions of each body."""
    from fractions import Fraction

    from atlas.core import contact_modes as mech

    out = np.empty(np.shape(beta1), np.int8)
    for idx in np.ndindex(out.shape):
        c1, s1 = (Fraction(float(v)) for v in mech.direction(beta1[idx]))
        c2, s2 = (Fraction(float(v)) for v in mech.direction(beta2[idx]))
        D = c1 * s2 - s1 * c2
        out[idx] = (
            0 if D < 0 or (c1 <= 0 and s2 <= 0) else 1 if c1 > 0 and s2 > 0 and s1 * c2 >= 0 else 2
        )
    return out


def test_mechanism_over_a_model_box():
    """``model_box=``: per body, ``ss_over_models`` over the whole model space equals the exact
    closed form at the body's geometry (the ladder's classes give all three regions); over a
    bounded box every witness model is on its side by the exact tier at that body."""
    from atlas.core import contact_modes as mech
    from atlas.core import exact
    from atlas.core.model_box import WITNESS_NAMES

    kw = dict(theta="0.05pi:0.45pi:9", mu="0:2:9")
    ds = mechanism_atlas("ladder", model_box={}, **kw)
    code = ds["ss_over_models"].values
    b1, b2 = ds["beta1"].values, ds["beta2"].values
    np.testing.assert_array_equal(code, _over_models_closed_form(b1, b2))
    assert set(np.unique(code)) == {0, 1, 2} and ds["ss_over_models"].dims == ("theta", "mu")
    assert ds.attrs["model_box"] == "kappa=0:inf,q1=0:inf,q2=0:inf"
    assert "model_box='kappa=0:inf,q1=0:inf,q2=0:inf'" in ds.attrs["history"]
    box = mechanism_atlas("ladder", model_box="kappa=0.1:10,q=0:1", **kw)
    depends = np.argwhere(box["ss_over_models"].values == 2)
    assert len(depends) > 0 and box.attrs["over_models_undecided"] == 0
    for i, j in depends:
        dirs = [float(v) for a in (b1[i, j], b2[i, j]) for v in mech.direction(a)]
        w = [float(box[n][i, j]) for n in WITNESS_NAMES]
        assert exact.ss_hurwitz(*dirs, *w[:3]) in (1, 2)  # stable or neutral
        assert exact.ss_hurwitz(*dirs, *w[3:]) == 0  # unstable
    assert "ss_over_models" not in mechanism_atlas("ladder", **kw)


def test_cli_mechanism_model_box(tmp_path, capsys):
    """``atlas mechanism --model-box``: written with the box in the history; a bad box is one
    line naming model_box, exit 2, nothing written."""
    import xarray as xr

    from atlas.cli import main

    out = tmp_path / "m.nc"
    argv = ["mechanism", "ladder", "--theta", "0.1pi:0.4pi:3", "--mu", "0:1:3"]
    assert main([*argv, "--model-box", "q=0:1", "--out", str(out)]) == 0
    with xr.open_dataset(out) as ds:
        assert ds.attrs["model_box"] == "kappa=0:inf,q=0:1"
        assert "--model-box kappa=0:inf,q=0:1" in ds.attrs["history"]
        assert ds["ss_over_models"].dtype == np.int8
    capsys.readouterr()
    bad = tmp_path / "bad.nc"
    assert main([*argv, "--model-box", "kappa=-1:2", "--out", str(bad)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("atlas: error: model_box: kappa: ") and err.count("\n") == 1, err
    assert not bad.exists()


def test_api_size_refusal_is_the_cli_one(capsys, monkeypatch):
    """A grid that cannot fit in the memory available (each axis alone fits) is refused by
    ``mechanism_atlas`` with the command line's one line, before any grid is built (a
    1e10-point grid raised numpy's 74.5 GiB ``MemoryError`` from ``meshgrid``)."""
    from atlas.cli import main
    from atlas.data import body_atlas, limits

    monkeypatch.setattr(limits, "available_memory", lambda: 1 << 30)  # 1 GiB free
    axes = dict(theta="0:1.5:30000", mu="0:2:30000")
    assert main(["mechanism", "ladder", "--theta", axes["theta"], "--mu", axes["mu"]]) == 2
    want = capsys.readouterr().err.strip().splitlines()[-1].removeprefix("atlas: error: ")
    assert want.startswith("size: 9e+08 points")
    monkeypatch.setattr(body_atlas.np, "meshgrid", lambda *a, **k: pytest.fail("grid built"))
    with pytest.raises(MemoryError) as err:
        mechanism_atlas("ladder", **axes)
    assert str(err.value) == want
