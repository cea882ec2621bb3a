"""The straight class boundaries of a ``(beta1, beta2)`` slice (SPEC §1): ``beta1 = k pi/2``,
``beta2 = k pi/2`` and ``beta2 = beta1 + k pi``, in closed form, with the distances, signed values
and frames of the 13 lines that the boundary tracing (:mod:`atlas.data.boundaries`) uses."""

from __future__ import annotations

import math

import numpy as np

from atlas.data.boundary_curves import Curve

__all__ = [
    "LINE_GRADS",
    "class_lines",
    "line_distances",
    "line_frames",
    "line_labels",
    "line_values",
    "torus_class_lines",
]

TWO_PI = 2 * math.pi


def class_lines(b1_range=(0.0, TWO_PI), b2_range=(0.0, TWO_PI)) -> list[Curve]:
    """The straight class boundaries (SPEC §1) inside the box ``b1_range x b2_range`` [rad]:
    ``beta1 = k pi/2``, ``beta2 = k pi/2`` and ``beta2 = beta1 + k pi``, in closed form."""
    (x0, x1), (y0, y1) = b1_range, b2_range
    segs = []
    for k in range(5):
        v = k * math.pi / 2
        if x0 <= v <= x1:
            segs.append([[v, y0], [v, y1]])
        if y0 <= v <= y1:
            segs.append([[x0, v], [x1, v]])
    for k in (-1, 0, 1):
        lo, hi = max(x0, y0 - k * math.pi), min(x1, y1 - k * math.pi)
        if lo < hi:
            segs.append([[lo, lo + k * math.pi], [hi, hi + k * math.pi]])
    return [
        Curve("class", "class_line", -1, -1, np.array(s, float), np.zeros(2), on_class_line=True)
        for s in segs
    ]


def torus_class_lines() -> list[Curve]:
    """The class lines of the whole torus ``[0, 2 pi)^2`` [rad], each once: ``beta1, beta2 = k pi/2``
    (``k = 0..3``), ``beta2 = beta1`` and ``beta2 = beta1 + pi`` (in two parts, ``beta2 = beta1
    + pi`` and ``beta2 = beta1 - pi``), ending a float short of ``2 pi``."""
    end = math.nextafter(TWO_PI, 0.0)
    segs = []
    for k in range(4):
        v = k * math.pi / 2
        segs += [[[v, 0.0], [v, end]], [[0.0, v], [end, v]]]
    segs += [[[0.0, 0.0], [end, end]], [[0.0, math.pi], [math.pi, end]]]
    segs += [[[math.pi, 0.0], [end, math.pi]]]
    return [
        Curve("class", "class_line", -1, -1, np.array(s, float), np.zeros(2), on_class_line=True)
        for s in segs
    ]


def line_distances(xy) -> np.ndarray:
    """Distances [rad] of points ``(m, 2)`` to the 13 class lines (columns: ``beta1 = k pi/2``,
    ``beta2 = k pi/2`` for k = 0..4, then ``beta2 - beta1 = k pi`` for k = -1, 0, 1)."""
    k = np.arange(5) * (math.pi / 2)
    d1 = np.abs(xy[:, :1] - k)
    d2 = np.abs(xy[:, 1:] - k)
    dd = np.abs(xy[:, 1:] - xy[:, :1] - np.array([-1, 0, 1]) * math.pi) / math.sqrt(2)
    return np.concatenate([d1, d2, dd], axis=1)


def line_values(xy) -> np.ndarray:
    """Signed values of the 13 class-line functions at points ``(m, 2)``."""
    k = np.arange(5) * (math.pi / 2)
    return np.concatenate(
        [xy[:, :1] - k, xy[:, 1:] - k, xy[:, 1:] - xy[:, :1] - np.array([-1, 0, 1]) * math.pi],
        axis=1,
    )


#: gradients of the 13 class-line functions of :func:`line_values`
LINE_GRADS = np.array([[1.0, 0.0]] * 5 + [[0.0, 1.0]] * 5 + [[-1.0, 1.0]] * 3)


def line_labels(xy, near) -> np.ndarray:
    """Per vertex, the class line it lies on (within ``near`` [rad]; index of
    :func:`line_distances`), or -1."""
    dist = line_distances(xy)
    return np.where(dist.min(1) <= near, dist.argmin(1), -1)


def line_frames(box):
    """Per class line (the columns of :func:`line_distances`) inside the box: ``(m, base,
    direction, unit normal, t0, t1)``, points ``base + t direction`` for ``t0 <= t <= t1``; the
    normal points to where :func:`line_values` grows."""
    (x0, x1), (y0, y1), _ = box
    frames = []
    for k in range(5):
        v = k * math.pi / 2
        if x0 <= v <= x1:
            frames.append((k, (v, 0.0), (0.0, 1.0), (1.0, 0.0), y0, y1))
        if y0 <= v <= y1:
            frames.append((5 + k, (0.0, v), (1.0, 0.0), (0.0, 1.0), x0, x1))
    r = 1 / math.sqrt(2)
    for m, k in zip((10, 11, 12), (-1, 0, 1)):
        t0, t1 = max(x0, y0 - k * math.pi), min(x1, y1 - k * math.pi)
        if t0 < t1:
            frames.append((m, (0.0, k * math.pi), (1.0, 1.0), (-r, r), t0, t1))
    return frames
