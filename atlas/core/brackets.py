"""Certified brackets of the model-dependent boundaries in the ``(beta1, beta2)`` plane.

A boundary of a verdict field is where its certified value changes.  A *bracket* is a segment
``[p, q]`` of the plane whose two ends carry different certified values: the segment then meets
the boundary (the topological boundary of the region of ``p``'s value), so its midpoint lies
within ``|q - p| / 2`` of the true boundary.  :func:`bisect` shrinks brackets to a length ``tol``
with certified evaluations only (:func:`atlas.core.points.spectral_points` with exact settlement:
no tolerance, no guess), which is what makes the curves of :mod:`atlas.data.boundaries` certified.

The two fields (paper Sec. 4-6, SPEC §1):

* ``SS``: the code of ``stable_SS`` (0 unstable, 1 stable, 2 neutral);
* ``II``: 0 where II is inconsistent, else ``1 + stable_II`` (1 consistent and unstable,
  2 consistent and stable, 3 consistent and neutral): its boundaries are the II consistency
  boundary (one side 0) and the II stability boundary (both sides consistent), including the
  damped dominance switch of classes 15/32.

Angles are in radians; a point's direction is :func:`atlas.core.mechanics.direction` of its
angle, i.e. the certified statement is about the rounded direction vectors (within 1 ulp of the
nominal angle, far below any tolerance used here).
"""

from __future__ import annotations

import math

import numpy as np

from atlas.core import mechanics
from atlas.core import points as evaluate
from atlas.core.verdicts import UNDECIDED_FLAG

__all__ = ["FIELDS", "FIELD_LABELS", "field_codes", "bisect", "boundary_kind"]

#: the two batch sizes a kernel call sees: small batches are padded to ``MIN_BATCH`` points,
#: larger ones cut into padded batches of ``MAX_BATCH`` (two compilations per kernel)
MIN_BATCH = 4096
MAX_BATCH = 1 << 16
#: the padding point ``(beta1, beta2)`` [rad]: ``B = I`` (two uncoupled contacts).  The first
#: pass decides it (II by the closed form of diagonal ``B``; SS checked over damped, undamped,
#: one-q = 0 and extreme-ratio models in the tests), so padding never reaches the later tiers
PAD_POINT = (0.0, math.pi / 2)
#: the verdicts each field is made of
FIELDS = {"SS": ("stable_SS",), "II": ("consistent_II", "stable_II")}
#: the meaning of each code of a field
FIELD_LABELS = {
    "SS": {0: "SS unstable", 1: "SS stable", 2: "SS neutral"},
    "II": {
        0: "II inconsistent",
        1: "II consistent, unstable",
        2: "II consistent, stable",
        3: "II consistent, neutral",
    },
}


def _check_field(field: str) -> None:
    if field not in FIELDS:
        raise ValueError(f"field: must be one of {', '.join(FIELDS)}, got {field!r}")


def field_codes(field: str, beta1, beta2, kappa, q1, q2, *, dtype="float64") -> np.ndarray:
    """Certified codes (``int8``, module docstring) of ``field`` at broadcastable angle arrays
    ``beta1, beta2`` [rad] for scalar ``kappa, q1, q2`` [1]; every point settled exactly."""
    _check_field(field)
    b1, b2 = np.broadcast_arrays(np.asarray(beta1, np.float64), np.asarray(beta2, np.float64))
    b1, b2, out = b1.ravel(), b2.ravel(), np.empty(b1.size, np.int8)
    for start in range(0, b1.size, MAX_BATCH):
        part = slice(start, min(start + MAX_BATCH, b1.size))
        out[part] = _batch_codes(field, b1[part], b2[part], kappa, q1, q2, dtype)
    return out.reshape(np.broadcast_shapes(np.shape(beta1), np.shape(beta2)))


def _batch_codes(field, b1, b2, kappa, q1, q2, dtype) -> np.ndarray:
    """:func:`field_codes` of at most ``MAX_BATCH`` points, padded with :data:`PAD_POINT` to
    ``MIN_BATCH`` or ``MAX_BATCH`` points (two batch sizes: two compilations per kernel)."""
    n = b1.size
    pad = (MIN_BATCH if n <= MIN_BATCH else MAX_BATCH) - n
    b1, b2 = (np.pad(b, (0, pad), constant_values=v) for b, v in zip((b1, b2), PAD_POINT))
    c1, s1 = mechanics.direction(b1, dtype)
    c2, s2 = mechanics.direction(b2, dtype)
    res = evaluate.spectral_points(
        c1, s1, c2, s2, kappa, q1, q2, names=FIELDS[field], dtype=dtype, resolve=True
    )
    res = {k: v[:n] for k, v in res.items()}
    if any((v == UNDECIDED_FLAG).any() for v in res.values()):  # the exact tier never leaves one
        raise RuntimeError("field_codes: a point stayed undecided after exact settlement")
    if field == "SS":
        return res["stable_SS"].astype(np.int8)
    cons = res["consistent_II"].astype(np.int8)
    return np.where(cons == 1, 1 + res["stable_II"].astype(np.int8), 0).astype(np.int8)


def bisect(field: str, p, q, vp, vq, kappa, q1, q2, *, tol: float, dtype="float64"):
    """Shrink brackets ``[p, q]`` (``(m, 2)`` arrays of ``(beta1, beta2)`` [rad], codes ``vp != vq``)
    to a length ``<= tol`` [rad]; returns ``(p, q, vp, vq)``.

    The midpoint's certified code replaces the end whose code it equals; a third code replaces
    ``q`` (the bracket then straddles the boundary between ``vp`` and that code).  The number of
    halvings is ``ceil(log2(max length / tol))``, the same for every bracket (one kernel call each).
    """
    p, q = np.array(p, np.float64), np.array(q, np.float64)
    vp, vq = np.array(vp, np.int8), np.array(vq, np.int8)
    if (vp == vq).any():
        raise ValueError("vp: the two ends of a bracket must have different codes")
    if not tol > 0:
        raise ValueError(f"tol: must be positive, got {tol!r}")
    if len(p) == 0:
        return p, q, vp, vq
    longest = float(np.max(np.hypot(*(q - p).T)))
    for _ in range(max(0, math.ceil(math.log2(longest / tol)))):
        mid = 0.5 * (p + q)
        v = field_codes(field, mid[:, 0], mid[:, 1], kappa, q1, q2, dtype=dtype)
        to_p = v == vp
        p[to_p] = mid[to_p]
        q[~to_p], vq[~to_p] = mid[~to_p], v[~to_p]
    return p, q, vp, vq


def boundary_kind(field: str, a, b) -> np.ndarray:
    """Which boundary separates codes ``a`` and ``b`` of ``field``: ``"SS_stability"``,
    ``"II_consistency"`` (one side inconsistent) or ``"II_stability"``."""
    _check_field(field)
    a, b = np.broadcast_arrays(np.asarray(a), np.asarray(b))
    if field == "SS":
        return np.full(a.shape, "SS_stability", dtype=object)
    return np.where((a == 0) | (b == 0), "II_consistency", "II_stability").astype(object)
