"""``atlas.bench.boundaries``: contours and Hausdorff distances against closed forms."""

import numpy as np
import pytest

from atlas.bench.boundaries import contour_lines, hausdorff, masks, torus_hausdorff

BETA = np.linspace(0, 2 * np.pi, 129)
X, Y = np.meshgrid(BETA, BETA, indexing="ij")  # field[i, j] at (beta1 = BETA[i], beta2 = BETA[j])


def test_contour_of_a_linear_field_is_the_line():
    (line,) = contour_lines(BETA, X - 1.0, 0.0)  # beta1 = 1 for every beta2
    np.testing.assert_allclose(line[:, 0], 1.0, atol=1e-12)
    assert line[:, 1].min() == pytest.approx(0.0) and line[:, 1].max() == pytest.approx(2 * np.pi)


def test_hausdorff_of_shifted_circle():
    a = contour_lines(BETA, (X - 3) ** 2 + (Y - 3) ** 2 - 1, 0.0)
    b = contour_lines(BETA, (X - 3.1) ** 2 + (Y - 3) ** 2 - 1, 0.0)
    assert hausdorff(a, b, 0.01) == pytest.approx(0.1, abs=2e-3)
    assert hausdorff(a, a, 0.01) == pytest.approx(0.0, abs=1e-12)


def test_hausdorff_of_concentric_circles_is_the_radius_gap():
    a = contour_lines(BETA, (X - 3) ** 2 + (Y - 3) ** 2 - 1.0, 0.0)
    b = contour_lines(BETA, (X - 3) ** 2 + (Y - 3) ** 2 - 1.5**2, 0.0)
    assert hausdorff(a, b, 0.01) == pytest.approx(0.5, abs=2e-3)


def test_hausdorff_point_to_segment_not_to_vertices():
    """Two parallel segments 0.3 apart, vertices far apart: the distance is 0.3 exactly."""
    a = [np.array([[0.0, 0.0], [10.0, 0.0]])]
    b = [np.array([[-1.0, 0.3], [11.0, 0.3]])]
    assert hausdorff(a, b, 0.5) == pytest.approx(np.hypot(1.0, 0.3))  # b's ends stick out by 1
    b = [np.array([[0.0, 0.3], [10.0, 0.3]])]
    assert hausdorff(a, b, 0.5) == pytest.approx(0.3)


def test_hausdorff_of_empty_sets():
    line = [np.array([[0.0, 0.0], [1.0, 0.0]])]
    assert hausdorff([], [], 0.1) == 0.0
    assert np.isnan(hausdorff(line, [], 0.1)) and np.isnan(hausdorff([], line, 0.1))


def test_masks_undamped_draws_neutral_as_stable():
    res = {"stable_SS": np.array([0, 1, 2, 3]), "consistent_II": np.array([1, 0, 3, 1])}
    np.testing.assert_array_equal(masks(res, damped=False)["SS"], [0, 1, 1, 0])
    np.testing.assert_array_equal(masks(res, damped=True)["SS"], [0, 1, 0, 0])
    np.testing.assert_array_equal(masks(res, damped=True)["II"], [1, 0, 0, 1])


def test_hausdorff_sees_a_long_segment_beside_a_dense_polyline():
    """The same set drawn twice is at distance 0, even where the nearest vertices of one drawing
    all belong to a dense polyline 0.02 away from a long two-vertex segment."""
    dense = np.stack([np.full(500, 0.02), np.linspace(0.0, 1.0, 500)], 1)
    lines = [np.array([[0.0, 0.0], [0.0, 1.0]]), dense]
    assert hausdorff(lines, lines, 0.01) == pytest.approx(0.0, abs=1e-12)
    assert torus_hausdorff(lines, lines, 0.01) == pytest.approx(0.0, abs=1e-12)


def test_a_one_vertex_line_is_measured():
    """A polyline of one vertex (a curve cut to a point) still counts as a point of its set."""
    line = [np.array([[0.0, 0.0], [1.0, 0.0]])]
    dot = [np.array([[0.5, 0.25]])]
    assert hausdorff(dot, line, 0.01) == pytest.approx(np.hypot(0.5, 0.25))  # an end to the dot
    assert hausdorff(dot + line, line, 0.01) == pytest.approx(0.25, abs=1e-12)


def test_hausdorff_is_exact_next_to_a_dense_cluster():
    """A point on a long segment, halfway between two of its samples, with a cluster of 50
    vertices 1e-3 away: the 8 nearest samples are all in the cluster, yet the distance is the
    point's distance to the segment, 0 (it measured 1e-3 when only the 8 nearest were used)."""
    t = np.linspace(0.0, 2 * np.pi, 50)
    cluster = np.stack([1e-3 + 1e-6 * np.cos(t), 0.005 + 1e-6 * np.sin(t)], 1)
    a = [np.array([[0.0, 0.0], [0.0, 0.005], [0.0, 1.0]]), cluster]
    b = [np.array([[0.0, 0.0], [0.0, 1.0]]), cluster]
    assert hausdorff(a, b, 0.01) == pytest.approx(0.0, abs=1e-12)
    assert torus_hausdorff(a, b, 0.01) == pytest.approx(0.0, abs=1e-12)


def test_torus_quantiles_at_once_are_the_quantiles_one_by_one():
    """Two quantiles from one measurement of the distances are those of two calls: a dot 0.25
    off a segment (the largest distance, 0.25 by hand), and empty sets (NaN, or 0 for both)."""
    line = [np.array([[0.0, 0.0], [1.0, 0.0]])]
    dot = [np.array([[0.5, 0.25]])]
    both = torus_hausdorff(dot + line, line, 0.01, quantile=(1.0, 0.5))
    assert both == (
        torus_hausdorff(dot + line, line, 0.01),
        torus_hausdorff(dot + line, line, 0.01, 0.5),
    )
    assert both[0] == pytest.approx(0.25, abs=1e-12) and both[1] < 0.25
    assert np.isnan(torus_hausdorff(line, [], 0.01, quantile=(1.0, 0.99))).all()
    assert torus_hausdorff([], [], 0.01, quantile=(1.0, 0.99)) == (0.0, 0.0)


def test_ss_margin_on_a_grid_is_one_program():
    """The reference's SS margin runs as one jitted program (it was some 130 operations, each
    compiled on its own for every grid shape): at most one lowering for a new grid shape."""
    import jax

    from atlas.bench.boundaries import ss_margin
    from atlas.bench.grids import grid_inputs

    lowered = []

    def count(event, seconds, **kwargs):
        if event == "/jax/core/compile/jaxpr_to_mlir_module_duration":
            lowered.append(event)

    _, args = grid_inputs(22, 0.5, 0.05, 0.2, "float64")  # a grid shape no other test uses
    jax.monitoring.register_event_duration_secs_listener(count)
    try:
        got = ss_margin(args)
    finally:
        jax.monitoring.unregister_event_duration_listener(count)
    assert len(lowered) <= 1
    assert got.shape == (23, 23) and got.dtype == np.float64 and np.isfinite(got).all()
