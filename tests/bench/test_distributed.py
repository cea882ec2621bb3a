"""``atlas.bench.distributed``: the projection's arithmetic, the report, one in-process run."""

import math

import pytest

from atlas.bench import distributed as bd
from atlas.data.scene import Scene


def _run(scheduler, workers, seconds, cpu=1.0):
    return dict(
        scheduler=scheduler, workers=workers, warmup_seconds=3.0, seconds=seconds,
        points=2**21, points_per_second=2**21 / seconds, tiles=8, tile_points=2**18,
        tile_seconds=1.0, tile_cpu_seconds=cpu, write_seconds=0.25,
    )  # fmt: skip


RUNS = [
    _run("in-process", 1, 8.0),
    _run("LocalCluster, 1 worker(s)", 1, 10.0),
    _run("LocalCluster, 2 worker(s)", 2, 6.25),
]


def test_projection_is_rounds_times_the_cost_of_a_tile():
    p = bd._projection(RUNS, 1e11, (2, 16))
    tiles = math.ceil(1e11 / 2**18)  # 381470 tiles of 2**18 points
    assert p["projected_tiles"] == tiles
    assert p["ratio"] == {1: 1.0, 2: pytest.approx(1.6)}
    assert p["per_tile_seconds"] == 1.25
    assert p["projection"][2] == pytest.approx(math.ceil(tiles / 2) * 1.25)
    assert p["projection"][16] == pytest.approx(math.ceil(tiles / 16) * 1.25)


def _report(runs):
    return dict(scene="s", points=2**21, runs=runs, identical=True, machine="m",
                load=((1.0, 1.0, 1.0), (2.0, 1.0, 1.0)), **bd._projection(runs, 1e11, (2, 16)))  # fmt: skip


def test_markdown():
    md = bd.throughput_markdown(_report(RUNS), 1e11)
    assert md.startswith("# Distributed generation: throughput\n")
    assert "from atlas.bench import distributed" in md
    assert "| LocalCluster, 2 worker(s) | 6.2 | 335,544 | 1.60 | 1.00 | 1.00 | 0.25 | 3.0 |" in md
    assert "| in-process | 8.0 | 262,144 |  |" in md
    # 190735 rounds x 1.25 s = 66.2 h (hours below 3 days); 23842 x 1.25 s = 8.3 h
    assert "| 2 | 66.2 h | 66.2 h |" in md and "| 16 | 8.3 h | 8.3 h |" in md
    assert "**Caveat**" not in md
    busy = [RUNS[0], _run("LocalCluster, 1 worker(s)", 1, 10.0, cpu=1.8)]
    assert "about 1.8 cores" in bd.throughput_markdown(_report(busy), 1e11)


def test_in_process_measurement_writes_the_report(tmp_path):
    pytest.importorskip("zarr")
    # undamped: the report does not depend on the model, and the undamped kernels are the ones
    # most other tests compile (a damped model adds the spectral tier's programs)
    scene = Scene(beta1="0.1:6.1:8", beta2="0.05:6.1:4", kappa="0.5,2")
    rep = bd.measure_throughput(tmp_path, scene=scene, workers=(), tile_points=64)
    (run,) = rep["runs"]
    assert run["scheduler"] == "in-process" and run["points"] == 8 * 4 * 2
    assert rep["identical"] and rep["projected_tile_points"] == run["tile_points"]
    assert "| in-process |" in (tmp_path / "distributed.md").read_text()
