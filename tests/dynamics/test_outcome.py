"""Subclasses without a stable mode, outcome grids and maps (atlas.dynamics.outcome), the
``atlas simulate --map`` command and the Fig. 2 / outcome-map files written from them."""

import math
import os

import numpy as np
import pytest

from atlas import dynamics as S

PI = math.pi
CASES = S.fig2_cases()


# --------------------------------------------------------------------------- subclasses


def test_subclass_codes_of_fig2_points():
    # paper, Fig. 2 caption: a and b are points of subclass 132; Sec. 6.5: d, e in 142/143
    for name, code in (("a", 132), ("b", 132), ("c", 132), ("d", 142), ("e", 142)):
        p = CASES[name]
        assert S.subclass_codes(p["beta1"], p["beta2"], p["alpha"]) == code
        assert S.no_stable_subclass(p["beta1"], p["beta2"], p["alpha"])


def test_no_stable_subclass_includes_duals():
    # the dual of (beta1, beta2, alpha) is (pi/2 - beta2, pi/2 - beta1, pi/2 - alpha) (SPEC §1)
    p = CASES["a"]
    dual = (0.5 * PI - p["beta2"], 0.5 * PI - p["beta1"], 0.5 * PI - p["alpha"])
    assert S.subclass_codes(*dual) not in S.NO_STABLE_SUBCLASSES
    assert S.no_stable_subclass(*dual)
    # beta1 < pi/2 (i = 1), beta1 < beta2 < pi/2 (j = 2), alpha above both (k = 3): 123, whose
    # dual (pi/2 - 0.2, pi/2 - 0.1, pi/2 - 0.3) is again i = 1, j = 2, k = 1: 121; neither listed
    assert S.subclass_codes(0.1, 0.2, 0.3) == 123
    assert S.subclass_codes(0.5 * PI - 0.2, 0.5 * PI - 0.1, 0.5 * PI - 0.3) == 121
    assert not S.no_stable_subclass(0.1, 0.2, 0.3)


# --------------------------------------------------------------------------- outcome maps


def test_outcome_grid_avoids_degenerate_points():
    pts = []
    for n in (1, 2, 3, 4, 6, 9):
        b1, b2 = S.outcome_grid(n)
        B1, B2 = np.meshgrid(b1, b2, indexing="ij")
        for x in (b1, b2):
            assert np.min(np.abs(np.remainder(x / (PI / 2) + 0.5, 1.0) - 0.5)) > 0.1 / n
        dif = np.remainder((B2 - B1) / PI + 0.5, 1.0) - 0.5
        assert np.min(np.abs(dif)) > 0.1 / n
        pts.append(np.stack([B1.ravel(), B2.ravel()]))
    B1, B2 = np.concatenate(pts, axis=1)
    codes = S.subclass_codes(B1, B2, np.full(B1.shape, 0.35 * PI + 1e-3))
    assert np.all(codes > 0)  # no tie, nothing undecided


def test_outcome_map_3x3_decides_every_pixel():
    """Reviewer: 4 of 9 pixels of a 3x3 map were undetermined (short runs)."""
    b1, b2 = S.outcome_grid(3)
    ds = S.outcome_map(b1, b2)
    assert int(S.Outcome.UNDETERMINED) not in ds["outcome"].values


def test_horizon_extension_decides_a_run_with_long_flights():
    """Few impacts in t <= 150 (long flights): undetermined; simulate_outcome doubles t_end and
    gets the same verdict as a single run over the final horizon."""
    x1, x2, alpha = 0.143 * PI, 1.0 * PI, 0.35 * PI
    g0 = S.perturbed_initial_states([x1], [x2], alpha, 0.5)[0, 0, 0]
    kw = dict(k=(0.5, 1.0), g0=g0)
    short = S.simulate(x1, x2, alpha, t_end=150.0, **kw)
    assert S.classify(short) == S.Outcome.UNDETERMINED and short.status == S.Status.T_END
    out, res = S.simulate_outcome(x1, x2, alpha, t_end=150.0, **kw)
    assert out != S.Outcome.UNDETERMINED
    assert res.n_events > short.n_events
    horizon = 150.0 * 2 ** round(math.log2(max(res.t_final, 150.0) / 150.0 + 1e-9))
    direct = S.simulate(x1, x2, alpha, t_end=max(horizon, res.t_final), **kw)
    assert S.classify(direct) == out


def test_damped_map_settles_where_ss_is_stable():
    """q = 0.5: where SS is consistent (f* = B^-1 a > 0, SPEC §1) and max Re eig M < -0.02
    (paper eq. 8, plain eigenvalues), a 1 % perturbation must settle to SS."""
    b1, b2 = S.outcome_grid(6)
    kappa, q, alpha = 0.5, 0.5, 0.35 * PI
    ds = S.outcome_map(b1, b2, kappa=kappa, q=q, alpha=alpha, t_end=100.0)
    n_checked = 0
    for i, x1 in enumerate(b1):
        for j, x2 in enumerate(b2):
            B = np.array([[math.cos(x1), math.cos(x2)], [math.sin(x1), math.sin(x2)]])
            f = np.linalg.solve(B, [math.cos(alpha), math.sin(alpha)])
            M = np.block([[np.zeros((2, 2)), np.eye(2)], [-B @ np.diag([kappa, 1.0]), -q * B]])
            if np.all(f > 0) and np.linalg.eigvals(M).real.max() < -0.02:
                n_checked += 1
                assert ds["outcome"].values[i, j] == S.Outcome.SETTLES_SS, (x1, x2)
    assert n_checked >= 2


def test_outcome_map_dataset_contract(tmp_path):
    import xarray as xr

    from atlas.paper.figures_dynamics import write_outcome_map

    b1 = np.array([0.05, 0.2]) * PI
    b2 = np.array([0.65, 0.9]) * PI
    ds = S.outcome_map(b1, b2, kappa=0.5, q=0.0, n_perturb=2, seed=1, t_end=60.0)
    assert ds["outcome"].dtype == np.int8
    assert ds["outcome"].dims == ("beta1", "beta2")
    assert ds["beta1"].attrs["units"] == "rad" and ds["beta2"].attrs["units"] == "rad"
    meanings = ds["outcome"].attrs["flag_meanings"].split()
    assert meanings == [o.label for o in S.Outcome]
    np.testing.assert_array_equal(ds["outcome"].attrs["flag_values"], [int(o) for o in S.Outcome])
    assert "_FillValue" not in ds["outcome"].attrs
    assert set(np.unique(ds["outcome"].values)) <= {int(o) for o in S.Outcome}
    # same seed, same map
    ds2 = S.outcome_map(b1, b2, kappa=0.5, q=0.0, n_perturb=2, seed=1, t_end=60.0)
    np.testing.assert_array_equal(ds["outcome"].values, ds2["outcome"].values)
    with pytest.raises(ValueError, match="kappa"):
        S.outcome_map(b1, b2, kappa=float("nan"))
    # netCDF: written atomically, int8 flags without _FillValue, CF attributes
    path = tmp_path / "map.nc"
    write_outcome_map(ds, path)
    assert [p.name for p in tmp_path.iterdir()] == ["map.nc"]
    with xr.open_dataset(path) as back:
        assert back["outcome"].dtype == np.int8
        assert "_FillValue" not in back["outcome"].encoding or (
            back["outcome"].encoding["_FillValue"] is None
        )
        np.testing.assert_array_equal(back["outcome"].values, ds["outcome"].values)
        np.testing.assert_array_equal(back["no_stable_subclass"], ds["no_stable_subclass"])
        assert back.attrs["Conventions"].startswith("CF-")
        assert "outcome_atlas" in back.attrs["history"]
    import netCDF4

    with netCDF4.Dataset(path) as nc:
        assert "_FillValue" not in nc["outcome"].ncattrs()
        assert nc["outcome"].dtype == np.int8


def test_cli_simulate_map_writes_netcdf(tmp_path, capsys):
    import xarray as xr

    from atlas.cli import main

    path = tmp_path / "m.nc"
    assert main(["simulate", "--map", "--n", "2", "--q", "0.1", "--out", str(path)]) == 0
    assert "outcome map 2x2" in capsys.readouterr().out
    with xr.open_dataset(path) as ds:
        assert ds.sizes == {"beta1": 2, "beta2": 2, "outcome_class": len(S.Outcome)}
        assert ds.attrs["q1"] == 0.1 and ds.attrs["kappa"] == 0.5
        assert ds.attrs["engine"] == "fast"  # the default engine
        assert ds.attrs["history"].split(": ", 1)[1].startswith("atlas simulate --map --n 2")
        assert "stable_SS" in ds and "subclass_code" in ds  # the theory beside the outcomes
    assert main(["simulate", "--map", "--out", str(tmp_path / "m.txt")]) != 0


def test_cli_simulate_map_axes_of_generate(tmp_path, capsys):
    """The axes take the ranges of atlas generate; --dry-run counts trajectories over every
    axis; --store tiles, --resume continues; bad input: one line naming the parameter, exit 2,
    nothing written."""
    import xarray as xr

    from atlas.cli import main

    axes = ["--beta1", "0.1:3:3", "--beta2", "0.65pi", "--q1", "0,1", "--q2", "0.5", "--no-theory"]
    argv = ["simulate", "--map", *axes, "--n-perturb", "2", "--t-end", "40"]
    assert main([*argv, "--dry-run"]) == 0
    assert "atlas simulate --map: 12 points" in capsys.readouterr().out
    store, path = tmp_path / "m.tiles", tmp_path / "m.nc"
    assert main([*argv, "--store", str(store), "--slab", "2", "--out", str(path)]) == 0
    with xr.open_dataset(path) as ds:
        assert ds["outcome_count"].dims == ("beta1", "q1", "outcome_class")  # scalars: no dim
        assert ds.sizes["beta1"] == 3 and ds.sizes["q1"] == 2
        assert np.all(ds["outcome_count"].sum("outcome_class") == 2)
        first = ds["outcome_count"].values
    os.remove(store / "t000001.npy")
    again = [*argv, "--store", str(store), "--slab", "2", "--resume", "--overwrite"]
    assert main([*again, "--out", str(path)]) == 0
    assert "1 computed, 1 verified" in capsys.readouterr().err
    with xr.open_dataset(path) as ds:
        np.testing.assert_array_equal(ds["outcome_count"].values, first)
    for bad, name in (
        (["--beta1", "nope"], "beta1"),
        (["--kappa", "0"], "kappa"),
        (["--seed", "-1"], "seed"),
        (["--resume"], "resume"),
        (["--k1", "3"], "k1"),
        (["--kappa", "0.5,2", "--out", str(tmp_path / "f.png")], "out"),
        (["--workers", "0"], "workers"),
        (["--workers", "2", "--store", str(tmp_path / "s"), "--scheduler", "local:1"], "workers"),
    ):
        out = tmp_path / "bad.nc"
        rc = main(["simulate", "--map", "--n", "2", "--out", str(out), *bad])
        err = capsys.readouterr().err.strip()
        assert rc == 2 and err.startswith(f"atlas: error: {name}: ") and "\n" not in err, err
        assert not out.exists() and not (tmp_path / "f.png").exists()


def test_cli_simulate_map_several_initial_conditions(tmp_path, capsys):
    """--n-perturb runs per cell: the netCDF records the fraction of runs giving the outcome; the
    fast engine's outcomes equal the exact simulator's (--engine numpy) on the same runs."""
    import xarray as xr

    from atlas.cli import main

    for engine in ("fast", "numpy"):
        argv = ["simulate", "--map", "--n", "3", "--n-perturb", "3", "--engine", engine]
        assert main([*argv, "--out", str(tmp_path / f"{engine}.nc")]) == 0
    with (
        xr.open_dataset(tmp_path / "fast.nc") as fast,
        xr.open_dataset(tmp_path / "numpy.nc") as ref,
    ):
        assert fast.attrs["n_perturb"] == 3 and fast.attrs["trajectories"] == 27
        assert np.array_equal(fast["outcome"].values, ref["outcome"].values)
        assert np.array_equal(fast["agreement"].values, ref["agreement"].values)
    bad = tmp_path / "bad.nc"
    assert main(["simulate", "--map", "--n", "2", "--n-perturb", "0", "--out", str(bad)]) == 2
    assert not bad.exists()


@pytest.mark.slow
def test_outcome_map_files_beside_theory(tmp_path):
    from atlas.paper import figures
    from atlas.paper.figures_dynamics import outcome_map_files

    theory = figures.stability_map(31, 0.5, 0.0, 0.0)
    files = outcome_map_files(tmp_path, n=3, theory=theory)
    assert [f.name for f in files] == ["outcome_map.nc", "outcome_map.png"]
    assert all(f.stat().st_size > 0 for f in files)
    with pytest.raises(ValueError, match="theory"):
        outcome_map_files(tmp_path, n=2, theory=theory, kappa=2.0)


def test_fig2_table_states_the_simulated_outcomes(tmp_path):
    """``plot_fig2`` writes the panel outcomes beside what the paper says (caption and text
    disagree on d and e; the expected labels are the paper's caption, which the simulation
    confirms: see the Fig. 2 outcome tests above)."""
    from atlas.paper.figures_dynamics import plot_fig2

    plot_fig2(tmp_path, n_samples=200)
    rows = {
        line.split("|")[1].strip(): line
        for line in (tmp_path / "fig2.md").read_text().splitlines()
        if line.startswith("| ") and not line.startswith("| panel")
    }
    expect = dict(
        a="growing_bouncing",
        b="settles_SS",
        c="growing_bouncing",
        d="sustained_oscillation",
        e="growing_bouncing",
    )
    for panel, label in expect.items():
        assert f"**{label}**" in rows[panel], rows[panel]
    assert "caption:" in rows["d"] and "text:" in rows["e"]
