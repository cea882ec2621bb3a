"""One validation of a rigid body's parameters (:class:`atlas.core.rigid_body.Mechanism`, the body
registry :mod:`atlas.core.bodies` and the mechanism atlases): every bad value is a one-line
``ValueError`` naming the parameter, for scalars and broadcastable arrays alike."""

from __future__ import annotations

import math

import numpy as np

from atlas.core import checks
from atlas.core.body_kinematics import (
    BODY_VERTEX,
    CONTACT_KINDS,
    dot,
    first_bad,
    sliding_signs,
    tangent,
)

__all__ = ["check_body", "real", "vector", "unit", "TANGENT_TOL"]

#: a sliding vector is tangent if its normal component is at most this fraction of its length
TANGENT_TOL = 1e-9


def real(name, v, *, low=None, high=None, open_low=False, open_high=False):
    """``v`` as float (or float64 array), finite and within the bounds; else a one-line error."""
    x = checks.real(name, v, finite=False)  # booleans, strings, complex numbers refused
    bad = ~np.isfinite(x)
    if np.any(bad):
        raise ValueError(f"{name}: must be finite, got {first_bad(x, bad)}")
    for bound, is_open, below, word in ((low, open_low, True, ">"), (high, open_high, False, "<")):
        if bound is None:
            continue
        if below:
            bad = x <= bound if is_open else x < bound
        else:
            bad = x >= bound if is_open else x > bound
        if np.any(bad):
            op = word if is_open else word + "="
            raise ValueError(f"{name}: must be {op} {_fmt_bound(bound)}, got {first_bad(x, bad)}")
    return float(x) if x.ndim == 0 else x


def _fmt_bound(b):
    return "pi/2" if b == math.pi / 2 else f"{b:g}"


def vector(name, v):
    try:
        parts = tuple(v)
    except TypeError:
        raise ValueError(f"{name}: must be a 2-vector, got {v!r}") from None
    if len(parts) != 2:
        raise ValueError(f"{name}: must be a 2-vector, got {len(parts)} components")
    return tuple(real(name, p) for p in parts)


def unit(name, v):
    """``v / |v|``; a vector shorter than 2^-1000 is first scaled by 2^1100 (exact), so that its
    length is not rounded on the subnormal grid (``(1e-320, 1e-320)`` gave length 1.00013)."""
    x, y = vector(name, v)
    if np.any(np.maximum(np.abs(x), np.abs(y)) == 0.0):
        raise ValueError(f"{name}: normal has zero length")
    k = np.where(np.maximum(np.abs(x), np.abs(y)) < 2.0**-1000, 1100, 0)
    x, y = np.ldexp(x, k), np.ldexp(y, k)
    norm = np.hypot(x, y)
    return (x / norm, y / norm) if np.ndim(norm) else (float(x / norm), float(y / norm))


def _sign_input(name, s, n):
    """``s_j = +-1``, or the sign along ``t_j`` of a sliding vector tangent to the surface."""
    if s is None:
        return None
    if np.ndim(s) == 0 and not isinstance(s, (tuple, list)):
        if isinstance(s, bool) or s not in (1, -1):
            raise ValueError(f"{name}: sliding sign must be +1 or -1, got {s!r}")
        return int(s)
    vec = vector(name, s)
    along, off = dot(vec, tangent(n)), dot(vec, n)
    if np.ndim(along):
        raise ValueError(f"{name}: a sliding vector must be one vector, not arrays")
    if along == 0.0 or abs(off) > TANGENT_TOL * math.hypot(*vec):
        raise ValueError(
            f"{name}: sliding vector {tuple(float(c) for c in vec)} is not tangent to the surface "
            f"(normal component {float(off):.3g})"
        )
    return 1 if along > 0 else -1


def check_body(body: dict) -> dict:
    """Validated body parameters (scalars or broadcastable arrays), ``s2`` derived or checked.

    Keys: ``m, I`` [kg, kg m^2] ``> 0``; ``r1, r2`` [m] distinct; ``n1, n2`` nonzero (normalised);
    ``mu1, mu2 >= 0``; ``s1`` (``+-1`` or a tangent vector, default +1); ``s2`` (``None``: derived,
    :func:`sliding_signs`); ``kind1, kind2`` in :data:`CONTACT_KINDS` (default ``body_vertex``).
    Returns the same keys (plus ``rank1``: the contacts lie on one normal line); raises a one-line
    ``ValueError`` naming the first bad parameter.
    """
    out = {
        "m": real("m", body["m"], low=0.0, open_low=True),
        "I": real("I", body["I"], low=0.0, open_low=True),
    }
    for key in ("r1", "r2"):
        out[key] = vector(key, body[key])
    for key in ("n1", "n2"):
        out[key] = unit(key, body[key])
    same = np.logical_and(out["r1"][0] == out["r2"][0], out["r1"][1] == out["r2"][1])
    if np.any(same):
        raise ValueError(f"r2: contact coincides with r1 = {_point(out['r1'], same)}")
    for key in ("mu1", "mu2"):
        out[key] = real(key, body.get(key, 0.0), low=0.0)
    for key in ("kind1", "kind2"):
        kind = body.get(key, BODY_VERTEX)
        if kind not in CONTACT_KINDS:
            raise ValueError(f"{key}: unknown contact kind {kind!r} ({', '.join(CONTACT_KINDS)})")
        out[key] = kind
    s1 = _sign_input("s1", body.get("s1", 1), out["n1"])
    s2 = _sign_input("s2", body.get("s2"), out["n2"])
    out["s1"], out["s2"], out["rank1"] = (
        s1,
        *sliding_signs((out["r1"], out["r2"]), (out["n1"], out["n2"]), s1, s2),
    )
    return out


def _point(r, mask):
    if np.ndim(mask):
        return tuple(float(np.broadcast_to(c, mask.shape)[mask].flat[0]) for c in r)
    return tuple(float(c) for c in r)
