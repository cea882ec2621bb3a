"""Fig. 1 map: regions agree with the kernels (and the exact reference) at sampled pixels."""

import numpy as np
import pytest

from atlas.core import contact_modes, exact
from atlas.core.verdicts import Verdict
from atlas.paper.figures import _offset_grid, stability_map


@pytest.fixture(scope="module")
def ds():
    return stability_map(41, 0.5, 0.0, 0.0)


def test_schema(ds):
    assert ds["stable_SS"].dims == ("beta1", "beta2")
    assert ds["stable_SF"].dims == ("beta1",)
    assert ds["stable_SS"].dtype == np.int8
    assert set(np.unique(ds["class_code"].values)) <= set(contact_modes.ALL_CLASSES) | {
        0
    }  # 0: beta2 = beta1
    assert ds.attrs["n_undecided"] == 0


def test_regions_match_exact_reference(ds):
    rng = np.random.default_rng(0)
    b = _offset_grid(41)
    for i, j in rng.integers(0, 41, (25, 2)):
        c1, s1 = (float(v) for v in contact_modes.direction(b[i]))
        c2, s2 = (float(v) for v in contact_modes.direction(b[j]))
        r = exact.point_spectral(c1, s1, c2, s2, 0.5, 0.0, 0.0)
        for k in ("stable_SS", "consistent_II", "stable_II"):
            assert int(ds[k].values[i, j]) == r[k], (k, i, j)
        assert int(ds["class_code"].values[i, j]) == exact.point_codes(c1, s1, c2, s2)["class_code"]
        assert int(ds["stable_SF"].values[i]) == (Verdict.STABLE if c1 > 0 else Verdict.UNSTABLE)


def test_ss_margin_sign_matches_verdict_in_curved_classes(ds):
    # inside classes with curved boundaries, neutral <=> margin > 0 (q = 0)
    cls = ds["class_code"].values
    sel = np.isin(cls, (13, 23, 41, 46))
    ss = ds["stable_SS"].values[sel]
    m = ds["margin_SS"].values[sel]
    assert np.all((ss == Verdict.NEUTRAL) == (m > 0))


def test_damped_map_has_stable_cells():
    d = stability_map(21, 0.5, 1.0, 1.0, margins=False)
    assert (d["stable_SS"].values == Verdict.STABLE).any()
    interior = d["class_code"].values != 0  # det B = 0 on beta2 = beta1: double zero root, neutral
    assert not (d["stable_SS"].values[interior] == Verdict.NEUTRAL).any()


# --------------------------------------------------------------------------- drawing on a given ax


def _check_drawn(art, ax=None, fig=None):
    """Every returned item is an artist of ``ax`` (or of ``fig``), and the axes holds it."""
    from matplotlib.artist import Artist

    assert art, "nothing returned"
    for a in art:
        assert isinstance(a, Artist), type(a)
        if ax is not None:
            assert a.axes is ax or a in (ax.xaxis.label, ax.yaxis.label), a
        if fig is not None:
            assert a.figure is fig, a


def _axes():
    from matplotlib.figure import Figure

    return Figure().subplots()


def _outcome_dataset(kappa=0.5):
    import xarray as xr

    from atlas.dynamics import Outcome, outcome_grid

    b1, b2 = outcome_grid(3)
    codes = np.array([[int(o) for o in list(Outcome)[i : i + 3]] for i in range(3)], np.int8)
    attrs = dict(kappa=kappa, q1=0.0, q2=0.0, alpha=0.35 * np.pi, n_perturb=1, t_end=10.0)
    return xr.Dataset(
        {"outcome": (("beta1", "beta2"), codes)}, coords={"beta1": b1, "beta2": b2}, attrs=attrs
    )


def test_fig1_draw_functions_draw_on_the_given_ax(ds):
    import matplotlib

    from atlas.paper import drawing, plots

    before = {k: matplotlib.rcParams[k] for k in drawing.HATCH_STYLE}
    pos = drawing.label_positions(ds)
    for layer in plots.FIG1_LAYERS:
        ax = _axes()
        art = plots.draw_fig1_layer(ax, ds, layer, pos)
        _check_drawn(art, ax=ax)
        assert ax.get_title() and set(art) <= set(ax.get_children())
    ax = _axes()
    _check_drawn(plots.draw_fig1_variant(ax, ds, ds, pos), ax=ax)
    ax = _axes()
    rep = {"beta1": 0.3, "beta2": 2.0, "alpha": {1: 1.0, 2: 4.0}}
    art = plots.draw_class_diagram(ax, 13, rep)
    _check_drawn(art, ax=ax)
    assert sum(t.get_text() in ("1", "2") for t in ax.texts) == 2  # one label per subclass
    # the hatching style is scoped to the drawing: the global rcParams are untouched
    assert {k: matplotlib.rcParams[k] for k in drawing.HATCH_STYLE} == before
    with pytest.raises(ValueError, match="layer"):
        plots.draw_fig1_layer(_axes(), ds, "XY")


def test_fig1_multi_panel_draw_functions_fill_the_given_figure(ds):
    from matplotlib.figure import Figure

    from atlas.paper import plots

    fig = Figure()
    _check_drawn(plots.draw_fig1_stability(fig, ds), fig=fig)
    assert len(fig.axes) == len(plots.FIG1_LAYERS) and fig.legends
    fig = Figure()
    _check_drawn(plots.draw_fig1_variants(fig, [ds, ds]), fig=fig)
    assert sum(ax.get_visible() and ax.axison for ax in fig.axes) == 2  # 3rd panel switched off


def test_table2_draw_and_plot(tmp_path):
    from types import SimpleNamespace

    from atlas.paper import plots

    row = SimpleNamespace(
        cls=11, dual=11, IF="x", FI="-", II="(x)", CC="?", II_stability="model-dependent",
        subclasses={"FF": [1, 2], "SS": [3], "SF": [], "FS": [4]},
        stability={"FF": "stable", "SS": "unstable", "SF": "stable", "FS": "model-dependent"},
    )  # fmt: skip
    ax = _axes()
    tab, title = plots.draw_table2(ax, [row])
    _check_drawn([tab, title], ax=ax)
    assert tab[1, 0].get_text().get_text() == "11 (same)"
    assert tab[1, 2].get_facecolor()[:3] == pytest.approx((0x4D / 255,) * 3)  # SS unstable: dark
    path = plots.plot_table2(tmp_path / "t.png", [row])
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_dynamics_draw_functions_draw_on_the_given_ax(ds):
    from matplotlib.figure import Figure

    from atlas.dynamics import fig2_cases, simulate
    from atlas.paper import figures_dynamics as fd

    p = dict(fig2_cases()["d"], t_end=2.0)
    res = simulate(**p)
    ax = _axes()
    art = fd.draw_trajectory(ax, res, p, "d", "note", n_samples=50)
    _check_drawn(art, ax=ax)
    assert [line.get_label() for line in ax.get_lines()[:2]] == ["$d_1$", "$d_2$"]
    out = _outcome_dataset()
    ax = _axes()
    _check_drawn(fd.draw_outcome(ax, out), ax=ax)
    ax = _axes()
    _check_drawn(fd.draw_theory(ax, ds), ax=ax)
    ax = _axes()
    _check_drawn(fd.draw_no_stable_outline(ax, 0.35 * np.pi, n_outline=60), ax=ax)
    fig = Figure()
    _check_drawn(fd.draw_outcome_map(fig, out, theory=ds, n_outline=60), fig=fig)
    assert len(fig.axes) == 2
    with pytest.raises(ValueError, match="theory"):
        fd.draw_outcome_map(Figure(), _outcome_dataset(kappa=2.0), theory=ds)
    fig = Figure()
    runs = {"d": (p, res, fd.classify(res))}
    _check_drawn(fd.draw_fig2(fig, runs, n_samples=50), fig=fig)


def test_outcome_distribution_per_subclass_and_its_bars():
    """Runs per class summed over the cells of each subclass without a stable mode, split by the
    cell's SS verdict (hand-made counts: subclass 132 has two cells with SS unstable, one of them
    mixed, and one with SS stable; 142 one cell where SS is inconsistent; 121 is left out)."""
    import xarray as xr

    from atlas.core.verdicts import Verdict
    from atlas.dynamics import Outcome
    from atlas.paper import figures_dynamics as fd

    n = len(Outcome)
    counts = np.zeros((2, 3, n), np.int16)
    counts[0, 0, int(Outcome.IWC)] = 4
    counts[0, 1, int(Outcome.IWC)] = 1
    counts[0, 1, int(Outcome.GROWING_BOUNCING)] = 3
    counts[0, 2, int(Outcome.SETTLES_SS)] = 4
    counts[1, 0, int(Outcome.GROWING_BOUNCING)] = 4
    counts[1, 1, int(Outcome.SETTLES_FF)] = 4
    S, U = int(Verdict.STABLE), int(Verdict.UNSTABLE)
    dims = ("beta1", "beta2")
    ds = xr.Dataset(
        {
            "subclass_code": (dims, np.array([[132, 132, 132], [142, 121, 121]], np.int16)),
            "outcome_count": ((*dims, "outcome_class"), counts),
            "agreement": (dims, np.array([[1, 0.75, 1], [1, 1, 1]], np.float32)),
            "stable_SS": (dims, np.array([[U, U, S], [S, S, S]], np.int8)),
            "consistent_SS": (dims, np.array([[1, 1, 1], [0, 1, 1]], bool)),
        }
    )
    dist = fd.subclass_distribution(ds)
    assert list(dist) == [(132, "SS stable"), (132, "SS unstable"), (142, "SS unstable")]
    cells, mixed, c132 = dist[(132, "SS unstable")]
    assert (cells, mixed) == (2, 1)
    assert c132[int(Outcome.IWC)] == 5 and c132[int(Outcome.GROWING_BOUNCING)] == 3
    assert c132.sum() == 8
    assert dist[(132, "SS stable")][2][int(Outcome.SETTLES_SS)] == 4
    assert dist[(142, "SS unstable")][:2] == (1, 0)
    ax = _axes()
    _check_drawn(fd.draw_distribution(ax, ds, "t"), ax=ax)
    labels = [t.get_text() for t in ax.get_yticklabels()]
    assert labels == ["132, theory: SS stable", "132, theory: SS unstable",
                      "142, theory: SS unstable"]  # fmt: skip


def test_class_representatives_share_table_1s_program(monkeypatch):
    """Each class point's subclass codes over the alpha grid take six arrays of the grid's
    length, the program of Table 1's columns (which the audit compiles), not four scalars and
    two arrays: a program of their own, traced once more in a one-process ``atlas paper``."""
    from atlas.paper import figures

    shapes = []

    def subclass_code(*args):
        shapes.append({np.shape(a) for a in args})
        return np.zeros(np.shape(args[-1]), np.int16)

    monkeypatch.setattr(contact_modes, "subclass_code", subclass_code)
    reps = figures.class_representatives(n=24, n_alpha=64)
    assert len(shapes) == len(reps) > 0 and all(s == {(64,)} for s in shapes), shapes
