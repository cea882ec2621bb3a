"""The tiered driver (atlas.core.points): broadcasting, gathers, slabs, settlement, diagnostics."""

import numpy as np
import pytest

from atlas.core import exact
from atlas.core import points as evaluate
from atlas.core.mechanics import direction

FLAGS = ("stable_SS", "consistent_II", "stable_II")


def grid(n=12, dtype=np.float64):
    """A beta grid through the axis lines x kappa x (q1, q2) with zeros, as broadcastable axes."""
    g = np.arange(n) * (2 * np.pi / n)
    c, s = direction(g.astype(dtype), dtype)
    return (
        c[:, None, None, None, None],
        s[:, None, None, None, None],
        c[None, :, None, None, None],
        s[None, :, None, None, None],
        np.array([0.5, 2.0])[:, None, None],
        np.array([0.0, 0.1, 0.3])[:, None],
        np.array([0.0, 0.2]),
    )


def test_broadcast_equals_flat_points():
    """The grid path (per-axis inputs, gathers by index) equals the same points given flat."""
    args = grid()
    st = {}
    res = evaluate.spectral_points(*args, names=FLAGS + ("spectral_abscissa",), stats=st)
    shape = np.broadcast_shapes(*(a.shape for a in args))
    flat = [np.broadcast_to(a, shape).ravel() for a in args]
    ref = evaluate.spectral_points(*flat, names=FLAGS + ("spectral_abscissa",))
    for k in FLAGS:
        assert res[k].shape == shape
        assert np.array_equal(res[k].ravel(), ref[k]), k
    assert np.allclose(res["spectral_abscissa"].ravel(), ref["spectral_abscissa"])
    assert st["points"] == np.prod(shape) and st["undecided_after"] == 0
    assert set(st["undecided_by_name"]) == set(FLAGS)


def test_settled_points_match_exact():
    """Every verdict after settlement equals the exact tier (independent of the fast tiers)."""
    args = grid(8)
    res = evaluate.spectral_points(*args, names=FLAGS)
    shape = res["stable_SS"].shape
    pts = dict(
        zip(
            ("c1", "s1", "c2", "s2", "kappa", "q1", "q2"),
            (np.broadcast_to(a, shape).ravel().astype(np.float64) for a in args),
        )
    )
    ref = exact.resolve(pts, names=FLAGS)
    for k in FLAGS:
        assert np.array_equal(res[k].ravel(), ref[k]), k


def test_slabs_and_padding(monkeypatch):
    """Splitting a large grid into slabs (small BLOCK) and padding axes gives the same verdicts."""
    args = grid(10)
    ref = evaluate.spectral_points(*args, names=FLAGS, resolve=False)
    monkeypatch.setattr(evaluate, "BLOCK", 50)
    got = evaluate.spectral_points(*args, names=FLAGS, resolve=False)
    for k in FLAGS:
        assert np.array_equal(got[k], ref[k]), k


def test_only_what_is_asked():
    args = grid(6)
    st = {}
    res = evaluate.spectral_points(*args, names=("stable_SS",), stats=st)
    assert set(res) == {"stable_SS"}
    assert st["tier2_points"] >= 0 and st["roots_points"] == 0


def test_exact_failure_keeps_point_undecided(monkeypatch):
    def broken(points, names=()):
        raise ArithmeticError("no convergence")

    monkeypatch.setattr(exact, "resolve", broken)
    st = {}
    res = evaluate.spectral_points(*grid(8), names=FLAGS, stats=st)
    und = np.zeros(res["stable_SS"].shape, bool)
    for k in FLAGS:
        und |= res[k] == 3
    assert st["undecided_before"] > 0
    assert st["undecided_after"] == und.sum() == st["undecided_before"]
    assert len(st["exact_failures"]) == st["undecided_after"]


@pytest.mark.parametrize(
    "kw, name", [(dict(names=("nope",)), "names"), (dict(method="lu"), "method")]
)
def test_bad_options(kw, name):
    with pytest.raises(ValueError, match=f"^{name}:"):
        evaluate.spectral_points(*grid(4), **kw)


def test_eig_baseline_shapes():
    res = evaluate.spectral_points(*grid(4), names=FLAGS, method="eig")
    assert all(v.shape == (4, 4, 2, 3, 2) for v in res.values())


def test_scalar_point():
    """One point given as Python scalars (the notebook's click path)."""
    res = evaluate.spectral_points(-1.0, 0.0, 0.0, -1.0, 1.0, 0.1, 0.1, names=FLAGS)
    assert all(v.shape == () for v in res.values())
    assert res["consistent_II"] == 1 and res["stable_II"] == 0  # double root: closed form
