"""The invariant parameters of a point (SPEC §1), one typed pytree.

Every spectral kernel takes these seven arrays, in this order; a :class:`Invariants` unpacks like
the tuple ``(c1, s1, c2, s2, kappa, q1, q2)`` (``kernel(*inv)``) and is a JAX pytree (a
``NamedTuple``), so it can also travel through ``jax.jit`` as one argument.
"""

from __future__ import annotations

from typing import Any, NamedTuple

__all__ = ["Invariants", "KEYS", "PAD"]


class Invariants(NamedTuple):
    """Invariant parameters of points; fields are arrays that broadcast against each other (any
    shape; float32 or float64, one dtype for all seven in a kernel call), or Python floats.

    Attributes
    ----------
    c1, s1 : array
        Direction ``(cos beta1, sin beta1)`` of ``b1`` [1], rounded to the dtype
        (:func:`atlas.core.contact_modes.direction`).
    c2, s2 : array
        Direction ``(cos beta2, sin beta2)`` of ``b2`` [1].
    kappa : array
        Stiffness ratio ``k1 |b1| / (k2 |b2|)`` [1], ``> 0``.
    q1, q2 : array
        Damping ``q_j |b_j| / sqrt(k2 |b2|)`` [1], ``>= 0`` (time scaled by contact 2).
    """

    c1: Any
    s1: Any
    c2: Any
    s2: Any
    kappa: Any
    q1: Any
    q2: Any


#: the field names, in kernel order (keys of point dicts and dataset variables)
KEYS = Invariants._fields

#: a regular point every tier decides at once (``B = I``, ``kappa = 1``, undamped): padding of
#: fixed-length batches
PAD = Invariants(1.0, 0.0, 0.0, 1.0, 1.0, 0.0, 0.0)
