"""The model-dependence panel beside Fig. 1: its map against the closed form of the whole model
space (README "Verdicts over every contact model"), and the figure written."""

import numpy as np

from atlas.core.contact_modes import direction
from atlas.core.verdicts import OverModels
from atlas.paper import figure_models


def test_whole_model_space_map_and_figure(tmp_path):
    path = tmp_path / "models.png"
    (ds,) = figure_models.plot_model_dependence(path, n=24, boxes=("kappa=0:inf",))
    assert path.stat().st_size > 0
    b = ds.beta1.values
    (c1, s1), (c2, s2) = direction(b[:, None]), direction(b[None, :])
    D = c1 * s2 - s1 * c2  # offset grid: no point on a class line, float signs are exact
    expected = np.where(
        (D < 0) | ((c1 <= 0) & (s2 <= 0)),
        int(OverModels.UNSTABLE),
        np.where(
            (c1 > 0) & (s2 > 0) & (s1 * c2 >= 0), int(OverModels.STABLE), int(OverModels.DEPENDS)
        ),
    )
    np.testing.assert_array_equal(ds["ss_over_models"].values, expected)
    assert ds.attrs["over_models_undecided"] == 0
