"""The boundary-curve section of the bench: its rows carry the slice's certified work."""

import pytest

from atlas.bench import curves
from atlas.core import brackets


@pytest.mark.slow  # ~20 s CPU alone: the kernels a slice uses are compiled (no disk cache)
def test_rows_count_the_certified_work_of_the_slice(monkeypatch):
    """Each row holds the kernel calls and the points each later tier received for its slice
    (both fields, :func:`atlas.core.points.tally`): at least the calls the brackets module made
    while the slice was computed.  (The 4n reference is the same 8 x 8 slice here: cheap.)"""
    made, call = [], brackets.spectral_points

    def counted(*args, **kw):
        made.append(1)
        return call(*args, **kw)

    monkeypatch.setattr(brackets, "spectral_points", counted)
    got = curves._slice(8, curves.CURVE_CASES[0][1:], 1e-6)
    by_brackets = len(made)
    monkeypatch.setattr(curves, "_slice", lambda n, model, chord: got)
    rows = curves.curves(dict(curve_res=(8,), curve_cases=1))
    assert [r["field"] for r in rows] == ["SS", "II"]
    for r in rows:
        assert r["kernel_calls"] >= by_brackets > 0
        assert min(r[k] for k in ("tier2_points", "roots_points", "exact_points")) >= 0
        assert r["exact_points"] + r["tier2_points"] > 0  # a boundary needs the later tiers
