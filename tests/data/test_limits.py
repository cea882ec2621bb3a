"""Size estimates: output bytes equal what an atlas holds, a 1e14-point scene is refused at once
(memory, disk) with one line naming the numbers, and its tile plan is never materialised."""

import pytest
from work_count import counted

from atlas.data import limits
from atlas.data.engine import generate
from atlas.data.over_models import as_model_box
from atlas.data.scene import Scene
from atlas.data.tiles import TilePlan, tile_plan

HUGE = dict(beta1="0:2pi:10000000", beta2="0:2pi:10000000")


@pytest.mark.parametrize("dtype", ["float32", "float64"])
def test_output_bytes_equal_the_atlas(dtype):
    scene = Scene(beta1="0:2pi:8", beta2="0:2pi:6", alpha="0:2pi:3", kappa="0.5,2", q="0,1")
    ds = generate(scene, dtype=dtype, resolve=False)
    est = limits.generate_estimate(scene, dtype=dtype)
    assert est.points == 8 * 6 * 2 * 2
    assert est.output_bytes == sum(v.nbytes for v in ds.data_vars.values())


def test_output_bytes_count_the_verdicts_over_a_model_box():
    """With a model box the estimate holds the box's codes and witnesses too (SPEC §2: three
    int8 codes and 18 float64 witness parameters per (beta1, beta2) point), and they are what the
    atlas holds."""
    scene = Scene(beta1="0:2pi:4", beta2="0:2pi:3", kappa="0.5,2", q="0.1")
    ds = generate(scene, resolve=False, model_box="kappa=0.5:2,q=0.1:1")
    plain = limits.generate_estimate(scene)
    est = limits.generate_estimate(scene, model_box=as_model_box("kappa=0.5:2,q=0.1:1"))
    assert est.output_bytes - plain.output_bytes == 4 * 3 * (3 * 1 + 18 * 8)
    assert est.output_bytes == sum(v.nbytes for v in ds.data_vars.values())
    assert est.peak_bytes - plain.peak_bytes == 4 * 3 * (3 * 1 + 18 * 8)
    # ``seconds`` here is the estimate's model (limits.BOX_NS_PER_GEOMETRY), not a clock reading
    assert est.seconds > plain.seconds + 4 * 3 * 1e-3  # the II verdicts: ms per geometry
    whole = limits.generate_estimate(scene, model_box=as_model_box({}))  # nothing to settle
    assert whole.output_bytes == est.output_bytes and plain.seconds < whole.seconds < est.seconds


def test_huge_scene_refused_at_once(tmp_path, monkeypatch):
    """The estimate and its refusal do no work beyond parsing the scene: no function of the
    modules that compute is called and under 1 MB is allocated."""
    scene = Scene(**HUGE, kappa="0.5,2", outputs="stable_SS,model_dependent_SS")
    with counted() as work:
        est = limits.generate_estimate(scene, outputs=[tmp_path / "a.nc"])
        assert 1e14 <= est.peak_bytes < 1.01e14  # the model_dependent_SS accumulator: 1 B/pair
        with pytest.raises(MemoryError, match=r"^size: 2e\+14 points need ~9\d\.\d TiB of memory"):
            est.check()
    assert not work.calls and not work.jax and work.peak_bytes < 1 << 20, work
    # the disk: 1e14 int8 values of stable_SS (uncompressed) to a 1 GiB file system
    monkeypatch.setattr(limits, "free_disk", lambda path: 1 << 30)
    est = limits.generate_estimate(
        Scene(**HUGE, outputs="stable_SS"), distributed=True, outputs=[tmp_path / "a.zarr"]
    )
    with pytest.raises(OSError, match=r"^size: 1e\+14 points write ~90\.9 TiB .* 1\.0 GiB free"):
        est.check()
    assert "1e+14 points" in est.describe()


def test_tile_plan_is_lazy():
    scene = Scene(**HUGE, outputs="stable_SS")
    with counted() as work:
        plan = tile_plan(scene)
    assert isinstance(plan, TilePlan) and work.peak_bytes < 1 << 16, work  # not ~1e8 tiles
    per = -(-(10**7) // plan.block2) if plan.block2 else 1
    assert len(plan) == -(-(10**7) // plan.slab) * per
    assert plan[-1][1] == 10**7 and plan[0][0] == 0
    small = TilePlan(5, 7, 2, 3)
    want = [(a, min(a + 2, 5), c, min(c + 3, 7)) for a in range(0, 5, 2) for c in range(0, 7, 3)]
    assert list(small) == want and small == want and small[1:3] == want[1:3]
    assert TilePlan.of(small.describe()) == small


def test_outcome_estimate_counts_every_axis_and_the_theory():
    """Points = trajectories over every axis x n_perturb; the bytes written are those of the
    outcome variables (8 int16 counts, int8 outcome, float32 agreement, the subclass flag per
    cell) plus the theory verdicts of the scene; tiles bound the trajectories held at once."""
    scene = Scene(beta1="0:2pi:8", beta2="0:2pi:6", alpha="0.1,0.2,0.3", kappa="0.5,2", q=0.5)
    cells = 8 * 6 * 3 * 2
    est = limits.outcome_estimate(scene, 5, theory=False)
    assert est.points == cells * 5 and est.command == "simulate --map"
    assert est.output_bytes == cells * (8 * 2 + 1 + 4 + 1)
    both = limits.outcome_estimate(scene, 5)
    assert both.output_bytes == est.output_bytes + limits.generate_estimate(scene).output_bytes
    tiled = limits.outcome_estimate(scene, 5, theory=False, tile_runs=10)
    assert tiled.peak_bytes == est.peak_bytes - (cells * 5 - 10) * limits.OUTCOME_TRAJECTORY_BYTES
    slow = limits.outcome_estimate(scene, 5, theory=False, engine="numpy")
    assert slow.seconds > 10 * est.seconds


def test_outcome_estimate_grows_with_the_horizon():
    """A run's time is proportional to its horizon ``t_end`` (the exact simulator's sub-steps):
    the default horizon is ``Dynamics``' own, and 1e4 costs 1e4 / 150 times as much (it was the
    same 0.0064 s whatever ``t_end``)."""
    from atlas.dynamics.outcomes import Dynamics

    scene = Scene(beta1="0:2pi:8", beta2="0:2pi:8", kappa=2, q=0.5)
    base = limits.outcome_estimate(scene, 1, theory=False)
    assert limits.OUTCOME_T_END == Dynamics().t_end == 150.0
    for t_end in (15.0, 150.0, 1e4):
        est = limits.outcome_estimate(scene, 1, theory=False, t_end=t_end)
        assert est.seconds == pytest.approx(base.seconds * t_end / 150.0, rel=1e-12)


@pytest.mark.slow
def test_boundaries_estimate_against_the_bytes_written(tmp_path):
    """``atlas boundaries``' estimate of one output file against the files it writes for a model
    other than the one the constants were measured at (kappa 2, q 0.1): it covers the largest
    and is within 2x of it (it was 8 bytes per point: 2 KiB for ~1 MB here)."""
    from atlas.data.boundaries import boundaries

    scene = Scene(beta1="0:2pi:24", beta2="0:2pi:24", kappa="0.5", q="0.3")
    b = boundaries(scene)
    sizes = []
    for ext, write in (("nc", b.to_netcdf), ("csv", b.to_csv), ("json", b.to_geojson)):
        write(tmp_path / f"b.{ext}")
        sizes.append((tmp_path / f"b.{ext}").stat().st_size)
    est = limits.boundaries_estimate(24, 24, 2, 1)
    assert max(sizes) <= est.output_bytes <= 2 * max(sizes), (sizes, est.output_bytes)
