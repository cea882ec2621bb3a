"""Certified signs of polynomials on boxes: Bernstein coefficients in exact integers.

A polynomial ``p(x_1, ..., x_n)`` with rational coefficients is given on a box whose axes are
intervals ``[lo, hi]``, ``[lo, inf)`` or ``(0, hi]`` / ``(0, inf)``.  Each axis is mapped onto
``t`` in ``[0, 1]``: ``x = lo + (hi - lo) t`` (bounded) or ``x = lo + t / (1 - t)`` (unbounded);
``p(x(t)) (1 - t)^d`` (``d`` = the degree in that variable) is a polynomial in ``t`` with the sign of
``p`` on ``t < 1``.  Written in the tensor Bernstein basis of degree ``d`` on ``[0, 1]^n`` its
coefficients ``b_i`` (scaled to integers by a positive factor) give the classical certificate
(Farouki and Rajan 1987; Garloff 1986): every basis polynomial is ``>= 0`` on the box, so ``b >= 0``
proves ``p >= 0``.  For a *strict* sign on a box with some faces left out (an open end, the
excluded ``q = 0`` corner of :mod:`atlas.core.model_box`): a point in the relative interior of a
face ``F`` has every basis polynomial of a vertex of ``F`` strictly positive there, so ``b <= 0``
and, for each face that is not left out, one vertex coefficient of ``F`` ``< 0`` prove ``p < 0`` on
the box minus the faces left out.  Vertex coefficients are the values (times a positive factor)
at the vertices, so a subdivision also yields exact counterexamples.  Subdivision is de Casteljau
at ``t = 1/2`` (integers: the halves are scaled by ``2^d``).  Nothing is rounded.
"""

from __future__ import annotations

import collections
import functools
import itertools
import math
from fractions import Fraction
from math import comb

import numpy as np

__all__ = ["Poly", "Axis", "Template", "to_bernstein", "prove_any", "point_of"]

KINDS = ("<0", "<=0", ">0", ">=0")


class Poly:
    """Sparse polynomial in ``n`` variables with rational coefficients (``+``, ``*``, ``**``
    with ints and ``Poly``): the number type on which :mod:`atlas.core.expressions` runs here."""

    __slots__ = ("terms", "n")

    def __init__(self, terms: dict, n: int):
        self.terms = {e: c for e, c in terms.items() if c != 0}
        self.n = n

    @classmethod
    def var(cls, i: int, n: int) -> Poly:
        return cls({tuple(int(j == i) for j in range(n)): Fraction(1)}, n)

    @classmethod
    def const(cls, c, n: int) -> Poly:
        return cls({(0,) * n: Fraction(c)}, n)

    def _lift(self, o) -> Poly:
        return o if isinstance(o, Poly) else Poly.const(o, self.n)

    def __add__(self, o):
        out = dict(self.terms)
        for e, c in self._lift(o).terms.items():
            out[e] = out.get(e, 0) + c
        return Poly(out, self.n)

    __radd__ = __add__

    def __mul__(self, o):
        out: dict = {}
        for e1, c1 in self.terms.items():
            for e2, c2 in self._lift(o).terms.items():
                e = tuple(a + b for a, b in zip(e1, e2))
                out[e] = out.get(e, 0) + c1 * c2
        return Poly(out, self.n)

    __rmul__ = __mul__

    def __pow__(self, k: int):
        out = Poly.const(1, self.n)
        for _ in range(k):
            out = out * self
        return out

    def divide_var(self, i: int, k: int) -> Poly:
        """``self / x_i^k`` (every term must hold ``x_i^k``)."""
        if any(e[i] < k for e in self.terms):
            raise ValueError(f"divide_var: not divisible by x{i}^{k}")
        return Poly({e[:i] + (e[i] - k,) + e[i + 1 :]: c for e, c in self.terms.items()}, self.n)

    def degrees(self) -> tuple[int, ...]:
        return tuple(max((e[i] for e in self.terms), default=0) for i in range(self.n))


def sub(a, b):
    """The subtraction of :mod:`atlas.core.expressions` on :class:`Poly`."""
    return a + (-1) * b


class Axis:
    """One axis of a box: ``[lo, hi]`` (``hi = None``: unbounded above), ``open_lo``: ``lo`` not
    in the box (``kappa > 0``); ``lo == hi``: a fixed value."""

    def __init__(self, lo, hi=None, open_lo=False):
        self.lo = Fraction(lo)
        self.hi = None if hi is None else Fraction(hi)
        self.open_lo = bool(open_lo)
        self.fixed = self.hi is not None and self.hi == self.lo

    def map(self):
        """``(A, B, C, E)`` of ``x = (A + B t) / (C + E t)``."""
        if self.hi is None:
            return self.lo, 1 - self.lo, Fraction(1), Fraction(-1)
        return self.lo, self.hi - self.lo, Fraction(1), Fraction(0)

    def value(self, t: Fraction) -> Fraction:
        A, B, C, E = self.map()
        return (A + B * t) / (C + E * t)

    def excluded(self, side: int) -> bool:
        """Whether the face ``t = side`` is outside the box."""
        return (side == 0 and self.open_lo) or (side == 1 and self.hi is None)


def _tpoly(A, B, j, C, E, k):
    """Coefficients (in ``t``) of ``(A + B t)^j (C + E t)^k``."""
    out = [Fraction(1)]
    for a, b in [(A, B)] * j + [(C, E)] * k:
        out = [x * a + y * b for x, y in zip(out + [0], [0] + out)]
    return out


def _axis_matrix(axis: Axis, d: int) -> list:
    """The matrix taking power coefficients in ``x`` (degree ``d``) to Bernstein coefficients in
    ``t`` (degree ``d``, or 0 on a fixed axis)."""
    if axis.fixed:
        return [[axis.lo**j for j in range(d + 1)]]
    A, B, C, E = axis.map()
    power = [_tpoly(A, B, j, C, E, d - j) for j in range(d + 1)]  # column j: t-coefficients
    return [
        [
            sum(Fraction(comb(i, k), comb(d, k)) * power[j][k] for k in range(i + 1))
            for j in range(d + 1)
        ]
        for i in range(d + 1)
    ]


@functools.lru_cache(maxsize=256)
def _matrix(key, d: int) -> np.ndarray:
    """:func:`_axis_matrix` of the axis ``Axis(*key)`` (cached: one per box and degree)."""
    return np.array(_axis_matrix(Axis(*key), d), dtype=object)


def _fractions(p: Poly, axes, degrees) -> np.ndarray:
    """Rational Bernstein coefficients of ``p`` on ``axes`` in the given degrees."""
    arr = np.zeros(tuple(d + 1 for d in degrees), dtype=object)
    arr[...] = Fraction(0)
    for e, c in p.terms.items():
        arr[e] = c
    for i, (axis, d) in enumerate(zip(axes, degrees)):
        M = _matrix((axis.lo, axis.hi, axis.open_lo), d)
        arr = np.moveaxis(np.tensordot(M, arr, axes=([1], [i])), 0, i)
    return arr


def _to_ints(arrays):
    """Rational arrays times their common denominator (a positive factor), as Python ints."""
    den = math.lcm(*(v.denominator for a in arrays for v in a.flat))
    return [np.vectorize(lambda v: int(v * den), otypes=[object])(a) for a in arrays]


def to_bernstein(p: Poly, axes, degrees=None) -> np.ndarray:
    """Integer Bernstein coefficients (object array, one axis per variable) of ``p`` on the box
    ``axes``, up to a positive factor."""
    degrees = p.degrees() if degrees is None else degrees
    return _to_ints([_fractions(p, axes, degrees)])[0]


class Template:
    """Bernstein coefficients on a box of a polynomial whose coefficients are polynomials in
    parameters (variables ``n_box ...`` of ``p``), prepared once: per parameter monomial its
    integer Bernstein array; :meth:`at` sums them with the monomials' values (exact)."""

    def __init__(self, p: Poly, axes):
        n = len(axes)
        groups: dict = {}
        for e, c in p.terms.items():
            groups.setdefault(e[n:], {})[e[:n]] = c
        self.exps = list(groups) or [(0,) * (p.n - n)]
        polys = [Poly(groups.get(e, {}), n) for e in self.exps]
        degrees = tuple(max(q.degrees()[i] for q in polys) for i in range(n))
        self.dmax = max(sum(e) for e in self.exps)
        self.arrays = np.stack(_to_ints([_fractions(q, axes, degrees) for q in polys]))

    def at(self, values, N: int) -> np.ndarray:
        """Integer Bernstein coefficients (up to a positive factor) at parameters
        ``values[i] / N`` (``values``, ``N``: ints)."""
        vals = [
            math.prod(v**k for v, k in zip(values, e)) * N ** (self.dmax - sum(e))
            for e in self.exps
        ]
        return np.tensordot(np.array(vals, dtype=object), self.arrays, axes=1)


@functools.lru_cache(maxsize=32)
def _halving(d: int) -> np.ndarray:
    """The integer matrix ``(2, d + 1, d + 1)`` taking Bernstein coefficients ``b`` of degree
    ``d`` on ``[0, 1]`` to those on its halves, scaled by ``2^d`` (de Casteljau at ``t = 1/2``
    in closed form): left ``2^(d - r) sum_k C(r, k) b_k``, right ``2^i sum_m C(d - i, m)
    b_(i + m)``."""
    M = np.zeros((2, d + 1, d + 1), dtype=object)
    for r in range(d + 1):
        for k in range(r + 1):
            M[0, r, k] = 2 ** (d - r) * comb(r, k)
            M[1, d - r, d - r + k] = 2 ** (d - r) * comb(r, k)
    return M


def _split(b: np.ndarray, axis: int):
    """De Casteljau halves of ``b`` along ``axis`` (both scaled by ``2^d``; exact integers, one
    product with :func:`_halving`)."""
    rows = b.swapaxes(0, axis)
    d = rows.shape[0] - 1
    both = _halving(d).reshape(2 * (d + 1), d + 1).dot(rows.reshape(d + 1, -1))
    both = both.reshape((2,) + rows.shape)
    return both[0].swapaxes(0, axis), both[1].swapaxes(0, axis)


def _sign_ok(v, kind: str, strict: bool) -> bool:
    if kind[0] == "<":
        return v < 0 if strict else v <= 0
    return v > 0 if strict else v >= 0


def _faces(n: int, fixed):
    """Every face as a tuple of sides (0, 1 or None = free) with its vertices (tuples of 0/1)."""
    choices = [(0,) if f else (0, 1, None) for f in fixed]
    out = []
    for face in itertools.product(*choices):
        verts = list(itertools.product(*[(0, 1) if s is None else (s,) for s in face]))
        out.append((face, verts))
    return out


def _certified(b, kind, faces, left_out) -> bool:
    """Whether ``b`` proves ``p kind 0`` on the box minus the faces in ``left_out``."""
    if (b > 0).any() if kind[0] == "<" else (b < 0).any():
        return False
    if kind in ("<=0", ">=0"):
        return True
    at = lambda v: b[tuple(-s for s in v)]  # noqa: E731  (index 0 or -1 per axis)
    return all(f in left_out or any(_sign_ok(at(v), kind, True) for v in vs) for f, vs in faces)


def prove_any(conds, axes, patterns=(), budget: int = 256):
    """Prove that on the box ``axes`` (minus the faces of ``patterns``) every point satisfies at
    least one of ``conds``: each a pair ``(p, kind)`` (kind in ``<0 <=0 >0 >=0``; ``p`` a
    :class:`Poly` or its integer Bernstein coefficients on the box, e.g. from :class:`Template`)
    or a list of such pairs, which must all hold (a conjunction; tighter than a product).

    ``patterns``: faces left out besides the open ends, each a dict ``{axis: side}`` (a face lies
    in it when its sides agree on those axes).  Returns ``("proved", None)``, ``("counterexample",
    t)`` (``t``: a vertex, in box coordinates, inside the box where every condition fails, exactly)
    or ``("unknown", None)`` after ``budget`` boxes.
    """
    n = len(axes)
    fixed = [a.fixed for a in axes]
    conds = [c if isinstance(c, list) else [c] for c in conds]
    kinds = [[k for _, k in c] for c in conds]
    polys = [
        [p if isinstance(p, np.ndarray) else to_bernstein(p, axes) for p, _ in c] for c in conds
    ]
    degs = tuple(max(b.shape[i] - 1 for c in polys for b in c) for i in range(n))
    faces = _faces(n, fixed)
    queue = collections.deque([((Fraction(0),) * n, (Fraction(1),) * n, polys)])
    outs: dict = {}  # faces left out, per contact of the box with the whole box's faces
    for _ in range(budget):
        if not queue:
            return "proved", None
        lo, hi, bs = queue.popleft()
        on = tuple((lo[i] == 0, hi[i] == 1) for i in range(n))
        if on not in outs:
            outs[on] = _left_out(axes, patterns, on, faces)
        left_out = outs[on]
        if any(
            all(_certified(b, k, faces, left_out) for b, k in zip(bc, kc))
            for bc, kc in zip(bs, kinds)
        ):
            continue
        v = _failing_vertex(bs, kinds, faces, left_out)
        if v is not None:
            return "counterexample", tuple(hi[i] if s else lo[i] for i, s in enumerate(v))
        halves = _halves(lo, hi, bs, fixed, degs)
        if not halves:  # every condition constant here and not certified: it fails everywhere
            return "counterexample", tuple((a + b) / 2 for a, b in zip(lo, hi))
        queue.extend(halves)
    return ("proved", None) if not queue else ("unknown", None)


def _failing_vertex(bs, kinds, faces, left_out):
    """A vertex of the box, inside the whole box, where every condition fails (exactly)."""
    for f, vs in faces:
        if None in f or f in left_out:
            continue
        at = tuple(-s for s in vs[0])
        if all(
            any(not _sign_ok(b[at], k, k in ("<0", ">0")) for b, k in zip(bc, kc))
            for bc, kc in zip(bs, kinds)
        ):
            return vs[0]
    return None


def _left_out(axes, patterns, on, faces) -> frozenset:
    """The faces of a sub-box outside the whole box: on an open end of it, or in one of
    ``patterns`` (``on[i]``: whether the sub-box's low and high faces of axis ``i`` are the whole
    box's)."""

    def out(face):
        for i, s in enumerate(face):
            if s is not None and on[i][s] and axes[i].excluded(s):
                return True
        return any(all(face[i] == s and on[i][s] for i, s in p.items()) for p in patterns)

    return frozenset(f for f, _ in faces if out(f))


def _halves(lo, hi, bs, fixed, degs):
    """The two halves of a box along its widest splittable axis."""
    widths = [(hi[i] - lo[i], i) for i in range(len(lo)) if not fixed[i] and degs[i] > 0]
    if not widths:
        return []
    _, ax = max(widths)
    mid = (lo[ax] + hi[ax]) / 2
    parts = [[_split(b, ax) for b in bc] for bc in bs]
    lo2 = lo[:ax] + (mid,) + lo[ax + 1 :]
    hi1 = hi[:ax] + (mid,) + hi[ax + 1 :]
    return [
        (lo, hi1, [[p[0] for p in pc] for pc in parts]),
        (lo2, hi, [[p[1] for p in pc] for pc in parts]),
    ]


def point_of(axes, t) -> tuple[Fraction, ...]:
    """The model point (exact) of box coordinates ``t``."""
    return tuple(a.value(ti) for a, ti in zip(axes, t))
