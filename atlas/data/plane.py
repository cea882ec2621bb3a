"""Outputs on the beta1-beta2 plane for one model ``(kappa, q1, q2)`` (and one ``alpha``).

:func:`plane_outputs` runs, for any outputs of the registry (:mod:`atlas.data.outputs`), the point
kernels that compute them (:mod:`atlas.core.kernels`) on a grid of ``beta`` values: a kernel of
both angles on the plane ``c1, s1`` ``(n, 1)`` x ``c2, s2`` ``(1, n)``, a kernel of one angle on
its line, a certified kernel through its driver (tiers and exact settlement), undecided codes
settled exactly.  The explorer's maps (:func:`atlas.explore.maps.compute_map`) and the Fig. 1 maps
(:func:`atlas.paper.figures.stability_map`) are both built here, so they equal the slice of an
atlas whatever outputs the registry holds.
"""

from __future__ import annotations

import numpy as np

from atlas.core import contact_modes as mech
from atlas.core import kernels
from atlas.core.points import Verdicts
from atlas.data.outputs import OUTPUTS, kernel_of

__all__ = ["plane_outputs", "map_dims", "PLANE"]

PLANE = ("beta1", "beta2")


def map_dims(name: str) -> tuple[str, ...]:
    """Dimensions of an output on the plane: its angles among ``beta1, beta2`` (the model and
    ``alpha`` are scalar coordinates)."""
    return tuple(d for d in OUTPUTS[name].depends if d in PLANE)


def _inputs(beta, model, alpha, dt) -> tuple[dict, dict]:
    """Kernel inputs on the plane and on the lines (a one-angle kernel sees its angle as 1-D)."""
    c, s = (np.asarray(x, dt) for x in mech.direction(beta, dt))
    if alpha is None:
        ca = sa = np.zeros((), dt)
    else:
        ca, sa = (np.asarray(x, dt) for x in mech.direction(float(alpha), dt))
    common = {"ca": ca, "sa": sa, "kappa": model[0], "q1": model[1], "q2": model[2]}
    plane = {"c1": c[:, None], "s1": s[:, None], "c2": c[None, :], "s2": s[None, :], **common}
    line = {"c1": c, "s1": s, "c2": c, "s2": s, **common}
    return plane, line


def plane_outputs(
    names,
    beta,
    model: tuple[float, float, float],
    *,
    alpha: float | None = None,
    dtype="float64",
    resolve: bool = True,
    max_resolve: int | None = None,
) -> Verdicts:
    """Raw results of the outputs ``names`` on the grid ``beta`` [rad] (both angles).

    ``model``: ``(kappa, q1, q2)`` [1]; ``alpha`` [rad] for the outputs that need it.  Returns
    ``{name: array}`` shaped by :func:`map_dims` (``(n, n)``, ``(n,)`` or ``()``), undecided codes
    settled exactly if ``resolve`` (at most ``max_resolve`` points of a certified kernel), with the
    certified driver's diagnostics in ``.stats``.  Raises a one-line ``ValueError`` for an output without a kernel.
    """
    dt = np.dtype(dtype)
    beta = np.asarray(beta, np.float64).reshape(-1)
    plane, line = _inputs(beta, model, alpha, dt)
    by_kernel: dict = {}
    for name in names:
        by_kernel.setdefault(kernel_of(name), []).append(name)
    out, stats = {}, {}
    for k, want in by_kernel.items():
        both = "beta1" in k.params and "beta2" in k.params
        inputs = plane if both else line
        if k.driver is not None:
            args = [inputs[i] for i in k.inputs]
            res = k.driver(
                *args, names=tuple(want), dtype=dt, resolve=resolve, max_resolve=max_resolve
            )
            stats.update(res.stats)
        else:
            args = {i: dt.type(v) if isinstance(v, float) else v for i, v in inputs.items()}
            res = kernels.run(k, args)
            if resolve:
                full = {r: _full(v, r, beta.size) for r, v in res.items()}
                kernels.settle(k, full, {i: args[i] for i in k.inputs})
                res = full
        for r in want:
            out[r] = _full(np.asarray(res[r]), r, beta.size)
    return Verdicts({r: out[r] for r in names}, stats)


def _full(v: np.ndarray, name: str, n: int) -> np.ndarray:
    """``v`` broadcast to the shape of ``name`` on an ``n``-point grid (a writable copy)."""
    return np.broadcast_to(v, (n,) * len(map_dims(name))).copy()
