"""The step window shared by both event-to-event engines (atlas.dynamics.step_windows) against
dense sampling of closed-form segments; the limit brackets against the stop rule's own."""

import numpy as np
from samples import limit_bracket_inputs

from atlas.dynamics import step_windows as sw
from atlas.dynamics import stop_rule as SR


def test_window_keeps_growth_and_gaps_within_their_bounds():
    """Segments d(t) = p0 + p1 t + p2 t^2 + Re sum u exp(lam t) with a growing real mode, an
    oscillation and a decaying mode: over the window every term grows by at most GROWTH (the
    factor the curvature bound takes) and, where the window is called small (no sampling inside a
    step), densely sampled gaps stay within SMALL scale (closed form)."""
    rng = np.random.default_rng(3)
    n = 64
    lam = np.tile(np.array([0.4, -0.2, 0.9j, -0.9j]), (n, 1))
    lam[:, 0] *= rng.uniform(0.0, 1.5, n)  # some with a negligible growth rate
    valid = np.ones((n, 4), dtype=bool)
    U = (rng.normal(size=(n, 2, 4)) * rng.uniform(0.0, 1.0, (n, 1, 1))).astype(complex)
    U[:, :, 3] = U[:, :, 2].conj()
    p = rng.normal(size=(n, 2, 3)) * np.array([1.0, 0.3, 0.05])
    H, scale = np.full(n, 0.8), np.full(n, 0.5)
    for windows in (sw.WINDOWS, sw.LONG):
        w, small = sw.window(H, lam, valid, p, np.abs(U), scale, windows)
        assert np.all((w >= H) & (w <= windows * H))
        assert np.all(np.exp(lam.real.max(axis=1) * w) <= sw.GROWTH * (1 + 1e-12))
        assert 0 < (small & (w > H)).sum() < n  # both cases occur
        s = np.linspace(0.0, 1.0, 2001)[None, :] * w[:, None]  # (n, m)
        d = (p[:, :, :1] + p[:, :, 1:2] * s[:, None] + p[:, :, 2:] * s[:, None] ** 2
             + (U[:, :, :, None] * np.exp(lam[:, None, :, None] * s[:, None, None])).sum(2).real)  # fmt: skip
        assert np.all(np.abs(d[small]).max(axis=(1, 2)) <= sw.SMALL * scale[small])


def test_limit_steps_are_the_stop_rules_on_the_rows_near_a_limit():
    """The engine's row-restricted limit brackets equal :func:`stop_rule.limit_steps` on every
    row (``inf`` where no gap can reach a limit within the window), with both cases present."""
    d, v, M, scale, H = limit_bracket_inputs()
    n = d.shape[0]
    got = sw.limit_steps(d, v, M, scale, H)
    want = SR.limit_steps(d, v, M, scale, H)
    assert np.isfinite(got[0]).sum() > n // 2 and (~np.isfinite(got[0])).sum() > 0
    for a, b in zip(got, want, strict=True):
        np.testing.assert_array_equal(a, b)
