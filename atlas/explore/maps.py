"""The Fig. 1 layers of the beta1-beta2 plane at any resolution, for one model ``(kappa, q1, q2)``.

:func:`compute_map` goes through the same certified driver as every other caller
(:func:`atlas.core.points.spectral_points`, :mod:`atlas.core.mechanics`); undecided values are settled
by :mod:`atlas.core.exact`.  Variable names, dimensions and stored types follow the data contract
(SPEC §2), so a map equals the corresponding slice of an atlas from :func:`atlas.data.engine.generate`.

Grid: cell centres ``beta = (i + 1/2) 2 pi / n`` [rad].  For even ``n`` the centres ``beta`` and
``beta + pi`` are both on the grid, i.e. a whole line of cells lies on ``det B = 0``
(``beta2 = beta1 + pi``) up to the rounding of the directions (``|det B| ~ 1e-17``).  The kernels
take the sign of ``det B`` exactly (:func:`atlas.core.signs.det2_sign`), so these cells are
decided; a few damped ones may still leave ``consistent_II`` to the exact reference.
"""

from __future__ import annotations

import functools
import math
import time

import jax
import jax.numpy as jnp
import numpy as np
import xarray as xr

from atlas.core import mechanics as mech
from atlas.core import spectral
from atlas.core.points import SPECTRAL_NAMES, settle_codes, spectral_points
from atlas.data.outputs import (
    OUTPUTS,
    coord_attrs,
    in_group,
    to_storage,
    undecided,
    variable_attrs,
)

__all__ = [
    "beta_grid",
    "compute_map",
    "checked_model",
    "check_model",
    "BETA_LAYERS",
    "ALPHA_LAYERS",
    "SPECTRAL_LAYERS",
    "LAYERS",
    "DEFAULT_LAYERS",
]

#: layers that depend on beta1 and/or beta2 only
BETA_LAYERS = in_group("b1b2") + in_group("b1") + in_group("b2")
#: layers that also need alpha (Table 1, subclass code)
ALPHA_LAYERS = in_group("b1b2a")
#: layers that depend on the model (kappa, q1, q2): the spectral verdicts and the smooth SS margin
SPECTRAL_LAYERS = in_group("spectral") + ("margin_SS",)
LAYERS = BETA_LAYERS + ALPHA_LAYERS + SPECTRAL_LAYERS
DEFAULT_LAYERS = ("class_code", "stable_SS", "consistent_II", "stable_II")

_TABLE1 = tuple(k for k in ALPHA_LAYERS if k.startswith("consistent_"))
#: layers on the plane computed by :func:`_mech_kernel` (angles only)
_ANGLE_LAYERS = ("class_code", "cc_possible") + ALPHA_LAYERS
_PLANE = ("beta1", "beta2")
_MARGIN_COMMENT = "atlas.core.spectral.ss_margin: zero on the curved SS boundary"


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


# --------------------------------------------------------------------------- kernels


@functools.cache
def _mech_kernel(names: tuple[str, ...]):
    """One jitted kernel for the angle-only layers (broadcast: ``c1 (n,1)``, ``c2 (1,n)``)."""

    def kernel(c1, s1, c2, s2, ca, sa):
        out = {}
        if "class_code" in names:
            out["class_code"] = mech.class_code(c1, s1, c2, s2)
        if "cc_possible" in names:
            out["cc_possible"] = mech.cc_possible(c1, s2)
        if "subclass_code" in names:
            out["subclass_code"] = mech.subclass_code(c1, s1, c2, s2, ca, sa)
        if any(k in names for k in _TABLE1):
            modes = mech.consistent_modes(c1, s1, c2, s2, ca, sa)
            out.update({k: modes[k[-2:]] for k in _TABLE1 if k in names})
        return out

    return jax.jit(kernel)


@functools.cache
def _margin_kernel():
    return jax.jit(spectral.ss_margin)


# --------------------------------------------------------------------------- checks and grid


def _checked_layers(layers, alpha) -> tuple[str, ...]:
    layers = tuple(dict.fromkeys(layers))
    bad = [k for k in layers if k not in LAYERS]
    if bad:
        raise ValueError(f"layers: unknown layer(s) {bad} (known: {', '.join(LAYERS)})")
    if not layers:
        raise ValueError("layers: empty")
    need_alpha = [k for k in layers if k in ALPHA_LAYERS]
    if need_alpha and alpha is None:
        raise ValueError(f"alpha: layers {need_alpha} need an alpha value")
    return layers


def _working_dtype(dtype) -> np.dtype:
    dt = np.dtype(dtype)
    if dt not in (np.float32, np.float64):
        raise ValueError(f"dtype: must be float64 or float32, got {dtype!r}")
    return dt


def _components(angle, dt) -> tuple[np.ndarray, np.ndarray]:
    """``(cos, sin)`` of ``angle`` [rad] rounded to the working precision."""
    c, s = (np.asarray(x, dt) for x in mech.direction(angle, dt))
    return c, s


def _coords(b: np.ndarray, model: tuple, alpha) -> dict:
    coords = {k: (k, b, coord_attrs(k)) for k in _PLANE}
    coords.update({k: ((), v, coord_attrs(k)) for k, v in zip(("kappa", "q1", "q2"), model)})
    if alpha is not None:
        coords["alpha"] = ((), float(alpha), coord_attrs("alpha"))
    return coords


# --------------------------------------------------------------------------- layers


def _line_layers(layers, c, s, dt) -> dict:
    """The 1-D layers (one value per coordinate: SF, FS stability, IF, FI consistency)."""
    one_d = {
        "stable_SF": lambda: mech.stable_SF(jnp.asarray(c)),
        "consistent_IF": lambda: mech.consistent_IF(jnp.asarray(c), jnp.asarray(s)),
        "stable_FS": lambda: mech.stable_FS(jnp.asarray(s)),
        "consistent_FI": lambda: mech.consistent_FI(jnp.asarray(c), jnp.asarray(s)),
    }
    return {
        k: (OUTPUTS[k].depends, to_storage(k, np.asarray(f()), dt))
        for k, f in one_d.items()
        if k in layers
    }


def _angle_layers(layers, plane, ca, sa, dt, resolve) -> dict:
    """Class, subclass codes, CC and Table 1 on the plane; undecided codes settled exactly."""
    names = tuple(k for k in layers if k in _ANGLE_LAYERS)
    if not names:
        return {}
    zero = np.zeros((), dt)
    args = [jnp.asarray(a) for a in plane]
    args += [jnp.asarray(zero if a is None else a) for a in (ca, sa)]
    res = {k: np.array(v) for k, v in _mech_kernel(names)(*args).items()}
    full = (plane[0].size, plane[3].size)
    res = {k: np.broadcast_to(v, full).copy() for k, v in res.items()}
    if resolve:
        masks = {k: undecided(k, v) for k, v in res.items() if OUTPUTS[k].undecided is not None}
        settle_codes(res, masks, *plane, ca, sa)
    return {k: (_PLANE, to_storage(k, res[k], dt)) for k in names}


def _spectral_layers(layers, plane, model, dt, resolve, max_resolve, counts) -> dict:
    """SS and II verdicts (and the spectral abscissa) through the certified driver."""
    spec = tuple(k for k in layers if k in SPECTRAL_NAMES)
    if not spec:
        return {}
    res = spectral_points(
        *plane,
        *model,
        names=spec,
        dtype=dt,
        resolve=resolve,
        max_resolve=max_resolve,
    )
    counts.update(res.stats)
    return {k: (_PLANE, to_storage(k, res[k], dt)) for k in spec}


def _margin_layer(plane, model, dt) -> dict:
    """The smooth SS margin (:func:`atlas.core.spectral.ss_margin`) on the plane."""
    m = _margin_kernel()(
        *(jnp.asarray(a) for a in plane),
        *(jnp.asarray(dt.type(v)) for v in model),
    )
    return {"margin_SS": (_PLANE, to_storage("margin_SS", m, dt))}


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
        Any of :data:`LAYERS`.  ``margin_SS`` is :func:`atlas.core.spectral.ss_margin` (smooth, its zero
        set is the curved SS boundary); the others are the SPEC §2 variables.
    alpha : float, optional
        Direction of ``a`` [rad]; needed by :data:`ALPHA_LAYERS`.
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
    c, s = _components(b, dt)
    plane = (c[:, None], s[:, None], c[None, :], s[None, :])  # c1 s1 (n, 1), c2 s2 (1, n)
    ca, sa = (None, None) if alpha is None else _components(float(alpha), dt)
    counts = {"undecided_before": 0, "undecided_after": 0}
    out = {
        **_line_layers(layers, c, s, dt),
        **_angle_layers(layers, plane, ca, sa, dt, resolve),
        **_spectral_layers(layers, plane, model, dt, resolve, max_resolve, counts),
        **(_margin_layer(plane, model, dt) if "margin_SS" in layers else {}),
    }
    ds = _dataset(out, layers, _coords(b, model, alpha))
    ds.attrs.update(
        n_undecided_fast=counts["undecided_before"],
        n_undecided=counts["undecided_after"],
        dtype=str(dt),
        seconds=time.perf_counter() - t0,
    )
    return ds
