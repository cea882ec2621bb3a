"""Tests of the exact event-driven simulator (atlas.simulate) against closed forms, an invariant,
an independent integrator (scipy solve_ivp) and the paper's Fig. 2."""

import math

import numpy as np
import pytest

from atlas.dynamics import model as S

PI = math.pi
CASES = S.fig2_cases()


def _gap_events(t, kinds, contacts, states):
    m = np.array([k in (S.IMPACT, S.LIFTOFF) for k in kinds], dtype=bool)
    return t[m], [k for k, keep in zip(kinds, m, strict=True) if keep], contacts[m], states[m]


# --------------------------------------------------------------------------- closed forms


def test_single_contact_damped_oscillator_closed_form():
    """Contact 1 active, contact 2 far away: d1'' = -b11 k1 d1 - b11 q1 d1' - a1 (paper eq. 7)."""
    beta1, beta2, alpha = 0.1 * PI, 0.3 * PI, 0.25 * PI
    k1, q1 = 100.0, 4.0
    b11 = math.cos(beta1)
    a1 = math.cos(alpha)
    w0 = math.sqrt(b11 * k1)
    zeta = b11 * q1 / (2 * w0)
    wd = w0 * math.sqrt(1 - zeta**2)
    d_eq = -a1 / (b11 * k1)
    x0 = 0.2 * d_eq  # small enough that the force stays positive
    g0 = (d_eq + x0, 1e3, 0.0, 1e3)  # contact 2 far away and leaving
    res = S.simulate(beta1, beta2, alpha, k=(k1, 1.0), q=(q1, 0.0), g0=g0, t_end=3.0)
    assert res.n_events == 0
    assert res.status == S.Status.T_END
    t = np.linspace(0, 3.0, 301)
    x = np.exp(-zeta * w0 * t) * (x0 * np.cos(wd * t) + x0 * zeta * w0 / wd * np.sin(wd * t))
    g = res.sample(t)
    np.testing.assert_allclose(g[:, 0], d_eq + x, rtol=0, atol=1e-13 * abs(d_eq))
    # free gap: d2'' = b21 f1 - a2 integrated by the same closed form, checked at the end
    assert g[-1, 1] > 1e3


def test_free_flight_is_a_parabola():
    """FF: d'' = -a exactly (paper eq. 1 with f = 0)."""
    alpha = 1.2 * PI  # a points into the third quadrant: both gaps accelerate away
    g0 = np.array([0.5, 0.25, 0.1, -0.2])
    res = S.simulate(0.1 * PI, 0.6 * PI, alpha, g0=g0, t_end=5.0, stop_when_settled=False)
    a = np.array([math.cos(alpha), math.sin(alpha)])
    t = np.linspace(0, 5, 11)
    expect = g0[:2] + np.outer(t, g0[2:]) - 0.5 * np.outer(t**2, a)
    g = res.sample(t)
    assert res.n_events == 0
    np.testing.assert_allclose(g[:, :2], expect, rtol=1e-13, atol=1e-14)


def test_modal_energies_conserved_in_undamped_ss_phase():
    """q = 0, SS mode (Fig. 2b, no event): d'' = -B K (d - d*); with B K = V diag(mu) V^-1 every
    modal energy y_j'^2 + mu_j y_j^2, y = V^-1 (d - d*), is an invariant."""
    p = dict(CASES["b"], t_end=20.0)
    res = S.simulate(**p)
    assert res.n_events == 0
    B = np.array(
        [[math.cos(p["beta1"]), math.cos(p["beta2"])], [math.sin(p["beta1"]), math.sin(p["beta2"])]]
    )
    BK = B @ np.diag(p["k"])
    mu, V = np.linalg.eig(BK)
    assert np.all(np.abs(mu.imag) < 1e-12) and np.all(mu.real > 0)
    mu, V = mu.real, V.real
    a = np.array([math.cos(p["alpha"]), math.sin(p["alpha"])])
    d_star = -np.linalg.solve(BK, a)
    g = res.sample(np.linspace(0, 20.0, 2001))
    y = np.linalg.solve(V, (g[:, :2] - d_star).T).T
    yp = np.linalg.solve(V, g[:, 2:].T).T
    energy = yp**2 + mu * y**2
    np.testing.assert_allclose(energy, energy[0] + 0 * energy, rtol=1e-10)


def test_sample_matches_scipy_expm():
    res = S.simulate(**dict(CASES["d"], t_end=5.0))
    import scipy.linalg

    ts = np.linspace(0, 5.0, 37)
    seg = np.searchsorted(res._seg_t, ts, side="right") - 1
    ref = np.array(
        [
            (scipy.linalg.expm(res._system.modes[res._seg_mask[s]].E * (t - res._seg_t[s])))
            @ res._seg_z[s]
            for t, s in zip(ts, seg, strict=True)
        ]
    )[:, :4]
    np.testing.assert_allclose(res.sample(ts), ref, rtol=1e-12, atol=1e-15)


# --------------------------------------------------------------------------- solve_ivp


@pytest.mark.parametrize("name", list("abcde"))
def test_agrees_with_solve_ivp(name):
    """Gap events (impacts, lift-offs) and states agree with DOP853 at rtol 1e-12."""
    p = dict(CASES[name], t_end=10.0)
    res = S.simulate(**p)
    ref = S.simulate_solve_ivp(**p, method="DOP853", rtol=1e-12, atol=1e-15)
    t1, k1, c1, g1 = _gap_events(res.t_events, res.kinds, res.contacts, res.states)
    t2, k2, c2, g2 = _gap_events(ref["t_events"], ref["kinds"], ref["contacts"], ref["states"])
    assert k1 == k2
    np.testing.assert_array_equal(c1, c2)
    np.testing.assert_allclose(t1, t2, rtol=0, atol=1e-9)
    np.testing.assert_allclose(g1, g2, rtol=0, atol=1e-8)
    np.testing.assert_allclose(res.g_final, ref["g_final"], rtol=0, atol=1e-8)


# --------------------------------------------------------------------------- Fig. 2 outcomes


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


def test_fig2a_growing_bouncing():
    # paper Sec. 6.4: "unboundedly growing oscillations, during which both legs repeatedly hit
    # the ground"; the growth is irregular, the amplitude limit (1e4 x scale) is hit by t = 400
    res = S.simulate(**dict(CASES["a"], t_end=400.0))
    assert S.classify(res) == S.Outcome.GROWING_BOUNCING
    assert set(res.contacts[[k == S.IMPACT for k in res.kinds]]) == {1, 2}


def test_fig2b_settles_ss():
    # paper: "the SS mode is stable, which is confirmed by the simulation" (q = 0: neutral)
    res = S.simulate(**dict(CASES["b"], t_end=20.0))
    assert res.n_events == 0
    assert S.classify(res) == S.Outcome.SETTLES_SS


def test_fig2c_growing_bouncing_then_bounded():
    # paper: inverse chattering despite the locally stable SS mode (growing bouncing).  Over
    # t <= 100 the bouncing is still growing (impact speeds); the longer run shows it saturating
    # (impact speeds stay ~6, |d1| ~ 36), i.e. the initial excursion 0.05 grew ~700 times: still
    # growing bouncing (grew and saturated), not a *small* sustained oscillation.
    res = S.simulate(**dict(CASES["c"], t_end=100.0))
    assert S.classify(res) == S.Outcome.GROWING_BOUNCING
    long = S.simulate(**dict(CASES["c"], t_end=1000.0))
    assert S.classify(long) == S.Outcome.GROWING_BOUNCING
    st = S.trajectory_stats(long)
    T = long.t_final
    mid = st.v_imp[(st.t_imp >= T / 3) & (st.t_imp < 2 * T / 3)].max()
    late = st.v_imp[st.t_imp >= 2 * T / 3].max()
    assert late < 1.25 * mid  # saturated: the speed test alone would not call it growing
    assert long.scale == pytest.approx(0.05)
    assert st.late_amplitude.max() > 100 * 0.05  # the amplitude test does


def test_fig2d_sustained_oscillation_single_contact_bouncing():
    # The caption of Fig. 2d ("sustained small amplitude oscillation with repeated impacts")
    # matches the simulation; Sec. 6.5's text (growing, simultaneous impacts) does not: contact 1
    # never lifts off, only contact 2 bounces, with impact speed saturating near 0.1.
    res = S.simulate(**dict(CASES["d"], t_end=100.0))
    assert S.classify(res) == S.Outcome.SUSTAINED_OSCILLATION
    lifts = res.contacts[[k == S.LIFTOFF for k in res.kinds]]
    assert set(lifts.tolist()) == {2}
    # small: gaps stay within a few resting penetrations |a| / (k1 |b1|) = 0.01 (paper eq. 6)
    assert res.scale == pytest.approx(0.01)
    assert S.trajectory_stats(res).late_amplitude.max() < 10 * 0.01


def test_fig2e_growing_bouncing_with_simultaneous_impacts():
    # The caption of Fig. 2e ("resembles inverse chattering, with repeated simultaneous impacts")
    # matches; Sec. 6.5's text (sustained microscopic oscillation) does not.  Each landing of
    # contact 2 is an impact at both contacts: contact 1 (sliding at its SS penetration) is pushed
    # in to > 10x its resting penetration and both contacts lift off within 0.5 time units.
    res = S.simulate(**dict(CASES["e"], t_end=100.0))
    assert S.classify(res) == S.Outcome.GROWING_BOUNCING
    kinds = np.array(res.kinds)
    imp2 = np.flatnonzero((kinds == S.IMPACT) & (res.contacts == 2) & (res.t_events > 20))
    lift1 = res.t_events[(kinds == S.LIFTOFF) & (res.contacts == 1)]
    lift2 = res.t_events[(kinds == S.LIFTOFF) & (res.contacts == 2)]
    assert imp2.size >= 5
    g = res.sample(np.linspace(0, res.t_final, 200_001))
    t = np.linspace(0, res.t_final, 200_001)
    for n in imp2:
        t_imp = res.t_events[n]
        d1_rest = res.states[n, 0]
        assert d1_rest < 0  # contact 1 in contact when contact 2 lands
        l2 = lift2[lift2 > t_imp][0]
        l1 = lift1[lift1 > t_imp][0]
        assert abs(l1 - l2) < 0.5
        window = (t > t_imp) & (t < l2)
        assert g[window, 0].min() < 10 * d1_rest


# --------------------------------------------------------------------------- robustness


@pytest.mark.parametrize("theta", [1.0, 0.5])
def test_no_crossing_skipped_brute_force_scan(theta):
    """Many rapid events (Fig. 2d, ~230 events): every gap sign change seen on a very fine scan of
    the exact trajectory is a recorded impact/lift-off, and vice versa."""
    p = dict(CASES["d"], t_end=60.0)
    res = S.simulate(**p, theta=theta)
    t = np.linspace(0, res.t_final, 600_001)
    d = res.sample(t)[:, :2]
    for i in range(2):
        neg = d[:, i] <= 0
        scan = int(np.count_nonzero(neg[1:] != neg[:-1]))
        recorded = sum(
            1
            for k, c in zip(res.kinds, res.contacts, strict=True)
            if c == i + 1 and k in (S.IMPACT, S.LIFTOFF)
        )
        assert scan == recorded
    assert res.n_events > 100
    # the coarse and the default sub-step give the same event sequence
    ref = S.simulate(**p, theta=0.25)
    assert ref.kinds == res.kinds
    np.testing.assert_allclose(res.t_events, ref.t_events, rtol=0, atol=1e-10)


def test_grazing_double_crossing_inside_one_substep_is_found():
    """A free gap that dips just below 0 within one sub-step: d1(t) = d0 + v t + t^2/2 (a1 = -1)
    with its minimum -1e-9 at t = 0.01.  The first sub-step (0.2) ends with d1 > 0 again, so only
    the extremum test can find the impact at t = 0.01 - sqrt(2e-9)."""
    alpha = PI  # a = (-1, 0): d1'' = +1 in free flight
    tmin, depth = 0.01, 1e-9
    v = -tmin  # d1' = v + t vanishes at tmin
    d0 = 0.5 * tmin**2 - depth
    width = math.sqrt(2 * depth)
    res = S.simulate(
        0.25 * PI, 0.75 * PI, alpha, k=(100.0, 100.0), g0=(d0, 1.0, v, 1.0), t_end=0.05
    )
    kinds = [(k, c) for k, c in zip(res.kinds, res.contacts, strict=True)]
    assert kinds[:1] == [(S.IMPACT, 1)]
    np.testing.assert_allclose(res.t_events[0], tmin - width, rtol=1e-6)


def test_event_cap_returns_status():
    res = S.simulate(**dict(CASES["d"], t_end=1e6), max_events=50)
    assert res.status == S.Status.EVENT_CAP
    assert res.n_events >= 50 and res.n_events <= 52
    assert res.t_final < 1e6


def test_step_cap_returns_status():
    res = S.simulate(**dict(CASES["b"], t_end=1e9), max_steps=1000)
    assert res.status == S.Status.STEP_CAP


def test_iwc_detected_if_mode():
    """IF (paper Sec. 4.3): b11 < 0 and b21 > 0: contact 1 pushed in, force -> +inf."""
    beta1 = 0.6 * PI  # b11 = cos < 0, b21 = sin > 0
    res = S.simulate(
        beta1, 0.25 * PI, 0.3 * PI, k=(1.0, 1.0), g0=(-1e-3, 1.0, -1e-3, 0.5), t_end=200
    )
    assert res.status == S.Status.DIVERGED
    assert S.classify(res) == S.Outcome.IWC
    assert res.mode_final == "SF"


@pytest.mark.parametrize(
    "kwargs, name",
    [
        ({"k": (-1.0, 1.0)}, "k"),
        ({"k": (1.0, 0.0)}, "k"),
        ({"q": (-0.1, 0.0)}, "q"),
        ({"beta1": float("nan")}, "beta1"),
        ({"alpha": float("inf")}, "alpha"),
        ({"g0": (0.0, float("nan"), 0.0, 0.0)}, "g0"),
        ({"b_norm": (0.0, 1.0)}, "b_norm"),
        ({"t_end": -1.0}, "t_end"),
        ({"max_events": 0}, "max_events"),
    ],
)
def test_bad_input_raises_naming_parameter(kwargs, name):
    args = dict(beta1=0.1, beta2=2.0, alpha=0.5)
    args.update(kwargs)
    with pytest.raises(ValueError, match=name):
        S.simulate(**args)


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
        assert "outcome_map" in back.attrs["history"]
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
        assert ds.sizes == {"beta1": 2, "beta2": 2}
        assert ds.attrs["q1"] == 0.1 and ds.attrs["kappa"] == 0.5
    assert main(["simulate", "--map", "--out", str(tmp_path / "m.txt")]) != 0


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
