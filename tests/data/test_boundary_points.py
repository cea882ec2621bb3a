"""Proven enclosures of the points where the SS boundary meets a class line, against 50-digit
references: the closed form at q = 0 and mpmath roots of the Hurwitz minors when damped."""

import math

import mpmath as mp
import numpy as np
import pytest
import shapely
from reference_sympy import characteristic_coeffs_mp

from atlas.core import contact_modes, exact
from atlas.data import boundaries as bd
from atlas.data import boundary_points as bp

PI = math.pi
mp.mp.dps = 50


def _on_line(m, beta):
    """``(c1, s1, c2, s2)`` at angle ``beta`` along class line ``m`` (mpmath)."""
    c, s = mp.cos(beta), mp.sin(beta)
    axes = [(1, 0), (0, 1), (-1, 0), (0, -1), (1, 0)]
    if m < 5:
        return (*axes[m], c, s)
    if m < 10:
        return (c, s, *axes[m - 5])
    sign = 1 if m == 11 else -1
    return c, s, sign * c, sign * s


def _minors(m, beta, kappa, q1, q2):
    """The SS boundary's candidate functions at ``beta`` on line ``m``, from the characteristic
    polynomial p(l) = (l^2 + c1 d1)(l^2 + s2 d2) - c2 s1 d1 d2 (d1 = kappa + q1 l, d2 = 1 + q2 l)
    expanded here in mpmath (coefficients of l^3 .. l^0)."""
    c1, s1, c2, s2 = _on_line(m, beta)
    kappa, q1, q2 = (mp.mpf(float(v)) for v in (kappa, q1, q2))

    p = characteristic_coeffs_mp(c1, s1, c2, s2, kappa, q1, q2)[::-1]
    a0, a1, a2, a3 = p[:4]
    if q1 == 0 and q2 == 0:
        return [a2, a2 * a2 - 4 * a0]
    H2 = a3 * a2 - a1
    D = c1 * s2 - s1 * c2
    return [a3, H2, a1 * H2 - a3 * a3 * a0 if D != 0 else (q1 + kappa * q2) * H2 - kappa * a3**2]


def _line_of(p):
    """The class line ``m`` of a point and its angle along it (``beta2 = beta1 - pi`` is
    ``beta2 = beta1 + pi`` on the torus)."""
    for k in range(4):
        if p.beta1 == k * PI / 2:
            return k, p.beta2
        if p.beta2 == k * PI / 2:
            return 5 + k, p.beta1
    d = (p.beta2 - p.beta1) % (2 * PI)
    return (11 if min(d, 2 * PI - d) < 1e-9 else 12), p.beta1


def _reference(p, model):
    """The 50-digit angle of ``p`` along its line: a root of the candidate function that is
    smallest there (of its derivative for a tangency, a double root)."""
    m, beta = _line_of(p)
    k = int(np.argmin([abs(f) for f in _minors(m, mp.mpf(beta), *model)]))
    f = lambda b: _minors(m, b, *model)[k]  # noqa: E731
    g = (lambda b: mp.diff(f, b)) if p.kind == "touches_class_line" else f
    return m, mp.findroot(g, mp.mpf(beta))


def _ratios(points, model):
    out = []
    for p in points:
        m, ref = _reference(p, model)
        err = abs(ref - mp.mpf(p.beta1 if m >= 5 else p.beta2)) * (mp.sqrt(2) if m >= 10 else 1)
        out.append(float(err / p.uncertainty))
    return np.array(out)


@pytest.mark.parametrize("kappa", [0.5, 2.0])
def test_q0_tangencies_are_the_closed_form(kappa):
    """q = 0: the discriminant curve (kappa C1 - S2)^2 + 4 kappa S1 C2 = 0 touches beta2 = beta1
    where kappa cos + sin = 0 (disc = (kappa C + S)^2 there) and beta2 = beta1 + pi where
    kappa cos = sin (twice: beta1 = atan kappa and pi + atan kappa), found from the algebra
    alone; each proven enclosure holds the 50-digit closed form."""
    pts, _ = bp.ss_line_points((kappa, 0.0, 0.0), lines=(11, 12))
    touch = [p for p in pts if p.kind == "touches_class_line"]
    assert len(touch) == 4 and all(p.proven for p in touch)
    want = [PI - mp.atan(kappa), 2 * mp.pi - mp.atan(kappa), mp.atan(kappa), mp.pi + mp.atan(kappa)]
    for p in touch:
        err = min(abs(mp.mpf(p.beta1) - w) for w in want) * mp.sqrt(2)
        assert 0 < p.uncertainty < 1e-13 and err <= p.uncertainty


def test_points_of_a_slice_hold_their_enclosures(slice_32):
    """Every proven point of two 32 x 32 slices (SS, no check, chord 1e-4) lies within its
    uncertainty of the mpmath reference; the other points state no number."""
    for model in ((0.5, 0.0, 0.0), (2.0, 0.1, 0.1)):
        b = slice_32(model, fields=("SS",), chord=1e-4)
        proven = [p for p in b.points if p.proven]
        assert proven
        assert _ratios(proven, model).max() <= 1
        assert all(math.isnan(p.uncertainty) for p in b.points if not p.proven)


def _exact_ss(b1, b2, model):
    """The SS code at ``(b1, b2)`` from the exact tier alone (rational arithmetic)."""
    c1, s1 = (float(x) for x in contact_modes.direction(b1))
    c2, s2 = (float(x) for x in contact_modes.direction(b2))
    return exact.point_spectral(c1, s1, c2, s2, *model)["stable_SS"]


@pytest.mark.parametrize("chord", [bd.CHORD, 1e-4, 1e-2])
def test_seam_tangencies_found_at_every_chord(chord, slice_32):
    """q = 0, kappa 0.5: on the seam beta1 = 0 the discriminant is (kappa - sin beta2)^2, so the
    SS boundary touches it at beta2 = asin(kappa) = pi / 6 and 5 pi / 6 (50-digit closed form);
    the exact tier sees the code change next to both (on the side where sin beta1 cos beta2 < 0).  Both points are
    listed, proven, at the default chord (the traced polyline passes 1e-3 rad away and the point
    was dropped) as at a coarse one."""
    model = (0.5, 0.0, 0.0)
    want = [mp.asin(mp.mpf(0.5)), mp.pi - mp.asin(mp.mpf(0.5))]
    for w in want:  # the tangency is a boundary point: an independent code change beside it
        side = -1e-6 if mp.cos(w) > 0 else 1e-6
        assert [_exact_ss(side, float(w) + d, model) for d in (-1e-2, 0.0, 1e-2)] == [2, 0, 2]
    b = slice_32(model, fields=("SS",), chord=chord)  # 32 x 32, no check
    seam = [p for p in b.points if p.kind == "touches_class_line" and p.beta1 == 0.0]
    assert len(seam) == 2 and all(p.proven for p in seam)
    for p, w in zip(sorted(seam, key=lambda p: p.beta2), want):
        assert abs(mp.mpf(p.beta2) - w) <= p.uncertainty < 1e-13


def test_every_root_on_the_lines_is_counted_and_only_boundary_points_kept():
    """q = 0, kappa 0.5: on beta1 = pi / 2 the trace kappa cos beta1 + sin beta2 is sin beta2,
    zero at beta2 = 0 and at beta2 = pi, where t = tan(beta2 / 2) is infinite: both are counted.
    At beta2 = pi the SS code is 0 all around (exact tier), so it is not a boundary point and
    is not listed; the listed crossing is the discriminant's, where the code changes."""
    model = (0.5, 0.0, 0.0)
    roots = [float(b.mid()) for m, b, _ in bp.line_roots(model, lines=(1,))]
    assert min(abs(r - PI) for r in roots) == 0.0 and min(abs(r) for r in roots) < 1e-15
    around = [(PI / 2 + u, PI + v) for u in (-1e-6, 1e-6) for v in (-1e-3, 0.0, 1e-3)]
    assert {_exact_ss(*p, model) for p in around} == {0}
    pts, count = bp.ss_line_points(model, lines=(1,))
    assert count == len(roots) and not any(abs(p.beta2 - PI) < 1e-3 for p in pts)
    for p in pts:
        got = {
            _exact_ss(PI / 2 + u, p.beta2 + v, model) for u in (-1e-6, 1e-6) for v in (-1e-4, 1e-4)
        }
        assert len(got) > 1


def _torus_distance(xy, vertices) -> np.ndarray:
    """Per row of ``vertices``, its distance [rad] to ``xy`` on the torus (mpmath)."""
    two_pi = 2 * mp.pi
    out = []
    for x, y in vertices:
        d = [(mp.mpf(a) - b + mp.pi) % two_pi - mp.pi for a, b in zip((x, y), xy)]
        out.append(mp.sqrt(d[0] ** 2 + d[1] ** 2))
    return np.array(out, dtype=object)


def _segment_distance(xy, curves) -> float:
    """Distance [rad] of ``xy`` to the nearest segment of ``curves`` on the torus (each segment
    against the image of ``xy`` nearest to its first vertex)."""
    a = np.concatenate([c.vertices[:-1] for c in curves])
    d = np.concatenate([np.diff(c.vertices, axis=0) for c in curves])
    img = a + (np.asarray(xy) - a + PI) % (2 * PI) - PI
    t = np.clip(np.sum((img - a) * d, 1) / np.maximum(np.sum(d * d, 1), 1e-300), 0, 1)
    return float(np.hypot(*(a + t[:, None] * d - img).T).min())


@pytest.mark.parametrize("chord", [bd.CHORD, 1e-2])
def test_proven_points_lie_on_the_curves_at_every_chord(chord):
    """kappa 0.5, q = 0, 64 x 64: every proven point is on an SS curve (within the vertex
    tolerance of a segment, on the torus; up to 4.3e-5 rad off at the default chord and 2.2e-4
    at 1e-2 before they were spliced in),
    and the seam tangencies (0, asin kappa), (0, pi - asin kappa) (50-digit closed form) are
    vertices within their stated radius (half the vertex's bracket; its ends are NaN: an
    enclosure, not a bracket between two codes).  A proven point is on every SS curve that
    passes within twice the cover distance of it, as a vertex or within the vertex tolerance of
    a segment (only the nearest curve got it before: (6.1598, 0) stayed 3.2e-8 rad off a second
    curve at both chords), or the curve ends where another one reaching the point starts (a
    piece on a class line is not extended over a needle piece that covers the stretch).  The
    curves stay simple."""
    model = (0.5, 0.0, 0.0)
    g = np.arange(64) * 2 * PI / 64
    b = bd.slice_boundaries(g, g, *model, fields=("SS",), check=0, chord=chord)
    ss = [c for c in b.curves if c.field == "SS"]
    proven = [p for p in b.points if p.proven]
    assert len(proven) == b.attrs["SS_line_points"] == 10
    assert max(_segment_distance((p.beta1, p.beta2), ss) for p in proven) <= bd.TOL
    assert b.attrs["SS_points_off_curves"] == 0 and b.attrs["SS_points_attached"] >= 2
    for w in (mp.asin(mp.mpf(0.5)), mp.pi - mp.asin(mp.mpf(0.5))):
        dist = _torus_distance((0, w), np.concatenate([c.vertices for c in ss]))
        k = int(np.argmin(dist))
        bracket = np.concatenate([c.bracket for c in ss])[k]
        assert dist[k] <= bracket / 2 < 1e-14
    spliced = [(c, i) for c in ss for i in c.spliced]
    assert len(spliced) == b.attrs["SS_points_attached"]
    for c, i in spliced:  # each spliced vertex is a proven point, its ends no bracket
        assert c.ends is None or np.isnan(c.ends[i]).all()
        dist = [_torus_distance((p.beta1, p.beta2), c.vertices[i : i + 1])[0] for p in proven]
        assert min(dist) <= c.bracket[i] / 2 <= bd.TOL / 2
    assert all(shapely.is_simple(shapely.LineString(c.vertices)) for c in ss)
    for p in proven:  # on every curve it lies on: a vertex, or a segment within the tolerance
        for c in ss:
            seg = _segment_distance((p.beta1, p.beta2), [c])
            if seg <= 2 * b.attrs["SS_cover_distance"]:
                d = (c.vertices - (p.beta1, p.beta2) + PI) % (2 * PI) - PI
                on = np.hypot(*d.T).min() <= bd.TOL / 2 or seg <= bd.TOL
                assert on or _continued(c, (p.beta1, p.beta2), ss)


def _continued(c, xy, curves):
    """Whether an end of curve ``c`` is a vertex of another of ``curves`` that has a vertex at
    ``xy`` (within the vertex tolerance): that curve covers the stretch from ``c`` to the point
    (a piece on a class line is not stretched over it twice)."""
    for o in curves:
        if o is c:
            continue
        at_end = min(_torus_distance(e, o.vertices).min() for e in c.vertices[[0, -1]])
        if at_end <= bd.TOL and _torus_distance(xy, o.vertices).min() <= bd.TOL / 2:
            return True
    return False


def test_nearest_segment_keeps_the_point_exact_off_the_seams():
    """The image of a point on the torus is the point plus ``2 pi n``: the point itself where
    no seam lies between it and the segment (``a + ((x - a + pi) mod 2 pi) - pi`` rounds ``x =
    5.003289068692397`` to ``5.003289068692396`` with ``a = 5.017081365127511``: a proven
    point spliced 1 ulp off its enclosure's midpoint, onto the other side of a root)."""
    x, a = 5.003289068692397, 5.017081365127511
    curve = bd.Curve(
        "SS", "SS_stability", 1, 0, np.array([[a, a], [a - 0.03, a - 0.03]]),
        np.full(2, 1e-10), True, 2.0, 0.1, 0.1,
    )  # fmt: skip
    dist, i, k, t, img = bp.nearest_segment((x, x), [curve])
    assert (i, k) == (0, 0) and dist < 1e-15
    assert img.tolist() == [x, x]
    far = bp.nearest_segment((x - 2 * math.pi, x), [curve])[4]  # across a seam: shifted 2 pi
    assert far.tolist() == [x - 2 * math.pi + 2 * math.pi, x]


def _plane_distance(p, a, b) -> float:
    """Distance [rad] in the plane from point ``p`` to the segment ``a -> b`` (mpmath, 30
    digits)."""
    with mp.workdps(30):
        p, a, b = ([mp.mpf(float(v)) for v in x] for x in (p, a, b))
        dx, dy = b[0] - a[0], b[1] - a[1]
        den = dx * dx + dy * dy
        t = 0 if den == 0 else min(1, max(0, ((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / den))
        return float(mp.hypot(a[0] + t * dx - p[0], a[1] + t * dy - p[1]))


def test_torus_distances_are_the_nearest_image_distances():
    """Point-to-segment distances on the torus, against the smallest plane distance over the
    point's nine images ``xy + 2 pi (i, j)``, on random short segments as curves have them
    (some across a seam, some a single point) and points: equal where below 1 rad (farther, a
    point almost opposite on the torus may be measured from another image, never nearer); and the nearest segment, curve by curve and over all, is the one
    of smallest reference distance."""
    rng = np.random.default_rng(7)
    a = rng.uniform(0, 2 * math.pi, (40, 2))
    d = rng.normal(0, 0.05, (40, 2))
    d[::7] = 0.0
    xy = np.concatenate([rng.uniform(0, 2 * math.pi, (30, 2)), a[:5] + d[:5] / 3])
    dist, t, img = bp.torus_distances(xy, a, d)
    shifts = 2 * math.pi * np.array([(i, j) for i in (-1, 0, 1) for j in (-1, 0, 1)])
    for m, p in enumerate(xy):
        for n in range(len(a)):
            ref = min(_plane_distance(p + s, a[n], a[n] + d[n]) for s in shifts)
            assert dist[m, n] >= ref * (1 - 1e-12) - 1e-14
            if ref > 1.0:
                continue
            assert dist[m, n] == pytest.approx(ref, rel=1e-12, abs=1e-14)
            at = a[n] + t[m, n] * d[n]
            assert math.hypot(*(at - img[m, n])) == pytest.approx(ref, rel=1e-12, abs=1e-14)
    curves = [
        bd.Curve("SS", "SS_stability", 1, 0, np.cumsum(np.r_[a[i : i + 1], d[i : i + 4]], 0),
                 np.zeros(5))
        for i in (0, 10, 20)
    ] + [bd.Curve("SS", "SS_stability", 1, 0, a[30:31], np.zeros(1))]  # fmt: skip
    for p in xy[:8]:
        got = bp.nearest_segment(p, curves)
        ref = [
            min(_plane_distance(p + s, v[k], v[k + 1]) for s in shifts)
            for v in (c.vertices for c in curves[:3])
            for k in range(4)
        ]
        assert got[0] == pytest.approx(min(ref), rel=1e-12, abs=1e-14)
        assert 4 * got[1] + got[2] == int(np.argmin(ref))


def test_pairs_near_are_every_pair_within_reach():
    """The point-segment pairs within a reach found from the sorted segment starts are those of
    the full distance matrix (points and segments across both seams)."""
    rng = np.random.default_rng(3)
    a = np.concatenate([rng.uniform(0, 2 * math.pi, (300, 2)), [[6.28, 0.01], [0.001, 6.27]]])
    d = rng.normal(0, 0.02, a.shape)
    xy = np.concatenate([rng.uniform(0, 2 * math.pi, (200, 2)), a[-2:] + [[0.004, 0], [-0.003, 0]]])
    for reach in (1e-3, 0.05, 0.3):
        i, j = bp.pairs_near(xy, a, d, reach)
        want = np.argwhere(bp.torus_distances(xy, a, d)[0] <= reach)
        np.testing.assert_array_equal(np.stack([i, j], 1), want)
        assert reach < 0.05 or len(want) > 10
