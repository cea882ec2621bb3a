"""The audit's samples: batches of evaluated points and the exact or closed-form sets the claims share.

Searches: (i) class interiors from an offset grid (:func:`atlas.paper.tables.class_samples`) times a
``kappa`` ladder at ``Q = 0`` and times :data:`atlas.paper.tables.KAPPA_Q_SAMPLE`; (ii) seeded random
points: ``beta`` uniform, ``kappa = 10^U(-6, 6)``, damping in four equal groups -- ``q = 0``;
``q1 = q2 = 10^U(-4, 3)``; ``q1, q2`` independent ``10^U(-3, 3)`` (ratios up to 1e6); one of them 0.
Every function here is deterministic (seeded), so the order in which claims ask for samples does not
change any number.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from fractions import Fraction

import numpy as np

from atlas.core import contact_modes, expressions
from atlas.paper.audit.records import Counterexample, N, S, U
from atlas.paper.figures import evaluate_points

PI = math.pi


def directions(b1, b2):
    """``cos, sin`` of ``beta1`` and ``beta2`` [rad]: ``c1, s1, c2, s2``."""
    c1, s1 = contact_modes.direction(b1)
    c2, s2 = contact_modes.direction(b2)
    return c1, s1, c2, s2


def _classes(c1, s1, c2, s2):
    return np.asarray(contact_modes.class_code(*(np.asarray(v) for v in (c1, s1, c2, s2)))).astype(
        int
    )


@dataclass
class Points:
    """A batch of evaluated points: angles [rad], ``kappa, q1, q2`` [1], class codes, verdicts ``v``."""

    b1: np.ndarray
    b2: np.ndarray
    kappa: np.ndarray
    q1: np.ndarray
    q2: np.ndarray
    cls: np.ndarray
    v: dict

    def point(self, i, expect, note=""):
        """Point ``i`` as a :class:`Counterexample` that should show ``expect``."""
        return Counterexample(
            float(self.b1[i]),
            float(self.b2[i]),
            float(self.kappa[i]),
            float(self.q1[i]),
            float(self.q2[i]),
            expect,
            note,
        )

    def by_class(self, values, where=None):
        """``{class: set of values}`` over the points (optionally only where ``where``)."""
        where = np.ones(self.cls.shape, bool) if where is None else where
        out = {}
        for c in contact_modes.ALL_CLASSES:
            sel = (self.cls == c) & where
            out[c] = set(np.unique(np.asarray(values)[sel]).tolist())
        return out


def evaluate(b1, b2, kappa, q1, q2) -> Points:
    """Certified verdicts (undecided points settled exactly) at broadcastable inputs, flattened."""
    b1, b2, kappa, q1, q2 = np.broadcast_arrays(
        *(np.asarray(a, float) for a in (b1, b2, kappa, q1, q2))
    )
    b1, b2, kappa, q1, q2 = (a.ravel().copy() for a in (b1, b2, kappa, q1, q2))
    c1, s1, c2, s2 = directions(b1, b2)
    v = evaluate_points(c1, s1, c2, s2, kappa, q1, q2)
    return Points(b1, b2, kappa, q1, q2, _classes(c1, s1, c2, s2), v)


def random_points(n, seed=1) -> Points:
    """``n`` seeded random points in the four damping groups of the module docstring."""
    rng = np.random.default_rng(seed)
    b1, b2 = rng.uniform(0, 2 * PI, (2, n))
    kappa = 10.0 ** rng.uniform(-6, 6, n)
    g = np.arange(n) % 4
    qe = 10.0 ** rng.uniform(-4, 3, n)
    qa, qb = 10.0 ** rng.uniform(-3, 3, (2, n))
    q1 = np.where(g == 1, qe, np.where(g == 2, qa, np.where(g == 3, qa * (rng.random(n) < 0.5), 0)))
    q2 = np.where(g == 1, qe, np.where(g == 2, qb, np.where(g == 3, qb * (q1 == 0), 0)))
    return evaluate(b1, b2, kappa, q1, q2)


def class_grid(samples: dict, kq) -> Points:
    """Class samples (``{class: (n, 2) angles}``) x a list of ``(kappa, q1, q2)``."""
    pts = np.concatenate([samples[c] for c in contact_modes.ALL_CLASSES])
    kq = np.asarray(kq, float)
    B1 = np.repeat(pts[:, 0], len(kq))
    B2 = np.repeat(pts[:, 1], len(kq))
    K, Q1, Q2 = (np.tile(kq[:, i], len(pts)) for i in range(3))
    return evaluate(B1, B2, K, Q1, Q2)


@dataclass
class Table1Points:
    """Uniform random ``(beta1, beta2, alpha)`` with the kernels' Table 1 consistency and subclasses."""

    c1: np.ndarray
    s1: np.ndarray
    c2: np.ndarray
    s2: np.ndarray
    ca: np.ndarray
    sa: np.ndarray
    consistent: dict  # mode -> Consistency code per point
    subclass: np.ndarray


def table1_points(n: int = 20000, seed: int = 7) -> Table1Points:
    rng = np.random.default_rng(seed)
    b1, b2, al = rng.uniform(0, 2 * PI, (3, n))
    c1, s1, c2, s2 = directions(b1, b2)
    ca, sa = contact_modes.direction(al)
    args = [np.asarray(v) for v in (c1, s1, c2, s2, ca, sa)]
    cons = {k: np.asarray(v) for k, v in contact_modes.consistent_modes(*args).items()}
    sub = np.asarray(contact_modes.subclass_code(*args))
    return Table1Points(c1, s1, c2, s2, ca, sa, cons, sub)


@dataclass
class Matrix7Sample:
    """Matrix (7) of SF at random ``beta1, kappa, q1``, decided exactly (Appendix B).

    ``counts[key] = [points, points where the paper's claim holds]`` for the keys ``b>0, q>0``,
    ``b>0, q=0`` and ``b<0``; ``failing`` holds the keys with a point where it fails;
    ``kernel_mismatches`` counts points where the kernel (SF stable iff ``b11 > 0``) disagrees
    with ``sign(b11)``.
    """

    beta: np.ndarray
    kappa: np.ndarray
    q: np.ndarray
    b11: np.ndarray
    counts: dict
    failing: set
    kernel_mismatches: int


def matrix7_sample(n: int, seed: int = 11) -> Matrix7Sample:
    rng = np.random.default_rng(seed)
    beta = rng.uniform(0, 2 * PI, n)
    kap = 10.0 ** rng.uniform(-6, 6, n)
    q = np.where(np.arange(n) % 2 == 0, 0.0, 10.0 ** rng.uniform(-4, 3, n))
    c = np.asarray(contact_modes.direction(beta)[0], float)
    counts = {"b>0, q>0": [0, 0], "b>0, q=0": [0, 0], "b<0": [0, 0]}
    failing = set()
    for b, k, qq in zip(c, kap, q, strict=True):
        bb, K, Q = Fraction(float(b)), Fraction(float(k)), Fraction(float(qq))
        det, tr = bb * K, -bb * Q
        if b > 0:
            key = "b>0, q>0" if qq > 0 else "b>0, q=0"
            ok = det > 0 and tr < 0  # claimed: both eigenvalues with negative real parts
        else:
            key = "b<0"
            ok = det < 0  # claimed: two real eigenvalues of opposite signs (a saddle)
        if not ok:
            failing.add(key)
        counts[key][0] += 1
        counts[key][1] += int(ok)
    kern = np.asarray(contact_modes.stable_SF(np.asarray(c)))
    n_kernel_bad = int(np.sum((kern == S) != (c > 0)))
    return Matrix7Sample(beta, kap, q, c, counts, failing, n_kernel_bad)


@dataclass
class NegBK:
    """``-BK`` at the random points (``Q = 0``: the eigenvalues of M are ``+-sqrt`` of its own).

    ``det``, ``tr``, ``disc`` of ``-BK``; ``unstable``: the kernels' SS verdict is unstable;
    ``clear``: undamped and away from ties (``|det|, |tr|, |disc| > 1e-9``).
    """

    det: np.ndarray
    tr: np.ndarray
    disc: np.ndarray
    unstable: np.ndarray
    clear: np.ndarray


def neg_bk(R: Points, undamped) -> NegBK:
    c1, s1, c2, s2 = directions(R.b1, R.b2)
    det = R.kappa * expressions.det(c1, s1, c2, s2, sub=np.subtract)
    tr = -expressions.a2_undamped(R.kappa, c1, 1, s2, sub=np.subtract)
    disc = tr**2 - 4 * det
    clear = (np.abs(det) > 1e-9) & (np.abs(tr) > 1e-9) & (np.abs(disc) > 1e-9) & undamped
    return NegBK(det, tr, disc, R.v["stable_SS"] == U, clear)


def ss_word(vals) -> str:
    """``stable`` / ``unstable`` / ``model-dependent`` for a set of verdicts (neutral counts stable)."""
    v = {S if x == N else x for x in vals}
    return {frozenset({S}): "stable", frozenset({U}): "unstable"}.get(
        frozenset(v), "model-dependent"
    )


def fmt_classes(cs) -> str:
    """Sorted, comma-separated class codes (``none`` if empty)."""
    return ", ".join(str(c) for c in sorted(cs)) or "none"


def first(mask):
    """Index of the first true entry of ``mask``, or ``None``."""
    idx = np.flatnonzero(mask)
    return int(idx[0]) if idx.size else None
