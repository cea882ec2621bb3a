"""``atlas.data.class_lines``: the 13 straight class lines, checked against their definitions."""

import math

import numpy as np

from atlas.data import class_lines as cl

PI = math.pi


def test_thirteen_lines_in_the_full_square():
    lines = cl.class_lines()
    assert len(lines) == 13  # beta1 = k pi/2, beta2 = k pi/2 (k = 0..4), beta2 - beta1 = -pi, 0, pi
    ends = np.concatenate([c.vertices for c in lines])
    assert np.all(cl.line_distances(ends).min(1) < 1e-15)  # every end lies on a class line


def test_distances_are_values_over_gradient_norms():
    rng = np.random.default_rng(0)
    xy = rng.uniform(0, 2 * PI, (200, 2))
    norm = np.hypot(*cl.LINE_GRADS.T)
    np.testing.assert_allclose(cl.line_distances(xy), np.abs(cl.line_values(xy)) / norm)


def test_frames_run_on_their_line_with_the_normal_towards_larger_values():
    box = ((0.0, 2 * PI), (0.0, 2 * PI), 0.1)
    frames = cl.line_frames(box)
    assert sorted(m for m, *_ in frames) == list(range(13))
    for m, base, direction, normal, t0, t1 in frames:
        t = np.linspace(t0, t1, 7)
        on = np.asarray(base) + t[:, None] * np.asarray(direction)
        np.testing.assert_allclose(cl.line_values(on)[:, m], 0.0, atol=1e-15)
        off = on + 1e-3 * np.asarray(normal)
        np.testing.assert_allclose(cl.line_distances(off)[:, m], 1e-3, rtol=1e-9)
        assert np.all(cl.line_values(off)[:, m] > 0)


def test_labels_name_the_line_within_near():
    xy = np.array([[PI / 2 + 1e-9, 1.0], [1.0, 1.0 + PI + 2e-9], [1.0, 2.0]])
    np.testing.assert_array_equal(cl.line_labels(xy, near=1e-8), [1, 12, -1])
