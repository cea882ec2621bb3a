"""Outcome atlases (atlas.dynamics.outcomes): the CF dataset, the outcome distribution per cell,
the lanes of a multi-model atlas, the theory verdicts beside the outcomes, bad input."""

import math

import numpy as np
import pytest

from atlas import dynamics as D
from atlas.dynamics import outcomes as O

PI = math.pi


@pytest.fixture(scope="module")
def atlas4():
    """beta1 x beta2 x kappa x q (2 x 2 x 2 x 2 cells), 3 runs each, with the theory verdicts."""
    scene = O.outcome_scene("0.05pi,0.2pi", "0.65pi,0.9pi", kappa="0.5,2", q="0,0.5")
    return scene, O.outcome_atlas(scene, n_perturb=3, t_end=60.0)


def test_dataset_schema_and_cf_attributes(atlas4):
    from atlas.data.outputs import coord_attrs

    scene, ds = atlas4
    assert ds["outcome"].dims == ("beta1", "beta2", "kappa", "q")
    assert ds["outcome_count"].dims == ("beta1", "beta2", "kappa", "q", "outcome_class")
    assert ds["outcome"].dtype == np.int8 and ds["outcome_count"].dtype == np.int16
    assert ds["agreement"].dtype == np.float32 and ds["agreement"].attrs["units"] == "1"
    assert ds["no_stable_subclass"].dims == ("beta1", "beta2")  # alpha fixed
    codes = [int(o) for o in D.Outcome]
    for var in (ds["outcome"], ds["outcome_class"]):
        np.testing.assert_array_equal(var.attrs["flag_values"], codes)
        assert var.attrs["flag_meanings"].split() == [o.label for o in D.Outcome]
    np.testing.assert_array_equal(ds["outcome_class"].values, codes)
    for name in ("beta1", "beta2", "alpha", "kappa", "q"):
        assert ds[name].attrs == coord_attrs(name)
    assert ds["alpha"].ndim == 0 and ds.attrs["alpha"] == pytest.approx(0.35 * PI)
    assert ds.attrs["Conventions"] == "CF-1.10"
    assert ds.attrs["history"].endswith(")") and "outcome_atlas(" in ds.attrs["history"]
    assert ds.attrs["source"].startswith("painleve-atlas")
    assert ds.attrs["n_perturb"] == 3 and ds.attrs["trajectories"] == 16 * 3
    assert sum(ds.attrs[f"runs_{k}"] for k in D.fast_engine.DECIDED_BY) == 16 * 3
    assert ds.attrs["runs_within_rounding"] == 0


@pytest.mark.parametrize("engine", ["fast", "numpy"])
def test_runs_within_rounding_are_counted_by_every_engine(engine):
    """Row beta1 = pi of a 0:2pi:8 grid (kappa 0.1, q 0.05, alpha 0.3pi): at beta2 = 0 the SS
    'equilibrium' of ``det B = -1.2e-16`` starts a run that diverges with its free gap a rounding
    residue of the state (stop_rule.within_rounding): one run flagged, by either engine, with
    the same counts."""
    scene = O.outcome_scene("0:2pi:8", "0:2pi:8", alpha="0.3pi", kappa=0.1, q=0.05)
    counts, info = O.outcome_slab(scene, range(4, 5), O.Dynamics(engine=engine))
    assert info["runs_within_rounding"] == 1
    fast, _ = O.outcome_slab(scene, range(4, 5), O.Dynamics())
    np.testing.assert_array_equal(counts, fast)


def test_distribution_counts_sum_to_n_perturb(atlas4):
    _, ds = atlas4
    counts = ds["outcome_count"].values
    assert np.all(counts.sum(axis=-1) == 3)
    # majority: the most frequent class, ties to the smallest code (first maximum)
    best = counts.max(axis=-1)
    first = np.argmax(counts == best[..., None], axis=-1)
    np.testing.assert_array_equal(ds["outcome"].values, ds["outcome_class"].values[first])
    np.testing.assert_array_equal(ds["agreement"].values, (best / 3).astype(np.float32))


def test_theory_verdicts_equal_a_direct_generate(atlas4):
    """The verdicts beside the outcomes are those of atlas.generate over the same cells, asked
    independently here (a scene written out by hand, not the atlas's own)."""
    import atlas

    _, ds = atlas4
    ref = atlas.generate(
        atlas.Scene(
            beta1=np.array([0.05, 0.2]) * PI,
            beta2=np.array([0.65, 0.9]) * PI,
            alpha=0.35 * PI,
            kappa=[0.5, 2.0],
            q=[0.0, 0.5],
        )
    )
    assert set(ref.data_vars) <= set(ds.data_vars)
    for name in ref.data_vars:
        assert ds[name].dims == ref[name].dims, name
        np.testing.assert_array_equal(ds[name].values, ref[name].values, err_msg=name)
        assert ds[name].attrs["long_name"] == ref[name].attrs["long_name"]
    # paper, Fig. 2 caption: (0.05 pi, 0.65 pi) and (0.2 pi, 0.65 pi) at alpha 0.35 pi are 132
    assert ds["subclass_code"].values[0, 0] == 132 and ds["subclass_code"].values[1, 0] == 132


def test_each_lane_runs_its_own_cell(atlas4):
    """Every run of two cells of the 4-D atlas, re-run here by the exact simulator with the
    cell's own (kappa, q) and initial state: the counts are those outcomes."""
    scene, ds = atlas4
    b1 = scene.axes["beta1"].values
    b2 = scene.axes["beta2"].values
    xi = D.standard_normals(0, range(2), 2, 3)
    for i, j, k, m in ((0, 1, 1, 0), (1, 0, 0, 1)):
        kappa, q = (0.5, 2.0)[k], (0.0, 0.5)[m]
        g0 = D.initial_states(b1[i], b2[j], 0.35 * PI, kappa, xi[i, j])
        got = np.zeros(len(D.Outcome), int)
        for r in range(3):
            out, _ = D.simulate_outcome(
                b1[i], b2[j], 0.35 * PI, k=(kappa, 1.0), q=(q, q), g0=g0[r], t_end=60.0
            )
            got[int(out)] += 1
        np.testing.assert_array_equal(ds["outcome_count"].values[i, j, k, m], got)


def test_standard_normals_of_any_rows_equal_the_whole_draw():
    whole = D.standard_normals(7, range(5), 3, 2)
    np.testing.assert_array_equal(D.standard_normals(7, range(2, 4), 3, 2), whole[2:4])
    rng = np.random.default_rng(7)  # one stream in the order (beta1, beta2, run, component)
    np.testing.assert_array_equal(whole, rng.standard_normal((5, 3, 2, 4)))


@pytest.mark.parametrize(
    "kw, name",
    [
        (dict(n_perturb=0), "n_perturb"),
        (dict(n_perturb=2.5), "n_perturb"),
        (dict(n_perturb=40000), "n_perturb"),
        (dict(seed=-1), "seed"),
        (dict(seed=2**32), "seed"),  # numpy's seed range
        (dict(seed=10**23), "seed"),
        (dict(t_end=1e300), "t_end"),  # never ends (the simulator's sub-steps)
        (dict(t_end=1.0001e4), "t_end"),
        (dict(max_events=1.5), "max_events"),
        (dict(t_end=0.0), "t_end"),
        (dict(t_end=float("nan")), "t_end"),
        (dict(horizon_cap=0.5), "horizon_cap"),
        (dict(engine="gpu"), "engine"),
    ],
)
def test_bad_options_one_line_naming_the_parameter(kw, name):
    with pytest.raises(ValueError, match=f"^{name}: ") as e:
        O.Dynamics(**kw)
    assert "\n" not in str(e.value)


def test_bad_scene_one_line():
    import atlas

    with pytest.raises(ValueError, match="^alpha: "):
        O.outcome_atlas(atlas.Scene(beta1="0.1,0.2", beta2="1,2"))
    with pytest.raises(ValueError, match="^kappa: "):
        O.outcome_scene("0.1,0.2", "1,2", kappa="-1")
    with pytest.raises(ValueError, match="^slab: "):
        O.outcome_atlas(O.outcome_scene("0.1,0.2", "1,2"), slab=0)
    with pytest.raises(ValueError, match="^scene: "):
        O.outcome_atlas("fig1")


@pytest.mark.parametrize(
    "call, name",
    [
        (lambda: O.outcome_atlas(O.outcome_scene("0.1", "0.2"), theory="no"), "theory"),
        (lambda: O.outcome_map([0.1], [0.2], q=True), "q"),
        (lambda: O.outcome_map([1 + 2j], [0.2]), "beta1_values"),
        (lambda: O.outcome_map(["a"], [0.2]), "beta1_values"),
        (lambda: O.outcome_map([0.1], [0.2], q=(0.1, 0.2, 0.3)), "q"),
        (lambda: O.outcome_map([0.1], [0.2], kappa=True), "kappa"),
    ],
)
def test_api_values_refused_naming_the_parameter(call, name):
    with pytest.raises(ValueError, match=f"^{name}: ") as e:
        call()
    assert "\n" not in str(e.value)


def test_a_1e14_value_axis_is_a_size_refusal():
    with pytest.raises(MemoryError, match="^size: beta1 has 1e\\+14 values"):
        O.outcome_scene("0:2pi:100000000000000", "0.2")
