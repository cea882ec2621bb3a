"""Tips: where a boundary meets a class line at a shallow angle or tangentially (step 5b of
:mod:`atlas.data.boundaries`).  Each class line is scanned just off it on both sides; a code change
along it is where a boundary meets the line, and the tips found are inserted into the traced
polylines where tracing cut across a wedge or turned back inside a needle."""

from __future__ import annotations

import math

import numpy as np
import shapely

from atlas.core import brackets
from atlas.data.class_lines import line_frames, line_labels, line_values

__all__ = [
    "TIP_OFFSET", "attach_tips", "line_tips", "nearest_distance", "spike_tips", "unreached"
]  # fmt: skip


#: distance [rad] off a class line at which it is scanned for tips: 128 units in the last place
#: of ``2 pi`` (the points lie strictly on their side; ``beta2 - beta1`` is exact there)
TIP_OFFSET = 2.0**-43


def line_tips(fld, box, step, model, tol, dtype) -> dict:
    """Per class line ``m`` and side ``s`` (+1 / -1), certified brackets ``(p, q, vp, vq)`` where
    the code :data:`TIP_OFFSET` off the line on side ``s`` changes along it (samples every
    ``step`` [rad] of the line's parameter: ``beta2``, ``beta1``, or ``beta1`` on a diagonal;
    then bisection to ``tol``): where a boundary meets the line from that side.  A boundary that
    meets a line at a shallow angle leaves a wedge thinner than a grid cell that tracing cuts
    across; these are its tips, within ``TIP_OFFSET / sin(angle)`` of the true meeting
    point, and for a boundary tangent to the line as ``c x^2`` within ``(TIP_OFFSET / c)^(1/2)``
    (3e-7 rad for ``c = 1``)."""
    pts, keys = [], []  # every line and side in one batch: one kernel call per bisection step
    for m, base, direction, normal, t0, t1 in line_frames(box):
        t = np.linspace(t0, t1, max(2, math.ceil((t1 - t0) / step) + 1))
        line = np.asarray(base) + t[:, None] * np.asarray(direction)
        for side in (-1, 1):
            pts.append(line + side * TIP_OFFSET * np.asarray(normal))
            keys.append((m, side))
    if not pts:
        return {}
    run = np.repeat(np.arange(len(pts)), [len(x) for x in pts])
    xy = np.concatenate(pts)
    c = brackets.field_codes(fld, xy[:, 0], xy[:, 1], *model, dtype=dtype)
    i = np.flatnonzero((c[:-1] != c[1:]) & (run[:-1] == run[1:]))
    p, q, vp, vq = brackets.bisect(
        fld, xy[i], xy[i + 1], c[i], c[i + 1], *model, tol=tol, dtype=dtype
    )
    return {
        keys[r]: (p[run[i] == r], q[run[i] == r], vp[run[i] == r], vq[run[i] == r])
        for r in np.unique(run[i])
    }


def attach_tips(polys, tips, near, chord, reach) -> int:
    """Insert the tips of :func:`line_tips` into the polylines: a segment that still runs from
    a class line to a vertex off it and is longer than ``2 chord`` after refinement crosses a
    wedge; the nearest tip (within ``reach`` [rad] of its on-line end, on the line and side of
    the segment, with the region's code at one end of its bracket) becomes a vertex between
    the two, to be refined again.  Returns the number of tips attached."""
    labels = line_labels(polys.xy, near)
    k = np.flatnonzero(np.r_[polys.cid[1:] == polys.cid[:-1], False])
    length = np.hypot(*(polys.xy[k + 1] - polys.xy[k]).T)
    across = ((labels[k] < 0) != (labels[k + 1] < 0)) & (length > 2 * chord)
    rows = []
    for i in k[across]:
        on, off = (i, i + 1) if labels[i] >= 0 else (i + 1, i)
        m = labels[on]
        side = int(np.sign(line_values(polys.xy[off : off + 1])[0, m]))
        if (m, side) not in tips:
            continue
        p, q, vp, vq = tips[m, side]
        a = polys.region[polys.cid[i]]
        fit = ((vp == a) | (vq == a)) & (vp != vq)
        dist = np.where(fit, np.hypot(*(0.5 * (p + q) - polys.xy[on]).T), np.inf)
        j = int(dist.argmin())
        if dist[j] <= reach:
            pa, qa, other = (p[j], q[j], vq[j]) if vp[j] == a else (q[j], p[j], vp[j])
            rows.append((i, pa, qa, other))
    return _insert(polys, rows)


def spike_tips(polys, tips, near, chord, cell) -> int:
    """Insert the tips of :func:`line_tips` still farther than ``chord`` from the boundary they
    end: a boundary tangent to a class line leaves a needle along the line, thinner than the
    ``near`` labels resolve, where the polyline turns back short of the tip.  The vertex nearest
    to the tip among those on the tip's line (within ``near``), within a grid ``cell`` of it and
    with the tip's two codes, gets the tip as a new neighbour, on the side of its neighbour
    nearer to the tip; the path to the tip and back runs inside the needle.  Returns the number
    of tips inserted."""
    if not tips or not len(polys.xy):
        return 0
    a_v = np.array(polys.region, np.int16)[polys.cid]
    on = line_labels(polys.xy, near)
    rows = []
    for (m, _), (p, q, vp, vq) in tips.items():
        for t in range(len(p)):
            tip = 0.5 * (p[t] + q[t])
            dist = np.hypot(*(polys.xy - tip).T)
            codes = ((a_v == vp[t]) & (polys.other == vq[t])) | (
                (a_v == vq[t]) & (polys.other == vp[t])
            )
            if (dist[codes] <= chord).any():
                continue
            match = codes & (on == m) & (dist <= cell)
            if not match.any():
                continue
            i = int(np.flatnonzero(match)[dist[match].argmin()])
            nb = [
                j for j in (i - 1, i + 1) if 0 <= j < len(polys.xy) and polys.cid[j] == polys.cid[i]
            ]
            if not nb:
                continue
            j = min(nb, key=lambda j: dist[j])
            pa, qa = (p[t], q[t]) if vp[t] == a_v[i] else (q[t], p[t])
            rows.append((min(i, j), pa, qa, polys.other[i]))
    return _insert(polys, rows)


def _insert(polys, rows) -> int:
    """Insert tips as vertices: ``rows`` of ``(k, p, q, other)``, the tip's bracket ``(p, q)``
    (``p`` in the region) going between vertices ``k`` and ``k + 1``; both new segments are
    refined again.  Returns the number inserted."""
    if not rows:
        return 0
    k = np.array([r[0] for r in rows])
    pa, qa = np.array([r[1] for r in rows]), np.array([r[2] for r in rows])
    polys.todo[k] = True
    polys.append(
        xy=0.5 * (pa + qa),
        ends=np.stack([pa, qa], 1),
        other=np.array([r[3] for r in rows], np.int8),
        width=np.hypot(*(qa - pa).T),
        cid=polys.cid[k],
        key=0.5 * (polys.key[k] + polys.key[k + 1]),
        todo=np.ones(len(rows), bool),
        tip=np.ones(len(rows), bool),
    )
    return len(rows)


def unreached(tips, xy, cell) -> int:
    """Tips of :func:`line_tips` with no vertex within a grid ``cell`` [rad]: a boundary meets
    the class line there but no traced curve comes near (a band or wedge along the line thinner
    than the grid, seen by the line scan only): a branch the tracing lost, counted."""
    if not tips or not len(xy):
        return sum(len(v[0]) for v in tips.values())
    pts = np.concatenate([0.5 * (p + q) for p, q, _, _ in tips.values()])
    return int((nearest_distance(pts, xy) > cell).sum())


def nearest_distance(pts, xy) -> np.ndarray:
    """Per point of ``pts`` ``(m, 2)``, the plane distance [rad] to the nearest of ``xy``
    ``(n >= 1, 2)`` (:class:`shapely.STRtree`)."""
    pts, xy = np.asarray(pts, float).reshape(-1, 2), np.asarray(xy, float).reshape(-1, 2)
    tree = shapely.STRtree(shapely.points(xy))
    (i, _), dist = tree.query_nearest(shapely.points(pts), return_distance=True, all_matches=False)
    out = np.empty(len(pts))
    out[i] = dist
    return out
