"""What a run will cost, known before it starts: points, output bytes, peak memory, time.

Every writing command of ``atlas`` builds an :class:`Estimate` from its scene alone (no kernel
runs, no arrays of the scene's size), prints it with ``--dry-run``, and :meth:`Estimate.check`
refuses a run that cannot fit -- peak memory above the memory available now, output bytes above
the free space at the destination -- with one line naming the numbers and the way out.

The figures are estimates, not bounds: bytes per point measured on this code (peak RSS of
small runs, minus the interpreter and JAX runtime), times from the throughput in
``outputs/bench.md``.  Output sizes are *uncompressed*: netCDF files are zlib-compressed (flags
several-fold smaller), so ``--no-size-check`` runs a scene whose uncompressed size exceeds the
free space anyway.  A refused scene costs microseconds: nothing proportional to its points is
allocated (the tile plans of :mod:`atlas.data.distributed` are lazy too).
"""

from __future__ import annotations

import dataclasses
import math
import os
import shutil

from atlas.data.outputs import OUTPUTS, storage_dtype
from atlas.data.tiles import DEFAULT_SLAB_POINTS

__all__ = [
    "Estimate",
    "available_memory",
    "free_disk",
    "human_bytes",
    "generate_estimate",
    "grid_estimate",
    "boundaries_estimate",
    "outcome_estimate",
    "NS_PER_POINT",
]

#: rough single-core cost of the certified atlas kernels per point and output group [ns]
#: (outputs/bench.md: ~13 ns float32, ~21 ns float64 for all verdicts of a damped grid)
NS_PER_POINT = {"float32": 15.0, "float64": 25.0}
#: rough single-core cost of the verdicts over a box of models per (beta1, beta2) point [ns]:
#: SS ~16 us (outputs/bench.md, model-dependence map); II ~13 ms over a bounded box whose open
#: cells are settled, ~76 us over a box with an unbounded axis (361^2 first call; 6 us warm)
BOX_NS_PER_GEOMETRY = {"ss": 2.0e4, "ii bounded": 2.0e7, "ii unbounded": 1.0e5}
#: working bytes per point of a kernel tile (inputs, padded results, exact-tier bookkeeping)
TILE_BYTES_PER_POINT = 160
#: bytes per stored value a zarr tile holds at peak (the tile, its read-back copy, checksums)
STORE_PEAK_FACTOR = 4


def human_bytes(n: float) -> str:
    """``n`` bytes as ``"12.3 GiB"``."""
    n = float(n)
    for unit in ("B", "KiB", "MiB", "GiB", "TiB", "PiB"):
        if abs(n) < 1024 or unit == "PiB":
            return f"{n:.0f} {unit}" if unit == "B" else f"{n:.1f} {unit}"
        n /= 1024
    return f"{n:.1f} EiB"  # pragma: no cover


def _human_seconds(s: float) -> str:
    if s < 120:
        return f"{s:.2g} s"
    if s < 2 * 3600:
        return f"{s / 60:.2g} min"
    if s < 2 * 86400:
        return f"{s / 3600:.2g} h"
    if s < 2 * 365 * 86400:
        return f"{s / 86400:.2g} days"
    return f"{s / (365 * 86400):.2g} years"


def available_memory() -> int | None:
    """Bytes of memory available to a new allocation now (``MemAvailable``), or ``None``."""
    try:
        with open("/proc/meminfo") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    try:
        return os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (ValueError, OSError, AttributeError):  # pragma: no cover - no sysconf
        return None


def free_disk(path) -> int | None:
    """Free bytes on the file system that would hold ``path`` (its directory), or ``None``."""
    directory = os.path.dirname(os.path.abspath(os.fspath(path)))
    try:
        return shutil.disk_usage(directory).free
    except OSError:
        return None


@dataclasses.dataclass(frozen=True)
class Estimate:
    """The cost of one run: ``points`` evaluated, ``output_bytes`` (uncompressed) written to
    each of ``outputs`` (paths; outputs on one file system add up), ``peak_bytes`` of memory, ``seconds`` (rough, one core), and the way out
    for each limit (``memory_hint``, ``disk_hint``: what to change)."""

    command: str
    points: int
    output_bytes: int
    peak_bytes: int
    seconds: float
    outputs: tuple = ()
    memory_hint: str = "use a coarser grid"
    disk_hint: str = "use a coarser grid"

    def describe(self) -> str:
        """One line: the estimate and the room there is."""
        mem = available_memory()
        parts = [
            f"atlas {self.command}: {self.points:.4g} points",
            f"output ~{human_bytes(self.output_bytes)} uncompressed",
            f"peak memory ~{human_bytes(self.peak_bytes)}"
            + (f" of {human_bytes(mem)} available" if mem is not None else ""),
            f"~{_human_seconds(self.seconds)} on one core (rough)",
        ]
        for path in self.outputs:
            free = free_disk(path)
            if free is not None:
                parts.append(
                    f"{human_bytes(free)} free at {os.path.dirname(os.path.abspath(path))}"
                )
        return "; ".join(parts)

    def screen(self, dry_run: bool = False, no_size_check: bool = False) -> bool:
        """The ``--dry-run`` / ``--no-size-check`` rule of every command: with ``dry_run`` print
        :meth:`describe` and return true (stop here); else :meth:`check` unless
        ``no_size_check``, and return false (run)."""
        if dry_run:
            print(self.describe())
            return True
        if not no_size_check:
            self.check()
        return False

    def check(self) -> None:
        """``MemoryError`` / ``OSError`` (one line naming the numbers and the way out) when the run
        cannot fit in the memory available now or in the free space at an output."""
        mem = available_memory()
        if mem is not None and self.peak_bytes > mem:
            raise MemoryError(
                f"size: {self.points:.4g} points need ~{human_bytes(self.peak_bytes)} of memory, "
                f"{human_bytes(mem)} available: {self.memory_hint} (--dry-run shows the estimate)"
            )
        need = {}  # file system -> bytes written there (each output holds output_bytes)
        for path in self.outputs:
            where = os.path.dirname(os.path.abspath(path))
            try:
                dev = os.stat(where).st_dev
            except OSError:
                continue
            need.setdefault(dev, [where, 0])[1] += self.output_bytes
        for where, nbytes in need.values():
            free = free_disk(os.path.join(where, "x"))
            if free is not None and nbytes > free:
                raise OSError(
                    f"size: {self.points:.4g} points write ~{human_bytes(nbytes)} "
                    f"(uncompressed) to {where}, which has {human_bytes(free)} free: "
                    f"{self.disk_hint} (--no-size-check to try anyway: files are compressed)"
                )


def _output_bytes(scene, dtype: str) -> tuple[int, int]:
    """``(bytes of every output, bytes of the model-dependence accumulators)`` of a scene."""
    total = md = 0
    for name in scene.output_names:
        size = math.prod(scene.axes[d].size for d in scene.output_dims(name))
        total += size * storage_dtype(name, dtype).itemsize
        if OUTPUTS[name].needs:  # a reduction over the model samples
            md += size
    return total, md


def _box_cost(scene, dtype: str, bounded: bool) -> tuple[int, float]:
    """``(output bytes, seconds)`` of the verdicts over a box of models (``bounded``: every axis
    finite) on the scene's ``(beta1, beta2)`` points (:mod:`atlas.data.over_models`, every
    ``*_over_models`` output and its witnesses)."""
    geometry = math.prod(scene.axes[d].size for d in ("beta1", "beta2") if scene.axes[d].is_dim)
    box = [o for o in OUTPUTS.values() if o.computed_by and "over_models" in o.computed_by]
    nbytes = geometry * sum(storage_dtype(o.name, dtype).itemsize for o in box)
    ii = BOX_NS_PER_GEOMETRY["ii bounded" if bounded else "ii unbounded"]
    return nbytes, geometry * (BOX_NS_PER_GEOMETRY["ss"] + ii) * 1e-9


def generate_estimate(
    scene,
    *,
    dtype: str = "float64",
    tile_points: int = 1 << 16,
    distributed: bool = False,
    workers: int = 1,
    outputs=(),
    model_box=None,
) -> Estimate:
    """The cost of ``atlas generate`` of ``scene`` (streamed to netCDF, or tiles into a zarr
    store with ``distributed``; the store and the netCDF file both count at the destination;
    ``model_box``: with the verdicts over this :class:`~atlas.core.model_box.ModelBox`,
    :func:`_box_cost`)."""
    points = scene.points()
    out_bytes, md = _output_bytes(scene, dtype)
    box_bytes, box_seconds = (0, 0.0)
    if model_box is not None:
        bounded = all(math.isfinite(getattr(model_box, a)[1]) for a in ("kappa", "q1", "q2"))
        box_bytes, box_seconds = _box_cost(scene, dtype, bounded)
    out_bytes += box_bytes
    axes = sum(a.size for a in scene.axes.values()) * 8 * 4  # coordinates and their directions
    tile = min(tile_points, points) * TILE_BYTES_PER_POINT
    if distributed:
        per_point = out_bytes / max(points, 1)
        worker = STORE_PEAK_FACTOR * per_point * min(points, DEFAULT_SLAB_POINTS) + tile
        peak = axes + workers * worker
        written = out_bytes  # the store, and as much again for a netCDF copy
        mem_hint = "use a coarser grid or smaller tiles (--slab, --block2)"
    else:
        # model_dependent_* accumulate over (beta1, beta2) in memory; so do the box verdicts
        peak = axes + tile + md + box_bytes
        written = out_bytes
        mem_hint = (
            "use a coarser (beta1, beta2) grid or --outputs without model_dependent_*"
            if md
            else "use a coarser grid or a smaller --tile-points"
        )
    return Estimate(
        "generate",
        points,
        written,
        int(peak),
        points * NS_PER_POINT.get(dtype, 25.0) * 1e-9 * len(scene.output_names) ** 0.5
        + box_seconds,
        tuple(os.fspath(o) for o in outputs),
        memory_hint=mem_hint,
        disk_hint="use a coarser grid or fewer --outputs",
    )


def grid_estimate(
    command: str,
    points: int,
    *,
    bytes_per_point: float,
    output_bytes_per_point: float,
    seconds_per_point: float,
    outputs=(),
    hint: str = "use a coarser grid",
) -> Estimate:
    """The cost of a command that holds all its ``points`` in memory (``mechanism``,
    ``boundaries``, ``simulate --map``): ``bytes_per_point`` at peak, ``output_bytes_per_point``
    written."""
    return Estimate(
        command,
        int(points),
        int(points * output_bytes_per_point),
        int(points * bytes_per_point),
        points * seconds_per_point,
        tuple(os.fspath(o) for o in outputs),
        memory_hint=hint,
        disk_hint=hint,
    )


# Measured on this code (peak RSS growth / wall time of one run over the warm-up, float64):
#: ``atlas mechanism``: ladder 1000 x 1000 -> 320 B and 3.4 us per body; 12 float64 invariants
#: and the int8 verdicts written
MECHANISM = dict(bytes_per_point=400, output_bytes_per_point=110, seconds_per_point=4e-6)
#: ``atlas boundaries`` (points = grid nodes x check**2 x slices): 256 x 256, check 2 -> 3.9 kB
#: and 0.33 ms per grid node
BOUNDARIES = dict(bytes_per_point=1200, output_bytes_per_point=8, seconds_per_point=1e-4)
#: ``atlas boundaries`` bytes written per (kappa, q1, q2) slice and output file: the vertices are
#: refined to 1e-10 rad whatever the grid, so a slice's files hardly grow with it (measured at
#: kappa 2, q 0.1 on 16^2, 32^2, 64^2 grids: CSV 1.23, 1.25, 1.34 MB, GeoJSON 0.48-0.53 MB,
#: netCDF 0.30-0.33 MB): a constant and a part per grid value along beta1 and beta2
BOUNDARY_SLICE_BYTES = 1.2e6
BOUNDARY_EDGE_BYTES = 1.3e3


def boundaries_estimate(n1: int, n2: int, check: int, slices: int, outputs=()) -> Estimate:
    """The cost of ``atlas boundaries`` on an ``n1 x n2`` grid, ``check`` sub-samples per cell
    side, ``slices`` model slices: each output holds at most the largest file's bytes
    (:data:`BOUNDARY_SLICE_BYTES`)."""
    points = n1 * n2 * max(1, check) ** 2 * slices
    written = slices * (BOUNDARY_SLICE_BYTES + BOUNDARY_EDGE_BYTES * (n1 + n2)) + 8 * points
    opts = {**BOUNDARIES, "output_bytes_per_point": written / points}
    return grid_estimate("boundaries", points, outputs=outputs, **opts)


#: ``atlas simulate --map`` per trajectory: peak bytes (engine state, initial states, codes),
#: seconds by engine (outputs/bench.md: ~0.4 ms fast, ~0.012 s exact, run by run; jax ~0.04 s)
#: at the horizon :data:`OUTCOME_T_END`
OUTCOME_TRAJECTORY_BYTES = 2000
OUTCOME_SECONDS = {"fast": 4e-4, "numpy": 0.02, "jax": 0.04}
#: the horizon [scaled time] of :data:`OUTCOME_SECONDS` (``Dynamics``' default ``t_end``): a
#: run's time grows in proportion to its horizon, as the exact simulator's sub-steps do
OUTCOME_T_END = 150.0
#: stored bytes per cell of an outcome atlas: 8 int16 counts, int8 outcome, float32 agreement,
#: the no-stable-subclass flag
OUTCOME_CELL_BYTES = 8 * 2 + 1 + 4 + 1


def outcome_estimate(
    scene,
    n_perturb: int,
    *,
    engine: str = "fast",
    theory: bool = True,
    outputs=(),
    tile_runs: int | None = None,
    t_end: float = OUTCOME_T_END,
) -> Estimate:
    """The cost of an outcome atlas (``atlas simulate --map``) of ``scene``: points =
    trajectories (cells over every axis x ``n_perturb``), simulated ``tile_runs`` at a time
    (default all), each for a time proportional to its horizon ``t_end`` [scaled time]; with
    ``theory`` the theory verdicts of the same cells (:func:`generate_estimate`) are held and
    written too."""
    cells = math.prod(a.size for a in scene.axes.values())
    runs = cells * max(1, int(n_perturb))
    batch = runs if tile_runs is None else min(runs, int(tile_runs))
    out_bytes = cells * OUTCOME_CELL_BYTES
    peak = batch * OUTCOME_TRAJECTORY_BYTES + out_bytes
    per_run = OUTCOME_SECONDS.get(engine, OUTCOME_SECONDS["numpy"]) * t_end / OUTCOME_T_END
    seconds = runs * per_run
    if theory:
        th = generate_estimate(scene)
        out_bytes += th.output_bytes
        peak += th.output_bytes + th.peak_bytes
        seconds += th.seconds
    hint = "use a coarser grid, fewer --n-perturb, or --store with a smaller --slab"
    return Estimate(
        "simulate --map",
        runs,
        int(out_bytes),
        int(peak),
        seconds,
        tuple(os.fspath(o) for o in outputs),
        memory_hint=hint,
        disk_hint="use a coarser grid",
    )
