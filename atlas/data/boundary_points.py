"""Proven enclosures of the points where an SS boundary meets a class line (codimension 2).

On a class line the SS boundary's defining polynomials become univariate: with ``t = tan(beta /
2)`` along the line (``cos beta = (1 - t^2) / (1 + t^2)``, ``sin beta = 2 t / (1 + t^2)``) each is
a rational function of ``t`` with exact rational coefficients (``kappa, q1, q2`` read as exact
dyadic rationals), whose numerator ``R(t)`` is factored over Q (python-flint).  A real root of a
factor of multiplicity 1 is a transversal crossing of that component with the line
(``crosses_class_line``); of even multiplicity, a tangency (``touches_class_line``: the boundary
leaves the line tangentially).  Arb root isolation gives a certified interval of ``t``, and
``beta = 2 atan(t)`` in ball arithmetic a certified interval of the angle: the stated uncertainty
is its radius, a proven bound.

The components (characteristic polynomial ``l^4 + a3 l^3 + a2 l^2 + a1 l + a0``, paper eq. 9,
written once in :mod:`atlas.core.expressions` and evaluated here on rational functions of ``t``
with ``k1 = kappa``, ``k2 = 1``): ``a3 = q1 c1 + q2 s2``, ``a2 = kappa c1 + s2 + q1 q2 D``, ``a1 =
(q1 + kappa q2) D``, ``a0 = kappa D`` with ``D = c1 s2 - s1 c2``.  Damped, SS is stable iff the
Routh-Hurwitz minors are positive, and the boundary lies on ``a3 = 0``, ``H2 = a3 a2 - a1 = 0`` or
``G = 0`` (:func:`atlas.core.expressions.G`, ``H3 = D G``, equal to ``(q1 + kappa q2) H2 - kappa
a3^2``) or a class line ``D = 0``; undamped (``q1 = q2 = 0``) on ``a2 = 0`` or ``disc = a2^2 - 4 a0
= (kappa c1 - s2)^2 + 4 kappa s1 c2 = 0``.  A numerator may carry extra factors ``1 + t^2``
(no real roots).
Every root on every class line is found (``beta = pi``, ``t`` infinite, from the numerator's
degree deficit); a component's zero set is a boundary only where the other minors allow it, so a
root is reported where the certified SS code just off the line changes along the line next to it
(:func:`ss_line_points`), wherever the traced curves are.
"""

from __future__ import annotations

import math
import operator
from dataclasses import replace
from fractions import Fraction

import flint
import numpy as np
import shapely

from atlas.core import brackets, expressions
from atlas.data.boundary_curves import Curve, Point
from atlas.data.boundary_tips import TIP_OFFSET

__all__ = [
    "attach_points",
    "line_polynomials",
    "line_roots",
    "nearest_segment",
    "real_roots",
    "root_codes",
    "ss_line_points",
    "angle_from_tan_half",
    "curve_segments",
    "pair_distances",
    "pairs_near",
    "torus_distances",
]

TWO_PI = 2 * math.pi


class _Rat:
    """``num / (1 + t^2)^k``: a polynomial in the line parameter over a power of ``1 + t^2``."""

    W = flint.fmpq_poly([1, 0, 1])

    def __init__(self, num, k=0):
        self.num, self.k = flint.fmpq_poly(num), k

    def _lift(self, k):
        return self.num * self.W ** (k - self.k)

    def __add__(self, o):
        o = o if isinstance(o, _Rat) else _Rat([o])
        k = max(self.k, o.k)
        return _Rat(self._lift(k) + o._lift(k), k)

    __radd__ = __add__

    def __neg__(self):
        return _Rat(-self.num, self.k)

    def __sub__(self, o):
        return self + (-o)

    def __rsub__(self, o):
        return (-self) + o

    def __mul__(self, o):
        o = o if isinstance(o, _Rat) else _Rat([o])
        return _Rat(self.num * o.num, self.k + o.k)

    __rmul__ = __mul__

    def __pow__(self, n: int):
        return _Rat(self.num**n, self.k * n)


_COS = _Rat([1, 0, -1], 1)
_SIN = _Rat([0, 2], 1)
_AXES = {0: (1, 0), 1: (0, 1), 2: (-1, 0), 3: (0, -1), 4: (1, 0)}


def _on_line(m):
    """``(c1, s1, c2, s2)`` along class line ``m`` (columns of
    :func:`atlas.data.class_lines.line_distances`) as functions of ``t = tan(beta / 2)``, ``beta``
    the line's free angle (``beta2`` on ``beta1 = k pi/2``, else ``beta1``)."""
    if m < 5:
        return (*_AXES[m], _COS, _SIN)
    if m < 10:
        return (_COS, _SIN, *_AXES[m - 5])
    sign = 1 if m == 11 else -1
    return _COS, _SIN, sign * _COS, sign * _SIN


def _components(c1, s1, c2, s2, kappa, q1, q2) -> dict:
    """The SS boundary's defining polynomials (module docstring) at the given values
    (:mod:`atlas.core.expressions` with ``k1 = kappa``, ``k2 = 1``)."""
    sub = operator.sub
    if q1 == 0 and q2 == 0:
        return {
            "a2": expressions.a2_undamped(kappa, c1, 1, s2, sub=sub),
            "disc": expressions.disc_undamped(kappa, c1, 1, s2, s1, c2, sub=sub),
        }
    D = expressions.det(c1, s1, c2, s2, sub=sub)
    a3, a2, a1, _ = expressions.coefficients(c1, s1, c2, s2, kappa, 1, q1, q2, D, sub=sub)
    return {
        "a3": a3,
        "H2": expressions.hurwitz_H2(a3, a2, a1, sub=sub),
        "G": expressions.G(c1, s1, c2, s2, kappa, 1, q1, q2, D, sub=sub),
    }


def _restrictions(m, kappa, q1, q2) -> dict:
    """Per component, its restriction ``num / (1 + t^2)^k`` to class line ``m`` (a ``_Rat``);
    identically zero components (the line lies in them) are left out."""
    model = [flint.fmpq(*Fraction(float(v)).as_integer_ratio()) for v in (kappa, q1, q2)]
    comps = _components(*_on_line(m), *model)
    return {k: v for k, v in comps.items() if isinstance(v, _Rat) and v.num != 0}


def line_polynomials(m, kappa, q1, q2) -> dict:
    """Per component, the numerator ``R(t)`` (``flint.fmpq_poly``) of its restriction to class
    line ``m``; identically zero components (the line lies in them) are left out."""
    return {k: v.num for k, v in _restrictions(m, kappa, q1, q2).items()}


def real_roots(R) -> list[tuple[flint.arb, int]]:
    """Certified real roots of ``R`` (arb balls of ``t``) with their multiplicity."""
    out = []
    _, factors = R.factor()
    for f, mult in factors:
        num = flint.fmpz_poly([int(c * f.denom()) for c in f.coeffs()])
        for z, _ in num.complex_roots():
            if z.imag == 0:  # flint isolates real roots with an exactly zero imaginary part
                out.append((z.real, mult))
    return out


def angle_from_tan_half(t: flint.arb) -> flint.arb:
    """``2 atan(t)`` wrapped into ``[0, 2 pi)`` as a ball [rad]."""
    beta = 2 * t.atan()
    return beta + 2 * flint.arb.pi() if beta.mid() < 0 else beta


def _point_xy(m, beta: float) -> tuple[float, float]:
    if m < 5:
        return m * math.pi / 2 % TWO_PI, beta
    if m < 10:
        return beta, (m - 5) * math.pi / 2 % TWO_PI
    return beta, (beta + (m - 11) * math.pi) % TWO_PI


#: the class lines of the torus: ``beta = 2 pi`` (columns 4 and 9) is ``beta = 0``, and
#: ``beta2 = beta1 - pi`` (column 10) is ``beta2 = beta1 + pi``
TORUS_LINES = (0, 1, 2, 3, 5, 6, 7, 8, 11, 12)


def _restriction_roots(r) -> list[tuple[flint.arb, int]]:
    """Certified angles (balls [rad]) where a restriction ``num / (1 + t^2)^k`` vanishes, with
    multiplicities: the real roots of ``num``, and ``beta = pi`` (``t`` infinite) with
    multiplicity ``2 k - deg num`` when the numerator's degree falls short of ``2 k``."""
    out = [(angle_from_tan_half(t), mult) for t, mult in real_roots(r.num)]
    if r.num.degree() < 2 * r.k:
        out.append((flint.arb.pi(), 2 * r.k - r.num.degree()))
    return out


def _line_roots(m, model) -> list[tuple[flint.arb, int]]:
    """The certified angles (balls [rad]) where the components vanish on line ``m``, each with
    its largest multiplicity over the components whose enclosures overlap it (at ``q = 0`` the
    trace ``a2`` vanishes simply where ``disc`` touches a diagonal)."""
    out = []
    for r in _restrictions(m, *model).values():
        for beta, mult in _restriction_roots(r):
            same = [k for k, (b, _) in enumerate(out) if b.overlaps(beta)]
            if not same:
                out.append((beta, mult))
                continue
            k = same[0]
            b, mu = out[k]
            out[k] = (beta if beta.rad() < b.rad() else b, max(mu, mult))
    return out


def line_roots(model, lines=TORUS_LINES) -> list[tuple[int, flint.arb, int]]:
    """Every root of the components' restrictions to the class lines ``lines``: ``(m, beta,
    multiplicity)``, ``beta`` a certified ball [rad] along line ``m``.  These are all the places
    where an SS boundary can meet a class line (the algebraic count)."""
    return [(m, beta, mult) for m in lines for beta, mult in _line_roots(m, model)]


#: the stretch [rad] of line on each side of a root over which the codes next to the line are
#: compared (capped at a quarter of the distance to the next root on the line), and the fractions
#: of it sampled: a boundary tangent to the line as ``c x^2`` is seen for ``c > TIP_OFFSET /
#: (ROOT_SPAN / 16)^2``, i.e. ``c > 3e-4``
ROOT_SPAN = 1e-5
ROOT_SAMPLES = np.array([-1.0, -1 / 16, 0.0, 1 / 16, 1.0])


def _frame(m) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(base, direction, unit normal)`` of line ``m``: points ``base + beta direction``."""
    if m < 5:
        return np.array([m * math.pi / 2, 0.0]), np.array([0.0, 1.0]), np.array([1.0, 0.0])
    if m < 10:
        return np.array([0.0, (m - 5) * math.pi / 2]), np.array([1.0, 0.0]), np.array([0.0, 1.0])
    r = 1 / math.sqrt(2)
    return np.array([0.0, (m - 11) * math.pi]), np.array([1.0, 1.0]), np.array([-r, r])


def _spans(roots) -> np.ndarray:
    """Per root, :data:`ROOT_SPAN` or a quarter of the distance to the nearest other root on its
    line (around the torus), whichever is smaller."""
    mids = np.array([float(b.mid()) for _, b, _ in roots])
    lines = np.array([m for m, _, _ in roots])
    out = np.full(len(roots), ROOT_SPAN)
    for i in range(len(roots)):
        d = np.abs(mids[lines == lines[i]] - mids[i])
        d = np.minimum(d, TWO_PI - d)
        d = d[d > 0]
        if d.size:
            out[i] = min(ROOT_SPAN, 0.25 * d.min())
    return out


def root_codes(fld, roots, model, dtype="float64") -> np.ndarray:
    """Certified codes ``(n, 2, len(ROOT_SAMPLES))`` of ``fld`` next to each root of
    :func:`line_roots`: on the line's two sides (:data:`atlas.data.boundary_tips.TIP_OFFSET`
    off it), at :data:`ROOT_SAMPLES` of its span (:func:`_spans`) along it."""
    if not roots:
        return np.zeros((0, 2, ROOT_SAMPLES.size), np.int8)
    span = _spans(roots)
    pts = []
    for (m, beta, _), h in zip(roots, span):
        base, direction, normal = _frame(m)
        along = base + (float(beta.mid()) + h * ROOT_SAMPLES)[:, None] * direction
        pts += [along - TIP_OFFSET * normal, along + TIP_OFFSET * normal]
    xy = np.concatenate(pts)
    codes = brackets.field_codes(fld, xy[:, 0], xy[:, 1], *model, dtype=dtype)
    return codes.reshape(len(roots), 2, ROOT_SAMPLES.size)


def ss_line_points(
    model, dtype="float64", lines=TORUS_LINES, roots=None
) -> tuple[list[Point], int]:
    """Proven points where the SS boundary meets the class lines ``lines`` (indices ``m``), found
    from the algebra: every root of :func:`line_roots` next to which the certified SS code on a
    side of the line changes along it (:func:`root_codes`); kind ``touches_class_line`` (even
    multiplicity), ``crosses_class_line`` (a change on both sides) or ``leaves_class_line``
    (one side).  Returns the points and the number of roots (the algebraic count).  The
    uncertainty bounds the distance of the stated point to the true one: the radius of the
    certified angle interval plus the rounding of the stated coordinates, times ``sqrt 2`` on a
    diagonal (both coordinates move).  ``roots``: :func:`line_roots` if already computed."""
    roots = line_roots(model, lines) if roots is None else roots
    codes = root_codes("SS", roots, model, dtype)
    changes = (codes != codes[:, :, :1]).any(axis=2)  # (n, side)
    out = []
    for (m, beta, mult), ch in zip(roots, changes):
        if not ch.any():
            continue
        x, y = _point_xy(m, float(beta.mid()) % TWO_PI)
        unc = (float(beta.rad()) + 4 * math.ulp(TWO_PI)) * (math.sqrt(2) if m >= 10 else 1.0)
        kind = ("leaves_class_line", "crosses_class_line")[int(ch.all())]
        kind = "touches_class_line" if mult % 2 == 0 else kind
        out.append(Point(x, y, kind, unc, *model, proven=True, field="SS"))
    return out, len(roots)


def curve_segments(curves) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Every segment of ``curves``: ``(a, d, curve, k)``, segment ``k`` of curve ``curve`` from
    ``a`` to ``a + d`` [rad] (a curve with fewer than two vertices has none)."""
    vs = [c.vertices for c in curves if len(c.vertices) >= 2]
    if not vs:
        e = np.zeros(0, int)
        return np.zeros((0, 2)), np.zeros((0, 2)), e, e
    sizes = [len(v) - 1 for v in vs]
    owner = np.repeat([i for i, c in enumerate(curves) if len(c.vertices) >= 2], sizes)
    k = np.concatenate([np.arange(m) for m in sizes])
    return (np.concatenate([v[:-1] for v in vs]), np.concatenate([np.diff(v, axis=0) for v in vs]),
            owner, k)  # fmt: skip


#: the most point-segment pairs :func:`torus_distances` holds at once
PAIR_BLOCK = 1 << 20


def pair_distances(p, a, d) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Distances [rad] on the torus from points ``p`` to segments ``a -> a + d`` (broadcastable
    ``(..., 2)`` arrays): ``(dist, t, image)``, the point's image ``p + 2 pi j`` nearest to the
    segment's start (segments far shorter than ``pi``), at fraction ``t`` of it (``p`` itself
    where ``j = 0``: no rounding off the seams)."""
    near = a + (p - a + math.pi) % TWO_PI - math.pi  # the image nearest to the start
    img = p + TWO_PI * np.round((near - p) / TWO_PI)
    t = np.sum((img - a) * d, -1) / np.maximum(np.sum(d * d, -1), 1e-300)
    t = np.clip(t, 0.0, 1.0)
    return np.hypot(*np.moveaxis(a + t[..., None] * d - img, -1, 0)), t, img


def torus_distances(xy, a, d) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`pair_distances` from every point of ``xy`` ``(m, 2)`` to every segment ``a -> a +
    d`` ``(n, 2)``: ``(dist, t, image)``, each ``(m, n)`` (``image`` ``(m, n, 2)``), in blocks of
    :data:`PAIR_BLOCK` pairs."""
    xy = np.asarray(xy, float).reshape(-1, 2)
    m, n = len(xy), len(a)
    dist, t, img = np.empty((m, n)), np.empty((m, n)), np.empty((m, n, 2))
    rows = max(1, PAIR_BLOCK // max(n, 1))
    for s in range(0, m, rows):
        got = pair_distances(xy[s : s + rows, None, :], a, d)
        dist[s : s + rows], t[s : s + rows], img[s : s + rows] = got
    return dist, t, img


def pairs_near(xy, a, d, reach) -> tuple[np.ndarray, np.ndarray]:
    """The pairs ``(i, j)`` (sorted) of a point of ``xy`` ``(m, 2)`` and a segment ``a -> a + d``
    ``(n, 2)`` within ``reach`` [rad] on the torus (:func:`pair_distances`), found among the
    segments whose start's ``beta1`` lies within ``reach`` plus the longest segment of the
    point's (sorted starts, not every pair)."""
    xy = np.asarray(xy, float).reshape(-1, 2)
    span = reach + float(np.abs(d).max(initial=0.0))
    if not len(xy) or not len(a):
        return np.zeros(0, int), np.zeros(0, int)
    key = a[:, 0] % TWO_PI
    order = np.argsort(key, kind="stable")
    ext = np.concatenate([key[order] - TWO_PI, key[order], key[order] + TWO_PI])
    v = xy[:, 0] % TWO_PI
    lo = np.searchsorted(ext, v - span) if span < math.pi else np.full(len(xy), len(a))
    hi = np.searchsorted(ext, v + span, "right") if span < math.pi else lo + len(a)
    size = hi - lo
    i = np.repeat(np.arange(len(xy)), size)
    j = np.tile(order, 3)[np.arange(size.sum()) - np.repeat(np.cumsum(size) - size - lo, size)]
    keep = pair_distances(xy[i], a[j], d[j])[0] <= reach
    pairs = np.unique(np.stack([i[keep], j[keep]], 1), axis=0).reshape(-1, 2)
    return pairs[:, 0], pairs[:, 1]


def _per_curve(curves, xy) -> list[tuple[float, int, float, np.ndarray]]:
    """Per curve of ``curves``, its segment nearest to ``xy`` [rad] on the torus: ``(distance,
    segment k, t, image)`` (:func:`torus_distances`; the first of equally near ones; distance
    ``inf`` for a curve without a segment)."""
    xy = np.asarray(xy, float)
    out = [(math.inf, -1, 0.0, xy)] * len(curves)
    a, d, owner, k = curve_segments(curves)
    if not len(a):
        return out
    dist, t, img = (v[0] for v in torus_distances(xy, a, d))
    order = np.lexsort((dist, owner))  # stable: the first of equal distances first
    first = order[np.r_[True, owner[order][1:] != owner[order][:-1]]]
    for j in first:
        out[owner[j]] = (float(dist[j]), int(k[j]), float(t[j]), img[j])
    return out


def nearest_segment(xy, curves) -> tuple[float, int, int, float, np.ndarray]:
    """The segment of ``curves`` nearest to ``xy`` [rad] on the torus: ``(distance, curve,
    segment k, t, image)`` (:func:`torus_distances`; the first of equally near ones; distance
    ``inf`` and curve ``-1`` when no curve has a segment)."""
    a, d, owner, k = curve_segments(curves)
    if not len(a):
        return math.inf, -1, -1, 0.0, np.asarray(xy, float)
    dist, t, img = (v[0] for v in torus_distances(xy, a, d))
    j = int(dist.argmin())
    return float(dist[j]), int(owner[j]), int(k[j]), float(t[j]), img[j]


def _spliced(c: Curve, k: int, t: float, xy, radius: float) -> Curve:
    """``c`` with the vertex ``xy`` spliced in after vertex ``k`` (before the first vertex or
    after the last where the nearest place is the curve's end); its ``bracket`` is twice its
    proven ``radius``, its ``ends`` NaN (an enclosure, not a bracket between two codes), its
    index in ``spliced``."""
    last = len(c.vertices) - 2
    at = 0 if (k == 0 and t == 0.0) else (k + 2 if (k == last and t == 1.0) else k + 1)
    ends = None if c.ends is None else np.insert(c.ends, at, np.nan, axis=0)
    return replace(
        c,
        vertices=np.insert(c.vertices, at, xy, axis=0),
        bracket=np.insert(c.bracket, at, 2 * radius),
        ends=ends,
        spliced=tuple(sorted([i + (i >= at) for i in c.spliced] + [at])),
    )


def attach_points(curves, points, reach, within, near, tol) -> tuple[list[Curve], int]:
    """Splice each proven point into every curve it lies on that does not already pass within
    ``reach`` [rad] of it: every curve within ``near`` [rad] of it (the distance to which the
    drawn curves follow the true ones) and the nearest curve if within ``within`` [rad] (a
    traced curve that passes a tangency farther off); only where the point's enclosure is no
    wider than the vertex tolerance ``tol`` [rad] (the file's promise for every vertex).  A
    vertex (:func:`_spliced`) where the curve passes or ends nearest to it, the point's image on
    the torus taken into ``[0, 2 pi)`` (the shift added to its radius); a splice that would make
    the curve cross itself is not made.  The other vertices keep their brackets.  Returns the
    curves and the number of splices (a point on two curves counts twice)."""
    curves, attached = list(curves), 0
    for p in points:
        if not p.proven:
            continue
        found = _per_curve(curves, (p.beta1, p.beta2))
        dist = np.array([f[0] for f in found] + [math.inf])
        targets = set(np.flatnonzero(dist <= near)) | ({int(dist.argmin())} & {
            i for i in range(len(curves)) if dist[i] <= within})  # fmt: skip
        for i in sorted(targets):
            d, k, t, img = found[i]
            if d <= reach:
                continue
            xy = np.clip(img, 0.0, np.nextafter(TWO_PI, 0.0))
            radius = p.uncertainty + float(np.hypot(*(xy - img)))
            if 2 * radius > tol:
                continue
            c = _spliced(curves[i], k, t, xy, radius)
            if shapely.is_simple(shapely.LineString(c.vertices)):
                curves[i], attached = c, attached + 1
    return curves, attached
