"""Tests of :mod:`atlas.dynamics.event_bounds` against closed forms and dense sampling."""

import math

import numpy as np

from atlas.dynamics import event_bounds as eb


def _sampled(c, w, lam, s):
    return c[0] + c[1] * s + c[2] * s**2 + (w[None, :] * np.exp(np.outer(s, lam))).sum(1).real


def test_keeps_sign_closed_forms():
    lam = np.array([-0.1 + 1j, -0.1 - 1j, 0, 0])
    valid = np.array([True, True, False, False])
    inf = np.array(np.inf)
    # 1 - 0.9 cos(t) e^{-t/10} > 0; 0.5 - cos(t) e^{-t/10} is not
    assert eb.keeps_sign(np.array([1.0, 0, 0]), np.array([0.45, 0.45, 0, 0]), lam, valid, inf)[0]
    assert not eb.keeps_sign(np.array([0.5, 0, 0]), np.array([0.5, 0.5, 0, 0]), lam, valid,
                             inf)[0]  # fmt: skip
    # 1 - t + t^2 / 2 > 0 (no real root); 1 - 2 t + t^2 / 2 has roots 2 -+ sqrt(2)
    z = np.zeros(4, dtype=complex)
    assert eb.keeps_sign(np.array([1.0, -1, 0.5]), z, lam, valid, inf)[0]
    assert not eb.keeps_sign(np.array([1.0, -2, 0.5]), z, lam, valid, inf)[0]
    # growing: e^{t} - 0.5 e^{-t} - 0.2 > 0 for t >= 0; -e^{t} + 2 is not
    lam2 = np.array([1.0, -1.0, 0, 0], dtype=complex)
    v2 = np.array([True, True, False, False])
    assert eb.keeps_sign(np.array([-0.2, 0, 0]), np.array([1.0, -0.5, 0, 0]), lam2, v2, inf)[0]
    assert not eb.keeps_sign(np.array([2.0, 0, 0]), np.array([-1.0, 0, 0, 0]), lam2, v2, inf)[0]


def test_keeps_sign_is_never_wrong_on_random_functions():
    """Wherever the certificate holds, a dense sampling over [0, 60] finds no sign change."""
    rng = np.random.default_rng(7)
    n_ok = 0
    s = np.linspace(0, 60, 6001)
    for _ in range(3000):
        re = rng.normal(size=2) * 0.3
        im = np.abs(rng.normal(size=2))
        lam = np.array([re[0] + 1j * im[0], re[0] - 1j * im[0], re[1], -abs(re[1]) - 0.1])
        w1 = rng.normal() + 1j * rng.normal()
        w = np.array([w1, np.conj(w1), rng.normal(), rng.normal()])
        c = np.array([rng.normal() + 2, rng.normal(), rng.normal() * 0.1])
        valid = np.ones(4, dtype=bool)
        ok = eb.keeps_sign(c, w, lam, valid, np.array(60.0))[0]
        if ok:
            n_ok += 1
            assert _sampled(c, w, lam, s).min() > 0
    assert n_ok > 50


def test_safe_steps_bracket_the_first_crossing():
    """No sign change before sigma_lo, one by sigma_hi (f = cos(t) - 0.3 from several points)."""
    for t0 in np.linspace(0.0, 1.2, 13):
        A = np.cos(t0) - 0.3
        lo, hi = eb.safe_steps(np.array(A), np.array(-np.sin(t0)), np.array(1.0))
        root = math.acos(0.3) - t0
        assert lo <= root * (1 + 1e-12)
        assert hi >= root * (1 - 1e-12)
