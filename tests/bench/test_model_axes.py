"""``atlas.bench.model_axes``: the 2-D and 5-D grid rows, their tier counts as printed."""

import numpy as np

from atlas.bench import model_axes, report
from atlas.bench.config import CONFIG
from atlas.core.points import spectral_points

FLAGS = ("stable_SS", "consistent_II", "stable_II")


def _by_hand(n, models):
    """The inputs of an ``n x n`` beta grid over ``models`` (scalars: 2-D; sequences: the 5-D
    layout of ``atlas generate``), built here without the module under test."""
    beta = np.linspace(0.0, 2 * np.pi, n)
    c, s = np.cos(beta), np.sin(beta)
    c[np.abs(c) < 1e-15], s[np.abs(s) < 1e-15] = 0.0, 0.0
    dims = 2 if np.ndim(models[0]) == 0 else 5
    e = lambda a, d: np.asarray(a, float).reshape([-1 if i == d else 1 for i in range(dims)])  # noqa: E731
    if dims == 2:
        return (e(c, 0), e(s, 0), e(c, 1), e(s, 1), *(np.asarray(m, float) for m in models))
    return (e(c, 0), e(s, 0), e(c, 1), e(s, 1), *(e(m, 2 + i) for i, m in enumerate(models)))


def test_printed_tier_counts_equal_the_driver_counts(monkeypatch):
    """Every tier count the bench prints for a small 2-D and 5-D grid equals the count the
    driver reports for the same grid computed here (no clock involved); the handful-of-points
    host path off, so that these small grids reach the later tiers."""
    from atlas.core import points

    monkeypatch.setattr(points, "HOST_POINTS", 0)
    # one call a grid (no timing repeats: the counts are those of every call)
    monkeypatch.setattr(model_axes, "timeit", lambda call, **kw: call() or 1.0)
    cfg = dict(CONFIG["tiny"], model_grids=dict(two_d=(9,), five_d=12), budget=0.0)
    rows = model_axes.measure(cfg)
    md = "\n".join(report.model_grids_section(rows))
    header = next(ln for ln in md.splitlines() if ln.startswith("| grid |"))
    cols = [c.strip() for c in header.strip("|").split("|")]
    printed = {}
    for ln in md.splitlines():
        cells = [c.strip() for c in ln.strip("|").split("|")]
        if ln.startswith("| 2-D") or ln.startswith("| 5-D"):
            printed[cells[0]] = dict(zip(cols, cells))
    assert len(printed) == 2
    counted = set()
    for label, n, models in ((next(k for k in printed if k.startswith("2-D")), 9, (0.5, 0.1, 0.1)),
                             (next(k for k in printed if k.startswith("5-D")), 12, model_axes.MODELS)):  # fmt: skip
        st = spectral_points(*_by_hand(n, models), names=FLAGS, resolve=True).stats
        row = printed[label]
        assert (
            int(row["points"])
            == int(row["first pass"])
            == st["points"]
            == n * n * (1 if label.startswith("2-D") else 32)
        )
        assert int(row["tier 2"]) == st["tier2_points"]
        assert int(row["enclosures"]) == st["roots_points"]
        assert int(row["exact"]) == st["undecided_before"]
        assert int(row["left undecided"]) == st["undecided_after"] == 0
        counted |= {k for k in ("tier2_points", "roots_points") if st[k]}
    assert counted  # the later tiers received points: the comparison is not of zeros alone


def test_ratios():
    rows = [
        dict(grid="2-D a", dtype="float32", ns_per_point=10.0),
        dict(grid="5-D b", dtype="float32", ns_per_point=12.0),
        dict(grid="2-D a", dtype="float64", ns_per_point=20.0),
        dict(grid="5-D b", dtype="float64", ns_per_point=30.0),
    ]
    model_axes._ratios(rows)
    assert [r["over_2d"] for r in rows] == [1.0, 1.2, 1.0, 1.5]
    assert [r["f32_over_f64"] for r in rows] == [0.5, 0.4, "", ""]


def test_section_absent_without_rows():
    assert report.model_grids_section([]) == []
