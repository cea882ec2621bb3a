"""Tier 2's second program (:func:`atlas.core.rootfree._tier2_dominance`, the shifted root
counts) runs only on a batch with a point left to it; the verdicts are those of both programs
either way (the reference: program 2 called on every batch)."""

import numpy as np
import pytest

from atlas.core import contact_modes, rootfree

N = 256  # the later tiers' batch (atlas.core.points.LATER_BATCH): no new compilation


def _batches(model, seed=3):
    """A batch of random directions for ``model``, and the same batch with its dominance points
    (program 1's flag) replaced by its first other point."""
    b1, b2 = np.random.default_rng(seed).uniform(0, 2 * np.pi, (2, N))
    args = (*contact_modes.direction(b1), *contact_modes.direction(b2))
    args = (*args, *(np.full(N, v) for v in model))
    dominance = np.asarray(rootfree._tier2_decide(*args, ss=True, ii=True, iters=24)[3])
    keep = np.flatnonzero(~dominance)
    idx = np.where(dominance, keep[0], np.arange(N))
    return [args, tuple(a[idx] for a in args)]


@pytest.mark.parametrize("model", [(2.0, 0.1, 0.1), (7.3, 0.8, 0.02), (0.5, 0.0, 0.0),
                                   (2.0, 0.0, 5e-324)])  # fmt: skip
def test_program_2_runs_only_for_dominance(monkeypatch, model):
    real, calls = rootfree._tier2_dominance, []
    for args in _batches(model):
        decided = rootfree._tier2_decide(*args, ss=True, ii=True, iters=24)
        want = real(*args, *decided[1:])
        calls.clear()
        monkeypatch.setattr(rootfree, "_tier2_dominance", lambda *a: calls.append(1) or real(*a))
        got = rootfree.tier2(*args)
        monkeypatch.undo()
        assert len(calls) == int(np.asarray(decided[3]).any())
        assert np.array_equal(np.asarray(got[0]), np.asarray(decided[0]))
        for g, w in zip(got[1:], want):
            g, w = np.asarray(g), np.asarray(w)
            assert g.dtype == w.dtype == np.int8 and np.array_equal(g, w)
    if min(model[1:]) > 0:  # the random batch has a dominance point: program 2 is exercised
        assert np.asarray(
            rootfree._tier2_decide(*_batches(model)[0], ss=True, ii=True, iters=24)[3]
        ).any()
