"""Side labels of boundary pieces, re-evaluated by the exact tier alone."""

import math

import numpy as np
import pytest

from atlas.core import contact_modes, exact
from atlas.data import boundaries as bd
from atlas.data.boundary_sides import side_step

PI = math.pi
DAMPED = (2.0, 0.1, 0.1)


def _exact_code(field, c1, s1, c2, s2, model):
    v = exact.point_spectral(float(c1), float(s1), float(c2), float(s2), *model)
    if field == "SS":
        return v["stable_SS"]
    return 0 if v["consistent_II"] == 0 else 1 + v["stable_II"]


def _code_at(field, point, model):
    c1, s1 = contact_modes.direction(point[0])
    c2, s2 = contact_modes.direction(point[1])
    return _exact_code(field, c1, s1, c2, s2, model)


def _on_line_code(field, point, model):
    """The exact code on the class line nearest to ``point``, with the line's exact directions
    (None where two lines cross within 1e-6 rad: the line is ambiguous)."""
    x, y = point
    axes = {0: (1, 0), 1: (0, 1), 2: (-1, 0), 3: (0, -1), 4: (1, 0)}
    k1, k2 = round(x / (PI / 2)), round(y / (PI / 2))
    d1, d2 = abs(x - k1 * PI / 2), abs(y - k2 * PI / 2)
    j = round((y - x) / PI)
    dd = abs(y - x - j * PI) / math.sqrt(2)
    if sorted([d1, d2, dd])[1] < 1e-6:
        return None
    if dd <= min(d1, d2):
        t = 0.5 * (x + y - j * PI)
        c, s = math.cos(t), math.sin(t)
        sign = 1 if j == 0 else -1
        return _exact_code(field, c, s, sign * c, sign * s, model)
    if d1 <= d2:
        c2, s2 = contact_modes.direction(y)
        return _exact_code(field, *axes[k1], c2, s2, model)
    c1, s1 = contact_modes.direction(x)
    return _exact_code(field, c1, s1, *axes[k2], model)


def _check_labels(b, model, per_piece=4, seed=0):
    """At up to ``per_piece`` segments of every piece, both ends stepped ``side_step`` (or the
    piece's smaller ``side_offset``) off the segment (normal computed here) to the left and to the right carry the piece's ``side_left``
    and ``side_right`` in exact arithmetic (but at a spliced codimension-2 point); on a class line, the line's own exact code is
    ``side_on`` if that is set, else one of the two sides."""
    rng = np.random.default_rng(seed)
    step = side_step(bd.TOL)
    checked = 0
    for c in (c for c in b.curves if c.field != "class"):
        assert c.side_left > c.side_right  # oriented: the higher code on the left
        v = c.vertices
        off = c.side_offset if np.isfinite(c.side_offset) else step  # proven closer to the line
        for k in rng.choice(len(v) - 1, min(per_piece, len(v) - 1), replace=False):
            t = (v[k + 1] - v[k]) / np.hypot(*(v[k + 1] - v[k]))
            n = np.array([-t[1], t[0]])
            for j in (k, k + 1):
                if j in c.spliced:  # a proven codimension-2 point: three codes meet there
                    continue
                end = v[j]
                assert _code_at(c.field, end + off * n, model) == c.side_left
                assert _code_at(c.field, end - off * n, model) == c.side_right
                if c.on_class_line:
                    on = _on_line_code(c.field, end, model)
                    if on is None:
                        continue
                    want = c.side_on if c.side_on >= 0 else None
                    assert on == want if want is not None else on in (c.side_left, c.side_right)
            checked += 1
    return checked


def _codes(c):
    return c.side_left, c.side_right, c.side_on


@pytest.fixture(scope="module")
def undamped():
    g = np.arange(32) * 2 * PI / 32
    return bd.slice_boundaries(g, g, 0.5, 0.0, 0.0, check=0, chord=1e-3)


def test_labels_hold_off_every_piece_undamped(undamped):
    """Fig. 1 slice: a stretch of beta1 = pi was carried by two coincident II pieces with the
    line's own code as a side; now the codes found on either side, one piece per stretch."""
    assert _check_labels(undamped, (0.5, 0.0, 0.0)) > 50
    on_pi = [
        c
        for c in undamped.curves
        if c.field == "II" and c.on_class_line and np.allclose(c.vertices[:, 0], PI, atol=1e-6)
    ]
    assert on_pi
    same = [(a, c) for i, a in enumerate(on_pi) for c in on_pi[i + 1 :]]
    for a, c in ((a, c) for a, c in same if _codes(a) == _codes(c)):
        lo, hi = (
            max(a.vertices[:, 1].min(), c.vertices[:, 1].min()),
            min(a.vertices[:, 1].max(), c.vertices[:, 1].max()),
        )
        assert lo >= hi - 1e-12  # no two pieces over the same stretch (they may share an end)


def _damped_32(model, slice_32, fields):
    """Slice ``model`` on the 32 x 32 grid, no check, chord 1e-4; kappa 2, q 0.1 with both
    fields whatever ``fields`` (traced once for both tests below: a field's curves do not
    depend on the other field being traced)."""
    return slice_32(model, fields=("SS", "II") if model == DAMPED else fields, chord=1e-4)


def test_labels_hold_off_every_piece_damped(slice_32):
    """Damped SS along beta2 = beta1 +- k pi: unstable on one side, stable on the other, the
    neutral code only on the line itself (side_on)."""
    model = DAMPED
    b = _damped_32(model, slice_32, ("SS", "II"))
    assert _check_labels(b, model) > 50
    diag = [
        c
        for c in b.curves
        if c.field == "SS" and c.on_class_line and np.ptp(c.vertices[:, 0]) > 1e-3
    ]
    assert len(diag) >= 3 and all((c.side_left, c.side_right, c.side_on) == (1, 0, 2) for c in diag)


@pytest.mark.parametrize("model", [DAMPED, (7.3, 0.8, 0.02)])
def test_diagonal_pieces_carry_the_neutral_code_up_to_the_corner(model, slice_32):
    """Damped SS on beta2 = beta1: the exact code on the line (``c1 = c2``, ``s1 = s2``, at each
    vertex's beta1) is neutral, different from both sides, and every piece on it says so, up to
    the corner (0, 0): a 2e-8 rad piece there, traced a nudge past 2 pi on beta2 = beta1 + 2 pi
    (no column of the lines), had ``side_on = -1`` (its vertices taken as on beta2 = 2 pi)."""
    b = _damped_32(model, slice_32, ("SS",))
    diag = [
        c
        for c in b.curves
        if c.field == "SS"
        and c.on_class_line
        and (np.abs((c.vertices[:, 1] - c.vertices[:, 0] + PI) % (2 * PI) - PI) < 1e-9).all()
    ]
    assert any(np.hypot(*c.vertices.T).min() < 1e-6 for c in diag)  # the corner piece
    for c in diag:
        for x in c.vertices[:, 0]:
            cx, sx = (float(v) for v in contact_modes.direction(x))
            on = _exact_code("SS", cx, sx, cx, sx, model)
            assert on not in (c.side_left, c.side_right) and c.side_on == on
