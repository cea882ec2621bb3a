"""Pieces as simple paths on the torus: wrapped, cut into simple parts, no stretch twice."""

import math

import numpy as np
import pytest
import shapely

from atlas.data.boundary_curves import Curve
from atlas.data.boundary_paths import simple_paths

TWO_PI = 2 * math.pi


def _curve(xy, left=2, right=0):
    xy = np.asarray(xy, float)
    return Curve("SS", "SS_stability", left, right, xy, np.full(len(xy), 1e-11))


def test_a_curve_that_doubles_back_becomes_simple_without_the_retraced_stretch():
    """A polyline running 0 -> 1 -> 0.5 -> 1.5 along a line (a stretch three times) is cut
    into simple parts and the stretch kept once per direction."""
    x = np.r_[np.linspace(0, 1, 11), np.linspace(0.95, 0.5, 10), np.linspace(0.55, 1.5, 20)]
    c = _curve(np.stack([x, 0.3 + 0 * x], 1))
    assert not shapely.is_simple(shapely.LineString(c.vertices))
    out, dropped = simple_paths([c], chord=1e-6)
    assert out and dropped > 0
    assert all(shapely.is_simple(shapely.LineString(p.vertices)) for p in out)
    forward = [p for p in out if p.vertices[-1, 0] > p.vertices[0, 0]]
    covered = sum(np.ptp(p.vertices[:, 0]) for p in forward)
    assert covered <= 1.5 + 1e-9  # each stretch of x in [0, 1.5] at most once going forward


def test_vertices_are_wrapped_and_cut_at_the_seam():
    c = _curve([[6.0, 1.0], [6.2, 1.0], [TWO_PI + 3e-8, 1.0], [0.1 + TWO_PI, 1.1]])
    out, _ = simple_paths([c], chord=1e-6)
    xy = np.concatenate([p.vertices for p in out])
    assert (xy >= 0).all() and (xy < TWO_PI).all()
    assert len(out) == 2
    # both parts end at the interpolated crossing point, which has no bracket
    assert out[0].vertices[-1, 0] == np.nextafter(TWO_PI, 0) and out[1].vertices[0, 0] == 0.0
    assert np.isnan(out[0].bracket[-1]) and np.isnan(out[1].bracket[0])


def test_a_piece_along_the_seam_stays_whole():
    """A class-line piece on beta1 = 0 whose vertices alternate between the two sides of the
    seam (2 pi - 1e-12, 2 pi + 3e-8) was cut into fragments with the segments across the seam
    dropped; every part now reaches the seam, and together they cover the whole stretch."""
    y = np.linspace(1.50, 1.57, 8)
    x = np.where(np.arange(8) % 2 == 0, TWO_PI - 1e-12, TWO_PI + 3e-8)
    c = _curve(np.stack([x, y], 1))
    out, _ = simple_paths([c], chord=1e-6)
    ys = np.concatenate([p.vertices[:, 1] for p in out])
    assert ys.min() == 1.50 and ys.max() == 1.57
    assert sum(np.ptp(p.vertices[:, 1]) for p in out) == pytest.approx(0.07)
    for p in out:
        assert (p.vertices >= 0).all() and (p.vertices < TWO_PI).all()
