"""The layers of the beta1-beta2 plane at any resolution, for one model ``(kappa, q1, q2)``.

A layer is any output of the registry (:mod:`atlas.data.outputs`) with a point kernel: a newly
registered output is a layer at once.  :func:`compute_map` runs the registry's kernels through
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

import math
import time

import numpy as np
import xarray as xr

from atlas.core import kernels
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
    "DEFAULT_LAYERS",
]

DEFAULT_LAYERS = ("class_code", "stable_SS", "consistent_II", "stable_II")
_MARGIN_COMMENT = "atlas.core.hurwitz.ss_margin: zero on the curved SS boundary"


def layers() -> tuple[str, ...]:
    """Every layer: the outputs of the registry with a point kernel, in registry order."""
    return kernel_outputs()


def _params(name: str) -> tuple[str, ...]:
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
    return tuple(out)


def check_layer(name: str, param: str = "layer") -> tuple[str, ...]:
    """The group of layer ``name`` (:func:`layer_groups`); a one-line ``ValueError`` naming
    ``param`` for an unknown name or an output that is not a map layer."""
    if name in OUTPUTS and OUTPUTS[name].kernel is None:
        o = OUTPUTS[name]
        how = "a reduction over the model samples" if o.needs else f"computed by {o.computed_by}"
        raise ValueError(f"{param}: {name} is not a map layer ({how}, no point kernel)")
    for g in layer_groups():
        if name in g:
            return g
    raise ValueError(f"{param}: unknown layer {name!r} (known: {', '.join(layers())})")


def needs_alpha(name: str) -> bool:
    """Whether layer ``name`` depends on ``alpha``."""
    return "alpha" in _params(name)


def needs_model(name: str) -> bool:
    """Whether layer ``name`` depends on the model ``(kappa, q1, q2)``."""
    return "model" in _params(name)


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
) -> xr.Dataset:
    """Layers of the beta1-beta2 plane for one model ``(kappa, q1, q2)`` (and one ``alpha``).

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

    Returns
    -------
    xarray.Dataset
        Variables with the dims and types of an atlas (``stable_SF`` spans ``beta1`` only, ...);
        attributes ``n_undecided_fast``, ``n_undecided`` (spectral flags) and ``seconds``.
    """
    t0 = time.perf_counter()
    layers = _checked_layers(layers, alpha)
    model = checked_model(kappa, q1, q2)
    dt = _working_dtype(dtype)
    b = beta_grid(n) if beta is None else np.asarray(beta, np.float64).reshape(-1)
    raw = plane_outputs(
        layers, b, model, alpha=alpha, dtype=dt, resolve=resolve, max_resolve=max_resolve
    )
    counts = {"undecided_before": 0, "undecided_after": 0, **raw.stats}
    out = {k: (map_dims(k), to_storage(k, v, dt)) for k, v in raw.items()}
    ds = _dataset(out, layers, _coords(b, model, alpha))
    ds.attrs.update(
        n_undecided_fast=counts["undecided_before"],
        n_undecided=counts["undecided_after"],
        dtype=str(dt),
        seconds=time.perf_counter() - t0,
    )
    return ds
