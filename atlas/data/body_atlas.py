"""Atlases of real mechanisms: built-in bodies over physical axes.

A mechanism scene sweeps physical parameters of a built-in body (the registry
:mod:`atlas.core.bodies`: e.g. the ladder's angle ``theta`` [rad] and friction coefficient ``mu``
[1]) and stores, on those physical coordinates (with units), the derived invariants ``beta1, beta2, alpha, kappa, q1, q2``,
the entries of ``B`` [1/kg] and ``a`` [m/s^2] of eq. (1), and every verdict of the atlas at them,
so ``ds.sel(mu=0.6, method="nearest")`` reads one body's verdicts.  One friction coefficient
``mu`` applies to both contacts.  The verdicts (every atlas output of the registry with a verdict
kernel, :func:`atlas.data.outputs.verdict_outputs`) are those of
:func:`atlas.core.rigid_body.verdicts_at` (certified kernels, undecided points settled exactly).

Every parameter that is not an axis is stored with its units (:func:`stored_units`): the body's own
declared parameters (e.g. the ladder's ``L`` [m], ``m`` [kg]), the derived ``I`` [kg m2], the contact model ``k1, k2`` [N/m],
``c1, c2`` [N s/m], gravity ``g`` [m s-2] (along ``-y``) and the state's ``speed`` [m/s] (contact 1's
sliding speed; default 0, the zero-speed limit), the sliding signs ``s1, s2`` and, as attributes, the
contact kinds.  ``fixed={"L": 3.0, "c1": 20.0}`` (CLI ``--fixed L=3,c1=20``) changes them; every value
goes through the validation of :mod:`atlas.core.rigid_body` and the declared ranges.

``model_box=`` (CLI ``--model-box kappa=0.01:100,q1=0:1,q2=0:1``) adds, per body, the verdicts over
that box of contact models (``ss_over_models`` and its witness models, :mod:`atlas.data.box_points`):
for the body's geometry ``(beta1, beta2)``, whether SS is stable for every model of the box, for
none, or depends on the model -- the body's own ``kappa, q1, q2`` replaced by the box.
"""

from __future__ import annotations

import math
import shlex

import numpy as np
import xarray as xr

from atlas.core import checks, config
from atlas.core.bodies import BODIES, DERIVED, MODEL, Body
from atlas.core.rigid_body import body_invariants, verdicts_at
from atlas.data import limits
from atlas.data.engine import REFERENCES
from atlas.data.io import check_output_path, write_netcdf
from atlas.data.outputs import coord_attrs, storage_dtype, variable_attrs, verdict_outputs
from atlas.data.scene import parse_values

__all__ = ["MECHANISM_SCENES", "MechanismScene", "mechanism_atlas", "run_cli", "stored_units"]


#: a mechanism scene is a body of the registry (:class:`atlas.core.bodies.Body`: ``axes`` maps an
#: axis name to ``(default range, units, long_name, body parameters it sets)``)
MechanismScene = Body
#: the built-in mechanism scenes: the body registry itself (a body registered at run time is one)
MECHANISM_SCENES = BODIES

_INVARIANTS = {
    "beta1": None,
    "beta2": None,
    "alpha": None,
    "kappa": None,
    "q1": None,
    "q2": None,
    "b11": ("1/kg", "B_11 of eq. (1): gap 1 response to a unit normal force at contact 1"),
    "b12": ("1/kg", "B_12 of eq. (1): gap 1 response to a unit normal force at contact 2"),
    "b21": ("1/kg", "B_21 of eq. (1): gap 2 response to a unit normal force at contact 1"),
    "b22": ("1/kg", "B_22 of eq. (1): gap 2 response to a unit normal force at contact 2"),
    "a1": ("m s-2", "a_1 of eq. (1): free acceleration term of gap 1"),
    "a2": ("m s-2", "a_2 of eq. (1): free acceleration term of gap 2"),
}


#: the contact model and state, with their defaults (SI)
_MODEL = {k: default for k, (_u, _l, default) in MODEL.items()}


def stored_units(scene: MechanismScene) -> dict:
    """Units and long names of every parameter a mechanism atlas of ``scene`` stores (axes or
    fixed values): the body's declared parameters, the contact model and state, ``m, I, s1, s2``."""
    out = {k: (p.units, p.meaning) for k, p in scene.params.items()}
    out.update({k: (u, long_name) for k, (u, long_name, _d) in MODEL.items()})
    return {**out, **DERIVED}


def _fixed_values(scene: MechanismScene, fixed: dict) -> dict:
    """Every non-axis parameter: the body function's defaults and the model's, ``fixed`` applied."""
    sets = {p for *_r, ps in scene.axes.values() for p in ps}
    out = {k: v for k, v in scene.defaults.items() if k not in sets}
    out.update(_MODEL)
    unknown = sorted(set(fixed) - set(out))
    if unknown:
        raise ValueError(
            f"fixed: {unknown[0]!r} is not a fixed parameter of {scene.body} ({', '.join(out)})"
        )
    out.update(fixed)
    return out


def _axis_values(scene: MechanismScene, overrides: dict) -> dict:
    unknown = set(overrides) - set(scene.axes)
    if unknown:
        raise ValueError(
            f"{sorted(unknown)[0]}: not an axis of {scene.body} ({', '.join(scene.axes)})"
        )
    out = {}
    for name, (default, *_rest) in scene.axes.items():
        values, _ = parse_values(overrides.get(name, default), name)
        out[name] = np.atleast_1d(values)
    return out


def _validated(scene: MechanismScene, build):
    """``build()``, its one-line ``ValueError`` naming a body parameter that an axis sets renamed to
    the axis (``mu_floor: must be >= 0`` -> ``mu: ...``): the checks are those of
    :mod:`atlas.core.rigid_body`, one validation for every path."""
    try:
        return build()
    except ValueError as e:
        name, sep, rest = str(e).partition(": ")
        for axis, (_d, _u, _l, sets) in scene.axes.items():
            if sep and name in sets:
                raise ValueError(f"{axis}: {rest}") from None
        raise


def mechanism_atlas(
    name: str,
    *,
    dtype: str = "float64",
    fixed: dict | None = None,
    history: str | None = None,
    model_box=None,
    size_check: bool = True,
    **axes,
) -> xr.Dataset:
    """The atlas of built-in mechanism scene ``name`` (:data:`MECHANISM_SCENES`) over its physical
    axes (ranges in the syntax of :func:`atlas.data.scene.parse_values`, e.g. ``mu="0:2:101"``).

    ``fixed``: values of the other parameters (module docstring; SI units of :func:`stored_units`);
    ``history``: the command recorded in ``history`` (default: this call, every axis range and fixed
    value); ``model_box``: a box of contact models (:class:`~atlas.core.model_box.ModelBox`, its
    text or a dict) whose verdicts are added; ``size_check``: refuse a grid too large for the memory
    available, as the command line does (:func:`atlas.data.limits.grid_estimate`).
    """
    if name not in MECHANISM_SCENES:
        raise ValueError(f"mechanism: unknown {name!r} (built-in: {', '.join(MECHANISM_SCENES)})")
    box = None if model_box is None else _checked_box(model_box)
    dtype = checks.float_dtype(dtype)
    scene = MECHANISM_SCENES[name]
    consts = _fixed_values(scene, dict(fixed or {}))
    values = _axis_values(scene, axes)
    if size_check:
        points = math.prod(v.size for v in values.values())
        limits.grid_estimate("mechanism", points, **limits.MECHANISM).check()
    grids = np.meshgrid(*values.values(), indexing="ij")
    params = {k: v for k, v in consts.items() if k not in _MODEL}
    for (_d, _u, _l, sets), grid in zip(scene.axes.values(), grids):
        params.update({p: grid for p in sets})
    model = {k: consts[k] for k in ("k1", "k2", "c1", "c2", "speed")}

    def build():
        body = scene(**params)
        g = _real_g(consts["g"])
        return body, body_invariants(body, **model, g=(0.0, -g))

    body, inv = _validated(scene, build)
    # an invariant that no axis changes (a block's alpha over mu) spans the grid too
    inv = {k: np.broadcast_to(v, grids[0].shape) for k, v in inv.items()}
    names = verdict_outputs()
    verdicts = verdicts_at(
        *(inv[k] for k in ("beta1", "beta2", "alpha", "kappa", "q1", "q2")),
        dtype=dtype,
        names=names,
    )
    dims = tuple(scene.axes)
    data = {}
    for k, meta in _INVARIANTS.items():
        attrs = coord_attrs(k) if meta is None else {"units": meta[0], "long_name": meta[1]}
        data[k] = (dims, inv[k], attrs)
    for k in names:
        data[k] = (dims, verdicts[k].astype(storage_dtype(k, dtype)), variable_attrs(k))
    data["omega"] = (dims, inv["omega"], {"units": "rad s-1", "long_name": "angular velocity"})
    coords = {
        axis: (axis, values[axis], {"units": units, "long_name": long_name})
        for axis, (_d, units, long_name, _s) in scene.axes.items()
    }
    stored = dict(consts)
    stored.update(m=body["m"], I=body["I"], s1=body["s1"], s2=inv["s2"])
    coords.update(_stored_coords(scene, stored, dims, inv["beta1"].shape))
    if history is None:
        history = _call(name, _specs(scene, axes), fixed, box, dtype)
    attrs = {
        "Conventions": "CF-1.10",
        "title": f"painleve-atlas mechanism scene {name!r}: {scene.description}",
        "source": config.source(),
        "history": config.history(history),
        "references": REFERENCES,
        "mechanism": scene.body,
        "dtype": dtype,
        "contact1_kind": body.get("kind1", "body_vertex"),
        "contact2_kind": body.get("kind2", "body_vertex"),
    }
    if box is not None:
        attrs.update(_add_box_verdicts(data, dims, inv, box, dtype))
    return xr.Dataset(data, coords=coords, attrs=attrs)


def _stored_coords(scene, stored: dict, dims: tuple, shape: tuple) -> dict:
    """The parameters that are no axis as coordinates with their units: a scalar where the
    value is the same everywhere, else over the axes."""
    units = stored_units(scene)
    coords = {}
    for k, v in stored.items():
        v = np.asarray(v, np.float64)
        v = np.broadcast_to(v, shape) if v.ndim else v
        if v.ndim and np.all(v == v.flat[0]):
            v = v.flat[0]
        unit, long_name = units[k]
        coords[k] = (dims if np.ndim(v) else (), v, {"units": unit, "long_name": long_name})
    return coords


def _call(name: str, specs: dict, fixed, box, dtype: str) -> str:
    """The ``mechanism_atlas`` call that made the atlas (its ``history``)."""
    args = [f"{a}={values_spec!r}" for a, values_spec in specs.items()]
    args += [f"fixed={dict(fixed)!r}"] if fixed else []
    args += [f"model_box={str(box)!r}"] if box is not None else []
    return f"atlas.mechanism_atlas({', '.join([repr(name), *args, f'dtype={dtype!r}'])})"


def _checked_box(model_box):
    from atlas.data.over_models import as_model_box  # noqa: PLC0415 - only on request

    return as_model_box(model_box)


def _add_box_verdicts(data: dict, dims: tuple, inv: dict, box, dtype) -> dict:
    """The verdicts over ``box`` at every body's ``(beta1, beta2)`` added to ``data``; returns
    the attributes (the box, undecided counts before and after the settlement)."""
    from atlas.data.box_points import point_values  # noqa: PLC0415 - only on request

    res = point_values(inv["beta1"], inv["beta2"], box, dtype=dtype)
    stats = res.pop("stats")
    for k, v in res.items():
        data[k] = (dims, v.astype(storage_dtype(k, dtype)), variable_attrs(k))
    return {
        "model_box": str(box),
        "over_models_undecided_before_settlement": int(stats.get("undecided_before", 0)),
        "over_models_undecided": int(stats.get("undecided_after", 0)),
    }


def _real_g(g) -> float:
    try:
        g = float(g)
    except (TypeError, ValueError):
        raise ValueError(f"g: cannot interpret {g!r} as a number") from None
    if not (np.isfinite(g) and g > 0):
        raise ValueError(f"g: must be finite and > 0 (along -y), got {g}")
    return g


def _specs(scene: MechanismScene, axes: dict) -> dict:
    """Every axis's range as given (default ranges filled in)."""
    return {a: axes.get(a, default) for a, (default, *_r) in scene.axes.items()}


def summary(ds: xr.Dataset) -> str:
    """A few lines on a mechanism atlas: points, classes present, II consistent/stable counts."""
    n = int(ds.class_code.size)
    classes = ", ".join(str(c) for c in np.unique(ds.class_code.values))
    lines = [
        f"{ds.attrs['title']}",
        f"{n} bodies over {', '.join(f'{d} ({ds.sizes[d]})' for d in ds.class_code.dims)}",
        f"classes: {classes}",
        f"b11 < 0 (Painleve at contact 1): {int((ds.b11 < 0).sum())}; "
        f"b22 < 0: {int((ds.b22 < 0).sum())}",
    ]
    for k in ("consistent_II", "stable_II", "stable_SS"):
        counts = {int(c): int(m) for c, m in zip(*np.unique(ds[k].values, return_counts=True))}
        lines.append(f"{k}: {counts} (codes: {ds[k].attrs.get('flag_meanings', '')})")
    for k in [v for v in ds.data_vars if "model_box" in ds.attrs and v.endswith("_over_models")]:
        counts = {int(c): int(m) for c, m in zip(*np.unique(ds[k].values, return_counts=True))}
        lines.append(
            f"{k} over the model box {ds.attrs['model_box']}: {counts} (codes: "
            f"{ds[k].attrs.get('flag_meanings', '')}); undecided "
            f"{ds.attrs['over_models_undecided_before_settlement']} before the settlement, "
            f"{ds.attrs['over_models_undecided']} after"
        )
    return "\n".join(lines)


def parse_fixed(text: str | None) -> dict:
    """``"L=3,c1=20"`` -> ``{"L": 3.0, "c1": 20.0}`` (one-line errors naming ``fixed`` or the key)."""
    out = {}
    for item in (text or "").split(","):
        if not item.strip():
            continue
        key, sep, val = (t.strip() for t in item.partition("="))
        if not sep or not key:
            raise ValueError(f"fixed: expected KEY=VALUE, got {item.strip()!r}")
        if key in out:
            raise ValueError(f"fixed: {key} given twice")
        values, is_dim = parse_values(val, key)
        if is_dim:
            raise ValueError(f"{key}: a fixed parameter takes one number, got {val!r}")
        out[key] = float(values)
    return out


def run_cli(
    name, out=None, overwrite=False, dtype="float64", fixed=None, model_box=None, **axes
) -> int:
    """``atlas mechanism NAME [--AXIS RANGE ...] [--fixed K=V,...] [--model-box BOX] [--out
    FILE.nc]``; the file's ``history`` is this command line with every axis range explicit."""
    box = None if model_box is None else _checked_box(model_box)  # refused before any work
    if out is not None:
        check_output_path(out, overwrite)
    given = {a: v for a, v in axes.items() if v is not None}
    scene = MECHANISM_SCENES[name]
    words = ["atlas", "mechanism", name]
    for a, spec in _specs(scene, given).items():
        words += [f"--{a}", str(spec)]
    words += ["--fixed", fixed] if fixed else []
    words += ["--model-box", str(box)] if box is not None else []
    words += ["--dtype", dtype] if dtype != "float64" else []
    words += ["--out", str(out)] if out is not None else []
    words += ["--overwrite"] if overwrite else []
    history = " ".join(shlex.quote(w) for w in words)
    ds = mechanism_atlas(  # the command line screened the size already (--no-size-check)
        name, dtype=dtype, fixed=parse_fixed(fixed), history=history, model_box=box,
        size_check=False, **given,
    )  # fmt: skip
    print(summary(ds))
    if out is not None:
        write_netcdf(ds, out, overwrite=overwrite)
        print(f"wrote {out}")
    return 0
