"""``atlas generate``: its options -> a :class:`~atlas.data.scene.Scene` and
:class:`~atlas.data.engine.RunOptions` -> a streamed netCDF4 file
(:func:`atlas.data.io.generate_to_file`) or, with ``--scheduler``/``--store``/``--resume``/
``--slab``/``--block2``, tiles into a resumable zarr store
(:func:`atlas.data.distributed.generate_distributed`) and then netCDF; ``--model-box`` adds the
verdicts over a box of models either way.

Every refusal is one line naming the option (``ValueError``/``OSError``, exit 2 from
:mod:`atlas.cli`), raised before any computation; a killed or failed store run says that
``--resume`` continues it.
"""

from __future__ import annotations

import importlib.util
import os
import sys

from atlas.core.config import use_compile_cache
from atlas.data.engine import DEFAULT_TILE_POINTS, RunOptions
from atlas.data.io import check_output_path, generate_to_file
from atlas.data.limits import generate_estimate
from atlas.data.scene import Scene, builtin
from atlas.data.store_guard import settle, write_failure

__all__ = ["run_cli", "scene_from_options", "parse_physical"]

#: the physical contact parameters ``--physical`` takes (:meth:`Scene.from_physical`)
PHYSICAL = ("k1", "k2", "q1", "q2", "b1", "b2")


def run_cli(
    *,
    scene=None,
    physical=None,
    outputs=None,
    out=None,
    overwrite=False,
    method="certified",
    dtype="float64",
    resolve=True,
    tile_points=DEFAULT_TILE_POINTS,
    progress=False,
    history=None,
    dry_run=False,
    no_size_check=False,
    scheduler=None,
    store=None,
    resume=False,
    slab=None,
    block2=None,
    model_box=None,
    **ranges,
) -> int:
    """``atlas generate`` (the options of its parser; ``ranges``: ``beta1 ... q2`` of
    :func:`scene_from_options`; ``history``: the command line)."""
    sc = scene_from_options(scene, physical, outputs, **ranges)
    opts = RunOptions(method, dtype, resolve, tile_points, progress, history)
    screen = (dry_run, no_size_check)
    if resume or any(a is not None for a in (scheduler, store, slab, block2)):
        where = dict(scheduler=scheduler, store=store, resume=resume, slab=slab, block2=block2)
        return _run_store(sc, opts, out, overwrite, screen, model_box=model_box, **where)
    if model_box is not None:
        return _run_over_models(sc, opts, out, overwrite, screen, model_box)
    out = out if out is not None else f"{sc.name}.nc"
    check_output_path(out, overwrite)  # fail before any computation
    estimate = generate_estimate(sc, dtype=opts.dtype, tile_points=opts.tile_points, outputs=[out])
    if estimate.screen(*screen):
        return 0
    use_compile_cache()
    stats = generate_to_file(sc, out, opts, overwrite=overwrite)
    print(
        f"atlas generate: {stats['path']}: {stats['points']} points in {stats['seconds']:.2f} s "
        f"({stats['points_per_second']:.3g} points/s), {stats['bytes'] / 1e6:.2f} MB; "
        f"undecided {stats['undecided_fast']} before, {stats['undecided']} after exact resolution",
        file=sys.stderr,
    )
    return 0


def _run_over_models(sc, opts, out, overwrite, screen, model_box) -> int:
    """``--model-box``: the atlas in memory plus ``ss_over_models`` and the II verdicts over the
    box (:mod:`atlas.data.over_models`),
    written atomically."""
    from atlas.data import over_models  # noqa: PLC0415 - only on request
    from atlas.data.engine import generate  # noqa: PLC0415
    from atlas.data.io import write_netcdf  # noqa: PLC0415

    box = over_models.as_model_box(model_box)  # refused before any work
    out = out if out is not None else f"{sc.name}.nc"
    check_output_path(out, overwrite)
    estimate = generate_estimate(
        sc, dtype=opts.dtype, tile_points=opts.tile_points, outputs=[out], model_box=box
    )
    if estimate.screen(*screen):
        return 0
    use_compile_cache()
    ds = generate(sc, opts, model_box=box)
    write_netcdf(ds, out, overwrite=overwrite, tile_points=opts.tile_points)
    print(
        f"atlas generate: {out}: over the model box {box}: "
        f"{ds.attrs['over_models_seconds']:.2f} s, undecided "
        f"{ds.attrs['over_models_undecided_before_settlement']} before, "
        f"{ds.attrs['over_models_undecided']} after settlement; II: "
        f"{ds.attrs['ii_over_models_seconds']:.2f} s, undecided "
        f"{ds.attrs['ii_over_models_undecided_before_settlement']} before, "
        f"{ds.attrs['ii_over_models_undecided']} after",
        file=sys.stderr,
    )
    return 0


def scene_from_options(
    scene=None,
    physical=None,
    outputs=None,
    beta1=None,
    beta2=None,
    alpha=None,
    kappa=None,
    q=None,
    q1=None,
    q2=None,
) -> Scene:
    """A built-in ``scene`` (its fields overridden by the given ranges) or explicit ranges; with
    ``physical`` (``"k1=..,k2=..[,q1=..,q2=..,b1=..,b2=..]"``) the model comes from the physical
    contact parameters (:meth:`Scene.from_physical`) instead of ``kappa``/``q``."""
    given = dict(beta1=beta1, beta2=beta2, alpha=alpha, kappa=kappa, q=q, q1=q1, q2=q2)
    fields = {k: v for k, v in given.items() if v is not None}
    if outputs is not None:
        fields["outputs"] = outputs
    model = None
    if physical is not None:
        for k in ("kappa", "q", "q1", "q2"):
            if k in fields:
                raise ValueError(f"physical: conflicts with --{k}")
        model = parse_physical(physical)
    if "q" in fields and ("q1" in fields or "q2" in fields):
        raise ValueError("q: give either --q or --q1 and --q2, not both")
    base = builtin(scene, **fields) if scene else None
    if model is None:
        return base if base is not None else Scene(**fields)
    if base is not None:
        fields = {f: getattr(base, f) for f in ("beta1", "beta2", "alpha", "outputs", "name")}
    return Scene.from_physical(**model, **fields)


def parse_physical(text: str) -> dict:
    """``"k1=100,k2=200,q1=20"`` -> ``{"k1": 100.0, ...}`` (``k1`` and ``k2`` required; one-line
    errors naming the parameter; the values are checked by :meth:`Scene.from_physical`)."""
    kw = {}
    for item in text.split(","):
        if not item.strip():
            continue
        if "=" not in item:
            raise ValueError(f"physical: expected key=value, got {item.strip()!r}")
        key, val = (s.strip() for s in item.split("=", 1))
        if key not in PHYSICAL:
            raise ValueError(f"physical: unknown parameter {key!r} ({', '.join(PHYSICAL)})")
        if key in kw:
            raise ValueError(f"physical: {key} given twice")
        try:
            kw[key] = float(val)
        except ValueError:
            raise ValueError(f"{key}: cannot parse {val!r} as a number") from None
    for key in ("k1", "k2"):
        if key not in kw:
            raise ValueError(f"physical: {key} is required")
    return kw


# --- tiles into a zarr store --------------------------------------------------------------------


def _run_store(
    sc, opts, out, overwrite, screen, *, scheduler, store, resume, slab, block2, model_box=None
) -> int:
    """``--scheduler/--store/--resume``: tiles into a zarr store, then netCDF (with
    ``--model-box`` the verdicts over the box in every tile, :mod:`atlas.data.box_tiles`)."""
    if model_box is not None:
        from atlas.data.over_models import as_model_box  # noqa: PLC0415 - only on request

        model_box = as_model_box(model_box)  # refused before any work
    scheduler = scheduler_arg(scheduler or "inprocess")
    _require_dask(scheduler)
    store = _store_path(sc, out, store, resume, overwrite)
    outs = [store] if out is None else [store, out]
    if out is not None:
        check_output_path(out, overwrite)  # fail before any computation
    estimate = generate_estimate(
        sc,
        dtype=opts.dtype,
        tile_points=opts.tile_points,
        distributed=True,
        workers=_local_workers(scheduler),
        outputs=outs,
        model_box=model_box,
    )
    if estimate.screen(*screen):
        return 0
    use_compile_cache()
    from atlas.data.distributed import generate_distributed  # noqa: PLC0415 - xarray, dask: only here

    try:
        s = generate_distributed(
            sc,
            store,
            opts,
            scheduler=scheduler,
            slab=slab,
            block2=block2,
            resume=resume,
            overwrite=overwrite,
            to_netcdf=out,
            overwrite_netcdf=overwrite,
            model_box=model_box,
        )
    except KeyboardInterrupt:
        if not os.path.isdir(store):
            raise
        raise KeyboardInterrupt(
            f"finished tiles are kept in {store}: continue with the same command and --resume"
        ) from None
    except (OSError, RuntimeError) as e:
        err = write_failure(store, e)
        if err is None:  # not a failed write (a refused argument, a bug)
            raise
        raise err from None
    print(_summary(s), file=sys.stderr)
    return 0


def scheduler_arg(text: str):
    """``--scheduler`` -> the ``scheduler`` argument of ``generate_distributed``."""
    if text == "inprocess":
        return None
    kind, _, n = text.partition(":")
    if kind == "local":
        if text == "local" or (n.isdigit() and int(n) >= 1):
            return text
        raise ValueError(f"scheduler: expected local:N with N >= 1, got {text!r}")
    proto, sep, address = text.partition("://")
    if sep and proto and address:
        return text
    raise ValueError(
        f"scheduler: expected inprocess, local, local:N or a scheduler address tcp://HOST:PORT, "
        f"got {text!r}"
    )


def _local_workers(scheduler) -> int:
    """Worker processes of a ``local[:N]`` scheduler (1 otherwise: the estimate's worst case)."""
    if isinstance(scheduler, str) and scheduler.startswith("local"):
        n = scheduler.partition(":")[2]
        return int(n) if n else (os.cpu_count() or 1)
    return 1


def _store_path(sc, out, store, resume, overwrite) -> str:
    """The zarr store of ``--store`` (default: the netCDF name with ``.zarr``), checked against
    ``--resume`` / ``--overwrite``."""
    stem = out if out is not None else f"{sc.name}.nc"
    store = store or (os.path.splitext(stem)[0] + ".zarr")
    if resume and overwrite:
        raise ValueError("resume: --resume continues the store, --overwrite replaces it; not both")
    from atlas.data.tile_store import is_atlas_store  # noqa: PLC0415 - xarray: only here

    settle(store, is_atlas_store)  # the old copy a killed replacement left beside the store
    if resume and not os.path.exists(store):
        raise FileNotFoundError(f"resume: store {store} does not exist")
    if os.path.exists(store) and not (resume or overwrite):
        raise FileExistsError(
            f"store: {store} exists (use --resume to continue it or --overwrite to replace it)"
        )
    return store


def _summary(s: dict) -> str:
    """The line ``atlas generate`` prints for a :func:`generate_distributed` summary."""
    where = s["store"] if s["netcdf"] is None else f"{s['netcdf']} (store {s['store']})"
    return (
        f"atlas generate: {where}: {s['points']} points in {s['seconds']:.2f} s "
        f"({s['points_per_second']:.3g} points/s) on {s['scheduler']} with {s['workers']} "
        f"worker(s); {s['tiles']} tiles: {len(s['computed'])} computed, {len(s['verified'])} "
        f"verified, {len(s['missing'])} missing and {len(s['corrupt'])} corrupt before; "
        + (f"repaired {', '.join(s['repaired'])}; " if s.get("repaired") else "")
        + f"undecided {s['undecided_fast']} before, {s['undecided']} after exact resolution"
        + (_box_summary(s["over_models"]) if "over_models" in s else "")
    )


def _box_summary(a: dict) -> str:
    """The part of :func:`_summary` about the verdicts over a model box (their counts)."""
    return (
        f"; over the model box {a['model_box']}: undecided "
        f"{a['over_models_undecided_before_settlement']} before, {a['over_models_undecided']} "
        f"after settlement; II: undecided {a['ii_over_models_undecided_before_settlement']} "
        f"before, {a['ii_over_models_undecided']} after"
    )


def _require_dask(scheduler) -> None:
    """``ValueError`` naming ``scheduler`` if zarr (and, for a cluster, distributed) is missing."""
    needed = ("zarr", "dask") if scheduler is None else ("zarr", "dask", "distributed")
    missing = [m for m in needed if importlib.util.find_spec(m) is None]
    if missing:  # pragma: no cover - the dask extra is missing
        raise ValueError(
            f"scheduler: needs the dask extra (pip install -e '.[dask]'): no {', '.join(missing)}"
        )
