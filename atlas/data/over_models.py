"""Verdicts over a box of contact models as atlas variables (:mod:`atlas.core.model_box`,
:mod:`atlas.core.ii_over_models`).

``ss_over_models``, ``ii_consistent_over_models`` and ``ii_stable_over_models``
(:class:`atlas.core.verdicts.OverModels` codes) and their witnesses
(``<prefix>_witness_<side>_<kappa|q1|q2>``, float64, NaN where the code is not "depends") span
``beta1, beta2`` only: the model box replaces the scene's model axes for them.  They are added to an
atlas on request (``atlas.generate(scene, model_box=...)``, ``atlas generate --model-box ...``: all
three; :func:`add_over_models`: SS, :func:`add_ii_over_models`: II), never by default.  The box is
stored as the global attribute ``model_box``; the undecided counts as ``over_models_*`` (SS) and
``ii_over_models_*`` (II).
"""

from __future__ import annotations

import time

import numpy as np
import xarray as xr

from atlas.core import contact_modes as mech
from atlas.core import ii_over_models as iim
from atlas.core import model_box as mb
from atlas.data.outputs import variable_attrs

__all__ = [
    "as_model_box",
    "over_models",
    "add_over_models",
    "add_ii_over_models",
    "add_all_over_models",
    "OVER_MODELS_OUTPUTS",
    "II_OVER_MODELS_OUTPUTS",
]

#: the variables :func:`add_over_models` adds (SS)
OVER_MODELS_OUTPUTS = ("ss_over_models", *mb.WITNESS_NAMES)
#: the variables :func:`add_ii_over_models` adds (II consistency and stability)
II_OVER_MODELS_OUTPUTS = iim.II_OUTPUTS


def as_model_box(value) -> mb.ModelBox:
    """A :class:`atlas.core.model_box.ModelBox` from itself, its text (``"kappa=0.01:100,q=0:1"``)
    or a dict of :func:`atlas.core.model_box.model_box` keywords; one-line ``ValueError``
    (:func:`atlas.core.model_box.checked`)."""
    return mb.checked(value)


def over_models(beta1, beta2, box, dtype: str = "float64", *, ii: bool = False) -> xr.Dataset:
    """The variables of :data:`OVER_MODELS_OUTPUTS` (``ii``: of :data:`II_OVER_MODELS_OUTPUTS`)
    on the grid ``beta1 x beta2`` [rad] (directions rounded to ``dtype`` as in an atlas);
    ``.attrs``: the box and the run's counts."""
    box = as_model_box(box)
    b1 = xr.DataArray(np.atleast_1d(np.asarray(beta1, np.float64)), dims="beta1")
    b2 = xr.DataArray(np.atleast_1d(np.asarray(beta2, np.float64)), dims="beta2")
    return _compute(b1, b2, box, dtype, _II if ii else _SS)


#: (kernel, its outputs, the attributes' prefix) of SS and of II
_SS = (mb.ss_over_models, OVER_MODELS_OUTPUTS, "over_models")
_II = (iim.ii_over_models, II_OVER_MODELS_OUTPUTS, "ii_over_models")


def _compute(b1: xr.DataArray, b2: xr.DataArray, box, dtype, what=_SS) -> xr.Dataset:
    kernel, names, prefix = what
    c1, s1 = (np.asarray(v, np.float64) for v in mech.direction(b1.values, dtype))
    c2, s2 = (np.asarray(v, np.float64) for v in mech.direction(b2.values, dtype))
    dims = b1.dims + b2.dims
    shape = (c1.size, c2.size)
    start = time.perf_counter()
    res = kernel(c1.reshape(-1, 1), s1.reshape(-1, 1), c2.reshape(1, -1), s2.reshape(1, -1), box)
    seconds = time.perf_counter() - start
    data = {}
    for name in names:
        arr = np.asarray(res[name]).reshape(shape)
        arr = arr.reshape(np.shape(b1.values) + np.shape(b2.values))
        data[name] = xr.Variable(dims, arr, variable_attrs(name))
    attrs = {
        "model_box": str(box),
        f"{prefix}_undecided_before_settlement": int(res.stats["undecided_before"]),
        f"{prefix}_undecided": int(res.stats["undecided_after"]),
        f"{prefix}_seconds": round(seconds, 3),
    }
    return xr.Dataset(data, coords={b1.name or "beta1": b1, b2.name or "beta2": b2}, attrs=attrs)


def add_over_models(ds: xr.Dataset, box, what=_SS) -> xr.Dataset:
    """``ds`` with the :data:`OVER_MODELS_OUTPUTS` over its ``beta1, beta2`` (coordinates or
    scalars) and the box's attributes added (a new Dataset)."""
    box = as_model_box(box)
    b1, b2 = ds["beta1"], ds["beta2"]
    extra = _compute(b1, b2, box, ds.attrs.get("dtype", "float64"), what)
    out = ds.copy()
    for name in what[1]:
        out[name] = extra[name].variable
    out.attrs.update(extra.attrs)
    return out


def add_ii_over_models(ds: xr.Dataset, box) -> xr.Dataset:
    """:func:`add_over_models` for :data:`II_OVER_MODELS_OUTPUTS`."""
    return add_over_models(ds, box, _II)


def add_all_over_models(ds: xr.Dataset, box) -> xr.Dataset:
    """``ds`` with SS and II over the model box (:func:`add_over_models`,
    :func:`add_ii_over_models`)."""
    return add_ii_over_models(add_over_models(ds, box), box)
