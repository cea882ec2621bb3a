"""Curve ends: a curve that stops short of its proven point is extended to it, a dropped segment
between two ends is bridged, and every end left with nothing near it is reported and breaks
``complete``.  References: mpmath roots of ``p`` (paper eq. 9) at 60 digits."""

import math

import numpy as np
import pytest
from samples import eq9_roots

from atlas.data import boundaries as bd
from atlas.data import boundary_ends, boundary_points
from atlas.data.boundary_curves import Curve, Point

PI = math.pi
DAMPED = (2.0, 0.1, 0.1)
#: the proven leave point of the II boundary on beta2 = beta1 - pi at kappa 2, q 0.1
LEAVE = (4.2487413713838835, 1.1071487177940904)


def _ii_consistent(b1, b2, model, dps=60) -> bool:
    """Whether ``p`` (paper eq. 9, ``k2 = 1``) has a real root ``l > 0`` at ``(b1, b2)`` [rad]
    (II consistent), by mpmath at ``dps`` digits (an independent reference)."""
    import mpmath

    zs = eq9_roots(b1, b2, model, dps)
    with mpmath.workdps(dps):
        return any(abs(z.imag) < mpmath.mpf(10) ** -40 and z.real > 0 for z in zs)


@pytest.fixture(scope="module")
def damped_64():
    g = np.arange(64) * 2 * PI / 64
    return bd.slice_boundaries(g, g, *DAMPED, fields=("SS", "II"))


def test_the_stretch_up_to_the_leave_point_is_covered(damped_64):
    """At kappa 2, q 0.1 (64 x 64) the II boundary arrives at the proven leave point
    (4.2487414, 1.1071487) on ``beta2 = beta1 - pi`` from below the line.  Along the last 1e-5
    rad before it, mpmath finds II consistent 1e-9 above the line and inconsistent 1e-9 below
    (a boundary within 1e-9 of the line), and every such sample lies within twice the cover
    distance of an II curve (before: the on-line piece ended 7.3e-6 rad short of the point, a
    sample in between 5e-6 from every curve, and ``complete`` was 1); the point is a spliced
    vertex of a curve."""
    b = damped_64
    curves = [c for c in b.curves if c.field == "II"]
    reach = 2 * b.attrs["II_cover_distance"]
    for s in np.linspace(1e-7, 1e-5, 12):
        x = LEAVE[0] - s
        y = x - PI
        assert _ii_consistent(x, y + 1e-9, DAMPED) != _ii_consistent(x, y - 1e-9, DAMPED), s
        d = boundary_points.nearest_segment((x, y), curves)[0]
        assert d <= reach, (s, d)
    at = [c.vertices[k] for c in curves for k in c.spliced]
    assert any(np.hypot(*(v - LEAVE)) < 1e-12 for v in at)


def test_no_end_is_left_dangling(damped_64):
    """Every end of the slice's curves lies on another curve or at a point: the two II and
    SS ends short of a proven point are extended (II 1, SS 2) and four dropped SS segments
    bridged; none left, ``dangling_ends`` 0 for both fields."""
    a = damped_64.attrs
    assert a["II_ends_extended"] >= 1 and a["SS_ends_extended"] + a["SS_ends_bridged"] >= 1
    assert a["SS_dangling_ends"] == a["II_dangling_ends"] == 0
    assert not [p for p in damped_64.points if p.kind == "dangling_curve_end"]


def _curve(xy, left=2, right=0):
    xy = np.asarray(xy, float)
    return Curve("II", "II_consistency", left, right, xy, np.zeros(len(xy)), False, *DAMPED)


def test_a_curve_end_with_nothing_near_it_is_dangling():
    """Two pieces of one polyline with a segment between them cut out: both inner ends are
    dangling (nothing within ``reach``), the outer ones too unless a point stands there; and a
    slice with one breaks ``complete``."""
    a = _curve([[1.0, 1.0], [1.1, 1.1]])
    b = _curve([[1.2, 1.2], [1.3, 1.3]])
    pts = [Point(1.0, 1.0, "leaves_class_line", 1e-15, *DAMPED, proven=True, field="II")]
    got = boundary_ends.dangling([a, b], pts, 1e-6)
    assert sorted(round(xy[0], 6) for xy, _ in got) == [1.1, 1.2, 1.3]
    assert all(d == pytest.approx(math.hypot(xy[0] - 1, xy[1] - 1)) for xy, d in got)
    assert boundary_ends.dangling([a, b], pts, 0.2) == []
    ok = dict(kappa=2.0, q1=0.1, q2=0.1, II_lines_complete=1, II_line_length_left_uncovered=0.0)
    assert bd._completeness([ok | {"II_dangling_ends": 0}])["complete"] == 1
    assert bd._completeness([ok | {"II_dangling_ends": 2}])["complete"] == 0


def test_a_segment_off_the_boundary_is_not_proven():
    """:func:`boundary_ends.proven_segment` proves the stretch along the II boundary that
    arrives at the leave point (mpmath above) and refuses a segment 1e-4 rad below it, where
    no boundary runs."""
    end = np.array([LEAVE[0] - 1e-5, LEAVE[1] - 1e-5])
    c = _curve([end - 1e-6, end])
    assert boundary_ends.proven_segment(c, end, np.array(LEAVE), 1e-6, 1e-10)
    low = np.array([0.0, 1e-4])
    assert not boundary_ends.proven_segment(c, end - low, np.array(LEAVE) - low, 1e-6, 1e-10)


def _ss_stable(b1, b2, model, dps=60) -> bool:
    """Whether every root of ``p`` (paper eq. 9, ``k2 = 1``) at ``(b1, b2)`` [rad] has a negative
    real part (SS stable), by mpmath at ``dps`` digits (an independent reference)."""
    return max(z.real for z in eq9_roots(b1, b2, model, dps)) < 0


def test_a_fine_grid_extends_an_end_as_far_as_a_coarse_one():
    """kappa 2, q 0.1: the SS boundary leaves beta2 = beta1 + pi at (pi/4, 5 pi/4) tangentially;
    the 1024^2 slice (checked grid 4097^2) stopped its curve at END, 1.6e-3 rad short of the
    point, farther than one of its cells (reported dangling), where the 256^2 slice ran on to it
    (the bench's Hausdorff distance 1.3e-4 rad between the two).  The same grid spacing on a box
    around it: the stretch is covered (mpmath: a stability change within 2e-6 rad of each
    sample, and a curve within 2e-6 + twice the cover distance; 1.3e-4 before)."""
    end, leave = np.array([0.7844469014337165, 3.9256581784576223]), np.array([PI / 4, 5 * PI / 4])
    h = 2 * PI / 4096
    box = bd.slice_boundaries(
        np.arange(480, 560) * h, np.arange(2520, 2600) * h, *DAMPED, fields=("SS",), check=0
    )
    loose = np.array(box.attrs["SS_dangling_end_points"]).reshape(-1, 2)
    assert (np.hypot(*(loose - end).T) > 1e-3).all()
    curves = [c for c in box.curves if c.field == "SS"]
    d = (leave - end) / np.hypot(*(leave - end))
    normal = np.array([-d[1], d[0]])
    for f in (0.1, 0.3, 0.5, 0.7, 0.9):
        xy = end + f * (leave - end)
        sides = {_ss_stable(*(xy + s * 2e-6 * normal), DAMPED) for s in (-1, 1)}
        assert sides == {True, False}
        dist = boundary_points.nearest_segment(xy, curves)[0]
        assert dist <= 2e-6 + 2 * box.attrs["SS_cover_distance"]
