"""Marching triangles on the Kuhn triangulation of a grid: the boundary of a region given by
its nodes, as chains of grid edges that cross it.

Every cell ``(i, i+1) x (j, j+1)`` is split along its diagonal ``(i, j) - (i+1, j+1)`` (or, where
the caller says so, along the other one).  On a
grid whose nodes lie on the class lines (``beta = k pi/2`` and ``beta2 = beta1 + k pi`` on an
``n x n`` grid of ``[0, 2 pi)`` with ``n`` divisible by 4) all 13 class lines are then edges of the
triangulation.  A band thinner than a cell along a diagonal line, seen only by the nodes on the
line, is traced as one strip; marching squares (:mod:`contourpy`) sees the same nodes as
separate diamonds, because its saddle cells (two opposite corners in the region) are resolved
without the diagonal.  A triangle has no saddle: its region nodes are connected.

Each crossing edge has the region at one end and not at the other, so every vertex of the
result is a bracket of the region's boundary.
"""

from __future__ import annotations

import numpy as np

__all__ = ["region_boundaries"]


def _edges(n1: int, n2: int, flip):
    """End nodes (flat indices) of the horizontal ``(i, j)-(i+1, j)``, vertical ``(i, j)-(i, j+1)``
    and diagonal edges (per cell ``(i, j)-(i+1, j+1)``, or ``(i+1, j)-(i, j+1)`` where ``flip``),
    in that order, and per triangle its three edge ids."""
    idx = np.arange(n1 * n2).reshape(n1, n2)
    ends = [
        (idx[:-1, :], idx[1:, :]),  # H (n1-1, n2)
        (idx[:, :-1], idx[:, 1:]),  # V (n1, n2-1)
        (np.where(flip, idx[1:, :-1], idx[:-1, :-1]), np.where(flip, idx[:-1, 1:], idx[1:, 1:])),
    ]
    sizes = [a.size for a, _ in ends]
    off = np.cumsum([0] + sizes[:-1])
    h = off[0] + np.arange(sizes[0]).reshape(n1 - 1, n2)
    v = off[1] + np.arange(sizes[1]).reshape(n1, n2 - 1)
    d = off[2] + np.arange(sizes[2]).reshape(n1 - 1, n2 - 1)
    f = flip[..., None]
    # split along (i,j)-(i+1,j+1): triangles [(i,j) (i+1,j) (i+1,j+1)], [(i,j) (i,j+1) (i+1,j+1)];
    # along (i+1,j)-(i,j+1): [(i,j) (i+1,j) (i,j+1)], [(i+1,j) (i+1,j+1) (i,j+1)]
    first = np.where(
        f, np.stack([h[:, :-1], v[:-1, :], d], -1), np.stack([h[:, :-1], v[1:, :], d], -1)
    )
    second = np.where(
        f, np.stack([v[1:, :], h[:, 1:], d], -1), np.stack([v[:-1, :], h[:, 1:], d], -1)
    )
    a = np.concatenate([x.ravel() for x, _ in ends])
    b = np.concatenate([y.ravel() for _, y in ends])
    return a, b, np.concatenate([first.reshape(-1, 3), second.reshape(-1, 3)])


def _chains(nb: np.ndarray) -> list[list[int]]:
    """Walk a graph of degree <= 2 (``nb``: ``(m, 2)`` neighbours, -1 for none): open chains from
    their ends first, then closed loops (their first node repeated at the end)."""
    seen = [False] * len(nb)
    deg = (nb >= 0).sum(1)
    links = nb.tolist()  # Python lists: the walk is a Python loop over the crossing edges
    out = []
    for start in np.concatenate([np.flatnonzero(deg < 2), np.flatnonzero(deg == 2)]).tolist():
        if seen[start]:
            continue
        chain, prev, cur = [start], -1, start
        seen[cur] = True
        while True:
            a, b = links[cur]
            nxt = a if a != prev else b
            if nxt < 0:
                break  # the open end
            if seen[nxt]:
                chain.append(nxt)  # back at the start: a closed loop
                break
            chain.append(nxt)
            seen[nxt] = True
            prev, cur = cur, nxt
        out.append(chain)
    return out


def region_boundaries(inside, flip=None) -> list[tuple[np.ndarray, np.ndarray]]:
    """The boundary of the region ``inside`` (bool ``(n1, n2)`` on the grid's nodes) as polylines
    of crossing edges (cells split along ``(i, j)-(i+1, j+1)``, or along ``(i+1, j)-(i, j+1)``
    where the bool ``(n1-1, n2-1)`` ``flip`` is set): per polyline, the flat node indices of each edge's end in the region and
    of its end out of it, in order along the boundary.  Closed polylines repeat their first edge
    at the end (as :mod:`contourpy` repeats the first point); open ones end on the grid's edge."""
    inside = np.asarray(inside, bool)
    n1, n2 = inside.shape
    if n1 < 2 or n2 < 2:
        return []
    flip = np.zeros((n1 - 1, n2 - 1), bool) if flip is None else np.asarray(flip, bool)
    a, b, tri = _edges(n1, n2, flip)
    flat = inside.ravel()
    crossing = flat[a] != flat[b]
    if not crossing.any():
        return []
    compact = np.full(a.size, -1)
    compact[crossing] = np.arange(int(crossing.sum()))
    hit = crossing[tri]
    two = tri[hit.sum(1) == 2]  # a triangle is crossed by 0 or 2 of its edges
    pair = compact[two[hit[hit.sum(1) == 2]].reshape(-1, 2)]
    m = int(crossing.sum())
    nb = np.full((m, 2), -1)
    src = np.concatenate([pair[:, 0], pair[:, 1]])
    dst = np.concatenate([pair[:, 1], pair[:, 0]])
    order = np.argsort(src, kind="stable")
    src, dst = src[order], dst[order]
    first = np.r_[True, src[1:] != src[:-1]]
    nb[src[first], 0] = dst[first]
    nb[src[~first], 1] = dst[~first]
    ea, eb = a[crossing], b[crossing]
    a_in = flat[ea]
    p_in, p_out = np.where(a_in, ea, eb), np.where(a_in, eb, ea)
    return [(p_in[c], p_out[c]) for c in map(np.asarray, _chains(nb))]
