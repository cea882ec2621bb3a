"""The layers of the beta1-beta2 plane at any resolution, for one model ``(kappa, q1, q2)``.

A layer is any output of the registry (:mod:`atlas.data.outputs`) with a point kernel: a newly
registered output is a layer at once.  The verdicts over a box of contact models (the registry's
outputs with the codes of :func:`atlas.core.verdicts.over_models_codes`, ``ss_over_models`` ...) are layers too
(:func:`box_layers`): they do not depend on one model but on a model box (``model_box=``), and are
computed, with their witness models, by the function the registry names for them.  :func:`compute_map` runs the registry's kernels through
:func:`atlas.data.plane.plane_outputs` (the certified driver of every other caller, undecided
values settled by :mod:`atlas.core.exact`).  Variable names, dimensions and stored types follow the data contract
(SPEC §2), so a map equals the corresponding slice of an atlas from :func:`atlas.data.engine.generate`.

Grid: cell centres ``beta = (i + 1/2) 2 pi / n`` [rad].  For even ``n`` the centres ``beta`` and
``beta + pi`` are both on the grid, i.e. a whole line of cells lies on ``det B = 0``
(``beta2 = beta1 + pi``) up to the rounding of the directions (``|det B| ~ 1e-17``).  The kernels
take the sign of ``det B`` exactly (:func:`atlas.core.signs.det2_sign`), so these cells are
decided; a few damped ones may still leave ``consistent_II`` to the exact reference.
"""

from __future__ import annotations

import importlib
import math
import time

import numpy as np
import xarray as xr

from atlas.core import kernels
from atlas.core.model_box import ModelBox
from atlas.core.verdicts import is_over_models
from atlas.data.outputs import OUTPUTS, coord_attrs, kernel_outputs, to_storage, variable_attrs
from atlas.data.plane import PLANE, map_dims, plane_outputs

__all__ = [
    "beta_grid",
    "compute_map",
    "checked_model",
    "check_model",
    "check_layer",
    "needs_alpha",
    "needs_model",
    "layers",
    "layer_groups",
    "box_layers",
    "map_layers",
    "is_box_layer",
    "witness_outputs",
    "checked_box",
    "box_values",
    "DEFAULT_LAYERS",
    "WHOLE_BOX",
]

DEFAULT_LAYERS = ("class_code", "stable_SS", "consistent_II", "stable_II")
_MARGIN_COMMENT = "atlas.core.hurwitz.ss_margin: zero on the curved SS boundary"
#: the whole model space ``kappa > 0``, ``q1, q2 >= 0`` as text (the box layers' default)
WHOLE_BOX = str(ModelBox())
#: the coordinates of a witness model, in the order of its registry outputs' last word
WITNESS_VARS = ("kappa", "q1", "q2")


def layers() -> tuple[str, ...]:
    """Every layer of one model: the outputs of the registry with a point kernel, in registry
    order."""
    return kernel_outputs()


def box_layers() -> tuple[str, ...]:
    """The layers over a box of models: the registry's outputs with
    :func:`~atlas.core.verdicts.over_models_codes` (``ss_over_models`` ...), in registry order."""
    return tuple(n for n, o in OUTPUTS.items() if is_over_models(o.codes))


def map_layers() -> tuple[str, ...]:
    """Every layer the widget offers: :func:`layers`, then :func:`box_layers`."""
    return layers() + box_layers()


def is_box_layer(name: str) -> bool:
    """Whether ``name`` is a verdict over a box of models (:func:`box_layers`)."""
    return name in OUTPUTS and is_over_models(OUTPUTS[name].codes)


def witness_outputs(name: str) -> dict[str, tuple[str, str, str]]:
    """The witness models of box layer ``name`` as registry outputs: ``side -> (kappa, q1, q2)``
    output names, from the names ``<prefix>_witness_<side>_<kappa|q1|q2>`` (``<prefix>_over_models``
    the layer), sides in registry order (``ss_over_models``: ``stable``, ``unstable``)."""
    prefix = name.removesuffix("_over_models") + "_witness_"
    found: dict[str, dict] = {}
    for n in OUTPUTS:
        side, _, var = n.removeprefix(prefix).rpartition("_")
        if n.startswith(prefix) and var in WITNESS_VARS and side:
            found.setdefault(side, {})[var] = n
    return {s: tuple(v[k] for k in WITNESS_VARS) for s, v in found.items() if len(v) == 3}


def _params(name: str) -> tuple[str, ...]:
    if OUTPUTS[name].kernel is None:  # a box layer or its witnesses
        return tuple(OUTPUTS[name].depends)
    return kernels.KERNELS[OUTPUTS[name].kernel].params


def layer_groups() -> tuple[tuple[str, ...], ...]:
    """Layers computed together: the batches of each kernel (one compiled kernel, or one pass
    of a certified driver, per group; switching between the layers of a group recomputes
    nothing)."""
    out = []
    for k in kernels.KERNELS.values():
        for batch in k.batches:
            group = tuple(r for r in batch if r in OUTPUTS and OUTPUTS[r].kernel == k.name)
            if group:
                out.append(group)
    for name in box_layers():
        out.append((name, *(w for ws in witness_outputs(name).values() for w in ws)))
    return tuple(out)


def check_layer(name: str, param: str = "layer") -> tuple[str, ...]:
    """The group of layer ``name`` (:func:`layer_groups`); a one-line ``ValueError`` naming
    ``param`` for an unknown name or an output that is not a map layer."""
    for g in layer_groups():
        if name in g:
            return g
    if name in OUTPUTS and OUTPUTS[name].kernel is None:
        o = OUTPUTS[name]
        how = "a reduction over the model samples" if o.needs else f"computed by {o.computed_by}"
        raise ValueError(f"{param}: {name} is not a map layer ({how}, no point kernel)")
    raise ValueError(f"{param}: unknown layer {name!r} (known: {', '.join(map_layers())})")


def needs_alpha(name: str) -> bool:
    """Whether layer ``name`` depends on ``alpha``."""
    return "alpha" in _params(name)


def needs_model(name: str) -> bool:
    """Whether layer ``name`` depends on the model ``(kappa, q1, q2)`` (a box layer depends on
    the model box instead)."""
    return "model" in _params(name) and OUTPUTS[name].kernel is not None


def checked_box(model_box) -> str:
    """A model box (a :class:`~atlas.core.model_box.ModelBox`, its text or a dict; ``None``: the
    whole model space) as its canonical text; a one-line ``ValueError`` naming ``model_box``."""
    from atlas.data.over_models import as_model_box  # noqa: PLC0415 - the box's parser

    return WHOLE_BOX if model_box is None else str(as_model_box(model_box))


def box_values(beta1, beta2, names, model_box=None, dtype="float64") -> xr.Dataset:
    """The box layers ``names`` and their witness outputs on the grid ``beta1 x beta2`` [rad]
    over ``model_box``, computed by the functions the registry names for them (``computed_by``,
    called with a Dataset of the grid and the box); attributes ``n_undecided_fast`` (before the
    settlement), ``n_undecided`` and ``model_box``."""
    box = checked_box(model_box)
    coords = {k: (k, np.atleast_1d(np.asarray(v, np.float64)), coord_attrs(k))
              for k, v in zip(PLANE, (beta1, beta2))}  # fmt: skip
    ds = xr.Dataset(coords=coords, attrs={"dtype": str(np.dtype(dtype))})
    for fn in dict.fromkeys(OUTPUTS[n].computed_by for n in names):
        module, _, attr = fn.rpartition(".")
        ds = getattr(importlib.import_module(module), attr)(ds, box)
    keep = [k for n in names for k in (n, *(w for ws in witness_outputs(n).values() for w in ws))]
    out = ds[list(dict.fromkeys(keep))]
    undecided = {k: int(v) for k, v in ds.attrs.items() if k.endswith("undecided")}
    before = {k: int(v) for k, v in ds.attrs.items() if k.endswith("before_settlement")}
    out.attrs = dict(
        model_box=box,
        n_undecided_fast=sum(before.values()),
        n_undecided=sum(undecided.values()),
    )
    return out


def beta_grid(n: int) -> np.ndarray:
    """Cell centres ``(i + 1/2) 2 pi / n`` [rad], ``i = 0 .. n-1`` (no centre on an axis)."""
    n = int(n)
    if n < 1:
        raise ValueError(f"n: must be a positive integer, got {n}")
    return (np.arange(n) + 0.5) * (2 * np.pi / n)


def check_model(kappa: float, q1: float, q2: float) -> None:
    """One-line errors for a bad model: ``kappa > 0``, ``q1, q2 >= 0``, all finite."""
    for name, v, lo in (("kappa", kappa, None), ("q1", q1, 0.0), ("q2", q2, 0.0)):
        if not math.isfinite(v):
            raise ValueError(f"{name}: must be finite, got {v}")
        if lo is None and v <= 0:
            raise ValueError(f"{name}: must be > 0, got {v}")
        if lo is not None and v < lo:
            raise ValueError(f"{name}: must be >= 0, got {v}")


def checked_model(kappa, q1, q2=None) -> tuple[float, float, float]:
    """``(kappa, q1, q2)`` as checked floats; ``q2=None`` means ``q2 = q1``."""
    q1 = float(q1)
    q2 = q1 if q2 is None else float(q2)
    kappa = float(kappa)
    check_model(kappa, q1, q2)
    return kappa, q1, q2


# --------------------------------------------------------------------------- checks and grid


def _checked_layers(layers, alpha) -> tuple[str, ...]:
    layers = tuple(dict.fromkeys(layers))
    if not layers:
        raise ValueError("layers: empty")
    for k in layers:
        check_layer(k, "layers")
    need_alpha = [k for k in layers if needs_alpha(k)]
    if need_alpha and alpha is None:
        raise ValueError(f"alpha: layers {need_alpha} need an alpha value")
    return layers


def _working_dtype(dtype) -> np.dtype:
    dt = np.dtype(dtype)
    if dt not in (np.float32, np.float64):
        raise ValueError(f"dtype: must be float64 or float32, got {dtype!r}")
    return dt


def _coords(b: np.ndarray, model: tuple, alpha) -> dict:
    coords = {k: (k, b, coord_attrs(k)) for k in PLANE}
    coords.update({k: ((), v, coord_attrs(k)) for k, v in zip(("kappa", "q1", "q2"), model)})
    if alpha is not None:
        coords["alpha"] = ((), float(alpha), coord_attrs("alpha"))
    return coords


def _dataset(out: dict, layers, coords: dict) -> xr.Dataset:
    ds = xr.Dataset({k: out[k] for k in layers}, coords=coords)
    for k in layers:
        ds[k].attrs.update(variable_attrs(k))
    if "margin_SS" in layers:
        ds["margin_SS"].attrs["comment"] = _MARGIN_COMMENT
    return ds


def compute_map(
    kappa: float = 0.5,
    q1: float = 0.0,
    q2: float | None = None,
    n: int = 513,
    dtype="float64",
    layers=DEFAULT_LAYERS,
    *,
    alpha: float | None = None,
    beta=None,
    resolve: bool = True,
    max_resolve: int | None = None,
    model_box=None,
) -> xr.Dataset:
    """Layers of the beta1-beta2 plane for one model ``(kappa, q1, q2)`` (and one ``alpha``), and
    the box layers over one model box.

    Parameters
    ----------
    kappa : float
        ``k1 |b1| / (k2 |b2|)`` [1], ``> 0``.
    q1, q2 : float
        Dimensionless damping ``q_j |b_j| / sqrt(k2 |b2|)`` [1], ``>= 0``; ``q2=None`` means
        ``q2 = q1`` (the atlas dimension ``q``).
    n : int
        Grid size: ``n x n`` cell centres (:func:`beta_grid`), unless ``beta`` is given.
    dtype : {"float64", "float32"}
        Working precision of the kernels (direction vectors are rounded to it).
    layers : sequence of str
        Any of :func:`layers`.  ``margin_SS`` is :func:`atlas.core.hurwitz.ss_margin` (smooth, its zero
        set is the curved SS boundary); the others are the SPEC §2 variables.
    alpha : float, optional
        Direction of ``a`` [rad]; needed by the layers that depend on it.
    beta : array_like, optional
        Explicit 1-D grid [rad] for both beta1 and beta2 (instead of ``n``).
    resolve : bool
        Settle values the certified fast path leaves undecided with :mod:`atlas.core.exact` (at most
        ``max_resolve`` points of the spectral layers; the rest stay undecided = 3).
    model_box : ModelBox, str or dict, optional
        The box of models of the box layers (:func:`box_layers`; ``"kappa=0.01:100,q=0:1"``,
        :func:`atlas.data.over_models.as_model_box`); default the whole model space.  Their
        witness outputs come with them; they are always settled.

    Returns
    -------
    xarray.Dataset
        Variables with the dims and types of an atlas (``stable_SF`` spans ``beta1`` only, ...);
        attributes ``n_undecided_fast``, ``n_undecided`` (spectral flags and box layers),
        ``seconds`` and, with box layers, ``model_box``.
    """
    t0 = time.perf_counter()
    layers = _checked_layers(layers, alpha)
    model = checked_model(kappa, q1, q2)
    dt = _working_dtype(dtype)
    boxed = [g[0] for g in layer_groups() if is_box_layer(g[0]) and set(g) & set(layers)]
    box = checked_box(model_box) if boxed else None
    b = beta_grid(n) if beta is None else np.asarray(beta, np.float64).reshape(-1)
    own = [k for k in layers if OUTPUTS[k].kernel is not None]
    ds = _model_map(own, b, model, alpha, dt, resolve, max_resolve)
    if box is not None:
        extra = box_values(b, b, boxed, box, dt)
        for k in extra.data_vars:
            ds[k] = extra[k].variable
        for k in ("n_undecided_fast", "n_undecided"):
            ds.attrs[k] += extra.attrs[k]
        ds.attrs["model_box"] = box
    ds.attrs.update(dtype=str(dt), seconds=time.perf_counter() - t0)
    return ds


def _model_map(layers, b, model, alpha, dt, resolve, max_resolve) -> xr.Dataset:
    """The layers of one model (:func:`compute_map` without the box layers)."""
    if not layers:
        return xr.Dataset(
            coords={k: (k, b, coord_attrs(k)) for k in PLANE},
            attrs=dict(n_undecided_fast=0, n_undecided=0),
        )
    raw = plane_outputs(
        layers, b, model, alpha=alpha, dtype=dt, resolve=resolve, max_resolve=max_resolve
    )
    counts = {"undecided_before": 0, "undecided_after": 0, **raw.stats}
    out = {k: (map_dims(k), to_storage(k, v, dt)) for k, v in raw.items()}
    ds = _dataset(out, layers, _coords(b, model, alpha))
    ds.attrs.update(
        n_undecided_fast=counts["undecided_before"], n_undecided=counts["undecided_after"]
    )
    return ds
