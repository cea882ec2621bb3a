"""The checksummed zarr store of an atlas computed tile by tile (its format, not the scheduling).

Layout (a local zarr directory, zarr 2 or 3)::

    STORE/                  the atlas: coordinates, variables, CF attributes (SPEC §2)
    STORE/_tiles/t000012    one empty group per finished tile; its attributes are the tile record

The layout is created up front from :func:`atlas.data.engine.schema` of the full scene
(:func:`create_layout`; arrays allocated lazily: unwritten chunks read as fill values), in a
temporary directory renamed onto ``STORE``.  The store's ``atlas_plan`` attribute is the *plan*
(:func:`make_plan`): the scene, the run options, the tiles (:mod:`atlas.data.tiles`), the
SHA-256 of every coordinate and the package/JAX versions, with a hash of itself.

A tile writes its variables into its region (``beta1`` in ``[start, stop)``, and ``beta2`` in
``[start2, stop2)`` for 2-D blocks; zarr chunks are aligned with the tiles, so concurrent tiles
never touch the same chunk), reads the region back, and only then writes its record
(:func:`write_tile`): the SHA-256 of the raw bytes (dtype, shape, data) of every variable's region,
the undecided counts (over a model box also its counts, :mod:`atlas.data.box_tiles`) and timings,
with a checksum of the record itself.  A variable lacking a split
dimension is written by the tile that owns it (:func:`atlas.data.tiles.owns`); the checksums of the
tiles sharing it (``shared`` in the record) must agree.

Every byte of a store is checked: coordinates against the plan, the raw bytes of every metadata
file (attributes included) against a record in the ``_tiles`` group that also keeps a copy of the
attributes (:func:`record_attrs`, :func:`corrupt_arrays`, :func:`repair_layout`), and each tile
against its record (:func:`verify_tile`).  A finished store has ``atlas_complete = 1``
(:func:`mark_complete`).
"""

from __future__ import annotations

import hashlib
import json
import os
import shutil
import tempfile
import time

import numpy as np
import xarray as xr

from atlas.core import interrupts
from atlas.data import store_guard
from atlas.data import tiles as tiling
from atlas.data.box_tiles import tile_counts
from atlas.data.engine import Schema, block_shape
from atlas.data.tiles import TilePlan

__all__ = [
    "TILES",
    "PLAN_ATTR",
    "FORMAT_VERSION",
    "CHUNK_POINTS",
    "open_store",
    "is_atlas_store",
    "digest",
    "read_record",
    "drop_record",
    "make_plan",
    "stored_plan",
    "check_resumable",
    "create_layout",
    "corrupt_arrays",
    "repair_layout",
    "write_tile",
    "verify_tile",
    "stored_history",
    "mark_complete",
]

#: maximum elements per zarr chunk (chunks never straddle slabs)
CHUNK_POINTS = 1 << 20
TILES = "_tiles"
#: attribute of the ``_tiles`` group: SHA-256 of every attribute of the store
ATTRS_RECORD = "attributes_sha256"
PLAN_ATTR = "atlas_plan"
FORMAT_VERSION = 2
_METADATA = ("zarr.json", ".zarray", ".zattrs", ".zgroup", ".zmetadata")


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


def digest(arr) -> str:
    """SHA-256 of an array's dtype, shape and raw bytes (C order)."""
    a = np.ascontiguousarray(np.asarray(arr))
    h = hashlib.sha256(f"{a.dtype.str}{a.shape}".encode())
    h.update(a.tobytes())
    return h.hexdigest()


def _sha(text: str) -> str:
    return hashlib.sha256(text.encode()).hexdigest()


def make_plan(scene, sch: Schema, tiles, opts: dict) -> dict:
    """The plan of a store: scene, coordinate checksums, variables, tiles, versions and the run
    options ``opts``, with ``hash`` over all of them (a resume must match it)."""
    coords = {k: digest(v) for k, (_, v, _) in sch.coords.items()}
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


def open_store(store) -> xr.Dataset:
    """The atlas in a zarr store (lazy; attributes as stored, flag values as JSON lists)."""
    return xr.open_zarr(os.fspath(store), consolidated=False, chunks=None)


def stored_plan(store: str) -> dict:
    """The plan of an existing store (``FileNotFoundError`` / ``ValueError`` naming ``store``)."""
    import zarr

    if not os.path.isdir(store):
        raise FileNotFoundError(f"store: {store} does not exist")
    try:
        attrs = dict(zarr.open_group(store, mode="r").attrs)
        return json.loads(attrs[PLAN_ATTR])
    except Exception:
        if os.path.isdir(os.path.join(store, TILES)):
            raise ValueError(
                f"store: {store}: its root metadata (zarr.json, {PLAN_ATTR}) is damaged; the same "
                "command with --resume restores it from its record"
            ) from None
        raise ValueError(f"store: {store} is not an atlas store (no {PLAN_ATTR})") from None


def check_resumable(store: str, plan: dict) -> None:
    """Check that ``store`` was made for ``plan`` before a resume: its plan, or, when the root
    metadata is damaged (unreadable, or a plan whose hash is not its own), the copy of the root
    attributes in the intact attribute record, which then restores them.  ``ValueError`` naming
    ``store`` and what differs otherwise."""
    try:
        old = stored_plan(store)
    except ValueError:
        old = None
    if old is not None and old.get("hash") == plan["hash"]:
        return
    rec = _attrs_record(store)
    try:
        copy = json.loads(rec["attributes"][""][PLAN_ATTR]) if rec else None
    except (KeyError, TypeError, ValueError):
        copy = None
    if copy is not None and copy.get("hash") == plan["hash"]:
        _restore_root(store, rec["attributes"][""])
        return
    if old is None:
        raise ValueError(
            f"store: {store} is not an atlas store, or its root metadata and their record are "
            "both damaged (start again with --overwrite)"
        )
    if old.get("model_box") != plan.get("model_box"):
        was, now = (p.get("model_box") or "no model box" for p in (old, plan))
        raise ValueError(
            f"model_box: store {store} was made over {was}, this run asks for {now} (give the "
            "store's --model-box to resume it, or name a new store)"
        )
    diff = [k for k in plan if k != "hash" and old.get(k) != plan[k]] or ["hash"]
    raise ValueError(
        f"store: {store} was created for a different atlas (differs in {', '.join(diff)})"
    )


def _restore_root(store: str, attrs: dict) -> None:
    """Write the root group's metadata anew with the attributes ``attrs`` (its arrays kept)."""
    import zarr

    try:
        zarr.open_group(store, mode="r")
    except Exception:  # unreadable root metadata
        for meta in ("zarr.json", ".zgroup", ".zattrs"):
            if os.path.exists(os.path.join(store, meta)):
                os.unlink(os.path.join(store, meta))
    zarr.open_group(store, mode="a").attrs.put(attrs)


def is_atlas_store(store: str) -> bool:
    """True if ``store`` is a directory this module laid out: a readable plan, or (root metadata
    damaged) the ``_tiles`` group of the tile records."""
    try:
        stored_plan(store)
        return True
    except (OSError, ValueError):
        return any(os.path.isfile(os.path.join(store, TILES, f)) for f in ("zarr.json", ".zgroup"))


# --- tile records -------------------------------------------------------------------------------


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


def drop_record(store: str, i: int):
    """Remove the record of tile ``i`` (before its regions are rewritten)."""
    shutil.rmtree(os.path.join(store, TILES, f"t{i:06d}"), ignore_errors=True)


def _region_digests(ds: xr.Dataset, names, split: dict) -> dict:
    return {k: digest(ds[k].isel(tiling.region(ds[k].dims, split)).values) for k in names}


def _tile_fields(tile) -> dict:
    out = {"start": tile[0], "stop": tile[1]}
    if len(tile) == 4:
        out.update(start2=tile[2], stop2=tile[3])
    return out


def _counted(ds):
    return [(k, v) for k, v in ds.data_vars.items() if "undecided" in v.attrs]


def write_tile(store: str, i: int, tile, ds: xr.Dataset, run: dict) -> dict:
    """Write the regions tile ``i`` owns of its atlas ``ds``, read them back, then write and
    return its record (``run``: ``exact_failures``, ``points``, ``seconds``, ``cpu_seconds`` of
    computing it; over a model box also the tile's ``box_counts``, :mod:`atlas.data.box_tiles`)."""
    import zarr

    split = tiling.ranges("beta1" in ds.dims, tile)
    names = list(ds.data_vars)
    box_counts = tile_counts(ds)
    digests = {k: digest(ds[k].values) for k in names}
    owned = [k for k in names if tiling.owns(ds[k].dims, split)]
    t1 = time.perf_counter()
    groups = {}
    for k in owned:  # one write per region shape (all variables of a write share its dims)
        groups.setdefault(tuple(tiling.region(ds[k].dims, split)), []).append(k)
    for key, ks in groups.items():
        part = ds[ks]
        part = part.drop_vars(list(part.coords))
        if key:
            part.to_zarr(store, region={d: slice(*split[d]) for d in key}, consolidated=False)
        else:
            part.to_zarr(store, mode="r+", consolidated=False)
    written = _region_digests(open_store(store), owned, split)
    for k, h in written.items():
        if h != digests[k]:
            raise OSError(f"store: tile {i} variable {k} reads back different bytes")
    rec = {
        "index": i,
        **_tile_fields(tile),
        "checksums": {k: digests[k] for k in names if tiling.unique(ds[k].dims, split)},
        "shared": {k: digests[k] for k in names if not tiling.unique(ds[k].dims, split)},
        "undecided_fast": {k: int(v.attrs["undecided_fast"]) for k, v in _counted(ds)},
        "undecided": {k: int(v.attrs["undecided"]) for k, v in _counted(ds)},
        "total_undecided_fast": int(ds.attrs["undecided_fast"]),
        "total_undecided": int(ds.attrs["undecided_after_resolve"]),
        **({"box_counts": box_counts} if box_counts else {}),
        "exact_failures": [list(p) for p in run["exact_failures"]],
        "points": int(run["points"]),
        "seconds": run["seconds"],
        "cpu_seconds": run["cpu_seconds"],
        "write_seconds": time.perf_counter() - t1,
        "source": ds.attrs["source"],
        "host": os.uname().nodename,
        "pid": os.getpid(),
    }
    rec["record_sha256"] = _sha(json.dumps(rec, sort_keys=True))
    zarr.open_group(store, path=_record_path(i), mode="w").attrs.put(rec)
    return rec


def verify_tile(store: str, i: int, tile) -> dict | None:
    """The tile's record if the store holds exactly the recorded bytes of the regions it owns."""
    rec = read_record(store, i)
    if rec is None or any(rec.get(k) != v for k, v in _tile_fields(tile).items()):
        return None
    try:
        ds = open_store(store)
        split = tiling.ranges("beta1" in ds.dims, tile)
        recorded = {**rec["checksums"], **rec["shared"]}
        want = {k: h for k, h in recorded.items() if tiling.owns(ds[k].dims, split)}
        got = _region_digests(ds, list(want), split)
    except Exception:  # undecodable chunk bytes
        return None
    return rec if got == want else None


# --- metadata and attributes --------------------------------------------------------------------


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


def record_attrs(store: str) -> None:
    """Record the checksums of the metadata files and a copy of every attribute (to restore
    them), with a checksum of the record itself, in the attributes of the ``_tiles`` group."""
    import zarr

    body = {"metadata": _metadata_digests(store), "attributes": _all_attrs(store)}
    text = json.dumps(body, default=repr)
    zarr.open_group(store, path=TILES, mode="r+").attrs.put(
        {ATTRS_RECORD: text, ATTRS_RECORD + "_sha256": _sha(text)}
    )


def _attrs_record(store: str) -> dict | None:
    """The record of :func:`record_attrs` if it is intact, else ``None``."""
    import zarr

    try:
        rec = dict(zarr.open_group(store, path=TILES, mode="r").attrs)
        text = rec[ATTRS_RECORD]
        if _sha(text) != rec.get(ATTRS_RECORD + "_sha256"):
            return None
        return json.loads(text)
    except Exception:
        return None


def corrupt_arrays(store: str, plan: dict) -> list[str]:
    """The coordinates whose stored bytes differ from the plan's checksums, and ``"attributes"``
    when a byte of the metadata (attributes included) differs from its record."""
    import zarr

    bad = []
    for name, want in plan["coords"].items():
        try:
            ok = digest(zarr.open_array(store, path=name, mode="r")[...]) == want
        except Exception:  # undecodable metadata or chunk bytes
            ok = False
        if not ok:
            bad.append(name)
    rec = _attrs_record(store)
    ok = rec is not None and rec["metadata"] == _metadata_digests(store)
    return bad + ([] if ok else ["attributes"])


def repair_layout(store: str, sch: Schema, names, plan: dict | None = None) -> None:
    """Rewrite the coordinates ``names`` from the schema and (with ``"attributes"``) every
    metadata file from a fresh layout of ``plan`` and every attribute from its record; a damaged
    record is rebuilt from the metadata it describes when that verifies against ``plan`` and the
    schema (:func:`_rebuild_record`).  ``ValueError`` naming ``store`` if that does not restore
    every metadata byte."""
    import zarr

    rec = _attrs_record(store) if "attributes" in names else None
    if rec is not None and plan is not None:
        _fresh_metadata(store, sch, plan, rec["metadata"])
    group = zarr.open_group(store, mode="r+")
    for name in names:
        if name in sch.coords:
            _beyond_repair(store, name, lambda n=name: group[n].__setitem__(..., sch.coords[n][1]))
    if "attributes" not in names:
        return
    if rec is None and plan is not None:
        _rebuild_record(store, sch, plan)
        return
    if rec is not None:
        attrs = rec["attributes"]
        group.attrs.put(attrs.pop(""))
        for name, a in attrs.items():
            _beyond_repair(store, name, lambda n=name, a=a: group[n].attrs.put(a))
    if rec is None or rec["metadata"] != _metadata_digests(store):
        what = "its record" if rec is None else "the metadata other than attributes"
        raise ValueError(
            f"store: {store}: {what} damaged beyond repair (start again with --overwrite)"
        )


def _beyond_repair(store: str, name: str, fix) -> None:
    """``fix()``, or ``ValueError`` naming ``name`` if its array metadata is unreadable."""
    try:
        fix()
    except Exception:
        raise ValueError(
            f"store: {store}: the metadata of {name} is damaged beyond repair (start again with "
            "--overwrite)"
        ) from None


def _fresh_metadata(store: str, sch: Schema, plan: dict, recorded: dict) -> None:
    """Replace every metadata file whose bytes differ from ``recorded`` by the same file of a
    fresh layout of ``plan`` (the layout is a function of the plan; its attributes are then
    restored from the record)."""
    bad = [rel for rel, h in _metadata_digests(store).items() if recorded.get(rel) != h]
    bad += [rel for rel in recorded if not os.path.exists(os.path.join(store, rel))]
    if not bad:
        return
    first = TilePlan.of(plan["tiles"])[0]
    block2 = first[3] - first[2] if len(first) == 4 else None
    with tempfile.TemporaryDirectory() as tmp:
        fresh = os.path.join(tmp, "s")
        create_layout(fresh, sch, first[1] - first[0], plan, block2)
        for rel in bad:
            if os.path.exists(os.path.join(fresh, rel)):
                shutil.copyfile(os.path.join(fresh, rel), os.path.join(store, rel))


def _same_value(a, b) -> bool:
    try:
        return bool(np.array_equal(np.asarray(a), np.asarray(b)))
    except Exception:
        return a == b


def _attrs_differ(store: str, sch: Schema, plan: dict) -> list[str]:
    """What of the store's attributes differs from ``plan`` and the schema: ``"atlas_plan"``,
    global attribute names, variable names (only the attributes the schema fixes are compared:
    the undecided counts and ``history`` are rewritten when a run finishes)."""
    try:
        attrs = _all_attrs(store)
        root = attrs[""]
        bad = [] if json.loads(root[PLAN_ATTR]).get("hash") == plan["hash"] else [PLAN_ATTR]
    except Exception:
        return ["zarr.json"]
    bad += [k for k, v in sch.attrs.items() if k != "history" and not _same_value(root.get(k), v)]
    fixed_attrs = {k: a for k, (_, _, a) in sch.coords.items()}
    fixed_attrs.update({k: v[2] for k, v in sch.variables.items()})
    for name, fixed in fixed_attrs.items():
        got = attrs.get(name, {})
        if any(not _same_value(got.get(k), v) for k, v in fixed.items()):
            bad.append(name)
    return bad


def _rebuild_record(store: str, sch: Schema, plan: dict) -> None:
    """Write the attribute record anew from the store's metadata, after checking that metadata
    against the plan and the schema (``ValueError`` naming what differs otherwise)."""
    import zarr

    for meta in ("zarr.json", ".zgroup", ".zattrs"):  # unreadable: zarr lists no array
        path = os.path.join(store, TILES, meta)
        if os.path.exists(path):
            try:
                zarr.open_group(store, path=TILES, mode="r")
            except Exception:
                os.unlink(path)
    zarr.open_group(store, path=TILES, mode="a")
    bad = _attrs_differ(store, sch, plan)
    if bad:
        raise ValueError(
            f"store: {store}: the record of the attributes is damaged and the attributes differ "
            f"from this atlas in {', '.join(bad)} (start again with --overwrite)"
        )
    record_attrs(store)


def create_layout(store: str, sch: Schema, slab: int, plan: dict, block2: int | None = None):
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
        record_attrs(tmp)
        os.chmod(tmp, 0o777 & ~_umask())
        interrupts.check()
        store_guard.install(tmp, store)  # an existing store is moved aside, never deleted first
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def stored_history(store: str, default: str) -> str:
    """The store's ``history`` attribute (``default`` if it has none)."""
    import zarr

    return str(zarr.open_group(store, mode="r").attrs.get("history", default))


def mark_complete(store: str, attrs: dict, var_attrs: dict) -> None:
    """Write the final global and per-variable attributes, ``atlas_complete = 1``, and record
    them (killed before the record: the attributes differ from it, and a resume restores the
    recorded ones, ``atlas_complete = 0``, and finishes again)."""
    import zarr

    group = zarr.open_group(store, mode="r+")
    for k, a in var_attrs.items():
        group[k].attrs.update(a)
    group.attrs.update({**attrs, "atlas_complete": 1})
    record_attrs(store)
