"""Timing a slider move (:func:`atlas.explore.measure_redraw`)."""

from __future__ import annotations

from atlas.explore import maps, redraw


def test_measure_redraw(bounded_det_b):
    rows = redraw.measure_redraw(
        n=16, cases=((0.3, 0.3),), layers=("stable_SS",), repeats=2, max_resolve=3
    )
    (r,) = rows
    assert r["n"] == 16 and r["layer"] == "stable_SS" and (r["q1"], r["q2"]) == (0.3, 0.3)
    assert r["total_ms"] >= r["compute_ms"] > 0
    want = maps.compute_map(r["kappa"], 0.3, n=16, layers=("stable_SS",), resolve=False)
    assert r["n_undecided_fast"] == want.attrs["n_undecided_fast"] > 3
    assert r["n_undecided"] == r["n_undecided_fast"] - 3
    assert "stable_SS" in redraw.format_redraw(rows)
