"""Every algebraic root of the SS line restrictions accounted for.  The verdict ``not_boundary`` is
checked independently: the exact tier's codes on a small circle around the root are one code on
each side of the line (no boundary but the line itself comes near it)."""

import functools
import math

import mpmath
import numpy as np
import pytest
from samples import eq9_roots, exact_code

from atlas.data import boundaries as bd
from atlas.data import boundary_germs, boundary_points, boundary_roots

PI = math.pi
Q0 = (0.5, 0.0, 0.0)
DAMPED = (2.0, 0.1, 0.1)


@functools.cache
def _account(model):
    """The SS line roots of slice ``model``, which of them the codes list, and their verdicts
    (computed once per slice: shared by the tests below, which only read them)."""
    roots = boundary_points.line_roots(model)
    codes = boundary_points.root_codes("SS", roots, model)
    listed = (codes != codes[:, :, :1]).any(axis=(1, 2))
    germs = boundary_germs.germ_roots("SS", model)
    return roots, listed, boundary_roots.account_roots("SS", model, roots, germs, listed)


def _rings(field, model, roots, verdicts, only=None):
    """``(m, ball, ring)`` of each ``not_boundary`` root of ``field`` that is not a simple root
    of one boundary polynomial (or for which ``only(m, ball)`` holds); ``ring``: 24 ``(angle,
    (beta1, beta2))`` on a circle of radius 1e-7 rad around it (none on the line)."""
    if only is None:

        def only(m, ball):
            return not boundary_roots._simple_single(field, model, m, ball)

    out = []
    for (m, ball, _), v in zip(roots, verdicts):
        if v != "not_boundary" or not only(m, ball):
            continue
        at, _ = _point(m, float(ball.mid()))
        angles = (np.arange(24) + 0.5) * PI / 12
        out.append(
            (m, ball, [(a, at + 1e-7 * np.array([math.cos(a), math.sin(a)])) for a in angles])
        )
    return out


@pytest.mark.parametrize("model, n", [(Q0, 28), (DAMPED, 44)])
def test_every_root_has_a_verdict(model, n):
    """Each root gets one verdict; a listed proven point is a ``point``; both seam tangencies
    at q = 0, ``(0, pi/6)`` and ``(0, 5 pi/6)``, are points; crossings of class lines are
    multiples of ``pi/2``."""
    roots, listed, verdicts = _account(model)
    assert len(verdicts) == len(roots) == n
    assert set(verdicts) <= set(boundary_roots.KINDS)
    assert all(v == "point" for v, on in zip(verdicts, listed) if on)
    for (m, ball, _), v in zip(roots, verdicts):
        beta = float(ball.mid())
        if v == "class_crossing":
            assert abs(beta / (PI / 2) - round(beta / (PI / 2))) < 1e-12
        if m == 0 and model == Q0 and min(abs(beta - PI / 6), abs(beta - 5 * PI / 6)) < 1e-12:
            assert v == "point"
    assert verdicts.count("not_boundary") >= 8


def _point(m, beta):
    if m < 5:
        return np.array([m * PI / 2, beta]), np.array([1.0, 0.0])
    if m < 10:
        return np.array([beta, (m - 5) * PI / 2]), np.array([0.0, 1.0])
    return np.array([beta, beta + (m - 11) * PI]), np.array([-1.0, 1.0]) / math.sqrt(2)


@functools.cache
def _account_ii(model):
    """:func:`_account` for II (its distinct germ roots; none listed)."""
    germs = boundary_germs.germ_roots("II", model)
    roots = boundary_roots.distinct(germs)
    return (
        roots,
        None,
        boundary_roots.account_roots("II", model, roots, germs, [False] * len(roots)),
    )


def test_ii_roots_are_counted_once_with_a_verdict():
    """II: the germ roots of the discriminant and the tie resultant, each distinct root once
    (76 -> 72 at kappa 2, q 0.1), every one with a verdict."""
    germs = boundary_germs.germ_roots("II", DAMPED)
    counts, _ = boundary_roots.ii_root_account(DAMPED, germs)
    assert len(germs) == 76 and counts["line_roots"] == 72
    assert sum(counts[f"line_roots_{k}"] for k in boundary_roots.KINDS) == 72


@pytest.mark.parametrize("field, model", [("SS", Q0), ("SS", DAMPED), ("II", DAMPED)])
def test_not_boundary_roots_have_one_code_per_side(field, model):
    """Around each ``not_boundary`` root, 24 points on a circle of radius 1e-7 rad (off the line
    by more than a tenth of it) and 1e-12 off the line 1e-7 along it on both sides (inside a
    needle a tangent boundary would leave): the exact tier's code is the same on all of one
    side.  (Roots decided from the branches through them are checked closer:
    :func:`test_ii_roots_decided_from_the_branches_through_them`; a boundary can pass them 5e-9
    rad off the line.)"""
    roots, _, verdicts = (_account if field == "SS" else _account_ii)(model)
    checked = branches = 0
    for (m, ball, _), v in zip(roots, verdicts):
        if v != "not_boundary":
            continue
        if field == "II" and _by_branches(model, m, ball):
            branches += 1
            continue
        at, normal = _point(m, float(ball.mid()))
        sides = {1: set(), -1: set()}
        along = np.array([normal[1], -normal[0]])
        near = [s * 1e-7 * along + r * 1e-12 * normal for s in (-1, 1) for r in (-1, 1)]
        ring = [1e-7 * np.array([math.cos(a), math.sin(a)]) for a in np.arange(24) * PI / 12]
        for off in near + ring:
            side = off @ normal
            if abs(side) > 1e-13:
                sides[int(np.sign(side))].add(exact_code(field, *(at + off), model))
        assert len(sides[1]) == 1 and len(sides[-1]) == 1, (m, float(ball.mid()), sides)
        checked += 1
    assert checked + branches == verdicts.count("not_boundary")


def _by_branches(model, m, ball):
    """Whether the II root ``ball`` of line ``m`` is decided neither by a simple root of one
    boundary polynomial nor by the signs of ``p``'s coefficients."""
    simple = boundary_roots._simple_single("II", model, m, ball)
    return not simple and not boundary_roots._inconsistent_near(model, m, ball)


def test_undecided_roots_are_listed_as_points(slice_32):
    """The undecided roots of a slice are its ``undecided_line_root`` points (not proven), stored
    with the other points; the counts per verdict add up to the algebraic count."""
    b = slice_32(Q0)
    counts = [b.attrs[f"SS_line_roots_{k}"] for k in boundary_roots.KINDS]
    assert sum(counts) == b.attrs["SS_line_roots"] == 28
    assert b.attrs["SS_line_roots_point"] == b.attrs["SS_line_points"] == 10
    left = [p for p in b.points if p.kind == "undecided_line_root" and p.field == "SS"]
    assert len(left) == b.attrs["SS_line_roots_undecided"]
    assert all(not p.proven and math.isnan(p.uncertainty) for p in left)
    ds = b.to_dataset()
    kinds = ds["point_kind"].values[ds["point_field"].values == "SS"].tolist()
    assert kinds.count("undecided_line_root") == len(left)


#: the issue's four slices and the paper's vanishing damping
SLICES = [Q0, (0.5, 1e-6, 1e-6), DAMPED, (2.0, 0.05, 0.3), (7.3, 0.8, 0.02)]


def _roots(b1, b2, model, dps=60):
    """The roots of ``p`` at ``(b1, b2)`` [rad] (:func:`samples.eq9_roots`, mpmath)."""
    return eq9_roots(b1, b2, model, dps)


def _abscissa(b1, b2, model):
    """The largest real part of the roots of ``p`` at ``(b1, b2)`` [rad] (:func:`_roots`)."""
    return max(float(z.real) for z in _roots(b1, b2, model))


@pytest.mark.parametrize("model", SLICES)
def test_no_ss_root_is_left_undecided(model):
    """Every root of the SS line restrictions has a decided verdict on the five slices (each had
    two undecided: a double root, or three boundary polynomials vanishing at once on a
    diagonal).  Each ``not_boundary`` root where several boundary polynomials vanish or one
    vanishes twice is checked against mpmath at 60 digits: on a ring of radius 1e-7 rad around
    it (24 points, none on the line) the largest real part is positive (SS unstable all round)."""
    roots, _, verdicts = _account(model)
    assert "undecided" not in verdicts
    rings = _rings("SS", model, roots, verdicts)
    for m, ball, ring in rings:
        for a, (x, y) in ring:
            assert _abscissa(x, y, model) > 0, (m, float(ball.mid()), a)
    assert len(rings) >= 2


def _unit(t):
    """The exact unit direction ``(cos, sin)`` of the angle ``2 atan(t)``, ``t`` rational."""
    return (1 - t * t) / (1 + t * t), 2 * t / (1 + t * t)


def _turn(u, v):
    return u[0] * v[0] - u[1] * v[1], u[0] * v[1] + u[1] * v[0]


def _exact_ii(m, beta, e, model):
    """The exact tier's II code at free angle ``beta`` [rad] of torus line ``m`` (``t`` the
    float nearest ``tan(beta / 2)``), moved off the line by the angle ``2 atan(e)`` (the fixed
    angle, or ``beta2`` on a diagonal), in rational arithmetic."""
    from fractions import Fraction

    from atlas.core import exact

    free, off = _unit(Fraction(math.tan(0.5 * beta))), _unit(Fraction(e))
    axis = [(1, 0), (0, 1), (-1, 0), (0, -1)]
    if m < 5:
        dirs = (*_turn(axis[m], off), *free)
    elif m < 10:
        dirs = (*free, *_turn(axis[m - 5], off))
    else:
        sign = 1 if m == 11 else -1
        dirs = (*free, *_turn((sign * free[0], sign * free[1]), off))
    v = exact.point_spectral(*dirs, *(Fraction(x) for x in model))
    return 0 if v["consistent_II"] == 0 else 1 + v["stable_II"]


@pytest.mark.parametrize("model", [Q0, DAMPED])
def test_ii_points_are_stored_proven(model, slice_32):
    """The II roots with verdict ``point`` are stored as proven points of field II (one per
    root, radius below 1e-13 rad) in the netCDF; the undecided ones as ``undecided_line_root``
    points, not proven, and no estimated crossing of a class line is left.  Independently, in the exact tier at rational points: 1e-6 rad before
    and after each point along its line, at some offset ``2 atan(2^-k)`` off it (k = 40, 80,
    120, 160) on one side, the II codes differ."""
    b = slice_32(model)
    ii = [p for p in b.points if p.field == "II" and p.proven and p.kind.endswith("class_line")]
    assert len(ii) == b.attrs["II_line_roots_point"] == b.attrs["II_line_points"] > 0
    assert all(0 < p.uncertainty < 1e-13 for p in ii)
    pts = [p for p in b.points if p.field == "II"]
    left = [p for p in pts if p.kind == "undecided_line_root"]
    assert len(left) == b.attrs["II_line_roots_undecided"]
    assert not any(p.proven for p in left)
    line = ("crosses_class_line", "leaves_class_line")
    assert not any(p.kind in line and not p.proven for p in pts)  # estimates replaced
    ds = b.to_dataset()
    assert ((ds["point_proven"].values == 1) & (ds["point_field"].values == "II")).sum() >= len(ii)
    for p in ii:
        m, beta = _line_of(p.beta1, p.beta2)
        assert any(
            _exact_ii(m, beta - 1e-6, e, model) != _exact_ii(m, beta + 1e-6, e, model)
            for k in (40, 80, 120, 160)
            for e in (2.0**-k, -(2.0**-k))
        ), (p.beta1, p.beta2, p.kind)


def _line_of(x, y):
    """``(m, free angle)`` of the torus class line through ``(x, y)`` [rad] (the first one)."""
    for m in range(4):
        if abs(x - m * PI / 2) < 1e-12 or (m == 0 and abs(x - 2 * PI) < 1e-12):
            return m, y
    for m in range(4):
        if abs(y - m * PI / 2) < 1e-12 or (m == 0 and abs(y - 2 * PI) < 1e-12):
            return m + 5, x
    return (11 if abs((y - x + PI) % (2 * PI) - PI) < 1e-12 else 12), x


def test_ii_roots_with_no_positive_root_of_p_are_decided():
    """At q = 0 the II roots where every coefficient of ``p`` is positive are ``not_boundary``;
    checked against mpmath at 60 digits: on a ring of radius 1e-7 rad around each (24 points)
    ``p`` has no real root ``l > 0`` (II inconsistent all round)."""
    roots, _, verdicts = _account_ii(Q0)
    assert verdicts.count("undecided") <= 12
    rings = _rings(
        "II", Q0, roots, verdicts, lambda m, b: boundary_roots._inconsistent_near(Q0, m, b)
    )
    for m, _, ring in rings:
        for a, (x, y) in ring:
            zs = _roots(x, y, Q0)
            assert not any(abs(z.imag) < 1e-40 and z.real > 0 for z in zs), (m, a, zs)
    assert len(rings) >= 10


def _line_spans(c, m, ends=False):
    """``(lo, hi)`` along class line ``m`` (``beta2`` on ``beta1 = k pi/2``, else ``beta1``) of
    each segment of curve ``c`` lying on that line (both ends within 1e-10 rad of it); with
    ``ends`` only the end segments at a spliced vertex."""
    v = c.vertices
    k = [PI / 2 * j for j in range(5)]
    if m < 5:
        near, axis = np.abs(v[:, 0] - k[m]) < 1e-10, 1
    elif m < 10:
        near, axis = np.abs(v[:, 1] - k[m - 5]) < 1e-10, 0
    else:
        near, axis = np.abs((v[:, 1] - v[:, 0] - (m - 11) * PI + PI) % (2 * PI) - PI) < 1e-10, 0
    on = near[1:] & near[:-1]
    if ends:
        at = np.zeros(len(on), bool)
        at[0], at[-1] = 0 in c.spliced, len(v) - 1 in c.spliced
        on &= at
    return np.sort(np.stack([v[:-1, axis], v[1:, axis]], 1)[on], 1)


@pytest.mark.parametrize("model", [Q0, DAMPED])
def test_points_on_the_lines_are_spliced_into_the_pieces_once(model, slice_32):
    """SS and II alike: every proven point that a piece on a class line comes within twice the
    cover distance of is a spliced vertex of such a piece (or the piece passes within ``tol``
    of it), and at each II one the exact tier's codes 1e-6 rad before and after it along its
    line differ at some offset ``2 atan(2^-k)`` (k = 40 .. 160); and no end segment at a
    spliced vertex covers a stretch of the line another piece of the field covers (overlap <=
    ``tol``).  Before, the II points were not
    spliced into the pieces on the lines (0 of 11 at q = 0), and extending an SS piece to its
    point covered a needle piece twice (1.5e-9 rad at kappa 2, q 0.1)."""
    b = slice_32(model)
    on_line = 0
    for fld in ("SS", "II"):
        pieces = [c for c in b.curves if c.field == fld and c.on_class_line]
        reach = 2 * b.attrs[f"{fld}_cover_distance"]
        for p in (p for p in b.points if p.field == fld and p.proven):
            xy = np.array([p.beta1, p.beta2])
            d = boundary_points.nearest_segment(xy, pieces)[0]
            at = [c.vertices[k] for c in pieces for k in c.spliced]
            hit = any(np.hypot(*(v - xy)) <= p.uncertainty + 1e-15 for v in at)
            assert d > reach or d <= bd.TOL or hit, (fld, p.beta1, p.beta2, d)
            if fld == "II" and hit:
                on_line += 1
                m, beta = _line_of(p.beta1, p.beta2)
                assert any(
                    _exact_ii(m, beta - 1e-6, e, model) != _exact_ii(m, beta + 1e-6, e, model)
                    for k in (40, 80, 120, 160)
                    for e in (2.0**-k, -(2.0**-k))
                ), (p.beta1, p.beta2)
        for m in range(13):  # an end spliced on covers no stretch another piece covers
            for c in pieces:
                rest = [_line_spans(o, m) for o in pieces if o is not c] + [np.zeros((0, 2))]
                rest = np.concatenate(rest)
                for lo, hi in _line_spans(c, m, ends=True):
                    overlap = np.minimum(rest[:, 1], hi) - np.maximum(rest[:, 0], lo)
                    assert (overlap <= bd.TOL).all(), (fld, m, lo, hi, overlap.max())
    assert on_line >= 8


def _sides(model, m, beta):
    """The exact tier's II codes on each side of line ``m`` around free angle ``beta`` [rad]: 24
    points on a circle of radius 1e-7 rad (those off the line by more than 1e-13) and 1e-12 off
    the line 1e-7 along it."""
    at, normal = _point(m, beta)
    along = np.array([normal[1], -normal[0]])
    near = [s * 1e-7 * along + r * 1e-12 * normal for s in (-1, 1) for r in (-1, 1)]
    ring = [1e-7 * np.array([math.cos(a), math.sin(a)]) for a in np.arange(24) * PI / 12]
    sides = {1: set(), -1: set()}
    for off in near + ring:
        if abs(off @ normal) > 1e-13:
            sides[int(np.sign(off @ normal))].add(exact_code("II", *(at + off), model))
    return sides


def _micro_sides(model, m, beta):
    """The exact tier's II codes on each side of line ``m`` within 1e-12 rad of free angle
    ``beta`` [rad]: at ``beta`` and ``beta +- 1e-12`` along it, ``2 atan(2^-k)`` off it (k = 43
    .. 160 at ``beta``, 60 .. 160 beside it): a boundary leaving the line at ``beta``, tangent
    (``e ~ s^2``) or not, separates some of them."""
    sides = {1: set(), -1: set()}
    for s, ks in ((0.0, (43, 60, 80, 100, 130, 160)), (-1e-12, (60, 80, 100, 130, 160)),
                  (1e-12, (60, 80, 100, 130, 160))):  # fmt: skip
        for k in ks:
            for sign in (-1, 1):
                sides[sign].add(_exact_ii(m, beta + s, sign * 2.0**-k, model))
    return sides


@pytest.mark.parametrize("model, left", [(Q0, 0), (SLICES[1], 0), (DAMPED, 0), (SLICES[3], 0),
                                         (SLICES[4], 0)])  # fmt: skip
def test_ii_roots_decided_from_the_branches_through_them(model, left):
    """An II root is decided where the boundary polynomials, squarefree, vanish simply there
    (at q = 0 ``disc_l p = 16 a0 (a2^2 - 4 a0)^2`` made every crossing a double root) or their
    zero sets through it are graphs over the line (``dG/de`` proven away from 0; two graphs in
    one quadrant told apart in the chart ``e = lam f^k``; the root refined on the polynomial that
    changes sign across its ball, not on one whose ball merely contains 0 there: at kappa 2, q
    0.1 a simple root 2.5e-5 rad away made two roots look like two graphs into one quadrant):
    undecided 12 / 11 / 15 / 12 / 15 -> 0 / 6 / 0 / 0 / 0 on the five slices (the six: roots
    1e-15 rad apart, :func:`test_crowded_ii_roots_against_mpmath`).  Each root not decided by the
    signs of ``p``'s coefficients and with no other break within 1e-12 rad is checked by the
    exact tier: one code on each side of the line on a circle of radius 1e-7 rad
    (:func:`_sides`; a simple root of one polynomial), or within 1e-12 rad
    (:func:`_micro_sides`; decided from the branches: at 1e-7 a boundary passes some of them
    5e-9 off the line, away from the root)."""
    roots, _, verdicts = _account_ii(model)
    assert verdicts.count("undecided") <= left
    checked = 0
    for (m, ball, _), v in zip(roots, verdicts):
        if v != "not_boundary" or boundary_roots._inconsistent_near(model, m, ball):
            continue
        if _frame(model, m, ball).exact:
            continue
        beta = float(ball.mid())
        sides = (_micro_sides if _by_branches(model, m, ball) else _sides)(model, m, beta)
        assert len(sides[1]) == 1 and len(sides[-1]) == 1, (m, float(ball.mid()), sides)
        checked += 1
    assert checked >= 3


def test_undecided_roots_carry_their_reason(tmp_path, monkeypatch):
    """Each undecided II root is stored with its reason, a key of
    :data:`boundary_roots.REASONS`, in the netCDF (``point_reason``), the CSV (``reason``) and
    the GeoJSON (property ``reason``); the other points with an empty one.  (No box tried: the
    roots of the paper's q 1e-6 slice that the branches decide are left ``no_box``.)"""
    import json

    import xarray as xr

    from atlas.data import boundary_branches
    from atlas.data.boundary_curves import Boundaries

    monkeypatch.setattr(boundary_branches, "H_FRACTIONS", ())
    model = SLICES[1]
    _, pts = boundary_roots.ii_root_account(model, boundary_germs.germ_roots("II", model))
    left = [p for p in pts if p.kind == "undecided_line_root"]
    assert len(left) >= 6 and all(p.reason == "no_box" for p in left)
    assert all(p.reason == "" for p in pts if p.kind != "undecided_line_root")
    b = Boundaries(points=pts)
    b.to_netcdf(tmp_path / "b.nc")
    b.to_csv(tmp_path / "b.csv")
    b.to_geojson(tmp_path / "b.json")
    with xr.open_dataset(tmp_path / "b.nc") as ds:
        assert [str(r) for r in ds["point_reason"].values] == [p.reason for p in pts]
    rows = [r.split(",") for r in (tmp_path / "b.csv").read_text().splitlines()]
    assert [r[rows[0].index("reason")] for r in rows[1:]] == [p.reason for p in pts]
    feats = json.loads((tmp_path / "b.json").read_text())["features"]
    assert [f["properties"]["reason"] for f in feats] == [p.reason for p in pts]


#: digits of the mpmath reference for roots 1e-15 rad apart, sampled 1e-40 and 1e-60 rad off
MP_DPS = 90


def _ii_code_mp(b1, b2, model):
    """The II code at ``(b1, b2)`` [rad] (mpmath numbers) from SPEC §1 directly, by mpmath at
    :data:`MP_DPS` digits: consistent iff ``p`` (eq. 9) has a real root ``l > 0`` whose
    eigenvector's gap part ``x`` (``(l^2 + B (K + l Q)) x = 0``, ``B = [[c1, c2], [s1, s2]]``,
    ``K = diag(kappa, 1)``, ``Q = diag(q1, q2)``) has ``x1 x2 > 0``; stable iff the strictly
    dominant root is such a root; 0 inconsistent, else 1 + stable."""
    import mpmath

    with mpmath.workdps(MP_DPS):
        kappa, q1, q2 = (mpmath.mpf(v) for v in model)
        c1, s1, c2, s2 = mpmath.cos(b1), mpmath.sin(b1), mpmath.cos(b2), mpmath.sin(b2)
        D = c1 * s2 - s1 * c2
        coeffs = [1, q1 * c1 + q2 * s2, kappa * c1 + s2 + q1 * q2 * D, D * (q1 + kappa * q2),
                  kappa * D]  # fmt: skip
        zs = mpmath.polyroots(coeffs, maxsteps=300, extraprec=300)
        tiny = mpmath.mpf(10) ** (20 - MP_DPS)

        def consistent(z):
            if abs(z.imag) > tiny or z.real <= 0:
                return False
            lam = z.real
            rows = [(lam**2 + c1 * (kappa + lam * q1), c2 * (1 + lam * q2)),
                    (lam**2 + s2 * (1 + lam * q2), s1 * (kappa + lam * q1))]  # fmt: skip
            row = max(rows, key=lambda r: max(abs(r[0]), abs(r[1])))  # x ~ (row[1], -row[0])
            assert max(abs(row[0]), abs(row[1])) > tiny
            return -row[0] * row[1] > 0

        if not any(consistent(z) for z in zs):
            return 0
        top = max(zs, key=lambda z: z.real)
        strict = all(top.real - z.real > tiny for z in zs if z is not top)
        return 1 + int(strict and consistent(top))


@functools.cache
def _line_breaks_mp(m, model):
    """The breaks of II line ``m`` (free angles [rad], mpmath at :data:`MP_DPS` digits): the real
    roots of the squarefree germ polynomials ``g_0`` (mpmath's ``polyroots``; flint only for the
    exact gcd) and the multiples of ``pi/2``, each once."""
    import mpmath

    out = []
    with mpmath.workdps(MP_DPS):
        for rows in boundary_germs.germs("II", m, model):
            g = rows[0] / rows[0].gcd(rows[0].derivative())
            cs = [mpmath.mpf(int(c.p)) / int(c.q) for c in reversed(g.coeffs())]
            for z in mpmath.polyroots(cs, maxsteps=400, extraprec=400):
                if abs(z.imag) < mpmath.mpf(10) ** (30 - MP_DPS):
                    out.append((2 * mpmath.atan(z.real)) % (2 * mpmath.pi))
        out += [j * mpmath.pi / 2 for j in range(4)]
        out.sort()
        return [b for i, b in enumerate(out) if i == 0 or b - out[i - 1] > mpmath.mpf(10) ** -60]


def _mp_point(m, beta, delta):
    """``(beta1, beta2)`` at free angle ``beta`` of line ``m``, ``delta`` off it (:func:`_exact_ii`)."""
    import mpmath

    if m < 5:
        return m * mpmath.pi / 2 + delta, beta
    if m < 10:
        return beta, (m - 5) * mpmath.pi / 2 + delta
    return beta, beta + (m - 11) * mpmath.pi + delta


@pytest.mark.slow
def test_crowded_ii_roots_against_mpmath():
    """The paper's q 1e-6 slice: damping splits the q = 0 quadruple points of the diagonals into
    three roots 5e-15 and 4e-14 rad apart, and moves roots 2.5e-13 and 5e-13 rad off the
    multiples of ``pi/2``; float64 angles cannot order them (6 undecided ``no_box``, and points
    claimed where the samples beside the root straddled a crossing of class lines).  Every II
    root with another break within 1e-12 rad (roots of the line polynomials by mpmath at 90
    digits) is decided, and its verdict agrees with mpmath's II codes (SPEC §1, 90 digits)
    a quarter of the way to its nearest break on each side and on the vertical through it,
    1e-40 and 1e-60 rad off the line: ``not_boundary`` one code per side, ``point`` two on some
    side, ``class_crossing`` a multiple of ``pi/2``."""
    import mpmath

    model = SLICES[1]
    roots, _, verdicts = _account_ii(model)
    assert "undecided" not in verdicts
    checked = {"point": 0, "not_boundary": 0, "class_crossing": 0}
    with mpmath.workdps(MP_DPS):
        for (m, ball, _), v in zip(roots, verdicts):
            breaks = _line_breaks_mp(m, model)
            mid, rad = mpmath.mpf(float(ball.mid())), 1.000001 * float(ball.rad())
            inside = [
                b for b in breaks if abs(b - mid) <= rad or 2 * mpmath.pi - abs(b - mid) <= rad
            ]
            assert len(inside) == 1, (m, float(mid), rad)
            r = inside[0]
            gap = min(min(abs(b - r), 2 * mpmath.pi - abs(b - r)) for b in breaks if b != r)
            if gap > 1e-12:
                continue
            checked[v] += 1
            if v == "class_crossing":
                assert min(abs(r - j * mpmath.pi / 2) for j in range(5)) < 1e-60
                continue
            sides = {}
            for s in (-1, 1):
                sides[s] = {
                    a: {_ii_code_mp(*_mp_point(m, r + a * gap / 4, s * mpmath.mpf(10) ** -k),
                                    model) for k in (40, 60)}
                    for a in (-1, 0, 1)
                }  # fmt: skip
            n_codes = [len(set().union(*sides[s].values())) for s in (-1, 1)]
            ok = n_codes == [1, 1] if v == "not_boundary" else max(n_codes) >= 2
            assert ok, (m, float(r), v, sides)
    assert all(checked.values()), checked  # every kind of verdict met among the crowded roots


@functools.cache
def _germ_roots(model):
    return boundary_germs.germ_roots("II", model)


def _frame(model, m, ball):
    """The frame of the II root ``ball`` of line ``m`` (:func:`atlas.data.root_frames.frame`)."""
    from atlas.data import root_frames

    others = [float(b.mid()) for k, b, _ in _germ_roots(model) if k == m]
    return root_frames.frame("II", model, m, ball, others)


def _hurwitz_stable(b1, b2, model) -> bool:
    """SS stable at ``(b1, b2)`` [rad] (mpmath numbers, at mpmath's precision): the Hurwitz
    conditions of ``p`` (paper eq. 9, ``k2 = 1``), ``a3``, ``a3 a2 - a1``, ``(a3 a2 - a1) a1 -
    a3^2 a0`` and ``a0`` all positive (none may vanish at a sample)."""
    kappa, q1, q2 = (mpmath.mpf(v) for v in model)
    c1, s1, c2, s2 = mpmath.cos(b1), mpmath.sin(b1), mpmath.cos(b2), mpmath.sin(b2)
    det = c1 * s2 - s1 * c2
    a3, a2 = q1 * c1 + q2 * s2, kappa * c1 + s2 + q1 * q2 * det
    a1, a0 = det * (q1 + kappa * q2), kappa * det
    hurwitz = (a3, a3 * a2 - a1, (a3 * a2 - a1) * a1 - a3**2 * a0, a0)
    assert all(h != 0 for h in hurwitz)
    return all(h > 0 for h in hurwitz)


def _antipodal_changes(model, n=128):
    """Reference: the angles ``beta1`` [rad] where the SS code ``1e-25`` rad off the line
    ``beta2 = beta1 + pi`` changes along it, on either side, with the bracket's width: a scan of
    ``n`` samples, then bisection at 50 digits to 1e-20 rad (:func:`_hurwitz_stable`); each
    change confirmed by the roots of ``p`` at the bracket's ends (mpmath, :func:`_roots`)."""
    out = []
    with mpmath.workdps(50):
        eps = mpmath.mpf(10) ** -25
        for s in (-1, 1):

            def stable(x, s=s):
                return _hurwitz_stable(x, x + mpmath.pi + s * eps, model)

            xs = [2 * mpmath.pi * k / n for k in range(n + 1)]
            codes = [stable(x) for x in xs]
            for lo, hi, c in zip(xs, xs[1:], codes):
                if stable(hi) == c:
                    continue
                while hi - lo > mpmath.mpf(10) ** -20:
                    mid = (lo + hi) / 2
                    lo, hi = (mid, hi) if stable(mid) == c else (lo, mid)
                for x, st in ((lo, c), (hi, not c)):  # roots of p on the two sides
                    top = max(z.real for z in _roots(x, x + mpmath.pi + s * eps, model, 50))
                    assert (top < 0) == st
                out.append((float((lo + hi) / 2), float(hi - lo)))
    return sorted(out)


def test_codimension_2_points_do_not_depend_on_chord_or_grid():
    """At kappa 2, q 0.1 the SS points on the class lines are the same proven points at every
    chord (1e-2, 1e-4, 1e-6) and on two grids (32^2, 48^2), each within the two radii of its
    counterpart; none is an estimate.  On ``beta2 = beta1 + pi`` they are the reference's
    changes of the code next to the line (:func:`_antipodal_changes`, mpmath), within their
    radii.  Before, at chord 1e-2 two estimated ``leaves_class_line`` points stood 0.07 and
    0.06 rad from the proven ones (the replacement reached one grid cell)."""
    ref = _antipodal_changes(DAMPED)
    assert len(ref) == 2
    kinds = ("leaves_class_line", "crosses_class_line", "touches_class_line")
    first = None
    for n in (32, 48):
        g = np.arange(n) * 2 * PI / n
        for chord in (1e-2, 1e-4, 1e-6):
            b = bd.slice_boundaries(g, g, *DAMPED, fields=("SS",), chord=chord)
            pts = [p for p in b.points if p.kind in kinds or p.kind == "undecided_line_root"]
            assert all(p.proven for p in pts), (n, chord, [(p.beta1, p.beta2) for p in pts])
            pts = sorted(pts, key=lambda p: (p.kind, p.beta1, p.beta2))
            on = [p for p in pts if abs((p.beta2 - p.beta1) % (2 * PI) - PI) < 1e-9]
            assert len(on) == len(ref)
            for p, (x, width) in zip(sorted(on, key=lambda p: p.beta1), ref):
                assert abs(p.beta1 - x) <= p.uncertainty + width, (n, chord, p.beta1, x)
            first = first or pts
            assert [p.kind for p in pts] == [p.kind for p in first]
            for p, o in zip(pts, first):
                d = np.abs(np.array([p.beta1 - o.beta1, p.beta2 - o.beta2]))
                gap = np.hypot(*np.minimum(d, 2 * PI - d))
                assert gap <= p.uncertainty + o.uncertainty, (n, chord, p.beta1, p.beta2)
