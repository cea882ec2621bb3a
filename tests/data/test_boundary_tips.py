"""``atlas.data.boundary_tips``: which tips are inserted into hand-made polylines."""

import numpy as np

from atlas.data import boundary_tips as bt
from atlas.data.boundaries import _Polys


def _polys():
    """One polyline of region 0 against code 2: two vertices on the diagonal beta2 = beta1 (line
    11), turning off it at the third."""
    xy = np.array([[1.0, 1.0], [1.5, 1.5], [2.0, 2.5]])
    n = len(xy)
    return _Polys(
        xy=xy,
        ends=np.stack([xy, xy], 1),
        other=np.full(n, 2, np.int8),
        width=np.zeros(n),
        cid=np.zeros(n, int),
        key=np.arange(n, dtype=float),
        todo=np.zeros(n, bool),
        tip=np.zeros(n, bool),
        region=[0],
    )


def _tip(x, y):
    p = np.array([[x, y]])
    return p, p + [0.0, 1e-12], np.array([2], np.int8), np.array([0], np.int8)


def test_a_needle_tip_on_the_line_of_a_vertex_is_inserted_next_to_it():
    polys = _polys()
    assert bt.spike_tips(polys, {(11, 1): _tip(1.6, 1.6)}, near=1e-6, chord=1e-6, cell=0.2) == 1
    assert len(polys.xy) == 4 and polys.tip.sum() == 1
    # next to the nearest vertex on the line, (1.5, 1.5), on the side of its neighbour nearer
    # to the tip, (1, 1)
    np.testing.assert_allclose(polys.xy[1], [1.6, 1.6])
    assert polys.todo[0] and polys.todo[1]  # both new segments are refined again


def test_tips_off_the_vertex_line_far_away_or_already_reached_are_not_inserted():
    """The rule that matters at small chords: a tip with the right codes on another line, or a
    cell away, is another boundary's (inserting it drew 1e-2 rad spikes at chord = 1e-8)."""
    tips = {
        (0, 1): _tip(0.0, 1.55),  # on beta1 = 0: no vertex of the polyline lies on that line
        (11, -1): _tip(3.0, 3.0),  # on the vertices' line, but 1.5 rad from them
        (11, 1): _tip(1.5, 1.5 + 1e-7),  # within the chord tolerance of a vertex: reached
    }
    polys = _polys()
    assert bt.spike_tips(polys, tips, near=1e-6, chord=1e-6, cell=0.2) == 0
    assert len(polys.xy) == 3
