"""``atlas.data.marching``: region boundaries on the Kuhn triangulation, checked against the
triangulation's definition (every crossing edge once, consecutive edges sharing a triangle)."""

import numpy as np
import pytest

from atlas.data.marching import region_boundaries


def _triangles(n1, n2, flip):
    """Node triples (flat indices) of the triangulation, written out cell by cell."""
    out = []
    for i in range(n1 - 1):
        for j in range(n2 - 1):
            a, b, c, d = i * n2 + j, (i + 1) * n2 + j, i * n2 + j + 1, (i + 1) * n2 + j + 1
            out += [(a, b, c), (b, d, c)] if flip[i, j] else [(a, b, d), (a, c, d)]
    return [frozenset(t) for t in out]


def _check(inside, flip=None):
    n1, n2 = inside.shape
    flip = np.zeros((n1 - 1, n2 - 1), bool) if flip is None else flip
    lines = region_boundaries(inside, flip)
    flat = inside.ravel()
    tris = _triangles(n1, n2, flip)
    edges = set()
    for t in tris:
        for u in t:
            for v in t:
                if u < v and flat[u] != flat[v]:
                    edges.add((u, v))
    seen = []
    for p_in, p_out in lines:
        assert flat[p_in].all() and not flat[p_out].any()
        pairs = [tuple(sorted(e)) for e in zip(p_in.tolist(), p_out.tolist())]
        closed = len(pairs) > 2 and pairs[0] == pairs[-1]
        seen += pairs[:-1] if closed else pairs
        for e, f in zip(pairs, pairs[1:]):  # consecutive edges lie in one triangle
            assert any(set(e) | set(f) <= t for t in tris)
    assert sorted(seen) == sorted(edges)  # every crossing edge exactly once
    return lines


def test_one_node_is_a_closed_hexagon():
    inside = np.zeros((5, 5), bool)
    inside[2, 2] = True
    (line,) = _check(inside)
    assert len(line[0]) == 7 and (line[0] == 12).all()  # 6 edges, the first repeated


def test_a_diagonal_strip_is_one_region():
    """Nodes on the diagonal i = j are one region, joined by the cells' diagonals: one closed
    boundary (marching squares sees separate diamonds around each node)."""
    inside = np.zeros((6, 6), bool)
    inside[[1, 2, 3, 4], [1, 2, 3, 4]] = True
    assert len(_check(inside)) == 1
    flip = np.ones((5, 5), bool)  # split the other way: the nodes are apart
    assert len(_check(inside, flip)) == 4


def test_a_half_plane_is_one_open_chain_across_the_grid():
    inside = np.zeros((6, 7), bool)
    inside[:, :3] = True
    (line,) = _check(inside)
    p_in, p_out = line
    assert p_in[0] // 7 in (0, 5) and p_in[-1] // 7 in (0, 5) and p_in[0] != p_in[-1]


@pytest.mark.parametrize("seed", range(6))
def test_random_regions(seed):
    rng = np.random.default_rng(seed)
    inside = rng.random((9, 11)) < 0.45
    flip = rng.random((8, 10)) < 0.3
    _check(inside, flip)


def test_empty_and_full_regions_and_a_single_row():
    assert region_boundaries(np.zeros((4, 4), bool)) == []
    assert region_boundaries(np.ones((4, 4), bool)) == []
    assert region_boundaries(np.ones((1, 4), bool)) == []
