"""Atlases beyond one process: tiles of a scene on dask workers, written into a resumable zarr store.

The scene is split along ``beta1`` into *slabs* of ``slab`` consecutive values, and, when one
``beta1`` value alone holds more points than a tile should (or ``block2`` is given), along ``beta2``
too, into 2-D ``(beta1, beta2)`` blocks (:func:`tile_plan`).  Each tile is an ordinary
:func:`atlas.generate` run on a sub-scene holding its block; generation is pointwise-deterministic
and the ``model_dependent_*`` reductions run over the model dimensions at fixed ``(beta1, beta2)``,
so the assembled tiles equal the single-process atlas bit for bit.

Store layout (a local zarr directory, zarr 2 or 3)::

    STORE/                  the atlas: coordinates, variables, CF attributes (SPEC §2)
    STORE/_tiles/t000012    one empty group per finished tile; its attributes are the tile record

The layout is created up front from :func:`atlas.data.engine.schema` of the full scene (arrays
allocated lazily: unwritten chunks read as fill values), in a temporary directory renamed onto
``STORE``.  A tile writes its variables into its region (``beta1`` in ``[start, stop)``, and
``beta2`` in ``[start2, stop2)`` for 2-D blocks; zarr chunks are aligned with the tiles, so
concurrent tiles never touch the same chunk), reads the region back, and only then writes its
record: the SHA-256 of the raw bytes (dtype, shape, data) of every variable's region, the undecided
counts and timings.  A variable lacking a split dimension (``stable_FS`` and ``consistent_FI`` have
no ``beta1``, ``stable_SF`` no ``beta2``) is computed by every tile that covers its region and
written by the first of them along the missing dimension; their checksums (``shared`` in the
record) must agree.

``resume=True`` verifies every recorded tile against the store (on the workers) and recomputes
tiles whose record is missing, unreadable, or whose bytes no longer match: after a resumed run the
records prove that no tile is missing or corrupt.  A finished store carries the global attributes
of :func:`atlas.generate` (undecided totals summed over the tiles) and ``atlas_complete = 1``.

Schedulers
----------
``scheduler=None``
    in this process, tile after tile (the same tile function, no dask);
``"local"`` / ``"local:N"``
    a :class:`distributed.LocalCluster` of N worker *processes* (default: the number of cores),
    one thread each, one JAX runtime per worker with XLA's intra-op threading off
    (:data:`WORKER_ENV`) and each worker pinned to its own core (:func:`pin_to_cpus`: XLA's task
    pool ignores the flags), so N workers use N cores; the workers share the CLI's persistent JAX
    compilation cache (:func:`worker_env`);
``"tcp://host:8786"`` or a :class:`distributed.Client`
    an existing cluster.  The workers need ``painleve-atlas`` (same version and JAX version as the
    client: the store records both and mixed versions are refused) and the store path on a shared
    file system.  Start the workers with one thread each and the same environment, e.g.::

        dask scheduler                                    # on host, port 8786
        XLA_FLAGS="--xla_cpu_multi_thread_eigen=false" \\
            dask worker tcp://host:8786 --nworkers 16 --nthreads 1   # on each machine

    then ``generate_distributed(scene, "/shared/atlas.zarr", scheduler="tcp://host:8786")``.

Example
-------
>>> from atlas import Scene
>>> from atlas.data.distributed import generate_distributed, open_store
>>> scene = Scene(beta1="0:2pi:64", beta2="0:2pi:64", kappa="0.5,2", q1="0,1", q2="0,1")
>>> summary = generate_distributed(scene, "atlas.zarr", scheduler="local:2",
...                                to_netcdf="atlas.nc")            # doctest: +SKIP
>>> # killed?  the same call with resume=True finishes the missing tiles
>>> ds = open_store("atlas.zarr")                                   # doctest: +SKIP
"""

from __future__ import annotations

import collections.abc
import contextlib
import dataclasses
import datetime
import hashlib
import json
import operator
import os
import shutil
import tempfile
import time

import numpy as np
import xarray as xr

from atlas.core import checks, interrupts
from atlas.core.config import CACHE_MIN_COMPILE_SECONDS, compile_cache_dir
from atlas.data.engine import (
    DEFAULT_TILE_POINTS,
    Schema,
    block_shape,
    check_options,
    generate,
    progress_bar,
    schema,
)
from atlas.data.io import NetCDFSink, check_output_path
from atlas.data.scene import Scene

__all__ = [
    "generate_distributed",
    "open_store",
    "verify_store",
    "tile_plan",
    "TilePlan",
    "WORKER_ENV",
    "worker_env",
    "local_cluster",
    "pin_to_cpus",
    "compute_tile",
    "read_record",
]

#: environment of LocalCluster workers: one JAX process per worker, no intra-op thread pools
WORKER_ENV = {
    "XLA_FLAGS": "--xla_cpu_multi_thread_eigen=false",
    "OMP_NUM_THREADS": "1",
    "MKL_NUM_THREADS": "1",
    "OPENBLAS_NUM_THREADS": "1",
}


def pin_to_cpus(cpus) -> list[int]:
    """Restrict every thread of this process to ``cpus`` (Linux); returns the threads pinned.

    XLA splits large fusions into parallel tasks on its own thread pool whatever ``XLA_FLAGS`` say
    (measured: one worker used 1.5-1.8 cores with ``--xla_cpu_multi_thread_eigen=false``), so a
    LocalCluster of N workers on N cores oversubscribed them (2 workers gave 1.12x one worker).
    Affinity is per thread on Linux: every existing thread is set, and threads created later
    inherit it.  A no-op (empty list) where ``os.sched_setaffinity`` does not exist.
    """
    if not hasattr(os, "sched_setaffinity"):  # pragma: no cover - macOS, Windows
        return []
    done = []
    for tid in os.listdir("/proc/self/task"):
        with contextlib.suppress(OSError):
            os.sched_setaffinity(int(tid), set(cpus))
            done.append(int(tid))
    return done


def local_cluster(n_workers: int):
    """``(cluster, client)``: a LocalCluster of ``n_workers`` single-thread worker processes with
    :func:`worker_env`, worker ``i`` pinned to core ``i mod ncores`` (:func:`pin_to_cpus`), so N
    workers use N cores."""
    from distributed import Client, LocalCluster

    cluster = LocalCluster(
        n_workers=n_workers,
        threads_per_worker=1,
        processes=True,
        env=worker_env(),
        dashboard_address=None,
        silence_logs=40,
    )
    client = Client(cluster)
    client.wait_for_workers(n_workers)
    cores = sorted(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else []
    if cores and n_workers <= len(cores):
        for i, addr in enumerate(sorted(client.scheduler_info()["workers"])):
            client.run(pin_to_cpus, [cores[i]], workers=[addr])
    return cluster, client


def worker_env() -> dict:
    """Environment for worker processes: :data:`WORKER_ENV` plus the persistent JAX compilation
    cache of the CLI (``$ATLAS_JAX_CACHE``, default ``~/.cache/painleve-atlas/jax``; ``0`` = off),
    so each worker loads the compiled kernels instead of compiling them again."""
    env = dict(WORKER_ENV)
    where = compile_cache_dir()
    if where is not None:
        env["JAX_COMPILATION_CACHE_DIR"] = where
        env.setdefault("JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS", str(CACHE_MIN_COMPILE_SECONDS))
    return env


#: default points per tile (largest output): a few kernel tiles, so per-tile overhead is amortized
DEFAULT_SLAB_POINTS = 1 << 18
#: maximum elements per zarr chunk (chunks never straddle slabs)
CHUNK_POINTS = 1 << 20
TILES = "_tiles"
#: attribute of the ``_tiles`` group: SHA-256 of every attribute of the store
ATTRS_RECORD = "attributes_sha256"
PLAN_ATTR = "atlas_plan"
FORMAT_VERSION = 2


# --- the plan -----------------------------------------------------------------------------------


def tile_plan(scene: Scene, slab: int | None = None, block2: int | None = None) -> TilePlan:
    """The tiles of a scene: ``[(start, stop), ...]`` (``beta1`` slabs; one tile if ``beta1`` is
    fixed), or ``[(start, stop, start2, stop2), ...]`` when ``beta2`` is split too (2-D blocks),
    as a lazy :class:`TilePlan` (no tile is materialised: a 1e14-point scene costs nothing).

    ``slab=None`` picks about :data:`DEFAULT_SLAB_POINTS` points per tile; if then one ``beta1``
    value alone holds more than that and ``block2`` is not given, ``beta2`` is split into blocks of
    about that many points as well.  ``block2`` = ``beta2`` values per tile.
    """
    n1 = scene.axes["beta1"].size if "beta1" in scene.dims else 1
    n2 = scene.axes["beta2"].size if "beta2" in scene.dims else 1
    per = max(1, scene.points() // n1)
    if slab is None:
        slab = max(1, min(n1, round(DEFAULT_SLAB_POINTS / per)))
        if block2 is None and per > DEFAULT_SLAB_POINTS and n2 > 1:
            block2 = max(1, round(DEFAULT_SLAB_POINTS / max(1, per // n2)))
            block2 = None if block2 >= n2 else block2
    s = _positive("slab", slab)
    if block2 is None:
        return TilePlan(n1, n2, s, None)
    b = _positive("block2", block2)
    if "beta2" not in scene.dims:
        raise ValueError("block2: the scene has a single beta2 value")
    return TilePlan(n1, n2, s, b)


@dataclasses.dataclass(frozen=True)
class TilePlan(collections.abc.Sequence):
    """The tiles of :func:`tile_plan`, computed on demand: ``n1`` x ``n2`` (beta1, beta2) values in
    slabs of ``slab`` beta1 values, split into blocks of ``block2`` beta2 values (``None``: not
    split).  A sequence of tuples; equal to the list of its tiles."""

    n1: int
    n2: int
    slab: int
    block2: int | None

    @property
    def _per1(self) -> int:
        return 1 if self.block2 is None else -(-self.n2 // self.block2)

    def __len__(self) -> int:
        return -(-self.n1 // self.slab) * self._per1

    def __getitem__(self, i):
        if isinstance(i, slice):
            return [self[j] for j in range(*i.indices(len(self)))]
        n = len(self)
        i = operator.index(i)
        if i < 0:
            i += n
        if not 0 <= i < n:
            raise IndexError(i)
        a, c = divmod(i, self._per1)
        a *= self.slab
        tile = (a, min(a + self.slab, self.n1))
        if self.block2 is None:
            return tile
        c *= self.block2
        return (*tile, c, min(c + self.block2, self.n2))

    def __eq__(self, other):
        if isinstance(other, collections.abc.Sequence) and not isinstance(other, str):
            return len(self) == len(other) and all(a == tuple(b) for a, b in zip(self, other))
        return NotImplemented

    __hash__ = None

    def describe(self) -> dict:
        """The plan's parameters (stored in the store's plan instead of every tile)."""
        return {"n1": self.n1, "n2": self.n2, "slab": self.slab, "block2": self.block2}

    @classmethod
    def of(cls, stored) -> TilePlan | list:
        """The tiles of a stored plan (:meth:`describe`, or a list of tiles)."""
        return cls(**stored) if isinstance(stored, dict) else [tuple(t) for t in stored]


def _positive(name, value) -> int:
    try:
        n = int(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name}: must be a positive integer, got {value!r}") from None
    if n < 1 or n != value:
        raise ValueError(f"{name}: must be a positive integer, got {value!r}")
    return n


def _sub_scene(scene: Scene, tile) -> Scene:
    kw = {}
    if "beta1" in scene.dims:
        kw["beta1"] = np.array(scene.axes["beta1"].values[tile[0] : tile[1]])
    if len(tile) == 4:
        kw["beta2"] = np.array(scene.axes["beta2"].values[tile[2] : tile[3]])
    return scene.replace(**kw) if kw else scene


def _split(has_beta1: bool, tile) -> dict:
    """``{dim: (start, stop)}``: the dimensions a tile is a range of."""
    out = {"beta1": (tile[0], tile[1])} if has_beta1 else {}
    if len(tile) == 4:
        out["beta2"] = (tile[2], tile[3])
    return out


def _region(dims, split) -> dict:
    """A variable's region in a tile (``{}``: the whole variable)."""
    return {d: slice(*split[d]) for d in split if d in dims}


def _unique(dims, split) -> bool:
    """The variable's region in this tile belongs to no other tile (it has every split dim)."""
    return all(d in dims for d in split)


def _owns(dims, split) -> bool:
    """The tile writes the variable's region: it is the first tile along the dims it lacks."""
    return all(d in dims or split[d][0] == 0 for d in split)


def _chunks(sch: Schema, name: str, slab: int, block2: int | None = None) -> tuple[int, ...]:
    """Zarr chunks aligned with the tiles: ``slab`` along beta1, ``block2`` along a split beta2."""
    dims = sch.variables[name][0]
    shape = tuple(sch.shape[d] for d in dims)
    fixed = {"beta1": slab} if "beta1" in dims else {}
    if block2 is not None and "beta2" in dims:
        fixed["beta2"] = block2
    if not fixed:
        return shape
    rest = [n for d, n in zip(dims, shape) if d not in fixed]
    rest = iter(
        block_shape(tuple(rest), max(1, CHUNK_POINTS // int(np.prod(list(fixed.values())))))
    )
    return tuple(min(fixed[d], n) if d in fixed else next(rest) for d, n in zip(dims, shape))


def _digest(arr) -> str:
    """SHA-256 of an array's dtype, shape and raw bytes (C order)."""
    a = np.ascontiguousarray(np.asarray(arr))
    h = hashlib.sha256(f"{a.dtype.str}{a.shape}".encode())
    h.update(a.tobytes())
    return h.hexdigest()


def _plan(scene, sch, tiles, opts) -> dict:
    coords = {k: _digest(v) for k, (_, v, _) in sch.coords.items()}
    variables = {k: [list(d), np.dtype(t).str] for k, (d, t, _, _) in sch.variables.items()}
    plan = {
        "format": FORMAT_VERSION,
        "scene": scene.describe(),
        "coords": coords,
        "variables": variables,
        "tiles": tiles.describe() if isinstance(tiles, TilePlan) else [list(t) for t in tiles],
        "source": sch.attrs["source"],
        **opts,
    }
    plan["hash"] = hashlib.sha256(json.dumps(plan, sort_keys=True).encode()).hexdigest()
    return plan


# --- store helpers ------------------------------------------------------------------------------


def _open(store) -> xr.Dataset:
    return xr.open_zarr(store, consolidated=False, chunks=None)


def open_store(store) -> xr.Dataset:
    """The atlas in a zarr store (lazy; attributes as stored, flag values as JSON lists)."""
    return _open(os.fspath(store))


def _record_path(i: int) -> str:
    return f"{TILES}/t{i:06d}"


def read_record(store: str, i: int) -> dict | None:
    """The record of tile ``i`` in ``store`` (checksums, undecided counts, timings), or None if
    the tile is not finished or its record is unreadable."""
    import zarr

    if not os.path.isdir(os.path.join(store, TILES, f"t{i:06d}")):
        return None
    try:
        rec = dict(zarr.open_group(store, path=_record_path(i), mode="r").attrs)
    except Exception:  # truncated or unreadable metadata: the tile counts as missing
        return None
    body = {k: v for k, v in rec.items() if k != "record_sha256"}
    if rec.get("record_sha256") != _sha(json.dumps(body, sort_keys=True)):
        return None  # any byte of the record changed
    return rec if rec.get("index") == i and "checksums" in rec else None


def _drop_record(store: str, i: int):
    shutil.rmtree(os.path.join(store, TILES, f"t{i:06d}"), ignore_errors=True)


def _region_digests(ds: xr.Dataset, names, split: dict) -> dict:
    return {k: _digest(ds[k].isel(_region(ds[k].dims, split)).values) for k in names}


_METADATA = ("zarr.json", ".zarray", ".zattrs", ".zgroup", ".zmetadata")


def _metadata_digests(store: str) -> dict:
    """SHA-256 of the raw bytes of every metadata file of the store (array and group metadata
    with their attributes; the tile records have their own checksums)."""
    out = {}
    for dirpath, dirnames, filenames in os.walk(store):
        rel = os.path.relpath(dirpath, store)
        if rel == TILES or rel.startswith(TILES + os.sep):
            dirnames[:] = []
            continue
        if rel == ".":
            dirnames[:] = [d for d in dirnames if d != TILES]
        for f in filenames:
            if f in _METADATA:
                with open(os.path.join(dirpath, f), "rb") as fh:
                    out[os.path.normpath(os.path.join(rel, f))] = hashlib.sha256(
                        fh.read()
                    ).hexdigest()
    return out


def _all_attrs(store: str) -> dict:
    """The attributes of the store and of every array in it, in their stored order."""
    import zarr

    root = zarr.open_group(store, mode="r")
    out = {"": dict(root.attrs)}
    for name, arr in root.arrays():
        out[name] = dict(arr.attrs)
    return out


def _sha(text: str) -> str:
    return hashlib.sha256(text.encode()).hexdigest()


def _record_attrs(store: str) -> None:
    """Record the checksums of the metadata files and a copy of every attribute (to restore
    them), with a checksum of the record itself, in the attributes of the ``_tiles`` group."""
    import zarr

    body = {"metadata": _metadata_digests(store), "attributes": _all_attrs(store)}
    text = json.dumps(body, default=repr)
    zarr.open_group(store, path=TILES, mode="r+").attrs.put(
        {ATTRS_RECORD: text, ATTRS_RECORD + "_sha256": _sha(text)}
    )


def _attrs_record(store: str) -> dict | None:
    """The record of :func:`_record_attrs` if it is intact, else ``None``."""
    import zarr

    try:
        rec = dict(zarr.open_group(store, path=TILES, mode="r").attrs)
        text = rec[ATTRS_RECORD]
        if _sha(text) != rec.get(ATTRS_RECORD + "_sha256"):
            return None
        return json.loads(text)
    except Exception:
        return None


def _corrupt_arrays(store: str, plan: dict) -> list[str]:
    """The coordinates whose stored bytes differ from the plan's checksums, and ``"attributes"``
    when a byte of the metadata (attributes included) differs from its record."""
    import zarr

    bad = []
    for name, digest in plan["coords"].items():
        try:
            ok = _digest(zarr.open_array(store, path=name, mode="r")[...]) == digest
        except Exception:  # undecodable metadata or chunk bytes
            ok = False
        if not ok:
            bad.append(name)
    rec = _attrs_record(store)
    ok = rec is not None and rec["metadata"] == _metadata_digests(store)
    return bad + ([] if ok else ["attributes"])


def _repair_layout(store: str, sch: Schema, names) -> None:
    """Rewrite the coordinates ``names`` from the schema and (with ``"attributes"``) every
    attribute from its record; ``ValueError`` naming ``store`` if that does not restore every
    metadata byte (the record itself, or metadata other than attributes, damaged)."""
    import zarr

    group = zarr.open_group(store, mode="r+")
    for name in names:
        if name in sch.coords:
            group[name][...] = sch.coords[name][1]
    if "attributes" in names:
        rec = _attrs_record(store)
        if rec is not None:
            attrs = rec["attributes"]
            group.attrs.put(attrs.pop(""))
            for name, a in attrs.items():
                group[name].attrs.put(a)
        if rec is None or rec["metadata"] != _metadata_digests(store):
            raise ValueError(
                f"store: {store}: metadata damaged beyond its record (start again with --overwrite)"
            )


def _create_layout(store: str, sch: Schema, slab: int, plan: dict, block2: int | None = None):
    """Write coordinates, attributes and lazily allocated variables to ``store`` atomically."""
    import dask.array as da
    import zarr

    parent = os.path.dirname(os.path.abspath(store))
    tmp = tempfile.mkdtemp(prefix=f".{os.path.basename(store)}.", suffix=".tmp", dir=parent)
    try:
        coords = {k: xr.Variable(d, v, a) for k, (d, v, a) in sch.coords.items()}
        data, enc = {}, {}
        for name, (dims, dt, attrs, _) in sch.variables.items():
            shape = tuple(sch.shape[d] for d in dims)
            chunks = _chunks(sch, name, slab, block2)
            data[name] = xr.Variable(dims, da.zeros(shape, dtype=dt, chunks=chunks or ()), attrs)
            enc[name] = {"_FillValue": None, "chunks": chunks} if dims else {"_FillValue": None}
        for k in coords:
            enc[k] = {"_FillValue": None}
        attrs = {**sch.attrs, PLAN_ATTR: json.dumps(plan, sort_keys=True), "atlas_complete": 0}
        ds = xr.Dataset(data, coords=coords, attrs=attrs)
        ds.to_zarr(tmp, mode="w", compute=False, encoding=enc, consolidated=False)
        zarr.open_group(tmp, mode="r+").require_group(TILES)
        _record_attrs(tmp)
        os.chmod(tmp, 0o777 & ~_umask())
        interrupts.check()
        os.replace(tmp, store)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


# --- the tile tasks (run on the workers, or in process) -----------------------------------------


def compute_tile(scene: Scene, tile, opts: dict) -> tuple[xr.Dataset, dict]:
    """One tile of the atlas and its run summary, in this process (a separate function: tests
    slow it down, and :mod:`atlas.bench.distributed` warms the kernels with it)."""
    stats: dict = {}
    ds = generate(
        _sub_scene(scene, tile),
        method=opts["method"],
        dtype=opts["dtype"],
        resolve=opts["resolve"],
        tile_points=opts["tile_points"],
        stats=stats,
    )
    return ds, stats


def _tile_fields(tile) -> dict:
    out = {"start": tile[0], "stop": tile[1]}
    if len(tile) == 4:
        out.update(start2=tile[2], stop2=tile[3])
    return out


def _run_tile(store: str, scene: Scene, i: int, tile, opts: dict) -> dict:
    """Compute tile ``i``, write the regions it owns, read them back, then write its record."""
    import zarr

    _drop_record(store, i)
    t0, c0 = time.perf_counter(), time.process_time()
    ds, stats = compute_tile(scene, tile, opts)
    seconds, cpu = time.perf_counter() - t0, time.process_time() - c0
    split = _split("beta1" in ds.dims, tile)
    names = list(ds.data_vars)
    digests = {k: _digest(ds[k].values) for k in names}
    owned = [k for k in names if _owns(ds[k].dims, split)]
    t1 = time.perf_counter()
    groups = {}
    for k in owned:  # one write per region shape (all variables of a write share its dims)
        groups.setdefault(tuple(_region(ds[k].dims, split)), []).append(k)
    for key, ks in groups.items():
        part = ds[ks]
        part = part.drop_vars(list(part.coords))
        if key:
            region = {d: slice(*split[d]) for d in key}
            part.to_zarr(store, region=region, consolidated=False)
        else:
            part.to_zarr(store, mode="r+", consolidated=False)
    written = _region_digests(_open(store), owned, split)
    for k, h in written.items():
        if h != digests[k]:
            raise OSError(f"store: tile {i} variable {k} reads back different bytes")
    rec = {
        "index": i,
        **_tile_fields(tile),
        "checksums": {k: digests[k] for k in names if _unique(ds[k].dims, split)},
        "shared": {k: digests[k] for k in names if not _unique(ds[k].dims, split)},
        "undecided_fast": {k: int(v.attrs["undecided_fast"]) for k, v in _counted(ds)},
        "undecided": {k: int(v.attrs["undecided"]) for k, v in _counted(ds)},
        "total_undecided_fast": int(ds.attrs["undecided_fast"]),
        "total_undecided": int(ds.attrs["undecided_after_resolve"]),
        "exact_failures": [list(p) for p in stats.get("exact_failures", [])],
        "points": int(stats["points"]),
        "seconds": seconds,
        "cpu_seconds": cpu,
        "write_seconds": time.perf_counter() - t1,
        "source": ds.attrs["source"],
        "host": os.uname().nodename,
        "pid": os.getpid(),
    }
    rec["record_sha256"] = _sha(json.dumps(rec, sort_keys=True))
    zarr.open_group(store, path=_record_path(i), mode="w").attrs.put(rec)
    return rec


def _counted(ds):
    return [(k, v) for k, v in ds.data_vars.items() if "undecided" in v.attrs]


def _verify_tile(store: str, i: int, tile) -> dict | None:
    """The tile's record if the store holds exactly the recorded bytes of the regions it owns."""
    rec = read_record(store, i)
    if rec is None or any(rec.get(k) != v for k, v in _tile_fields(tile).items()):
        return None
    try:
        ds = _open(store)
        split = _split("beta1" in ds.dims, tile)
        recorded = {**rec["checksums"], **rec["shared"]}
        want = {k: h for k, h in recorded.items() if _owns(ds[k].dims, split)}
        got = _region_digests(ds, list(want), split)
    except Exception:  # undecodable chunk bytes
        return None
    return rec if got == want else None


# --- executors ----------------------------------------------------------------------------------


class _InProcess:
    """Runs the tile functions here, one after the other (the reference code path)."""

    workers = 1
    description = "in-process"

    def map(self, fn, calls):
        for key, args in calls:
            yield key, fn(*args)

    def close(self):
        pass


class _Dask:
    def __init__(self, scheduler):
        from distributed import Client

        self.cluster = None
        if isinstance(scheduler, Client):
            self.client, self.own = scheduler, False
        elif isinstance(scheduler, str) and scheduler.split(":")[0] == "local":
            n = scheduler.partition(":")[2]
            n = int(n) if n else (os.cpu_count() or 1)
            self.cluster, self.client = local_cluster(n)
            self.own = True
        elif isinstance(scheduler, str) and "://" in scheduler:
            try:
                self.client, self.own = Client(scheduler), True
            except (OSError, TimeoutError) as e:  # unreachable or not a dask scheduler
                raise OSError(f"scheduler: cannot connect to {scheduler}: {e}") from None
        else:  # pragma: no cover - rejected by _check_scheduler
            raise ValueError(f"scheduler: unsupported {scheduler!r}")
        self.workers = max(1, len(self.client.scheduler_info().get("workers", {})))
        self.description = str(scheduler if isinstance(scheduler, str) else "client")

    def map(self, fn, calls):
        from distributed import as_completed

        futures = {}
        for key, args in calls:
            futures[self.client.submit(fn, *args, pure=False)] = key
        try:
            for fut in as_completed(futures):
                yield futures[fut], fut.result()
        finally:
            self.client.cancel(list(futures))

    def close(self):
        if self.own:
            self.client.close()
        if self.cluster is not None:
            self.cluster.close()


def _check_scheduler(scheduler):
    """``ValueError`` naming ``scheduler`` unless it is None, local[:N], an address or a Client."""
    if scheduler is None or (isinstance(scheduler, str) and "://" in scheduler):
        return
    if isinstance(scheduler, str) and scheduler.split(":")[0] == "local":
        n = scheduler.partition(":")[2]
        if n == "" or (n.isdigit() and int(n) >= 1):
            return
        raise ValueError(f"scheduler: expected local:N with N >= 1, got {scheduler!r}")
    if type(scheduler).__name__ == "Client":
        return
    raise ValueError(
        f"scheduler: expected None, 'local', 'local:N', an address (tcp://host:8786) or a "
        f"distributed.Client, got {scheduler!r}"
    )


def _executor(scheduler):
    _check_scheduler(scheduler)
    if scheduler is None:
        return _InProcess()
    return _Dask(scheduler)


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
    plan = _stored_plan(store)
    ex = _executor(scheduler)
    try:
        report = _verify_all(ex, store, TilePlan.of(plan["tiles"]))[0]
    finally:
        ex.close()
    report["arrays"] = _corrupt_arrays(store, plan)
    return report


def _verify_all(ex, store, tiles):
    report = {"ok": [], "missing": [], "corrupt": []}
    recs = {}
    recorded = [i for i in range(len(tiles)) if read_record(store, i) is not None]
    missing = set(range(len(tiles))) - set(recorded)
    calls = [(i, (store, i, tuple(tiles[i]))) for i in recorded]
    for i, rec in ex.map(_verify_tile, calls):
        if rec is None:
            report["corrupt"].append(i)
        else:
            report["ok"].append(i)
            recs[i] = rec
    report["missing"] = sorted(missing)
    for k in report:
        report[k].sort()
    return report, recs


def _stored_plan(store: str) -> dict:
    import zarr

    if not os.path.isdir(store):
        raise FileNotFoundError(f"store: {store} does not exist")
    try:
        attrs = dict(zarr.open_group(store, mode="r").attrs)
        return json.loads(attrs[PLAN_ATTR])
    except Exception:
        raise ValueError(f"store: {store} is not an atlas store (no {PLAN_ATTR})") from None


def generate_distributed(
    scene: Scene,
    store,
    *,
    scheduler=None,
    slab: int | None = None,
    block2: int | None = None,
    resume: bool = False,
    overwrite: bool = False,
    method: str = "certified",
    dtype: str = "float64",
    resolve: bool = True,
    tile_points: int = DEFAULT_TILE_POINTS,
    to_netcdf=None,
    overwrite_netcdf: bool = False,
    progress=False,
    history: str | None = None,
) -> dict:
    """Generate an atlas tile by tile (on dask workers or in process) into a resumable zarr store.

    Parameters
    ----------
    scene : atlas.Scene
        The atlas; it is split along ``beta1`` (and ``beta2``, see :func:`tile_plan`).
    store : str or os.PathLike
        Zarr directory (a local or shared file system path).
    scheduler : None, "local", "local:N", "tcp://host:port" or distributed.Client
        Where the tiles run (see the module docstring); ``None``: in this process.
    slab : int, optional
        ``beta1`` values per tile (default: about :data:`DEFAULT_SLAB_POINTS` points per tile).
    block2 : int, optional
        ``beta2`` values per tile (2-D tiles); by default ``beta2`` is split only when ``slab`` is
        not given and one ``beta1`` value holds more than :data:`DEFAULT_SLAB_POINTS` points.
    resume : bool
        Continue an existing store: tiles whose record verifies against the stored bytes are
        kept, missing or corrupt ones recomputed.  The store must have been created for the same
        scene, options, tiles and package/JAX versions (else ``ValueError``).
    overwrite : bool
        Replace an existing store (without ``resume``); otherwise an existing store raises
        ``FileExistsError``.
    method, dtype, resolve, tile_points
        As for :func:`atlas.generate` (``tile_points`` = kernel tile inside each slab).
    to_netcdf : str or os.PathLike, optional
        Also convert the finished store to this netCDF4 file, streaming slab by slab through
        :class:`atlas.data.io.NetCDFSink` (atomic; same file as ``io.write_netcdf(generate(scene))``).
    overwrite_netcdf : bool
        Replace an existing netCDF file.
    progress : bool
        tqdm progress bar over tiles on stderr.
    history : str, optional
        Command recorded in the ``history`` attribute.

    Returns
    -------
    dict
        ``store``, ``netcdf``, ``scheduler``, ``workers``, ``tiles``, ``slab``, ``block2``
        (``None``: beta2 not split), ``points``,
        ``computed`` (tiles computed by this call), ``verified`` (kept after verification),
        ``missing`` / ``corrupt`` (found on resume), ``repaired`` (coordinates, ``"attributes"``:
        found damaged on resume and rewritten), ``seconds``, ``points_per_second``,
        ``tile_seconds`` / ``tile_cpu_seconds`` (worker-side wall / CPU time of generating each
        computed tile, compilation included), ``tile_points``, ``undecided_fast``, ``undecided``.
    """
    t0 = time.perf_counter()
    job = _job(scene, store, scheduler, slab, block2, method, dtype, resolve, tile_points, history)
    if to_netcdf is not None:
        check_output_path(to_netcdf, overwrite_netcdf)
    resumed = _prepare_store(job, resume, overwrite)
    ex = _executor(scheduler)
    bar = progress_bar(progress, len(job.tiles), "atlas tiles", unit="tile")
    try:
        report, recs, computed = _run_tiles(ex, job, resumed, bar)
        totals = _finalize(job.store, job.sch, job.plan, job.tiles, recs, computed, resumed)
    finally:
        if bar is not None:
            bar.close()
        ex.close()
    netcdf = _to_netcdf(job.store, job.sch, job.tiles, totals, to_netcdf, overwrite_netcdf)
    seconds = time.perf_counter() - t0
    return _summary(job, ex, netcdf, report, recs, computed, totals, seconds)


@dataclasses.dataclass(frozen=True)
class _Job:
    """One checked call of :func:`generate_distributed`: the scene, the store (absolute path),
    the tiles, the schema of the full atlas, the :func:`atlas.generate` options and the plan."""

    scene: Scene
    store: str
    tiles: TilePlan
    sch: Schema
    opts: dict
    plan: dict

    @property
    def slab(self) -> int:
        """``beta1`` values per tile."""
        return self.tiles[0][1] - self.tiles[0][0]

    @property
    def block2(self) -> int | None:
        """``beta2`` values per tile (``None``: ``beta2`` not split)."""
        first = self.tiles[0]
        return first[3] - first[2] if len(first) == 4 else None


def _job(scene, store, scheduler, slab, block2, method, dtype, resolve, tile_points, history):
    """The checked arguments of :func:`generate_distributed` (one-line errors naming the
    parameter), its tiles, schema and plan."""
    if not isinstance(scene, Scene):
        raise ValueError("scene: expected an atlas.Scene")
    method, dtype, tile_points = check_options(method, dtype, tile_points)
    resolve = checks.boolean("resolve", resolve)
    _check_scheduler(scheduler)
    store = os.path.abspath(os.fspath(store))
    tiles = tile_plan(scene, slab, block2)
    sch = schema(
        scene, method=method, dtype=dtype, resolve=resolve, tile_points=tile_points, history=history
    )
    opts = dict(method=method, dtype=dtype, resolve=bool(resolve), tile_points=tile_points)
    return _Job(scene, store, tiles, sch, opts, _plan(scene, sch, tiles, opts))


def _prepare_store(job: _Job, resume: bool, overwrite: bool) -> bool:
    """Resume an existing store made for the same plan, or lay out a new one (replacing an
    existing store only with ``overwrite``); true when resuming."""
    store = job.store
    exists = os.path.exists(store)
    if exists and resume:
        old = _stored_plan(store)
        if old.get("hash") != job.plan["hash"]:
            diff = [k for k in job.plan if k != "hash" and old.get(k) != job.plan[k]]
            raise ValueError(
                f"store: {store} was created for a different atlas (differs in {', '.join(diff)})"
            )
    elif exists and not overwrite:
        raise FileExistsError(f"store: {store} exists (use resume=True or overwrite=True)")
    else:
        if not os.path.isdir(os.path.dirname(store)):
            raise FileNotFoundError(f"store: directory {os.path.dirname(store)} does not exist")
        if exists:
            shutil.rmtree(store)
        _create_layout(store, job.sch, job.slab, job.plan, job.block2)
    return exists and resume


def _run_tiles(ex, job: _Job, resumed: bool, bar):
    """Verify the recorded tiles (when resuming), then compute the others on ``ex``.

    Returns ``(report, records, computed)``: the verification report (``None`` unless resuming),
    the records of every finished tile, and those of the tiles computed here.
    """
    damaged = []
    if resumed:
        damaged = _corrupt_arrays(job.store, job.plan)
        if damaged:
            _repair_layout(job.store, job.sch, damaged)
    report, recs = _verify_all(ex, job.store, job.tiles) if resumed else (None, {})
    if report is not None:
        report["arrays"] = damaged
    todo = [i for i in range(len(job.tiles)) if i not in recs]
    if bar is not None:
        bar.update(len(recs))
    calls = [(i, (job.store, job.scene, i, job.tiles[i], job.opts)) for i in todo]
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
    }


def _finalize(store, sch, plan, tiles, recs, computed, resumed) -> dict:
    """Check the records, sum the undecided counts, write the final attributes."""
    import zarr

    missing = [i for i in range(len(tiles)) if i not in recs]
    if missing:  # pragma: no cover - every tile either verified or computed
        raise RuntimeError(f"store: tiles {missing} missing after the run")
    dims = {k: v[0] for k, v in sch.variables.items()}
    has_b1 = "beta1" in sch.shape
    seen = {}  # (variable, region) -> (tile, checksum): tiles sharing a region must agree
    var_attrs, fast, final = {}, 0, 0
    for i in sorted(recs):
        rec, split = recs[i], _split(has_b1, tiles[i])
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
            if _owns(dims[k], split):
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
    interrupts.check()  # no store is marked complete after a stop signal
    group = zarr.open_group(store, mode="r+")
    history = str(group.attrs.get("history", sch.attrs["history"]))
    if resumed:
        now = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")
        history += f"\n{now}: resumed, {len(computed)} of {len(tiles)} tiles recomputed"
    for k, a in var_attrs.items():
        group[k].attrs.update(a)
    group.attrs.update({**attrs, "history": history, "atlas_complete": 1})
    _record_attrs(store)  # killed before this: the attributes differ from the record, and a
    # resume restores the recorded ones (atlas_complete = 0) and finishes again
    return {"attrs": attrs, "var_attrs": var_attrs, "history": history}


def _to_netcdf(store, sch, tiles, totals, path, overwrite):
    """Stream the store into a netCDF4 file with the schema's (typed) attributes."""
    if path is None:
        return None
    sink = NetCDFSink(path, overwrite)
    sch = Schema(sch.coords, sch.variables, {**sch.attrs, "history": totals["history"]}, sch.shape)
    ds = _open(store)
    has_b1 = "beta1" in sch.shape
    try:
        sink.begin(sch)  # inside: an interrupt while the header is written still aborts
        for tile in tiles:  # every region once, from the tile that owns it
            split = _split(has_b1, tile)
            for k, (dims, *_) in sch.variables.items():
                if _owns(dims, split):
                    reg = _region(dims, split)
                    index = tuple(reg.get(d, slice(None)) for d in dims)
                    sink.write(k, index, ds[k].isel(reg).values)
        return sink.finish(totals["attrs"], totals["var_attrs"])
    except BaseException:
        sink.abort()
        raise
