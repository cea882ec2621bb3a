"""``atlas.bench.model_box_map``: the Fig. 1 plane over every contact model, its row and section."""

import numpy as np

from atlas.bench import config, model_box_map, report


def _closed_form_shares(n: int) -> dict:
    """SS over the whole model space in closed form (``atlas.core.model_box``'s docstring, checked
    there against dense samples): unstable iff ``D < 0`` or ``c1, s2 <= 0``; stable iff ``D >= 0``,
    ``c1, s2 > 0``, ``s1 c2 >= 0``; depends otherwise."""
    b = (np.arange(n) + 0.5) * (2 * np.pi / n)
    c1, s1 = np.cos(b)[:, None], np.sin(b)[:, None]
    c2, s2 = np.cos(b)[None, :], np.sin(b)[None, :]
    d = c1 * s2 - s1 * c2
    unstable = (d < 0) | ((c1 <= 0) & (s2 <= 0))
    stable = ~unstable & (c1 > 0) & (s2 > 0) & (s1 * c2 >= 0)
    return dict(
        stable=stable.mean(), unstable=unstable.mean(), depends=1 - (stable | unstable).mean()
    )


def test_tiny_row_and_section():
    cfg = config.CONFIG["tiny"]
    rows = model_box_map.measure(cfg)
    assert [r["field"] for r in rows] == list(cfg["model_box_map"]["fields"]) == ["SS"]
    (row,) = rows
    n = cfg["model_box_map"]["n"]
    assert row["points"] == n * n and row["undecided_after"] == row["undecided"] == 0
    for k, v in _closed_form_shares(n).items():
        assert abs(row[k] - v) < 0.5 / (n * n), k
    assert row["ns_per_point"] > 0 and row["one_model_ns_per_point"] > 0
    text = "\n".join(model_box_map.section(rows))
    assert "Model-dependence map" in text and "| SS | 64 |" in text
    assert model_box_map.section([]) == []


def test_every_run_measures_the_map_and_the_report_prints_it(results):
    sizes = [cfg["model_box_map"]["n"] for cfg in config.CONFIG.values()]
    sizes = [m for n in sizes for m in (n.values() if isinstance(n, dict) else [n])]
    assert all(n % 4 == 0 for n in sizes)  # no cell on a class line
    assert config.CONFIG["full"]["model_box_map"]["fields"] == ("SS", "II")
    results.model_box_map = [dict(field="II", points=16, seconds=1.0, undecided_after=3)]
    assert "| II | 16 |" in report.build_report(results)
