"""The model-dependence panel beside Fig. 1: its map and the shares of the plane it reports against
the closed form of the whole model space (README "Verdicts over every contact model"), and the
figure written and declared among ``atlas paper``'s files.

The closed form, derived from the conditions of :mod:`atlas.core.model_box` off the class lines:
``D < 0`` gives ``a0 = kappa D < 0`` for every model; ``c1, s2 < 0`` gives ``a3 < 0`` (damped)
and ``a2 < 0`` (undamped), unstable for every model.  Stable for every model needs ``a3 > 0`` as
``q2 -> 0`` and as ``q1 -> 0`` (``c1 > 0``, ``s2 > 0``) and the undamped ``disc >= 0`` at
``kappa = s2 / c1``, where ``disc = 4 kappa s1 c2`` (``s1 c2 >= 0``); these make ``G >= 0`` and
``disc >= 0`` everywhere.  Every other geometry has a model on each side.
"""

import numpy as np
import pytest

from atlas import paper
from atlas.core.contact_modes import direction
from atlas.core.verdicts import OverModels
from atlas.paper import figure_models


def _closed_form(b):
    """The whole-model-space verdict on the grid ``b x b`` (float signs are exact off the class
    lines, which the offset grid avoids)."""
    (c1, s1), (c2, s2) = direction(b[:, None]), direction(b[None, :])
    D = c1 * s2 - s1 * c2
    return np.where(
        (D < 0) | ((c1 <= 0) & (s2 <= 0)),
        int(OverModels.UNSTABLE),
        np.where(
            (c1 > 0) & (s2 > 0) & (s1 * c2 >= 0), int(OverModels.STABLE), int(OverModels.DEPENDS)
        ),
    )


@pytest.fixture(scope="module")
def whole(tmp_path_factory):
    """The whole-model-space panel at ``atlas paper``'s CI size, written like ``atlas paper``."""
    path = tmp_path_factory.mktemp("models") / "fig1_models.png"
    (ds,) = figure_models.plot_model_dependence(
        path, n=figure_models.N_MODELS[2], boxes=figure_models.BOXES[:1]
    )
    return path, ds


def test_whole_model_space_map_and_figure(whole):
    path, ds = whole
    assert path.stat().st_size > 0
    np.testing.assert_array_equal(ds["ss_over_models"].values, _closed_form(ds.beta1.values))
    assert ds.attrs["over_models_undecided"] == 0


def test_reported_shares_agree_with_the_closed_form(whole):
    _, ds = whole
    expected = _closed_form(ds.beta1.values)
    lines = figure_models.fractions_markdown(ds)
    assert "kappa=0:inf" in lines[0] and f"{expected.shape[0]} x {expected.shape[1]}" in lines[0]
    for v in OverModels:
        k = int(np.count_nonzero(expected == int(v)))
        assert f"| {v.label} | {k} | {100 * k / expected.size:.2f} % |" in lines, v.label
    assert sum(k for k, _ in figure_models.fractions(ds).values()) == expected.size


def test_declared_among_the_paper_files():
    assert "fig1_models.png" in paper.files(quick=True)
    assert all(n % 4 == 0 for n in figure_models.N_MODELS)  # no cell on a class line


def test_the_key_fits_the_figure(whole):
    """Every entry of the key is inside the figure as drawn (one panel: the key of three entries
    in a row was wider than the 3.2-inch figure and lost both ends)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    from atlas.paper import drawing

    _, ds = whole
    fig = drawing.new_figure(figsize=(3.2, 3.8), layout="constrained")
    figure_models.draw_model_dependence(fig, [ds])
    renderer = FigureCanvasAgg(fig).get_renderer()
    fig.draw(renderer)
    box, key = fig.bbox, fig.legends[0].get_window_extent(renderer)
    assert box.x0 <= key.x0 and key.x1 <= box.x1, (key, box)
