"""Boundaries as certified curves: every boundary of a ``(beta1, beta2)`` slice as polylines.

:func:`boundaries` turns a scene (or an atlas) into :class:`Boundaries`, per model slice
``(kappa, q1, q2)``:

1. **Grid.** The certified codes of the two fields of :mod:`atlas.core.brackets` (``SS``: SS
   stability; ``II``: II consistency and stability) on the grid's nodes, settled exactly.
2. **No lost branch (the check).** The grid is resampled ``check`` times finer; a cell whose four
   corners agree while a finer sample inside it differs hides a branch (a small loop, or a curve
   entering and leaving through one edge).  If any such cell exists the finer grid replaces the
   grid and is checked again (at most ``max_levels`` times); cells still hiding a branch are
   counted in ``attrs["hidden_cells"]``.  This is a check, not a proof: a loop smaller than the
   finest sampling, or a second branch in a cell that already shows a change, can pass it.
3. **Tracing.** Marching triangles (:mod:`atlas.data.marching`: every cell split along its
   ``beta2 = beta1 + c`` diagonal, so that the class lines through the nodes are edges) on the
   indicator of each code's region gives polylines whose vertices lie on grid edges with different
   codes at the two ends: brackets.  The grid is shifted by ~1e-7 of a cell (:data:`NUDGE`) so
   that no node sits on a class line.
4. **Certified vertices.** :func:`atlas.core.brackets.bisect` shrinks every bracket to a length
   ``<= tol`` (default 1e-10 rad); the vertex is its midpoint, so it lies within ``tol / 2`` of the
   true boundary (the bracket's end codes are certified: floating point with proven error bounds,
   or exact rational arithmetic).
5. **Chords.** Between two vertices a new certified vertex is found on the perpendicular bisector
   of the chord (a bracket across it, then bisection); it is inserted until the chord's measured
   deviation (sagitta) is ``<= chord`` [rad].  The segments are therefore within about ``chord``
   of the curve (measured, not proven: a wiggle between two probes can hide).  Where the
   perpendicular through the middle finds no bracket (it runs through the crossing of two class
   lines from the region into the region), the quarter points are probed; a probe between two
   vertices of one kind (on one class line, or off the lines) that lands on the other kind has
   jumped across a wedge and is not used.  Besides fixed offsets (:data:`PROBE_OFFSETS`) the
   perpendicular is probed 1/2, 3/4, ... of the way to the nearest class line it crosses
   (:data:`LINE_APPROACH`): a band between a tangent boundary and the line is thinner there than
   any fixed fraction of the chord.
5b. **Tips.** A boundary that meets a class line at a shallow angle leaves a wedge thinner than
   a cell, which tracing cuts across.  Each class line is scanned :data:`atlas.data.boundary_tips.TIP_OFFSET` off it on
   both sides (samples every quarter cell, then bisection): a code change there is where a
   boundary meets the line.  A segment still running from the line to a vertex off it gets the
   nearest such tip (same line and side, the region's code at one end) as a vertex, and is
   refined again; a tip still farther than ``chord`` from its boundary (the polyline turned back
   inside the needle a tangent boundary leaves along the line) is inserted next to the nearest
   vertex with its codes.  Tips no curve comes near are counted
   (``attrs["<field>_tips_unreached"]``): a band along a line thinner than the grid, lost by the
   tracing.
6. **Pieces and codimension-2 points.** A region boundary is cut where the code on its other
   side changes (a ``junction`` of three codes, located between two certified vertices), and runs
   of vertices on a straight class line (``beta_j = k pi/2``, ``beta2 = beta1 + k pi``, SPEC §1)
   are split off as ``on_class_line`` pieces; the junctions, the points where a boundary leaves
   or crosses a class line, and where SS and II boundaries cross are returned as
   :attr:`Boundaries.points`.  Where an SS boundary meets a class line the point is located by
   its defining condition with a proven enclosure (:mod:`atlas.data.boundary_points`), then
   spliced into the nearest curve as a vertex carrying its proven radius (after step 8); every
   other point is an estimate (``proven = False``, ``uncertainty`` NaN).
7. **Side labels.** Each piece carries the certified codes found just off it on each side and on
   it (:mod:`atlas.data.boundary_sides`): cut where they change, oriented with the higher code on
   the left, coincident pieces on a line merged.
8. **Paths.** Coordinates in ``[0, 2 pi)``, every piece simple, no stretch twice
   (:mod:`atlas.data.boundary_paths`).

The straight class boundaries themselves are returned in closed form (``field = "class"``,
:mod:`atlas.data.class_lines`, with the lines' geometry).  The tips of step 5b live in
:mod:`atlas.data.boundary_tips`; the result objects and their storage (CF-1.10 geometry
containers, CSV, GeoJSON) in :mod:`atlas.data.boundary_curves`.
"""

from __future__ import annotations

import itertools
import math
import os
import sys
import time
from dataclasses import dataclass

import numpy as np
import shapely
from numpy.lib.stride_tricks import sliding_window_view

from atlas.core import brackets, checks
from atlas.data import (
    boundary_cover,
    boundary_ends,
    boundary_germs,
    boundary_paths,
    boundary_points,
    boundary_roots,
    boundary_sides,
    boundary_tips,
    limits,
    marching,
)
from atlas.data.boundary_args import (
    CHORD,
    CLI_DEFAULTS,
    MAX_CHECK,
    MAX_LEVELS,
    MIN_CHORD,
    MIN_TOL,
    TOL,
    check_args,
    check_memory,
)
from atlas.data.boundary_curves import Boundaries, Curve, Point, summary
from atlas.data.class_lines import (
    LINE_GRADS,
    class_lines,
    line_distances,
    line_labels,
    line_values,
    torus_class_lines,
)
from atlas.data.io import check_output_path
from atlas.data.scene import Scene

__all__ = [
    "CHORD",
    "MAX_CHECK",
    "MAX_LEVELS",
    "MIN_CHORD",
    "MIN_TOL",
    "check_memory",
    "TOL",
    "Boundaries",
    "Curve",
    "Point",
    "boundaries",
    "class_lines",
    "slice_boundaries",
    "summary",
]

TWO_PI = 2 * math.pi


# --- the grid and the lost-branch check ----------------------------------------------------------


def _wrapped(values) -> np.ndarray:
    """The axis values, with ``2 pi`` appended when they sample ``[0, 2 pi)`` uniformly."""
    v = np.asarray(values, np.float64)
    n = v.size
    if n >= 3 and v[0] == 0.0:
        h = TWO_PI / n
        if np.allclose(np.diff(v), h, rtol=1e-9, atol=0) and abs(v[-1] + h - TWO_PI) < 1e-9:
            return np.append(v, TWO_PI)
    return v


#: relative shift of the tracing grid off the class lines, per axis (fractions of a cell)
NUDGE = (1.3e-7, 2.9e-7)


def _nudged(axis, which: int) -> np.ndarray:
    """``axis`` shifted by ``NUDGE[which]`` of its smallest cell: a grid through the class lines
    (``beta = k pi/2``, ``beta2 = beta1 + k pi``) would put nodes on those lines, where the verdict
    is the degenerate one (e.g. SS neutral at ``det B = 0``) and cuts every curve running along
    them; the shifted nodes carry the verdict of one side (any node is a valid bracket end)."""
    if axis.size < 2:
        return axis
    return axis + NUDGE[which] * float(np.diff(axis).min())


def _finer(axis, k: int) -> np.ndarray:
    """``axis`` with ``k - 1`` points inserted uniformly in every interval (nodes kept)."""
    t = np.arange(k) / k
    inner = (axis[:-1, None] + t * np.diff(axis)[:, None]).ravel()
    return np.append(inner, axis[-1])


def _hidden_cells(coarse, fine, k: int) -> np.ndarray:
    """Cells (``(n1-1, n2-1)`` bool) whose corners agree but whose ``k``-finer samples differ."""
    win = sliding_window_view(fine, (k + 1, k + 1))[::k, ::k]
    varies = win.min(axis=(2, 3)) != win.max(axis=(2, 3))
    c = coarse
    same = (c[:-1, :-1] == c[1:, :-1]) & (c[:-1, :-1] == c[:-1, 1:]) & (c[:-1, :-1] == c[1:, 1:])
    return varies & same


def _finer_codes(fld, f1, f2, codes, k, model, dtype) -> np.ndarray:
    """Certified codes on the ``k``-finer grid ``f1 x f2`` (:func:`_finer`), whose every
    ``k``-th node is a node of the grid of ``codes`` (the same floats): only the other nodes,
    three quarters of them for ``k = 2``, are evaluated."""
    fine = np.empty((f1.size, f2.size), codes.dtype)
    new = np.ones(fine.shape, bool)
    new[::k, ::k] = False
    i, j = np.nonzero(new)
    fine[i, j] = brackets.field_codes(fld, f1[i], f2[j], *model, dtype=dtype)
    fine[::k, ::k] = codes
    return fine


def _checked_grid(fld, b1, b2, model, check, max_levels, dtype):
    """Axes and certified codes of the grid, refined until no cell hides a branch (step 2)."""
    codes = brackets.field_codes(fld, b1[:, None], b2[None, :], *model, dtype=dtype)
    hidden, levels = (0 if check > 1 else None), 0  # None: not checked
    while check > 1:
        f1, f2 = _finer(b1, check), _finer(b2, check)
        fine = _finer_codes(fld, f1, f2, codes, check, model, dtype)
        hidden = int(_hidden_cells(codes, fine, check).sum())
        if not hidden or levels == max_levels:
            break
        b1, b2, codes, levels = f1, f2, fine, levels + 1
    return b1, b2, codes, hidden, levels


# --- tracing and certified vertices --------------------------------------------------------------


def _traced_codes(codes) -> list[int]:
    """The codes whose region boundaries are traced: all present but the largest (the boundary
    between two codes is traced once, from the smaller one's region)."""
    return sorted(int(v) for v in np.unique(codes))[:-1]


def _flips(b1, b2, nodes) -> np.ndarray:
    """Cells (``(n1-1, n2-1)`` bool) to split along ``(i+1, j)-(i, j+1)``: those whose other
    diagonal ends at a node where a ``beta1 = k pi/2`` and a ``beta2 = k pi/2`` line cross and
    no ``beta2 = beta1 + k pi`` line passes (within a thousandth of a cell).  That diagonal would
    join opposite quadrants of the crossing, whose codes differ, through the node's own code
    (``nodes``: the grid's nodes, flat)."""
    cell = min(np.diff(b1).min(initial=np.inf), np.diff(b2).min(initial=np.inf))
    on = line_distances(nodes) <= 1e-3 * cell
    corner = (on[:, :5].any(1) & on[:, 5:10].any(1) & ~on[:, 10:].any(1)).reshape(b1.size, -1)
    return corner[:-1, :-1] | corner[1:, 1:]


def _trace(nodes, codes, a, flip):
    """Polylines of the boundary of the region ``codes == a`` (marching triangles,
    :mod:`atlas.data.marching`, cells split as :func:`_flips` says; no masking: the curves run on
    through the points where a third code meets them): per polyline, each vertex's bracket
    ``(p, q)`` on a grid edge, ``p`` in the region, and the code at ``q`` (``nodes``: the grid's
    nodes, flat, ``(n1 n2, 2)``)."""
    flat = codes.ravel()
    return [(nodes[i], nodes[o], flat[o]) for i, o in marching.region_boundaries(codes == a, flip)]


@dataclass
class _Polys:
    """Vertices of the region boundaries of one field and slice, sorted by ``(curve, key)``."""

    xy: np.ndarray  # (N, 2) vertices [rad]
    ends: np.ndarray  # (N, 2, 2) the certified bracket (p, q) of each vertex
    other: np.ndarray  # (N,) the code at q (the region's code a is at p)
    width: np.ndarray  # (N,) bracket length [rad]
    cid: np.ndarray  # (N,) polyline index
    key: np.ndarray  # (N,) position along the polyline
    todo: np.ndarray  # (N,) the segment to the next vertex still needs a chord probe
    tip: np.ndarray  # (N,) the vertex is a tip (atlas.data.boundary_tips)
    region: list  # per polyline: the code a of the region it bounds

    _PER_VERTEX = ("xy", "ends", "other", "width", "cid", "key", "todo", "tip")

    def sort(self):
        order = np.lexsort((self.key, self.cid))
        for name in self._PER_VERTEX:
            setattr(self, name, getattr(self, name)[order])

    def append(self, **cols):
        for name in self._PER_VERTEX:
            setattr(self, name, np.concatenate([getattr(self, name), cols[name]]))
        self.sort()

    def segments(self) -> np.ndarray:
        """Indices ``k`` of vertices whose segment to ``k + 1`` still needs a probe."""
        has_next = np.r_[self.cid[1:] == self.cid[:-1], False]
        return np.flatnonzero(self.todo & has_next)


def _certified_polys(fld, b1, b2, codes, model, tol, dtype) -> _Polys:
    """Steps 3-4: traced polylines with every vertex bisected to a bracket ``<= tol``."""
    lines, region = [], []
    nodes = np.stack(np.meshgrid(b1, b2, indexing="ij"), -1).reshape(-1, 2)
    flip = _flips(b1, b2, nodes)
    for a in _traced_codes(codes):
        for line in _trace(nodes, codes, a, flip):
            lines.append(line)
            region.append(a)
    if not lines:
        e = np.zeros(0)
        z = np.zeros((0, 2))
        b = e > 0
        return _Polys(z, np.zeros((0, 2, 2)), e.astype(np.int8), e, e.astype(int), e, b, b, [])
    sizes = [len(ln[0]) for ln in lines]
    ps, qs, vqs = (np.concatenate(c) for c in zip(*lines))
    vps = np.repeat(np.array(region, codes.dtype), sizes)
    p, q, _, vq = brackets.bisect(fld, ps, qs, vps, vqs, *model, tol=tol, dtype=dtype)
    return _Polys(
        xy=0.5 * (p + q),
        ends=np.stack([p, q], 1),
        other=vq,
        width=np.hypot(*(q - p).T),
        cid=np.repeat(np.arange(len(lines)), sizes),
        key=np.concatenate([np.arange(m, dtype=float) for m in sizes]),
        todo=np.ones(sum(sizes), bool),
        tip=np.zeros(sum(sizes), bool),
        region=region,
    )


#: offsets along a chord's perpendicular probed for a bracket, in chord lengths
PROBE_OFFSETS = np.array([-1, -1 / 4, -1 / 16, -1 / 64, 0, 1 / 64, 1 / 16, 1 / 4, 1])
#: where along the chord the perpendicular is probed: the middle, then (if no bracket was
#: found there) the quarter points
PROBE_FRACTIONS = (0.5, 0.25, 0.75)
#: the perpendicular is also probed at these fractions of the way to the nearest class line it
#: crosses within a chord length: a boundary that meets a line tangentially, as ``c x^p``,
#: leaves a band between the line and the chord ``2^(1-p)`` of the chord's distance wide,
#: thinner than any fixed offset for small ``c``
LINE_APPROACH = 1 - 2.0 ** -np.arange(1, 9)


def _offsets(base, n, w) -> np.ndarray:
    """Per segment, the sorted offsets [rad] probed along the unit normal ``n`` from ``base``:
    :data:`PROBE_OFFSETS` times ``w``, and the :data:`LINE_APPROACH` fractions of the way to the
    nearest class line crossed within ``w`` (a chord on a line does not count that line)."""
    rate = n @ LINE_GRADS.T
    with np.errstate(divide="ignore", invalid="ignore"):
        to_line = -line_values(base) / rate  # signed offset of each line along n
    dist = np.abs(to_line)
    dist = np.where((dist > 1e-6 * w[:, None]) & (dist <= w[:, None]), dist, np.inf)
    r, m = np.arange(len(base)), dist.argmin(1)
    nearest = np.where(np.isfinite(dist[r, m]), to_line[r, m], 0.0)
    extra = nearest[:, None] * LINE_APPROACH
    return np.sort(np.concatenate([w[:, None] * PROBE_OFFSETS, extra], axis=1), axis=1)


def _probe(fld, polys, k, frac, model, tol, dtype) -> dict:
    """Step 5 for segments ``k -> k + 1``: a certified vertex on the chord's perpendicular at
    ``frac`` of its length, bisected from the pair of neighbouring offsets (:func:`_offsets`)
    closest to the chord whose ends are in the region and out of it.  Returns per segment ``ok``
    (a bracket was found) and, where ok, the new vertex's columns, its sagitta (distance to the
    chord) and the chord's length."""
    A, B = polys.xy[k], polys.xy[k + 1]
    base, d = A + frac * (B - A), B - A
    length = np.maximum(np.hypot(*d.T), 1e-300)
    n = np.stack([-d[:, 1], d[:, 0]], 1) / length[:, None]
    side = polys.ends[:, 0] - polys.ends[:, 1]  # towards the region
    n *= np.sign(np.sum(n * (side[k] + side[k + 1]), axis=1))[:, None]
    a = np.array([polys.region[c] for c in polys.cid[k]], np.int8)
    off = _offsets(base, n, np.maximum(length, 8 * tol))
    pts = base[:, None, :] + off[:, :, None] * n[:, None, :]
    # each point of a segment once: without a class line near, the line offsets are all 0 (the
    # chord's middle, next to the boundary: the costly tiers); equal offsets are neighbours
    first = np.ones(off.shape, bool)
    first[:, 1:] = off[:, 1:] != off[:, :-1]
    uniq = pts[first]
    codes = brackets.field_codes(fld, uniq[:, 0], uniq[:, 1], *model, dtype=dtype)
    codes = codes[np.cumsum(first).reshape(off.shape) - 1]
    inside = codes == a[:, None]
    score = np.abs(off[:, :-1]) + np.abs(off[:, 1:])
    score = np.where(inside[:, :-1] != inside[:, 1:], score, np.inf)
    r, j = np.arange(k.size), score.argmin(1)
    ok = np.isfinite(score[r, j])
    jp = np.where(inside[r, j], j, j + 1)  # the end in the region
    jq = 2 * j + 1 - jp
    p, q, _, vq = brackets.bisect(
        fld, pts[r, jp][ok], pts[r, jq][ok], a[ok], codes[r, jq][ok], *model, tol=tol, dtype=dtype
    )
    C = 0.5 * (p + q)
    return dict(
        ok=ok,
        xy=C,
        ends=np.stack([p, q], 1),
        other=vq,
        width=np.hypot(*(q - p).T),
        key=(1 - frac) * polys.key[k[ok]] + frac * polys.key[k[ok] + 1],
        sag=np.abs(np.sum((C - base[ok]) * n[ok], axis=1)),
        length=length[ok],
    )


def _probe_all(fld, polys, k, model, tol, dtype) -> dict:
    """:func:`_probe` at the middle of every chord, then at its quarter points where the middle
    found no bracket: at the corner where two class lines cross with the region in opposite
    quadrants, the perpendicular through the middle of a symmetric chord passes through the
    crossing from the region into the region."""
    out = None
    todo = np.arange(k.size)
    for frac in PROBE_FRACTIONS:
        got = _probe(fld, polys, k[todo], frac, model, tol, dtype)
        got["row"] = todo[got["ok"]]
        out = got if out is None else {c: np.concatenate([out[c], got[c]]) for c in got}
        todo = todo[~got["ok"]]
        if not todo.size:
            break
    order = np.argsort(out["row"])
    out = {c: v[order] for c, v in out.items() if c != "ok"}
    out["ok"] = np.isin(np.arange(k.size), out["row"])
    return out


def _refine_chords(fld, polys, model, tol, chord, near, dtype, max_rounds=40) -> int:
    """Step 5: insert certified vertices until every chord's sagitta is ``<= chord``, and until
    the chords where the curve meets a class line or a third code are ``<= chord`` long (so the
    codimension-2 points are located to ``chord``); returns the number of segments whose probe
    found no bracket (left as they are)."""
    unrefined = 0
    for _ in range(max_rounds):
        k = polys.segments()
        if not k.size:
            break
        at, after = line_labels(polys.xy[k], near), line_labels(polys.xy[k + 1], near)
        tip = polys.tip[k] | polys.tip[k + 1]
        mixed = ((at != after) | (polys.other[k] != polys.other[k + 1])) & ~tip
        new = _probe_all(fld, polys, k, model, tol, dtype)
        ok = new.pop("ok")
        # a probe between two vertices of one kind (both on one class line, or both off the
        # lines; a tip counts as the kind of the other end) that lands on another kind jumped
        # across a wedge thinner than the chord: the zigzag it starts would not converge; the
        # segment is left as it is
        lab = np.full(k.size, -2)
        lab[ok] = line_labels(new["xy"], near)
        kind = np.where(polys.tip[k], after, at)
        jumped = ok & ((at == after) | tip) & (lab != kind)
        keep = ~jumped[ok]
        new = {c: v[keep] for c, v in new.items()}
        ok &= ~jumped
        unrefined += int((~ok).sum())
        polys.todo[k[~ok]] = False
        kk = k[ok]
        sag, length, key = new.pop("sag"), new.pop("length"), new.pop("key")
        new.pop("row")
        again = ((sag > chord) | (mixed[ok] & (length > 2 * chord))) & (length > 8 * tol)
        polys.todo[kk] = again
        polys.append(**new, cid=polys.cid[kk], key=key, todo=again, tip=np.zeros(kk.size, bool))
    return unrefined + int(polys.segments().size)


# --- pieces and codimension-2 points -------------------------------------------------------------


def _runs(labels) -> list[tuple[int, int, int]]:
    """``(start, stop, label)`` of maximal runs; on-line runs shorter than 2 count as curved."""
    lab = labels.copy()
    out = []
    for lbl, grp in itertools.groupby(enumerate(lab), key=lambda t: t[1]):
        idx = [i for i, _ in grp]
        out.append([idx[0], idx[-1] + 1, lbl if (lbl < 0 or len(idx) >= 2) else -1])
    merged = []
    for r in out:  # join neighbouring curved runs
        if merged and merged[-1][2] == -1 and r[2] == -1:
            merged[-1][1] = r[1]
        else:
            merged.append(r)
    return [tuple(r) for r in merged]


def _pieces(fld, polys, model, tol, box):
    """Step 6: each region boundary cut where the code on its other side changes (a junction of
    three codes, located between two certified vertices) and on the class lines; returns the
    curves and the codimension-2 points.  Each boundary between codes ``a < b`` is kept from the
    region of ``a`` only.  A vertex counts as on a class line within ``4 tol``, or within ten
    nudges of the grid (closer than that the grid cannot tell a curve from the line: the fragments
    that corner points such as ``(0, 2 pi)`` leave are labelled on the line)."""
    near = _near(tol, box[2])
    curves, pts = [], []
    for c, a in enumerate(polys.region):
        sel = polys.cid == c
        xy = polys.xy[sel]
        labels = line_labels(xy, near)
        other = _line_runs_other(polys.other[sel], labels)
        cols = (xy, polys.width[sel], polys.ends[sel])
        runs = [(b, list(g)) for b, g in itertools.groupby(range(len(xy)), key=lambda i: other[i])]
        for (b0, g0), (b1, g1) in zip(runs, runs[1:]):
            if b0 > a and b1 > a:  # a | b0 turns into a | b1: three codes meet in between
                m, n = xy[g0[-1]], xy[g1[0]]
                pts.append(Point(*(0.5 * (m + n)), "junction", math.nan, *model))
        for b, g in runs:
            if b > a:
                sl = slice(*_reaching(g[0], g[-1] + 1, labels))
                piece_curves, piece_pts = _line_pieces(
                    fld, a, b, [x[sl] for x in cols], model, near
                )
                curves += piece_curves
                pts += piece_pts
        if len(xy) and not np.array_equal(xy[0], xy[-1]):
            pts += _ends(xy, box, model)
    return curves, pts


def _reaching(start, stop, labels) -> tuple[int, int]:
    """The vertex range ``[start, stop)`` of a run, extended by the neighbouring vertex where the
    run ends off the class lines and that neighbour lies on one: a curve that reaches a line
    whose run carries another code (:func:`_line_runs_other`) keeps its last segment."""
    if start > 0 and labels[start] < 0 and labels[start - 1] >= 0:
        start -= 1
    if stop < len(labels) and labels[stop - 1] < 0 and labels[stop] >= 0:
        stop += 1
    return start, stop


def _near(tol, h) -> float:
    """Distance [rad] within which a vertex counts as on a class line: ``4 tol``, or ten nudges
    of a grid of cell ``h`` (closer than that the grid cannot tell a curve from the line)."""
    return max(4 * tol, 10 * max(NUDGE) * h)


def _line_runs_other(other, labels) -> np.ndarray:
    """``other`` with each run of vertices on one class line given the run's largest code: a band
    thinner than the grid's nudge along a class line (e.g. along ``det B = 0``) would otherwise cut
    the line piece at every node into junctions."""
    out = other.copy()
    for lbl, grp in itertools.groupby(range(len(other)), key=lambda i: labels[i]):
        idx = list(grp)
        if lbl >= 0:
            out[idx] = other[idx].max()
    return out


def _line_pieces(fld, a, b, cols, model, near):
    """One stretch of the boundary between codes ``a`` and ``b`` split on the class lines."""
    xy, width, ends = cols
    labels = line_labels(xy, near)
    kind = str(brackets.boundary_kind(fld, a, b)[()])
    runs = _runs(labels)
    curves, pts = [], []
    for start, stop, lbl in runs:
        lo, hi = (start, stop) if lbl >= 0 else (max(0, start - 1), min(len(xy), stop + 1))
        if hi - lo >= 2:  # curved pieces share their junction vertices with the line pieces
            sl = slice(lo, hi)
            curves.append(Curve(fld, kind, a, b, xy[sl], width[sl], lbl >= 0, *model, ends[sl]))
    for (_, e0, l0), (_, _, l1) in zip(runs, runs[1:]):
        if (l0 >= 0) != (l1 >= 0):
            j = e0 - 1 if l0 >= 0 else e0
            pts.append(Point(*xy[j], "leaves_class_line", math.nan, *model))
    return curves, pts + _crossings(xy, labels, model)


def _crossings(xy, labels, model) -> list[Point]:
    """Transversal crossings of a curved stretch with a class line (linear interpolation)."""
    g = line_values(xy)
    off = labels < 0
    seg = off[:-1] & off[1:]
    out = []
    for k, m in zip(*np.nonzero(seg[:, None] & (np.sign(g[:-1]) * np.sign(g[1:]) < 0))):
        t = g[k, m] / (g[k, m] - g[k + 1, m])
        p = xy[k] + t * (xy[k + 1] - xy[k])
        out.append(Point(*p, "crosses_class_line", math.nan, *model))
    return out


def _ends(xy, box, model) -> list[Point]:
    """Ends of an open region boundary inside the domain (none is expected: region boundaries
    close or reach the domain's edge; located within a grid cell, the ``uncertainty``)."""
    (x0, x1), (y0, y1), h = box
    out = []
    for p in (xy[0], xy[-1]):
        edge = min(p[0] - x0, x1 - p[0], p[1] - y0, y1 - p[1]) <= 0.5 * h
        if not edge:
            out.append(Point(*p, "end", math.nan, *model))
    return out


def _meetings(ss: list[Curve], ii: list[Curve], model, min_sin=1e-3) -> list[Point]:
    """Points where an SS boundary crosses an II boundary (segment intersections at an angle with
    ``|sin| >= min_sin``: boundaries that coincide over a stretch, as SS and II consistency do
    for ``q = 0``, are not codimension-2 points; pieces on class lines are left out)."""
    ss = [c for c in ss if not c.on_class_line]
    ii = [c for c in ii if not c.on_class_line]
    if not ss or not ii:
        return []
    a0 = np.concatenate([c.vertices[:-1] for c in ss])
    a1 = np.concatenate([c.vertices[1:] for c in ss])
    b0 = np.concatenate([c.vertices[:-1] for c in ii])
    b1 = np.concatenate([c.vertices[1:] for c in ii])
    la, lb = np.hypot(*(a1 - a0).T), np.hypot(*(b1 - b0).T)
    # candidate pairs: midpoints within half the two lengths (a superset of the crossings)
    tree = shapely.STRtree(shapely.points(0.5 * (b0 + b1)))
    near = 0.5 * (la + lb.max()) + 1e-12
    i, j = tree.query(shapely.points(0.5 * (a0 + a1)), predicate="dwithin", distance=near)
    order = np.lexsort((j, i))
    i, j = i[order], j[order]
    if not i.size:
        return []
    da, db, w = a1[i] - a0[i], b1[j] - b0[j], b0[j] - a0[i]
    den = da[:, 0] * db[:, 1] - da[:, 1] * db[:, 0]
    with np.errstate(all="ignore"):
        t = (w[:, 0] * db[:, 1] - w[:, 1] * db[:, 0]) / den
        u = (w[:, 0] * da[:, 1] - w[:, 1] * da[:, 0]) / den
    sin = np.abs(den) / np.maximum(la[i] * lb[j], 1e-300)
    hit = (sin >= min_sin) & (t >= 0) & (t < 1) & (u >= 0) & (u < 1)
    pts = a0[i[hit]] + t[hit, None] * da[hit]
    return [Point(*p, "SS_meets_II", math.nan, *model) for p in pts]


# --- drivers -------------------------------------------------------------------------------------


def slice_boundaries(
    beta1,
    beta2,
    kappa: float,
    q1: float,
    q2: float,
    *,
    fields=("SS", "II"),
    tol: float = TOL,
    chord: float = CHORD,
    check: int = 2,
    max_levels: int = 2,
    dtype="float64",
) -> Boundaries:
    """The boundary curves of one slice ``(kappa, q1, q2)`` over the grid ``beta1 x beta2``
    [rad] (module docstring, steps 1-6); ``attrs`` holds the run's diagnostics per field."""
    beta1, beta2 = (checks.real(k, v).ravel() for k, v in (("beta1", beta1), ("beta2", beta2)))
    shape = (beta1.size, beta2.size)
    fields = check_args(tol, chord, check, max_levels, fields, shape)
    tol, chord, check, max_levels = map(checks.plain, (tol, chord, check, max_levels))
    dtype = checks.float_dtype(dtype)
    model = tuple(_model_value(k, v) for k, v in (("kappa", kappa), ("q1", q1), ("q2", q2)))
    out = Boundaries()
    by_field = {}
    for fld in fields:
        t0 = time.perf_counter()
        grid = _field_grid(fld, beta1, beta2, model, check, max_levels, dtype)
        curves, pts, attrs = _field_curves(fld, grid, model, tol, chord, dtype)
        by_field[fld] = curves
        out.curves += curves
        out.points += pts
        out.attrs.update({f"{fld}_{k}": v for k, v in attrs.items()})
        out.attrs[f"{fld}_seconds"] = time.perf_counter() - t0
    out.points += _meetings(by_field.get("SS", []), by_field.get("II", []), model)
    for p in out.points:
        p.beta1, p.beta2 = float(p.beta1) % TWO_PI, float(p.beta2) % TWO_PI
    return out


def _field_grid(fld, beta1, beta2, model, check, max_levels, dtype) -> dict:
    """Steps 1-2: the nudged, checked grid of ``fld`` and its diagnostics."""
    b1, b2 = _nudged(_wrapped(np.sort(beta1)), 0), _nudged(_wrapped(np.sort(beta2)), 1)
    h = float(max(np.diff(b1).max(initial=0), np.diff(b2).max(initial=0)))
    b1, b2, codes, hidden, levels = _checked_grid(fld, b1, b2, model, check, max_levels, dtype)
    cell = float(max(np.diff(b1).max(initial=0), np.diff(b2).max(initial=0)))
    box = ((b1[0], b1[-1]), (b2[0], b2[-1]), h)
    return dict(b1=b1, b2=b2, codes=codes, hidden=hidden, levels=levels, box=box, cell=cell)


def _field_curves(fld, grid, model, tol, chord, dtype) -> tuple[list, list, dict]:
    """Steps 3-9 for one field on its checked grid (:func:`_field_grid`): the curves, the points
    and the diagnostics (``attrs`` without the field's prefix)."""
    b1, b2, box, cell = grid["b1"], grid["b2"], grid["box"], grid["cell"]
    polys = _certified_polys(fld, b1, b2, grid["codes"], model, tol, dtype)
    near = _near(tol, box[2])
    unrefined = _refine_chords(fld, polys, model, tol, chord, near, dtype)
    tips = boundary_tips.line_tips(fld, box, cell / 4, model, tol, dtype)
    # a wedge of a boundary tangent to the line is as wide as the square of the distance to its
    # tip: the grid first sees it ~sqrt(cell) away
    attached = boundary_tips.attach_tips(
        polys, tips, near, chord, reach=max(32 * cell, 4 * math.sqrt(cell))
    )
    spiked = boundary_tips.spike_tips(polys, tips, near, chord, cell)
    if attached or spiked:
        unrefined = _refine_chords(fld, polys, model, tol, chord, near, dtype)
    curves, pts = _pieces(fld, polys, model, tol, box)
    curves, dropped = boundary_sides.label_pieces(fld, curves, model, tol, near, dtype)
    curves, retraced = boundary_paths.simple_paths(curves, chord)
    for p in pts:
        p.field = fld
    attrs = {}
    distance = max(chord, near)
    roots = boundary_germs.germ_roots(fld, model)
    if fld == "SS":  # every algebraic root accounted for
        on_lines = boundary_points.line_roots(model)
        found, attrs["line_roots"] = boundary_points.ss_line_points(model, dtype, roots=on_lines)
        pts = boundary_roots.superseded(pts, found, cell, on_lines + roots, near) + found
        attrs["line_points"] = sum(p.proven for p in pts)
        counts, undecided = boundary_roots.ss_root_account(model, roots, dtype)
        attrs, pts = attrs | counts, pts + undecided
    else:
        counts, found = boundary_roots.ii_root_account(model, roots)
        pts = boundary_roots.superseded(pts, found, cell, roots, near) + found
        attrs |= counts | {"line_points": sum(p.proven for p in found)}
    added, left, (stretches, gap, left_over, unproven, pieces) = boundary_cover.cover_lines(
        fld, box, model, curves, roots, distance, tol, dtype
    )
    curves += added
    proven = [p for p in pts if p.proven]
    curves, spliced = boundary_roots.attach(curves, proven, tol, cell, 2 * distance, tol)
    curves, ends, end_attrs = _close_ends(
        fld, model, curves, proven, pts + left, (distance, cell, chord, tol), dtype
    )
    reached = np.concatenate([polys.xy] + [c.vertices for c in added])
    max_bracket = float(polys.width.max(initial=0.0))
    if max_bracket > tol:  # bisect shrinks every bracket to <= tol
        raise RuntimeError(f"tol: a vertex bracket is longer than {tol!r} rad")
    return (
        curves,
        pts + left + ends,
        attrs
        | {
            "grid": f"{b1.size}x{b2.size}",
            "refined_levels": grid["levels"],
            "hidden_cells": grid["hidden"],
            "unrefined_segments": unrefined,
            "unlabelled_segments": dropped,
            "retraced_vertices": retraced,
            "tips_attached": attached + spiked,
            "tips_unreached": boundary_tips.unreached(tips, reached, cell),
            "germ_roots": len(roots),
            "line_stretches": stretches,
            "cover_distance": distance,
            "uncovered_line_length": gap,
            "line_length_left_uncovered": left_over,
            "uncovered_pieces": pieces,
            "line_pieces_added": len(added),
            "line_intervals_unproven": len(unproven),
            "unproven_intervals": unproven,
            "lines_complete": int(not unproven),
            "points_attached": spliced
            + end_attrs["ends_extended"]
            + sum(len(c.spliced) for c in added),
            **end_attrs,
            "points_off_curves": _off_curves(proven, curves, 2 * distance),
            "max_bracket": max_bracket,
        },
    )


def _close_ends(fld, model, curves, proven, points, sizes, dtype):
    """The free curve ends of one field (:mod:`atlas.data.boundary_ends`): extended to a proven
    point of ``proven`` or bridged to another end where the segment is proven, the rest listed;
    within a grid cell or the longest segment :func:`atlas.data.boundary_ends.proven_segment`
    tries, whichever is longer (a finer grid extends no less: a boundary tangent to a class line
    leaves a wedge the tracing cuts across farther than a cell of a fine grid from its point).
    ``sizes`` = (cover distance, grid cell, chord, tol) [rad].  Returns the curves, the
    ``dangling_curve_end`` points and their diagnostics."""
    distance, cell, chord, tol = sizes
    reach, within = 2 * distance, max(cell, boundary_ends.longest_segment(chord))
    curves, extended = boundary_ends.extend_to_points(
        curves, proven, reach, within, chord, tol, dtype
    )
    bridges = boundary_ends.bridge(curves, reach, within, chord, tol, dtype)
    curves = curves + bridges
    loose = boundary_ends.dangling(curves, points, reach)
    ends = [Point(*xy, "dangling_curve_end", math.nan, *model, field=fld) for xy, _ in loose]
    return (
        curves,
        ends,
        {
            "ends_extended": extended,
            "ends_bridged": len(bridges),
            "dangling_ends": len(loose),
            "dangling_end_points": [xy for xy, _ in loose],
        },
    )


def _off_curves(points, curves, reach) -> int:
    """How many of ``points`` lie farther than ``reach`` [rad] from every segment of ``curves``
    on the torus (a proven codimension-2 point that no drawn curve comes near)."""
    a, d, _, _ = boundary_points.curve_segments(curves)
    if not points or not len(a):
        return len(points)
    xy = [(p.beta1, p.beta2) for p in points]
    return int((boundary_points.torus_distances(xy, a, d)[0].min(1) > reach).sum())


def _model_value(name, value) -> float:
    """One model parameter (``kappa > 0``, ``q1, q2 >= 0``: :func:`atlas.core.checks.model_values`)."""
    arr = checks.model_values(name, value)
    if arr.size != 1:
        raise ValueError(f"{name}: expected one number per slice, got {value!r}")
    return float(arr.ravel()[0])


def _is_dataset(source) -> bool:
    """Whether ``source`` is an ``xarray.Dataset`` (without importing xarray: a process that has
    not loaded it holds none)."""
    xr = sys.modules.get("xarray")
    return xr is not None and isinstance(source, xr.Dataset)


def _slices(source) -> tuple[np.ndarray, np.ndarray, list[tuple[float, float, float]]]:
    """``beta1, beta2`` and the model slices ``(kappa, q1, q2)`` of a scene or an atlas."""
    if isinstance(source, Scene):
        ax = source.axes
        get = {k: np.atleast_1d(a.values) for k, a in ax.items()}
    elif _is_dataset(source):
        get = {k: np.atleast_1d(source[k].values) for k in source.coords}
    else:
        raise TypeError("source: must be an atlas.Scene or an atlas xarray.Dataset")
    for k in ("beta1", "beta2", "kappa"):
        if k not in get:
            raise ValueError(f"source: has no {k}")
    for k, v in get.items():  # the command line's rules (atlas.data.scene) for every source
        if k in ("beta1", "beta2"):
            checks.real(k, v)
        elif k in ("kappa", "q", "q1", "q2"):
            checks.model_values(k, v)
    if "q1" in get and "q2" in get:
        models = list(itertools.product(get["kappa"], get["q1"], get["q2"]))
    else:
        q = get.get("q", np.zeros(1))
        models = [(k, v, v) for k, v in itertools.product(get["kappa"], q)]
    return get["beta1"].astype(float), get["beta2"].astype(float), models


def boundaries(source, *, size_check: bool = True, **options) -> Boundaries:
    """Certified boundary curves of every ``(kappa, q1, q2)`` slice of a scene or an atlas
    (the atlas's ``beta1 x beta2`` grid; options as :func:`slice_boundaries`), plus the
    closed-form class lines once.  Bad values are refused with the command line's messages, and
    with ``size_check`` a run that cannot fit in the memory available now, as the command line
    refuses it (:func:`atlas.data.limits.boundaries_estimate`)."""
    b1, b2, models = _slices(source)
    keys = ("tol", "chord", "check", "max_levels", "fields")
    args = {k: options[k] for k in keys if k in options}
    check_args(**(dict(tol=TOL, chord=CHORD, check=2, max_levels=2, fields=("SS",)) | args),
                shape=(b1.size, b2.size))  # fmt: skip
    if size_check:
        check = checks.plain(options.get("check", 2))
        limits.boundaries_estimate(b1.size, b2.size, check, len(models)).check()
    torus = all(_wrapped(np.sort(b)).size > b.size for b in (b1, b2))
    box = ((b1.min(), b1.max()), (b2.min(), b2.max()))
    out = Boundaries(curves=torus_class_lines() if torus else class_lines(*box))
    t0 = time.perf_counter()
    for model in models:
        one = slice_boundaries(b1, b2, *model, **options)
        out.curves += one.curves
        out.points += one.points
        out.attrs.setdefault("slices", []).append(
            dict(zip(("kappa", "q1", "q2"), model)) | one.attrs
        )
    args = ", ".join(f"{k}={v!r}" for k, v in sorted(options.items()))
    out.attrs.update(
        history=f"atlas.boundaries({args}) over {len(models)} slice(s)",
        tolerance=options.get("tol", TOL),
        chord_tolerance=options.get("chord", CHORD),
        seconds=time.perf_counter() - t0,
        **_completeness(out.attrs.get("slices", [])),
    )
    return out


def _completeness(slices) -> dict:
    """``complete``: 1 when every class-line stretch of every field and slice is proven covered
    (:mod:`atlas.data.boundary_cover`) and no curve ends with nothing near it
    (:func:`atlas.data.boundary_ends.dangling`), else 0; and the class-line length [rad] still
    uncovered, summed."""
    left = [v for s in slices for k, v in s.items() if k.endswith("_line_length_left_uncovered")]
    proven = [v for s in slices for k, v in s.items() if k.endswith("_lines_complete")]
    loose = [v for s in slices for k, v in s.items() if k.endswith("_dangling_ends")]
    complete = bool(slices) and all(proven) and not any(left) and not any(loose)
    return dict(complete=int(complete), uncovered_line_length=float(sum(left)))


def run_cli(
    out=None,
    csv=None,
    geojson=None,
    overwrite=False,
    fields=CLI_DEFAULTS["fields"],
    tol=TOL,
    chord=CLI_DEFAULTS["chord"],
    check=CLI_DEFAULTS["check"],
    dtype="float64",
    **axes,
) -> int:
    """``atlas boundaries --beta1 R --beta2 R --kappa V [--q V | --q1 V --q2 V] [--out F.nc]
    [--csv F.csv] [--geojson F.json]``."""
    paths = [p for p in (out, csv, geojson) if p is not None]
    real = [os.path.realpath(p) for p in paths]
    if len(set(real)) < len(real):
        raise ValueError("out: --out, --csv and --geojson must be different files")
    for path in paths:
        check_output_path(path, overwrite)
    scene = Scene(**{k: v for k, v in axes.items() if v is not None})
    names = tuple(f.strip() for f in fields.split(",") if f.strip())
    bd = boundaries(  # the command line screened the size already (--no-size-check)
        scene, size_check=False, fields=names, tol=tol, chord=chord, check=check, dtype=dtype
    )
    print(summary(bd))
    for path, write in ((out, bd.to_netcdf), (csv, bd.to_csv), (geojson, bd.to_geojson)):
        if path is not None:
            write(path)
            print(f"wrote {path}")
    return 0
