"""Atlases beyond one process: the tiles of a scene on dask workers (or in process) into a
resumable, checksummed zarr store, and from there into netCDF.

The pieces: :mod:`atlas.data.tiles` cuts the scene into tiles, :mod:`atlas.data.cluster` says
where they run, :mod:`atlas.data.tile_store` is the store's format (layout, tile records,
checksums).  This module runs them: :func:`generate_distributed` lays out (or resumes) a store,
computes every tile not yet verified, checks that tiles sharing a region agree, sums the undecided
counts and marks the store complete; :func:`verify_store` checks a store.

``resume=True`` verifies every recorded tile against the store (on the workers) and recomputes
tiles whose record is missing, unreadable, or whose bytes no longer match: after a resumed run the
records prove that no tile is missing or corrupt.  A finished store carries the global attributes
of :func:`atlas.generate` (undecided totals summed over the tiles) and ``atlas_complete = 1``.
Schedulers (``None``, ``"local[:N]"``, an address or a ``distributed.Client``): see
:mod:`atlas.data.cluster`; on an existing cluster, e.g.
``generate_distributed(scene, "/shared/atlas.zarr", scheduler="tcp://host:8786")``.

Example
-------
>>> from atlas import Scene
>>> from atlas.data.distributed import generate_distributed
>>> from atlas.data.tile_store import open_store
>>> scene = Scene(beta1="0:2pi:64", beta2="0:2pi:64", kappa="0.5,2", q1="0,1", q2="0,1")
>>> summary = generate_distributed(scene, "atlas.zarr", scheduler="local:2",
...                                to_netcdf="atlas.nc")            # doctest: +SKIP
>>> # killed?  the same call with resume=True finishes the missing tiles
>>> ds = open_store("atlas.zarr")                                   # doctest: +SKIP
"""

from __future__ import annotations

import dataclasses
import datetime
import os
import time

import xarray as xr

from atlas.core import interrupts
from atlas.data import box_tiles, over_models, store_guard, tile_store
from atlas.data import tiles as tiling
from atlas.data.cluster import check_scheduler, executor
from atlas.data.engine import MemorySink, RunOptions, Schema, progress_bar, run, schema
from atlas.data.io import NetCDFSink, check_output_path
from atlas.data.scene import Scene
from atlas.data.tiles import TilePlan, tile_plan

__all__ = ["generate_distributed", "verify_store", "compute_tile"]


# --- the tile tasks (run on the workers, or in process) -----------------------------------------


def compute_tile(
    scene: Scene, tile, options: RunOptions, model_box=None
) -> tuple[xr.Dataset, dict]:
    """One tile of the atlas and its run diagnostics, in this process, without progress bar (a
    separate function: tests slow it down, and :mod:`atlas.bench.distributed` warms the kernels
    with it); with ``model_box`` the verdicts over it on the tile's block too
    (:mod:`atlas.data.box_tiles`)."""
    opts = dataclasses.replace(options, progress=False, history=None)
    ds, stats = run(tiling.sub_scene(scene, tile), MemorySink(), opts)
    return (ds if model_box is None else box_tiles.add_to_tile(ds, model_box)), stats


def _run_tile(store: str, scene: Scene, i: int, tile, opts: RunOptions, box=None) -> dict:
    """Compute tile ``i``, write the regions it owns, read them back, then write its record."""
    tile_store.drop_record(store, i)
    t0, c0 = time.perf_counter(), time.process_time()
    ds, stats = compute_tile(scene, tile, opts, box)
    run = {
        "exact_failures": stats.get("exact_failures", []),
        "points": stats["points"],
        "seconds": time.perf_counter() - t0,
        "cpu_seconds": time.process_time() - c0,
    }
    return tile_store.write_tile(store, i, tile, ds, run)


# --- the driver ---------------------------------------------------------------------------------


def verify_store(store, scheduler=None) -> dict:
    """Check every tile of a store against its record.

    Returns ``{"ok": [...], "missing": [...], "corrupt": [...], "arrays": [...]}``: tile
    indices (*missing* = no readable record, *corrupt* = a record whose checksums the stored bytes
    no longer match) and the coordinates whose bytes differ from the plan's checksums, with
    ``"attributes"`` when any attribute of the store or of an array differs from its record.
    Every byte of the store is covered: a resume rewrites what is listed.
    """
    store = os.fspath(store)
    plan = tile_store.stored_plan(store)
    ex = executor(scheduler)
    try:
        report = _verify_all(ex, store, TilePlan.of(plan["tiles"]))[0]
    finally:
        ex.close()
    report["arrays"] = tile_store.corrupt_arrays(store, plan)
    return report


def _verify_all(ex, store, tiles):
    report = {"ok": [], "missing": [], "corrupt": []}
    recs = {}
    recorded = [i for i in range(len(tiles)) if tile_store.read_record(store, i) is not None]
    missing = set(range(len(tiles))) - set(recorded)
    calls = [(i, (store, i, tuple(tiles[i]))) for i in recorded]
    for i, rec in ex.map(tile_store.verify_tile, calls):
        if rec is None:
            report["corrupt"].append(i)
        else:
            report["ok"].append(i)
            recs[i] = rec
    report["missing"] = sorted(missing)
    for k in report:
        report[k].sort()
    return report, recs


def generate_distributed(
    scene: Scene,
    store,
    options: RunOptions | None = None,
    *,
    scheduler=None,
    slab: int | None = None,
    block2: int | None = None,
    resume: bool = False,
    overwrite: bool = False,
    to_netcdf=None,
    overwrite_netcdf: bool = False,
    model_box=None,
    **changes,
) -> dict:
    """Generate an atlas tile by tile (on dask workers or in process) into a resumable zarr store.

    Parameters
    ----------
    scene : atlas.Scene
        The atlas; it is split along ``beta1`` (and ``beta2``, see :func:`tile_plan`).
    store : str or os.PathLike
        Zarr directory (a local or shared file system path).
    scheduler : None, "local", "local:N", "tcp://host:port" or distributed.Client
        Where the tiles run (see :mod:`atlas.data.cluster`); ``None``: in this process.
    slab : int, optional
        ``beta1`` values per tile (default: about
        :data:`atlas.data.tiles.DEFAULT_SLAB_POINTS` points per tile).
    block2 : int, optional
        ``beta2`` values per tile (2-D tiles); by default ``beta2`` is split only when ``slab`` is
        not given and one ``beta1`` value holds more than
        :data:`atlas.data.tiles.DEFAULT_SLAB_POINTS` points.
    resume : bool
        Continue an existing store: tiles whose record verifies against the stored bytes are
        kept, missing or corrupt ones recomputed.  The store must have been created for the same
        scene, options, tiles and package/JAX versions (else ``ValueError``).
    overwrite : bool
        Replace an existing store (without ``resume``); otherwise an existing store raises
        ``FileExistsError``.
    options : atlas.data.engine.RunOptions, optional
        As for :func:`atlas.generate` (``tile_points`` = kernel tile inside each slab;
        ``progress``: a bar over tiles; ``history``: the command recorded).
    **changes
        Run options changed by name (see :class:`atlas.data.engine.RunOptions`).
    to_netcdf : str or os.PathLike, optional
        Also convert the finished store to this netCDF4 file, streaming slab by slab through
        :class:`atlas.data.io.NetCDFSink` (atomic; same file as ``io.write_netcdf(generate(scene))``).
    overwrite_netcdf : bool
        Replace an existing netCDF file.
    model_box : ModelBox, its text or a dict, optional
        Add the verdicts over it as ``atlas.generate`` does (:mod:`atlas.data.box_tiles`).

    Returns
    -------
    dict
        ``store``, ``netcdf``, ``scheduler``, ``workers``, ``tiles``, ``slab``, ``block2`` (``None``:
        beta2 not split), ``points``, ``computed`` (tiles computed by this call), ``verified``
        (kept), ``missing`` / ``corrupt`` (found on resume), ``repaired`` (coordinates,
        ``"attributes"``: rewritten), ``seconds``, ``points_per_second``, ``tile_seconds`` /
        ``tile_cpu_seconds`` (wall / CPU time of each computed tile on its worker, compilation
        included), ``tile_points``, ``undecided_fast``, ``undecided``, ``over_models`` (box counts).
    """
    t0 = time.perf_counter()
    job = _job(scene, store, scheduler, slab, block2, RunOptions.of(options, **changes), model_box)
    if to_netcdf is not None:
        check_output_path(to_netcdf, overwrite_netcdf)
    with store_guard.held(job.store, ours=tile_store.is_atlas_store):
        resumed = _prepare_store(job, resume, overwrite)
        ex = executor(scheduler)
        bar = progress_bar(job.opts.progress, len(job.tiles), "atlas tiles", unit="tile")
        try:
            report, recs, computed = _run_tiles(ex, job, resumed, bar)
            totals = _finalize(job.store, job.sch, job.plan, job.tiles, recs, computed, resumed)
        finally:
            if bar is not None:
                bar.close()
            ex.close()
        netcdf = _to_netcdf(job, recs, totals, to_netcdf, overwrite_netcdf)
    seconds = time.perf_counter() - t0
    return _summary(job, ex, netcdf, report, recs, computed, totals, seconds)


@dataclasses.dataclass(frozen=True)
class _Job:
    """One checked call of :func:`generate_distributed`: the scene, the store (absolute path),
    the tiles, the schema of the full atlas, the :func:`atlas.generate` options, the plan and the
    model box (``None``: none)."""

    scene: Scene
    store: str
    tiles: TilePlan
    sch: Schema
    opts: RunOptions
    plan: dict
    box: object = None

    @property
    def slab(self) -> int:
        """``beta1`` values per tile."""
        return self.tiles[0][1] - self.tiles[0][0]

    @property
    def block2(self) -> int | None:
        """``beta2`` values per tile (``None``: ``beta2`` not split)."""
        first = self.tiles[0]
        return first[3] - first[2] if len(first) == 4 else None


def _job(scene, store, scheduler, slab, block2, opts: RunOptions, model_box=None):
    """The checked arguments of :func:`generate_distributed` (one-line errors naming the
    parameter), its tiles, schema and plan."""
    if not isinstance(scene, Scene):
        raise ValueError("scene: expected an atlas.Scene")
    box = None if model_box is None else over_models.as_model_box(model_box)
    check_scheduler(scheduler)
    store = store_guard.check_place(store)
    tiles = tile_plan(scene, slab, block2)
    sch = schema(scene, opts)
    stored = opts.stored()
    if box is not None:
        sch = box_tiles.with_box(sch, opts.tile_points)
        stored["model_box"] = str(box)
    plan = tile_store.make_plan(scene, sch, tiles, stored)
    return _Job(scene, store, tiles, sch, opts, plan, box)


def _prepare_store(job: _Job, resume: bool, overwrite: bool) -> bool:
    """Resume an existing store made for the same plan, or lay out a new one (replacing an
    existing store only with ``overwrite``); true when resuming."""
    store = job.store
    exists = os.path.exists(store)
    if resume and not exists:
        raise FileNotFoundError(f"resume: store {store} does not exist")
    if exists and resume:
        tile_store.check_resumable(store, job.plan)  # a damaged root is restored from its record
    elif exists and not overwrite:
        raise FileExistsError(f"store: {store} exists (use resume=True or overwrite=True)")
    else:
        if not os.path.isdir(os.path.dirname(store)):
            raise FileNotFoundError(f"store: directory {os.path.dirname(store)} does not exist")
        store_guard.check_replaceable(store, tile_store.is_atlas_store, "an atlas store")
        tile_store.create_layout(store, job.sch, job.slab, job.plan, job.block2)  # by renames
    return exists and resume


def _run_tiles(ex, job: _Job, resumed: bool, bar):
    """Verify the recorded tiles (when resuming), then compute the others on ``ex``.

    Returns ``(report, records, computed)``: the verification report (``None`` unless resuming),
    the records of every finished tile, and those of the tiles computed here.
    """
    damaged = []
    if resumed:
        damaged = tile_store.corrupt_arrays(job.store, job.plan)
        if damaged:
            tile_store.repair_layout(job.store, job.sch, damaged, job.plan)
    report, recs = _verify_all(ex, job.store, job.tiles) if resumed else (None, {})
    if report is not None:
        report["arrays"] = damaged
    todo = [i for i in range(len(job.tiles)) if i not in recs]
    if bar is not None:
        bar.update(len(recs))
    calls = [(i, (job.store, job.scene, i, job.tiles[i], job.opts, job.box)) for i in todo]
    computed = {}
    for i, rec in ex.map(_run_tile, calls):
        interrupts.check()  # a stop signal lost in a gc callback still ends the run here
        recs[i] = computed[i] = rec
        if bar is not None:
            bar.update(1)
    return report, recs, computed


def _summary(job: _Job, ex, netcdf, report, recs, computed, totals, seconds) -> dict:
    """What :func:`generate_distributed` returns (see there)."""
    points = job.scene.points()
    return {
        "store": job.store,
        "netcdf": netcdf,
        "scheduler": ex.description,
        "workers": ex.workers,
        "tiles": len(job.tiles),
        "slab": job.slab,
        "block2": job.block2,
        "points": points,
        "computed": sorted(computed),
        "verified": sorted(set(recs) - set(computed)),
        "missing": report["missing"] if report else [],
        "corrupt": report["corrupt"] if report else [],
        "repaired": report["arrays"] if report else [],
        "seconds": seconds,
        "points_per_second": points / seconds if seconds > 0 else float("inf"),
        "tile_seconds": [computed[i]["seconds"] for i in sorted(computed)],
        "tile_cpu_seconds": [computed[i]["cpu_seconds"] for i in sorted(computed)],
        "tile_points": [computed[i]["points"] for i in sorted(computed)],
        "undecided_fast": totals["attrs"]["undecided_fast"],
        "undecided": totals["attrs"]["undecided_after_resolve"],
        **({"over_models": totals["box"]} if totals["box"] else {}),
    }


def _finalize(store, sch, plan, tiles, recs, computed, resumed) -> dict:
    """Check the records, sum the undecided counts, write the final attributes."""
    missing = [i for i in range(len(tiles)) if i not in recs]
    if missing:  # pragma: no cover - every tile either verified or computed
        raise RuntimeError(f"store: tiles {missing} missing after the run")
    dims = {k: v[0] for k, v in sch.variables.items()}
    has_b1 = "beta1" in sch.shape
    seen = {}  # (variable, region) -> (tile, checksum): tiles sharing a region must agree
    var_attrs, fast, final = {}, 0, 0
    for i in sorted(recs):
        rec, split = recs[i], tiling.ranges(has_b1, tiles[i])
        if rec["source"] != plan["source"]:
            raise RuntimeError(
                f"scheduler: tile {i} ran {rec['source']!r}, expected {plan['source']!r}"
            )
        for k, h in rec["shared"].items():
            key = (k, tuple(split[d] for d in split if d in dims[k]))
            j, h0 = seen.setdefault(key, (i, h))
            if h0 != h:
                raise RuntimeError(f"store: tile {i} disagrees with tile {j} on {k}")
        # variables a tile computes but does not own are counted by their owner
        fast += rec["total_undecided_fast"]
        final += rec["total_undecided"]
        for k in rec["undecided"]:
            if tiling.owns(dims[k], split):
                a = var_attrs.setdefault(k, {"undecided_fast": 0, "undecided": 0})
                a["undecided_fast"] += rec["undecided_fast"][k]
                a["undecided"] += rec["undecided"][k]
            else:
                fast -= rec["undecided_fast"][k]
                final -= rec["undecided"][k]
    attrs = {"undecided_fast": int(fast), "undecided_after_resolve": int(final)}
    failures = [p for i in sorted(recs) for p in recs[i]["exact_failures"]]
    if failures:
        attrs["exact_failures"] = len(failures)
        attrs["exact_failure_example"] = repr(tuple(failures[0]))
    box = box_tiles.total_counts(plan.get("model_box"), [recs[i].get("box_counts") for i in recs])
    attrs.update(box)
    interrupts.check()  # no store is marked complete after a stop signal
    history = tile_store.stored_history(store, sch.attrs["history"])
    if resumed:
        now = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")
        history += f"\n{now}: resumed, {len(computed)} of {len(tiles)} tiles recomputed"
    tile_store.mark_complete(store, {**attrs, "history": history}, var_attrs)
    return {"attrs": attrs, "var_attrs": var_attrs, "history": history, "box": box}


def _to_netcdf(job: _Job, recs: dict, totals: dict, path, overwrite):
    """Stream the store into a netCDF4 file with the schema's (typed) attributes, every region
    checked against the record of the tile that wrote it and the store's plan against this run's
    (``RuntimeError`` naming the store if anything changed under the run; no file)."""
    if path is None:
        return None
    store, sch, tiles = job.store, job.sch, job.tiles
    sink = NetCDFSink(path, overwrite)
    sch = Schema(sch.coords, sch.variables, {**sch.attrs, "history": totals["history"]}, sch.shape)
    ds = tile_store.open_store(store)
    has_b1 = "beta1" in sch.shape
    try:
        if tile_store.stored_plan(store).get("hash") != job.plan["hash"]:
            raise RuntimeError(f"store: {store} changed under this run (its plan); no file written")
        sink.begin(sch)  # inside: an interrupt while the header is written still aborts
        for i, tile in enumerate(tiles):  # every region once, from the tile that owns it
            split = tiling.ranges(has_b1, tile)
            sums = {**recs[i]["checksums"], **recs[i]["shared"]}
            for k, (dims, *_) in sch.variables.items():
                if tiling.owns(dims, split):
                    reg = tiling.region(dims, split)
                    index = tuple(reg.get(d, slice(None)) for d in dims)
                    values = ds[k].isel(reg).values
                    if tile_store.digest(values) != sums.get(k):
                        raise RuntimeError(
                            f"store: {store} changed under this run (tile {i}, {k}); no file "
                            "written"
                        )
                    sink.write(k, index, values)
        return sink.finish(totals["attrs"], totals["var_attrs"])
    except BaseException:
        sink.abort()
        raise
