"""Verdicts over a box of contact models at scattered points (not a grid).

:func:`point_values` gives, at points ``(beta1[i], beta2[i])`` of any shape (a mechanism atlas's
bodies, the midpoints of a bisection), every verdict over the box the registry declares
(:func:`atlas.core.verdicts.over_models_codes`) and its witness models, from the point function
named like the output in :mod:`atlas.core.model_box` (``ss_over_models``) or
:mod:`atlas.core.ii_over_models` (``ii_consistent_over_models``, ``ii_stable_over_models``): the
same proofs and exact-tier-checked witnesses as :mod:`atlas.data.over_models` on a grid.
"""

from __future__ import annotations

import numpy as np

from atlas.core import contact_modes as mech
from atlas.core import ii_over_models as iom
from atlas.core import model_box as mb
from atlas.core.verdicts import is_over_models
from atlas.data.over_models import as_model_box

__all__ = ["box_outputs", "point_values"]


#: the modules holding the point functions, each named like the output(s) it computes
_MODULES = (mb, iom)


def _point_function(name: str):
    return next((getattr(m, name) for m in _MODULES if hasattr(m, name)), None)


def box_outputs() -> tuple[str, ...]:
    """The registry's verdicts over a box that have a point function (module docstring), in
    registry order."""
    from atlas.data.outputs import OUTPUTS  # noqa: PLC0415

    return tuple(n for n, o in OUTPUTS.items() if is_over_models(o.codes) and _point_function(n))


def point_values(beta1, beta2, box, names=None, *, settle=True, dtype="float64") -> dict:
    """``{output: array}`` of the box verdicts ``names`` (default :func:`box_outputs`) and their
    witness outputs at the points ``(beta1, beta2)`` [rad] (broadcast; directions rounded to
    ``dtype`` as in an atlas) over ``box`` (a :class:`~atlas.core.model_box.ModelBox`, its text
    or a dict; a bad box is a one-line error naming ``model_box``);
    ``settle=False``: what the small budget leaves is ``UNDECIDED``.  ``.stats`` of each call's
    result is summed into the returned dict's ``"stats"`` entry (counts)."""
    box = as_model_box(box)
    b1, b2 = np.broadcast_arrays(np.asarray(beta1, np.float64), np.asarray(beta2, np.float64))
    c1, s1 = (np.asarray(v, np.float64) for v in mech.direction(b1, dtype))
    c2, s2 = (np.asarray(v, np.float64) for v in mech.direction(b2, dtype))
    out, stats = {}, {}
    names = box_outputs() if names is None else names
    for fn in dict.fromkeys(_point_function(n) for n in names):  # one call per function
        res = fn(c1, s1, c2, s2, box, settle=settle)
        out.update({k: np.asarray(v).reshape(b1.shape) for k, v in res.items()})
        for k, v in getattr(res, "stats", {}).items():
            stats[k] = stats.get(k, 0) + int(v)
    out["stats"] = stats
    return out
