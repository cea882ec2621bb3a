"""Throughput of distributed generation (:func:`atlas.data.distributed.generate_distributed`) in
process and on LocalClusters, and its report ``outputs/distributed.md``.

Run it with ``python -c "from atlas.bench import distributed; distributed.measure_throughput()"``.
"""

from __future__ import annotations

import os
import platform
import tempfile
import time

import jax
import numpy as np

from atlas.core.config import use_compile_cache
from atlas.data.cluster import local_cluster, worker_env
from atlas.data.distributed import compute_tile, generate_distributed
from atlas.data.engine import DEFAULT_TILE_POINTS, RunOptions
from atlas.data.io import atomic_write_text
from atlas.data.scene import Scene
from atlas.data.tile_store import read_record
from atlas.data.tiles import tile_plan

__all__ = ["MEASURE_SCENE", "measure_throughput", "throughput_markdown"]

#: the measured scene: 5-D, 2**21 points, grids off the axis directions (no exact resolution)
MEASURE_SCENE = dict(
    beta1="0.1:6.1:256",
    beta2="0.05:6.1:64",
    kappa="log:0.5:2:8",
    q1="log:0.1:1:4",
    q2="log:0.1:1:4",
)


def _warm(scene: Scene, tile, opts: RunOptions) -> float:
    """Compile (or load from the cache) the kernels of one tile; returns the seconds it took."""
    t0 = time.perf_counter()
    compute_tile(scene, tile, opts)
    return time.perf_counter() - t0


def _measure_one(scene, store, scheduler, slab, opts, n_workers) -> dict:
    """One configuration: warm-up (every process computes the first tile), then a timed
    :func:`generate_distributed`; medians of the per-tile timings of the records."""
    tiles = tile_plan(scene, slab)
    t0 = time.perf_counter()
    if scheduler is None:
        _warm(scene, tiles[0], opts)
        client = cluster = None
    else:
        cluster, client = local_cluster(n_workers)
        client.run(_warm, scene, tiles[0], opts)  # every worker compiles before the clock runs
    warm = time.perf_counter() - t0
    try:
        s = generate_distributed(
            scene, store, scheduler=client, slab=slab, overwrite=True, options=opts
        )
    finally:
        if client is not None:
            client.close()
            cluster.close()
    recs = [read_record(store, i) for i in range(s["tiles"])]
    return {
        "scheduler": "in-process" if scheduler is None else f"LocalCluster, {n_workers} worker(s)",
        "workers": n_workers,
        "warmup_seconds": warm,
        "seconds": s["seconds"],
        "points": s["points"],
        "points_per_second": s["points_per_second"],
        "tiles": s["tiles"],
        "tile_points": s["tile_points"][0],
        "tile_seconds": float(np.median(s["tile_seconds"])),
        "tile_cpu_seconds": float(np.median(s["tile_cpu_seconds"])),
        "write_seconds": float(np.median([r["write_seconds"] for r in recs])),
        "checksums": [r["checksums"] for r in recs],
    }


def _projection(runs, projected_points, projected_workers) -> dict:
    """Ratios to one worker and the wall time of ``projected_points`` on N workers: ceil(tiles /
    N) x the per-tile cost (generate + write) of the 1-worker run, wall and CPU."""
    by = {r["workers"]: r for r in runs[1:]}
    base = by.get(1, runs[0])
    per_tile = base["tile_seconds"] + base["write_seconds"]
    per_tile_cpu = base["tile_cpu_seconds"] + base["write_seconds"]
    n_tiles = int(np.ceil(projected_points / base["tile_points"]))
    rounds = {n: int(np.ceil(n_tiles / n)) for n in projected_workers}
    return {
        "ratio": {n: r["points_per_second"] / base["points_per_second"] for n, r in by.items()},
        "per_tile_seconds": per_tile,
        "per_tile_cpu_seconds": per_tile_cpu,
        "projected_tile_points": base["tile_points"],
        "projected_tiles": n_tiles,
        "projection": {n: k * per_tile for n, k in rounds.items()},
        "projection_cpu": {n: k * per_tile_cpu for n, k in rounds.items()},
    }


def measure_throughput(
    out="outputs",
    *,
    scene: Scene | None = None,
    workers=(1, 2),
    slab: int | None = None,
    tile_points: int = DEFAULT_TILE_POINTS,
    projected_points: float = 1e11,
    projected_workers=(2, 16, 128),
) -> dict:
    """Throughput of :func:`generate_distributed` in process and on LocalClusters; writes
    ``OUT/distributed.md`` (nothing if ``out`` is None).

    Every configuration is timed after a warm-up in which each process (this one, or every worker)
    computes the first tile, so compilation is excluded (the persistent compilation cache is shared).
    The per-tile cost of the 1-worker run (worker-side generation + writing the region and the
    record) projects the wall time of ``projected_points`` points on N workers, assuming tiles of
    the measured size and perfect scaling (each worker on its own core, the shared store not a
    bottleneck).

    Returns the numbers of the report (``runs``, ``ratio``, ``projection``).
    """
    use_compile_cache(worker_env().get("JAX_COMPILATION_CACHE_DIR"))
    scene = Scene(**MEASURE_SCENE) if scene is None else scene
    opts = RunOptions(method="certified", dtype="float64", resolve=True, tile_points=tile_points)
    load0 = os.getloadavg()
    runs = []
    with tempfile.TemporaryDirectory(prefix="atlas-measure-") as tmp:
        for n in (0, *workers):
            store = os.path.join(tmp, f"w{n}.zarr")
            runs.append(_measure_one(scene, store, "local" if n else None, slab, opts, max(n, 1)))
    report = {
        "scene": scene.describe(),
        "points": scene.points(),
        "runs": [{k: v for k, v in r.items() if k != "checksums"} for r in runs],
        "identical": all(r["checksums"] == runs[0]["checksums"] for r in runs),
        **_projection(runs, projected_points, projected_workers),
        "machine": f"{platform.node()}: {os.cpu_count()} cores, {platform.machine()}, "
        f"{platform.system()} {platform.release()}, Python {platform.python_version()}",
        "load": (load0, os.getloadavg()),
    }
    if out is not None:
        os.makedirs(out, exist_ok=True)
        path = os.path.join(out, "distributed.md")
        atomic_write_text(path, throughput_markdown(report, projected_points))
    return report


# --------------------------------------------------------------------------- distributed.md


def _hours(seconds: float) -> str:
    if seconds < 3600:
        return f"{seconds / 60:.1f} min"
    if seconds < 3 * 86400:
        return f"{seconds / 3600:.1f} h"
    return f"{seconds / 86400:.1f} days"


def _intro(rep) -> list[str]:
    r0 = rep["runs"][0]
    return [
        "# Distributed generation: throughput",
        "",
        'Generated by `python -c "from atlas.bench import distributed; '
        "distributed.measure_throughput(out='outputs')\"`.",
        "",
        f"* machine: {rep['machine']}; JAX {jax.__version__}.  **The machine is shared** with other "
        f"jobs (load average {rep['load'][0][0]:.1f} before, {rep['load'][1][0]:.1f} after the "
        "measurement), so the numbers are noisy and pessimistic.",
        f"* scene: `{rep['scene']}`, {rep['points']:,} points, {r0['tiles']} tiles of "
        f"{r0['tile_points']:,} points (beta1 slabs), certified method, float64, exact resolution "
        "on.",
        "* each configuration is timed after a warm-up (every process computes one tile first; the "
        "persistent compilation cache is shared), so compilation is excluded.",
        f"* all runs wrote bit-identical tiles (per-tile SHA-256): **{rep['identical']}**.",
        "",
    ]


def _runs_table(rep) -> list[str]:
    lines = [
        "| run | wall [s] | points/s | ratio to 1 worker | per tile: generate [s] | "
        "CPU [s] | write [s] | warm-up [s] |",
        "|---|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for r in rep["runs"]:
        ratio = rep["ratio"].get(r["workers"]) if r["scheduler"] != "in-process" else None
        ratio = "" if ratio is None else f"{ratio:.2f}"
        lines.append(
            f"| {r['scheduler']} | {r['seconds']:.1f} | {r['points_per_second']:,.0f} | {ratio} | "
            f"{r['tile_seconds']:.2f} | {r['tile_cpu_seconds']:.2f} | {r['write_seconds']:.2f} | "
            f"{r['warmup_seconds']:.1f} |"
        )
    lines += [
        "",
        "Per-tile columns are medians over the tiles, measured on the workers (CPU = process "
        "CPU time, all threads).  The in-process run uses XLA's intra-op threads; the workers "
        "run one dask thread each with XLA's Eigen thread pool off, every thread pinned to the "
        "worker's own core (`pin_to_cpus`): XLA splits large fusions over its task pool whatever "
        "the flags say, so unpinned workers used 1.5-1.8 cores each and oversubscribed the "
        "machine (CPU / wall = cores used per worker).",
        "",
    ]
    return lines


def _caveat(rep) -> list[str]:
    """A warning when one worker used clearly more than one core."""
    one = next((r for r in rep["runs"] if r["scheduler"] != "in-process"), None)
    if one is None or one["tile_cpu_seconds"] <= 1.2 * one["tile_seconds"]:
        return []
    return [
        f"**Caveat**: a 1-worker tile took {one['tile_cpu_seconds']:.2f} s of CPU in "
        f"{one['tile_seconds']:.2f} s of wall time, i.e. one worker process still used about "
        f"{one['tile_cpu_seconds'] / one['tile_seconds']:.1f} cores (other threads than the "
        "dask one: pinning failed?).  On this 2-core machine the 1-worker "
        "run therefore already used most of the machine, and the 2-worker ratio understates "
        "how throughput scales with cores; the CPU-time projection below is the per-core "
        "one.",
        "",
    ]


def _projection_section(rep, projected_points) -> list[str]:
    lines = [
        f"## Projection: {projected_points:.0e} points",
        "",
        f"Per-tile cost on one worker (generate + write, 1-worker run): "
        f"**{rep['per_tile_seconds']:.2f} s** wall as measured here, "
        f"{rep['per_tile_cpu_seconds']:.2f} s with CPU time in place of the generation's wall "
        f"time (what a dedicated core would take), for {rep['projected_tile_points']:,} points; "
        f"{projected_points:.0e} points = {rep['projected_tiles']:,} such tiles.  Wall time = "
        "ceil(tiles / N) x per-tile cost, assuming one core per worker, perfect scaling and a "
        "shared file system that keeps up (the 2-worker ratio above is what this shared 2-core "
        "machine achieved; the driver's scheduling overhead per tile is not included).",
        "",
        "| workers N | projected wall time (measured wall per tile) | (CPU per tile) |",
        "|---:|---:|---:|",
    ]
    for n, sec in rep["projection"].items():
        lines.append(f"| {n} | {_hours(sec)} | {_hours(rep['projection_cpu'][n])} |")
    lines += [
        "",
        "Tiles are `beta1` slabs, or `(beta1, beta2)` blocks when one `beta1` value holds more "
        "than 2**18 points, so a 1e11-point scene gets tiles of about the measured size as long "
        "as n_kappa x n_q1 x n_q2 (one `(beta1, beta2)` pair, the smallest tile) is no larger "
        "(see README, *Atlases on a cluster*).",
        "",
    ]
    return lines


def throughput_markdown(rep: dict, projected_points: float) -> str:
    """``distributed.md`` from the report of :func:`measure_throughput`."""
    parts = (
        _intro(rep) + _runs_table(rep) + _caveat(rep) + _projection_section(rep, projected_points)
    )
    return "\n".join(parts)
