"""Atlases of real mechanisms: built-in bodies over physical axes (issue 14).

A mechanism scene sweeps physical parameters of a built-in body of :mod:`atlas.core.mechanism`
(e.g. the ladder's angle ``theta`` [rad] and friction coefficient ``mu`` [1]) and stores, on those
physical coordinates (with units), the derived invariants ``beta1, beta2, alpha, kappa, q1, q2``,
the entries of ``B`` [1/kg] and ``a`` [m/s^2] of eq. (1), and every verdict of the atlas at them,
so ``ds.sel(mu=0.6, method="nearest")`` reads one body's verdicts.  One friction coefficient
``mu`` applies to both contacts.  The verdicts are those of :func:`atlas.core.mechanism.verdicts_at`
(certified kernels, undecided points settled exactly).
"""

from __future__ import annotations

import dataclasses

import numpy as np
import xarray as xr

from atlas.core import checks, config
from atlas.core.mechanism import BODIES, VERDICT_NAMES, body_invariants, verdicts_at
from atlas.data.io import check_output_path, write_netcdf
from atlas.data.outputs import coord_attrs, to_storage, variable_attrs
from atlas.data.scene import parse_values

__all__ = ["MECHANISM_SCENES", "MechanismScene", "mechanism_atlas", "run_cli"]


@dataclasses.dataclass(frozen=True)
class MechanismScene:
    """A built-in body over physical axes: ``axes`` maps an axis name to ``(default range, units,
    long_name, body parameters it sets)``."""

    body: str
    axes: dict
    description: str


MECHANISM_SCENES = {
    "ladder": MechanismScene(
        "ladder",
        {
            "theta": ("0.02pi:0.48pi:181", "rad", "ladder angle from the floor", ("theta",)),
            "mu": (
                "0:2:201",
                "1",
                "friction coefficient (floor and wall)",
                ("mu_floor", "mu_wall"),
            ),
        },
        "a uniform ladder on a floor leaning on a wall, slipping down (Mechanism.ladder)",
    ),
    "two_legged": MechanismScene(
        "two_legged",
        {
            "h": ("0.05:2:196", "m", "height of the centre of mass above the feet", ("h",)),
            "mu": ("0:2:201", "1", "friction coefficient (both legs)", ("mu1", "mu2")),
        },
        "a body on two legs (at +-0.2 m) sliding on a floor (Mechanism.two_legged)",
    ),
    "leaning_rod": MechanismScene(
        "leaning_rod",
        {
            "theta": ("0.02pi:0.48pi:181", "rad", "rod angle from the floor", ("theta",)),
            "mu": (
                "0:2:201",
                "1",
                "friction coefficient (floor and edge)",
                ("mu_floor", "mu_edge"),
            ),
        },
        "a rod on a floor resting on a table edge, slipping down (Mechanism.leaning_rod)",
    ),
}

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


def mechanism_atlas(name: str, *, dtype: str = "float64", **axes) -> xr.Dataset:
    """The atlas of built-in mechanism scene ``name`` (:data:`MECHANISM_SCENES`) over its physical
    axes (ranges in the syntax of :func:`atlas.data.scene.parse_values`, e.g. ``mu="0:2:101"``)."""
    if name not in MECHANISM_SCENES:
        raise ValueError(f"mechanism: unknown {name!r} (built-in: {', '.join(MECHANISM_SCENES)})")
    dtype = checks.float_dtype(dtype)
    scene = MECHANISM_SCENES[name]
    values = _axis_values(scene, axes)
    grids = np.meshgrid(*values.values(), indexing="ij")
    params = {}
    for (_d, _u, _l, sets), grid in zip(scene.axes.values(), grids):
        params.update({p: grid for p in sets})
    inv = body_invariants(BODIES[scene.body](**params))
    verdicts = verdicts_at(
        *(inv[k] for k in ("beta1", "beta2", "alpha", "kappa", "q1", "q2")), dtype=dtype
    )
    dims = tuple(scene.axes)
    data = {}
    for k, meta in _INVARIANTS.items():
        attrs = coord_attrs(k) if meta is None else {"units": meta[0], "long_name": meta[1]}
        data[k] = (dims, inv[k], attrs)
    for k in VERDICT_NAMES:
        data[k] = (dims, to_storage(k, verdicts[k], dtype), variable_attrs(k))
    coords = {
        axis: (axis, values[axis], {"units": units, "long_name": long_name})
        for axis, (_d, units, long_name, _s) in scene.axes.items()
    }
    attrs = {
        "Conventions": "CF-1.10",
        "title": f"painleve-atlas mechanism scene {name!r}: {scene.description}",
        "source": config.source(),
        "history": config.history(
            f"atlas.data.mechanisms.mechanism_atlas({name!r}, dtype={dtype!r})"
        ),
        "mechanism": scene.body,
        "dtype": dtype,
    }
    return xr.Dataset(data, coords=coords, attrs=attrs)


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
    return "\n".join(lines)


def run_cli(name, out=None, overwrite=False, dtype="float64", **axes) -> int:
    """``atlas mechanism NAME [--AXIS RANGE ...] [--out FILE.nc]``."""

    if out is not None:
        check_output_path(out, overwrite)
    given = {a: v for a, v in axes.items() if v is not None}
    ds = mechanism_atlas(name, dtype=dtype, **given)
    print(summary(ds))
    if out is not None:
        write_netcdf(ds, out, overwrite=overwrite)
        print(f"wrote {out}")
    return 0
