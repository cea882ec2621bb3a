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


def _growing_segments(n, seed, osc):
    """Segments with a growing real mode, a decaying one and an oscillation (growing where
    ``osc > 0``): ``p`` (n, 2, 3), ``U`` (n, 2, 4), ``lam`` (n, 4)."""
    rng = np.random.default_rng(seed)
    lam = np.tile(np.array([1.0, -0.3, osc + 0.9j, osc - 0.9j]), (n, 1))
    lam[:, 0] *= rng.uniform(0.3, 1.5, n)
    U = rng.normal(size=(n, 2, 4)) * np.array([1e-3, 0.3, 0.05, 0.05])
    U = U.astype(complex)
    U[:, :, 2] += 1j * rng.normal(size=(n, 2)) * 0.05
    U[:, :, 3] = U[:, :, 2].conj()
    p = rng.normal(size=(n, 2, 3)) * np.array([1.0, 0.1, 0.01])
    return p, U, lam


def _dense(p, U, lam, S, m=4001):
    """Gaps (n, 2, m) and forces of unit stiffness and damping 0.1 on ``[0, S]`` (closed form)."""
    s = np.linspace(0.0, 1.0, m)[None, :] * S[:, None]
    e = np.exp(lam[:, None, :, None] * s[:, None, None])
    d = (p[:, :, :1] + p[:, :, 1:2] * s[:, None] + p[:, :, 2:] * s[:, None] ** 2
         + (U[:, :, :, None] * e).sum(2).real)  # fmt: skip
    v = p[:, :, 1:2] + 2 * p[:, :, 2:] * s[:, None] + (U[:, :, :, None] * lam[:, None, :, None]
                                                      * e).sum(2).real  # fmt: skip
    return d, -d - 0.1 * v


def test_limit_reach_is_a_lower_bound_of_the_first_limit_passed():
    """No densely sampled gap passes the amplitude or the deep-penetration limit before
    :func:`sw.limit_reach`; the limit is passed within 5 % of that time after it on most rows
    (the bound follows the growing real term where the oscillation decays), and ``rest`` is
    returned where none is reached."""
    n = 200
    p, U, lam = _growing_segments(n, 5, -0.05)
    scale, rest = np.full(n, 1e-3), np.full(n, 30.0)
    reach = sw.limit_reach(p, U, lam, scale, rest)
    amp, pen = SR.limits(scale)
    d, _ = _dense(p, U, lam, reach)
    assert np.all((d <= amp[:, None, None]) & (d >= -SR.DEEP * pen[:, None, None]))
    d, _ = _dense(p, U, lam, 1.05 * reach)
    passed = ((d > amp[:, None, None]) | (d < -SR.DEEP * pen[:, None, None])).any(axis=(1, 2))
    assert passed[reach < rest].mean() > 0.9 and (reach < rest).mean() > 0.5
    assert np.all(reach <= rest)
    far = sw.limit_reach(p, U, lam, np.full(n, 1e6), np.full(n, 10.0))  # limits 1e10, 1e12
    np.testing.assert_allclose(far, 10.0, rtol=1e-9)


def test_no_event_within_is_kept_by_every_monitored_function():
    """Where :func:`sw.no_event_within` certifies a horizon, every densely sampled gap and
    closed contact's force keeps its recorded sign over it; both answers occur."""
    n = 200
    p, U, lam = _growing_segments(n, 6, 0.2)
    k, q = np.ones((n, 2)), np.full((n, 2), 0.1)
    S = np.random.default_rng(7).uniform(0.5, 12.0, n)
    d, f = _dense(p, U, lam, S)
    s = np.where(np.concatenate([d[:, :, 0], f[:, :, 0]], axis=1) > 0, 1.0, -1.0)
    ok = sw.no_event_within(s, p, U, lam, np.ones((n, 4), dtype=bool), k, q, S)
    assert 0 < ok.sum() < n
    kept = (np.sign(d) == s[:, :2, None]).all(axis=2)
    kept_f = (np.sign(f) == s[:, 2:, None]).all(axis=2) | (s[:, :2] > 0)
    assert np.all((kept & kept_f).all(axis=1)[ok])
