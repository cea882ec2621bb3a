"""Outcome atlases tile by tile into a resumable store, then one netCDF file.

The tiles are ``beta1`` slabs (:func:`atlas.data.tiles.tile_plan`); each is one
:func:`atlas.dynamics.outcomes.outcome_slab` call.  A cell's runs depend on the cell alone
(its initial states come from :func:`atlas.dynamics.outcome.standard_normals`, the engines run
lane by lane), so the assembled counts equal the single-process atlas bit for bit.

Store layout (a directory)::

    STORE/plan.json       the scene, the dynamics options, the tiles and the package versions
    STORE/t000012.npy     the outcome counts of tile 12 (int16, written atomically)
    STORE/t000012.json    its record: rows, SHA-256 of the ``.npy`` bytes, runs and timings

A record is written only after its tile file, so a killed run leaves finished tiles with records
and at most one tile without.  ``resume=True`` keeps every tile whose record matches the bytes of
its file and recomputes the others; the store must have been made for the same plan (else
``ValueError: store: ...``).  The theory verdicts are computed once, when the file is assembled.
"""

from __future__ import annotations

import contextlib
import hashlib
import io
import json
import math
import os
import re
import shutil
import tempfile

import numpy as np

from atlas.core import checks, config, interrupts
from atlas.data import store_guard
from atlas.data.cluster import check_scheduler, executor
from atlas.data.io import check_output_path, write_netcdf
from atlas.data.scene import Scene
from atlas.data.tiles import tile_plan
from atlas.dynamics.lane_pool import LanePool, check_workers
from atlas.dynamics.outcomes import (
    Dynamics,
    check_scene,
    integer,
    outcome_dataset,
    outcome_slab,
    sum_info,
)

__all__ = ["outcome_atlas_tiles", "default_slab", "is_outcome_store", "TILE_TRAJECTORIES"]

#: default trajectories per tile (a batch of the fast engine)
TILE_TRAJECTORIES = 1 << 15
PLAN = "plan.json"


def default_slab(scene: Scene, n_perturb: int) -> int:
    """``beta1`` values per tile: about :data:`TILE_TRAJECTORIES` trajectories."""
    per_row = n_perturb
    for key, ax in scene.axes.items():
        per_row *= 1 if key == "beta1" else ax.size
    return max(1, min(scene.axes["beta1"].size, round(TILE_TRAJECTORIES / per_row)))


def _sha(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def _plan(scene: Scene, dyn: Dynamics, tiles) -> dict:
    plan = {
        "scene": scene.describe(),
        "coords": {
            k: _sha(np.ascontiguousarray(a.values).tobytes()) for k, a in scene.axes.items()
        },
        "dynamics": dyn.attrs(),
        "tiles": tiles.describe(),
        "source": config.source(),
    }
    plan["hash"] = _sha(json.dumps(plan, sort_keys=True).encode())
    return plan


def _name(i: int, ext: str) -> str:
    return f"t{i:06d}.{ext}"


def _body_sha(rec: dict, key: str) -> str:
    """SHA-256 of a record's JSON without its own checksum field ``key``."""
    body = {k: v for k, v in rec.items() if k != key}
    return _sha(json.dumps(body, sort_keys=True).encode())


def _record(store: str, i: int, tile, plan_hash: str) -> dict | None:
    """The record of tile ``i`` if it is intact (its own checksum), made for the plan
    ``plan_hash`` and matches the bytes of its tile file; ``None`` otherwise (recomputed)."""
    try:
        with open(os.path.join(store, _name(i, "json")), encoding="utf-8") as fh:
            rec = json.load(fh)
        with open(os.path.join(store, _name(i, "npy")), "rb") as fh:
            ok = _sha(fh.read()) == rec["sha256"]
        ok = ok and rec["record_sha256"] == _body_sha(rec, "record_sha256")
    except (OSError, ValueError, KeyError, TypeError):
        return None
    same = rec.get("index") == i and rec.get("rows") == list(tile) and rec.get("plan") == plan_hash
    return rec if ok and same else None


def _write(path: str, data: bytes) -> None:
    """Write a store file at once (temporary file, then ``os.replace``): a store keeps each tile
    as soon as it is finished, also inside :func:`atlas.data.io.committed_together`."""
    tmp = f"{path}.{os.getpid()}.tmp"
    try:
        with open(tmp, "wb") as fh:
            fh.write(data)
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)
        raise


def _verified_records(store: str, tiles, plan_hash: str) -> dict:
    """``{tile index: record}`` of the tiles of ``store`` whose files check (:func:`_record`)."""
    recs = {}
    for i, tile in enumerate(tiles):
        rec = _record(store, i, tile, plan_hash)
        if rec is not None:
            recs[i] = rec
    return recs


def _run_tile(store: str, scene: Scene, dyn: Dynamics, i: int, tile, pool=None,
              plan_hash: str = "") -> dict:  # fmt: skip
    """Compute tile ``i`` (on the processes of ``pool``, if given), write its counts, then its
    record (with the plan's hash and a checksum of itself)."""
    counts, info = outcome_slab(scene, range(*tile), dyn, pool)
    buf = io.BytesIO()
    np.save(buf, counts, allow_pickle=False)
    data = buf.getvalue()
    rec = {"index": i, "rows": list(tile), "sha256": _sha(data), "info": info, "plan": plan_hash}
    rec["record_sha256"] = _body_sha(rec, "record_sha256")
    interrupts.check()
    _write(os.path.join(store, _name(i, "npy")), data)
    _write(os.path.join(store, _name(i, "json")), json.dumps(rec, sort_keys=True).encode())
    return rec


_OWN_FILE = re.compile(r"^(plan\.json|t\d{6}\.(npy|json)|.*\.tmp)$")


def is_outcome_store(store: str) -> bool:
    """True if every entry of the directory ``store`` is a file an outcome store holds, its plan
    among them (the marker :func:`outcome_atlas_tiles` replaces with ``overwrite``)."""
    try:
        names = os.listdir(store)
    except OSError:
        return False
    files = all(os.path.isfile(os.path.join(store, n)) for n in names)
    return PLAN in names and files and all(_OWN_FILE.match(n) for n in names)


def _stored_plan(store: str, plan: dict) -> dict | None:
    """The plan of ``store``: ``plan`` itself when the stored one is ours, damaged or not (a
    damaged one is rewritten from ``plan`` when the stored bytes differ only where a flipped bit
    can be: its own hash or a body whose hash is ours); ``ValueError`` naming what differs."""
    path = os.path.join(store, PLAN)
    try:
        with open(path, encoding="utf-8") as fh:
            text = fh.read()
    except OSError:
        raise ValueError(f"store: {store} is not an outcome-atlas store (no {PLAN})") from None
    try:
        old = json.loads(text)
        intact = isinstance(old, dict) and old.get("hash") == _body_sha(old, "hash")
    except ValueError:
        return None  # unreadable: the tile records decide
    if intact and old["hash"] == plan["hash"]:
        return plan
    diff = (
        [k for k in plan if k != "hash" and old.get(k) != plan[k]] if isinstance(old, dict) else []
    )
    if not intact and (not diff or old.get("hash") == plan["hash"]):
        return None  # damaged where a flipped bit can be: the tile records decide
    what = ", ".join(diff) if diff else "hash"
    raise ValueError(f"store: {store} was made for a different atlas (differs in {what})")


def _prepare(store: str, plan: dict, resume: bool, overwrite: bool, tiles) -> dict:
    """Continue an existing store of the same plan (its verified tile records), or lay out a
    new one (replacing a store the project wrote, only with ``overwrite``); ``None`` when new.

    A damaged ``plan.json`` is rewritten from ``plan`` when at least one tile record made for
    ``plan`` verifies against its data (the records carry the plan's hash), refused otherwise."""
    if resume:
        if not os.path.isdir(store):
            raise FileNotFoundError(f"resume: store {store} does not exist")
        stored = _stored_plan(store, plan)
        recs = _verified_records(store, tiles, plan["hash"])
        if stored is None:
            if not recs:
                raise ValueError(
                    f"store: {store}: {PLAN} is damaged and no tile record confirms it (start "
                    "again with overwrite)"
                )
            _write(os.path.join(store, PLAN), json.dumps(plan, sort_keys=True).encode())
        return recs
    exists = store_guard.check_replaceable(store, is_outcome_store, "an outcome-atlas store")
    if exists and not overwrite:
        raise FileExistsError(f"store: {store} exists (use resume or overwrite)")
    parent = os.path.dirname(store)
    if not os.path.isdir(parent):
        raise FileNotFoundError(f"store: directory {parent} does not exist")
    tmp = tempfile.mkdtemp(prefix=f".{os.path.basename(store)}.", suffix=".tmp", dir=parent)
    try:
        with open(os.path.join(tmp, PLAN), "w", encoding="utf-8") as fh:
            json.dump(plan, fh, sort_keys=True)
        store_guard.install(tmp, store)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    return None


def _assemble(store: str, plan: dict, recs: dict, n: int) -> np.ndarray:
    """The counts of every tile, read back and checked against this run's records and plan:
    ``RuntimeError`` naming the store if anything changed under the run."""
    try:
        ok = _stored_plan(store, plan) is plan
    except ValueError:
        ok = False
    parts = []
    for i in range(n):
        with open(os.path.join(store, _name(i, "npy")), "rb") as fh:
            data = fh.read()
        if not ok or _sha(data) != recs[i]["sha256"]:
            raise RuntimeError(
                f"store: {store} changed under this run ({PLAN if not ok else _name(i, 'npy')} "
                "is not what this run wrote or verified); no file written"
            )
        parts.append(np.load(io.BytesIO(data), allow_pickle=False))
    return np.concatenate(parts)


def outcome_atlas_tiles(
    scene: Scene,
    store,
    *,
    dynamics: Dynamics | None = None,
    slab: int | None = None,
    resume: bool = False,
    overwrite: bool = False,
    to_netcdf=None,
    overwrite_netcdf: bool = False,
    theory: bool = True,
    progress=None,
    history: str | None = None,
    scheduler=None,
    workers: int | None = 1,
) -> dict:
    """An outcome atlas tile by tile into the store directory ``store`` (see the module
    docstring), then, with ``to_netcdf``, the netCDF file of
    :func:`atlas.dynamics.outcomes.outcome_dataset` (atomic).

    Parameters
    ----------
    scene : atlas.Scene
        The parameters (``alpha`` required).
    store : path-like
        Store directory (its parent must exist).
    dynamics : Dynamics, optional
        Runs per cell, horizon, engine (default :class:`Dynamics` ``()``).
    slab : int, optional
        ``beta1`` values per tile (default :func:`default_slab`).
    resume, overwrite : bool
        Continue an existing store (same plan), or replace it.
    to_netcdf : path-like, optional
        The assembled atlas; ``overwrite_netcdf`` replaces an existing file.
    theory : bool
        Add the certified theory verdicts of the same cells.
    progress : callable, optional
        Called with ``(trajectories done, trajectories)`` after each tile.
    history : str, optional
        Command recorded in ``history``.
    scheduler : None, "local", "local:N", "tcp://host:port" or a distributed.Client
        Where the tiles run (:func:`atlas.data.cluster.executor`): in this process, on a dask
        LocalCluster of N single-thread workers, or on a running cluster whose workers see
        ``store``.
    workers : int or None
        Processes of the fast engine per tile in this process
        (:class:`atlas.dynamics.lane_pool.LanePool`; ``None``: the usable cores); 1 with a
        ``scheduler``.

    Returns
    -------
    dict
        ``store``, ``netcdf``, ``dataset`` (the assembled atlas), ``tiles``, ``slab``,
        ``computed`` and ``verified`` (tile indices), ``trajectories``, ``seconds``.
    """
    flags = dict(resume=resume, overwrite=overwrite, theory=theory,
                 overwrite_netcdf=overwrite_netcdf)  # fmt: skip
    scene, dyn, workers = _checked(scene, dynamics, scheduler, workers, flags)
    store = store_guard.check_place(store)
    slab = default_slab(scene, dyn.n_perturb) if slab is None else integer("slab", slab)
    tiles = tile_plan(scene, slab=slab)
    plan = _plan(scene, dyn, tiles)
    if to_netcdf is not None:
        check_output_path(to_netcdf, overwrite_netcdf)
    with store_guard.held(store, ours=is_outcome_store):
        counts, recs, resumed = _run_store(store, scene, dyn, tiles, plan, resume, overwrite,
                                           (scheduler, workers, progress))  # fmt: skip
    verified = sorted(resumed or {})
    info = sum_info(recs[i]["info"] for i in range(len(tiles)))
    call = _history(history, resumed is not None, len(tiles), len(verified))
    ds = outcome_dataset(scene, counts, dyn, info, theory=theory, history=call)
    netcdf = None
    if to_netcdf is not None:
        netcdf = write_netcdf(ds, to_netcdf, overwrite=overwrite_netcdf)
    computed = sorted(set(range(len(tiles))) - set(verified))
    return {"store": store, "netcdf": netcdf, "dataset": ds, "tiles": len(tiles), "slab": slab,
            "computed": computed, "verified": verified, "trajectories": int(info["trajectories"]),
            "seconds": float(info["seconds"])}  # fmt: skip


def _history(history, resumed: bool, tiles: int, verified: int):
    """The ``history`` of an atlas, saying how many tiles a resumed run computed."""
    if not resumed:
        return history
    return (history or "atlas.dynamics.outcome_tiles.outcome_atlas_tiles(...)") + (
        f" (resumed: {tiles - verified} of {tiles} tiles computed)"
    )


def _checked(scene, dynamics, scheduler, workers, flags):
    """``(scene, dynamics, workers)`` of :func:`outcome_atlas_tiles` checked (one-line
    ``ValueError`` naming the parameter); ``flags``: its booleans by name."""
    scene = check_scene(scene)
    for name, v in flags.items():
        checks.boolean(name, v)
    dyn = Dynamics() if dynamics is None else dynamics
    if not isinstance(dyn, Dynamics):
        raise ValueError("dynamics: expected an atlas.dynamics.Dynamics")
    check_scheduler(scheduler)
    workers = check_workers(workers)
    if scheduler is not None and workers > 1:
        raise ValueError(
            f"workers: the tiles run on the scheduler's workers, give 1, got {workers}"
        )
    return scene, dyn, workers


def _run_store(store, scene, dyn, tiles, plan, resume, overwrite, where):
    """Prepare the store, compute the tiles not verified, and assemble the counts: ``(counts,
    records, verified records on resume or None)``."""
    scheduler, workers, progress = where
    resumed = _prepare(store, plan, resume, overwrite, tiles)
    recs = dict(resumed or {})
    total = math.prod(a.size for a in scene.axes.values()) * dyn.n_perturb

    def report():
        if progress is not None:
            progress(sum(r["info"]["trajectories"] for r in recs.values()), total)

    report()
    ex = executor(scheduler)
    pool = LanePool(workers) if scheduler is None else None
    todo = [(i, (store, scene, dyn, i, tile, pool, plan["hash"])) for i, tile in enumerate(tiles)
            if i not in recs]  # fmt: skip
    try:
        for i, rec in ex.map(_run_tile, todo):
            recs[i] = rec
            interrupts.check()
            report()
    finally:
        ex.close()
        if pool is not None:
            pool.close()
    return _assemble(store, plan, recs, len(tiles)), recs, resumed
