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

Angles are in radians; a point's direction is :func:`atlas.core.contact_modes.direction` of its
angle, i.e. the certified statement is about the rounded direction vectors (within 1 ulp of the
nominal angle, far below any tolerance used here).
"""

from __future__ import annotations

import functools
import math

import numpy as np

from atlas.core import contact_modes
from atlas.core.points import FLAT_SMALL, spectral_points
from atlas.core.verdicts import UNDECIDED_FLAG

__all__ = [
    "FIELDS",
    "FIELD_LABELS",
    "bisect",
    "boundary_kind",
    "codes_of",
    "direction_codes",
    "field_codes",
]

#: the batch sizes a kernel call sees: the smallest batches are padded to ``SMALL_BATCH`` points,
#: the others to a multiple of ``MIN_BATCH``, cut into calls of at most ``MAX_BATCH`` (the first
#: pass runs them in :data:`atlas.core.points.FLAT_SMALL` or ``FLAT_BATCH`` chunks: two
#: compilations per kernel).  ``MIN_BATCH`` is also the batch a bisection's sections fill
#: (:func:`_sections`)
SMALL_BATCH = FLAT_SMALL
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
    """:func:`field_codes` of at most ``MAX_BATCH`` points (:func:`direction_codes` of their
    direction vectors)."""
    c1, s1 = contact_modes.direction(b1, dtype)
    c2, s2 = contact_modes.direction(b2, dtype)
    return direction_codes(field, c1, s1, c2, s2, kappa, q1, q2, dtype=dtype)


def direction_codes(
    field: str, c1, s1, c2, s2, kappa, q1, q2, *, dtype="float64", first_change=None
) -> np.ndarray:
    """Certified codes of ``field`` at 1-D arrays of at most ``MAX_BATCH`` direction vectors
    ``(c1, s1)``, ``(c2, s2)`` [1] (e.g. exactly on a class line: ``(c2, s2) = -(c1, s1)`` on
    ``beta2 = beta1 + pi``), padded with :data:`PAD_POINT` to ``SMALL_BATCH`` points or a
    multiple of ``MIN_BATCH`` (not to ``MAX_BATCH``: 7,786 points would cost 16 first-pass
    chunks instead of 2); every point settled exactly.

    ``first_change``: the codes ``vp`` of rows of samples (the points, row after row, ``n /
    len(vp)`` a row, in order along a bracket from an end of code ``vp``): per row, only the
    samples a search for a change of code needs are settled (:func:`_search`), the others are
    :data:`NO_CODE`."""
    _check_field(field)
    n = np.size(c1)
    pad = (SMALL_BATCH if n <= SMALL_BATCH else -(-n // MIN_BATCH) * MIN_BATCH) - n
    pc, ps = _pad_direction(np.dtype(dtype))
    c1, s1, c2, s2 = (
        _padded(v, w, pad) for v, w in ((c1, pc[0]), (s1, ps[0]), (c2, pc[1]), (s2, ps[1]))
    )
    needed = None if first_change is None else _row_needs(field, np.asarray(first_change), n)
    res = spectral_points(
        c1, s1, c2, s2, kappa, q1, q2, names=FIELDS[field], dtype=dtype, resolve=True,
        needed=needed,
    )  # fmt: skip
    res = {k: v[:n] for k, v in res.items()}
    codes = codes_of(field, res)
    if first_change is not None:
        vp = np.asarray(first_change)
        settled, differs = _known(field, res, np.repeat(vp, n // vp.size))
        if _search(settled, differs, vp.size)[0].any():  # a window left open
            raise RuntimeError("field_codes: a point stayed undecided after exact settlement")
        return np.where(settled, codes, NO_CODE).astype(np.int8)
    if any((v == UNDECIDED_FLAG).any() for v in res.values()):  # the exact tier never leaves one
        raise RuntimeError("field_codes: a point stayed undecided after exact settlement")
    return codes


@functools.cache
def _pad_direction(dtype) -> tuple[np.ndarray, np.ndarray]:
    """The direction vectors of :data:`PAD_POINT` in ``dtype``: ``(c, s)``, each ``(2,)``."""
    return contact_modes.direction(np.array(PAD_POINT), dtype)


def _padded(v, value, pad: int) -> np.ndarray:
    """``v`` as a 1-D array of its dtype's kind followed by ``pad`` copies of ``value``."""
    v = np.asarray(v, value.dtype).ravel()
    out = np.empty(v.size + pad, value.dtype)
    out[: v.size], out[v.size :] = v, value
    return out


#: the code of a sample left unsettled (:func:`direction_codes` with ``first_change``)
NO_CODE = -1


def _known(field: str, verdicts: dict, vp) -> tuple[np.ndarray, np.ndarray]:
    """Per point, whether its code of ``field`` is settled by the (partly undecided) verdicts,
    and whether it is known to differ from ``vp`` (settled and different, or II consistent
    against an inconsistent ``vp``)."""
    if field == "SS":
        ss = np.asarray(verdicts["stable_SS"])
        settled = ss != UNDECIDED_FLAG
        return settled, settled & (ss != vp)
    cons = np.asarray(verdicts["consistent_II"])
    stab = np.asarray(verdicts["stable_II"])
    settled = (cons == 0) | ((cons == 1) & (stab != UNDECIDED_FLAG))
    code = np.where(cons == 1, 1 + stab, 0)
    return settled, (settled & (code != vp)) | ((cons == 1) & (vp == 0))


def _search(settled, differs, rows: int) -> tuple[np.ndarray, np.ndarray]:
    """The state of the search for a change of code along each of ``rows`` rows of samples
    (flat ``settled`` and ``differs``, :func:`_known`): per sample, whether it lies in its row's
    window ``(lo, hi)`` or is ``hi`` unsettled, and whether it is the window's middle.

    ``hi`` is the first sample known to differ from the row's ``vp`` (the bracket's far end
    after the last sample), ``lo`` the last settled sample of code ``vp`` before it (the near
    end before the first): the samples between are unsettled, and ``[lo, hi]`` is a bracket.
    Settling the middle one halves the window (a bisection on the row's sample positions); it
    ends on the row's first change of code where the codes along the row change once (then
    identical to settling every sample), else on another change (a bracket all the same)."""
    settled, differs = settled.reshape(rows, -1), differs.reshape(rows, -1)
    s = settled.shape[1]
    j = np.arange(s)
    hi = np.where(differs.any(1), differs.argmax(1), s)[:, None]
    lo = np.max(np.where(settled & ~differs & (j < hi), j, -1), axis=1, keepdims=True)
    window = ((j > lo) & (j < hi)) | ((j == hi) & ~settled)
    middle = ((j == (lo + hi) // 2) & (hi - lo > 1)) | ((j == hi) & ~settled)
    return window.ravel(), middle.ravel()


def _row_needs(field: str, vp: np.ndarray, n: int):
    """The ``needed`` filter of :func:`atlas.core.points.spectral_points` for rows of samples
    (:func:`direction_codes`): the samples in each row's window (:func:`_search`) for tiers 2 and
    3, its middle for each round of exact settlement; never the padding."""
    vp_each = np.repeat(vp, n // vp.size)

    def needed(idx, verdicts, exact):
        head = {k: v[:n] for k, v in verdicts.items()}
        window, middle = _search(*_known(field, head, vp_each), vp.size)
        want = middle if exact else window
        return (idx < n) & want[np.minimum(idx, n - 1)]

    return needed


def codes_of(field: str, verdicts: dict) -> np.ndarray:
    """The codes of ``field`` (module docstring) from its verdicts (:data:`FIELDS`)."""
    if field == "SS":
        return np.asarray(verdicts["stable_SS"]).astype(np.int8)
    cons = np.asarray(verdicts["consistent_II"]).astype(np.int8)
    stab = np.asarray(verdicts["stable_II"]).astype(np.int8)
    return np.where(cons == 1, 1 + stab, 0).astype(np.int8)


#: the most sample points per bracket and kernel call of :func:`bisect` (a ``k``-section with
#: ``k`` up to 64 gains 6 bits a call where few brackets leave a padded batch mostly empty)
MAX_SECTIONS = 64


def _sections(n: int, ratio: float) -> int:
    """Sections per bracket for ``n`` brackets still ``ratio`` times too long: a power of two
    that fills one padded batch (:data:`MIN_BATCH`), at most :data:`MAX_SECTIONS`, no more than
    the ratio needs."""
    fill = 2 ** max(1, int(math.log2(max(MIN_BATCH // max(n, 1), 2))))
    need = 2 ** max(1, math.ceil(math.log2(max(ratio, 2.0))))
    return int(min(MAX_SECTIONS, fill, need))


def _first_changes(field, pts, vp, kappa, q1, q2, dtype) -> np.ndarray:
    """Codes ``(m, s)`` of the samples ``pts`` ``(m, s, 2)`` [rad] of ``m`` brackets from ends
    of codes ``vp``: certified where a search for a change of code along the row needed them
    (:func:`_search`), :data:`NO_CODE` elsewhere; rows in batches of at most :data:`MAX_BATCH`
    points (:func:`direction_codes` with ``first_change``)."""
    m, s = pts.shape[:2]
    out = np.empty((m, s), np.int8)
    rows = max(1, MAX_BATCH // s)
    for start in range(0, m, rows):
        part = slice(start, min(start + rows, m))
        c1, s1 = contact_modes.direction(pts[part, :, 0].ravel(), dtype)
        c2, s2 = contact_modes.direction(pts[part, :, 1].ravel(), dtype)
        codes = direction_codes(
            field, c1, s1, c2, s2, kappa, q1, q2, dtype=dtype, first_change=vp[part]
        )
        out[part] = codes.reshape(-1, s)
    return out


def _section_step(field, p, q, vp, vq, kappa, q1, q2, ratio, dtype):
    """One step of :func:`bisect` on brackets still ``ratio`` times too long: ``k - 1`` samples
    split each into ``k`` parts (:func:`_sections`); returns the new ``(p, q, vq)``."""
    k = _sections(len(p), ratio)
    t = np.arange(1, k) / k
    pts = p[:, None, :] + t[None, :, None] * (q - p)[:, None, :]  # (m, k - 1, 2)
    v = _first_changes(field, pts, vp, kappa, q1, q2, dtype)
    differs = (v != vp[:, None]) & (v != NO_CODE)
    differs = np.concatenate([differs, np.ones((len(p), 1), bool)], axis=1)
    i = differs.argmax(1)  # the first settled sample off vp's code (k - 1: q itself)
    r, inner = np.arange(len(p)), i < k - 1
    new_q = np.where(inner[:, None], pts[r, np.minimum(i, k - 2)], q)
    vq = np.where(inner, v[r, np.minimum(i, k - 2)], vq).astype(np.int8)
    p = np.where((i > 0)[:, None], pts[r, np.maximum(i - 1, 0)], p)
    return p, new_q, vq


def bisect(field: str, p, q, vp, vq, kappa, q1, q2, *, tol: float, dtype="float64"):
    """Shrink brackets ``[p, q]`` (``(m, 2)`` arrays of ``(beta1, beta2)`` [rad], codes ``vp != vq``)
    to a length ``<= tol`` [rad]; returns ``(p, q, vp, vq)``.

    Each kernel call evaluates ``k - 1`` points splitting every bracket into ``k`` equal parts
    (``k = 2``: bisection; larger where few brackets leave the batch mostly padding,
    :func:`_sections`); the first settled point whose certified code differs from ``vp``
    becomes ``q`` (with its code: a third code makes the bracket straddle the boundary between
    ``vp`` and it), the point before it (settled, of code ``vp``) ``p``.  The points the fast
    tiers leave undecided are settled exactly only as a bisection over the sample positions
    needs them (:func:`_search`): the first change of code along the bracket where it changes
    once.  Repeated until every bracket is ``<= tol`` long; a bracket is left alone once it is
    (only the longer ones are sampled: the samples of a bracket far below ``tol`` are all next
    to the boundary, where the exact tier decides most of them, and its result no longer
    depends on which other brackets share the calls).
    """
    p, q = np.array(p, np.float64), np.array(q, np.float64)
    vp, vq = np.array(vp, np.int8), np.array(vq, np.int8)
    if (vp == vq).any():
        raise ValueError("vp: the two ends of a bracket must have different codes")
    if not tol > 0:
        raise ValueError(f"tol: must be positive, got {tol!r}")
    if len(p) == 0:
        return p, q, vp, vq
    for _ in range(4 * 64):  # each call shrinks by at least 2 while the floats can
        length = np.hypot(*(q - p).T)
        a = np.flatnonzero(length > tol)  # a bracket <= tol is done
        if not a.size:
            return p, q, vp, vq
        p[a], q[a], vq[a] = _section_step(field, p[a], q[a], vp[a], vq[a], kappa, q1, q2,
                                          float(length[a].max()) / tol, dtype)  # fmt: skip
    raise RuntimeError(f"tol: brackets did not shrink to {tol!r} rad (float resolution)")


def boundary_kind(field: str, a, b) -> np.ndarray:
    """Which boundary separates codes ``a`` and ``b`` of ``field``: ``"SS_stability"``,
    ``"II_consistency"`` (one side inconsistent) or ``"II_stability"``."""
    _check_field(field)
    a, b = np.broadcast_arrays(np.asarray(a), np.asarray(b))
    if field == "SS":
        return np.full(a.shape, "SS_stability", dtype=object)
    return np.where((a == 0) | (b == 0), "II_consistency", "II_stability").astype(object)
