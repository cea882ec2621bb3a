"""Tests of :mod:`atlas.dynamics.event_bounds` against closed forms and dense sampling."""

import math

import numpy as np
import pytest

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


def test_may_keep_signs_never_rejects_a_certified_lane():
    """Random segments (gaps and forces, signs, growing, oscillating and decaying modes): wherever
    :func:`no_event_certificate` holds, the cheap necessary condition holds too, and it rejects
    over a third of the lanes the certificate rejects."""
    rng = np.random.default_rng(11)
    n = 20000
    re = rng.normal(size=(n, 2)) * 0.3
    re[rng.random(n) < 0.5, 1] = -0.2  # half without a growing real mode
    im = np.abs(rng.normal(size=n))
    lam = np.stack([re[:, 0] + 1j * im, re[:, 0] - 1j * im, re[:, 1], -np.abs(re[:, 1]) - 0.1], 1)
    valid = np.ones((n, 4), dtype=bool)
    w1 = rng.normal(size=(n, 2)) + 1j * rng.normal(size=(n, 2))
    UE = np.stack([w1, w1.conj(), rng.normal(size=(n, 2)), rng.normal(size=(n, 2))], axis=2)
    UE *= rng.uniform(0.0, 0.5, (n, 1, 1))
    p = rng.normal(size=(n, 2, 3)) * np.array([2.0, 0.3, 0.1])
    k, q = rng.uniform(0.2, 2.0, (n, 2)), rng.uniform(0.0, 1.0, (n, 2)) * (rng.random((n, 1)) < 0.5)
    c0 = np.concatenate([p[:, :, 0], -k * p[:, :, 0] - q * p[:, :, 1]], axis=1)
    s = np.where(c0 < 0, -1.0, 1.0)  # the signs the functions start with, mostly
    s[rng.random((n, 4)) < 0.05] *= -1
    horizon = np.where(rng.random(n) < 0.5, np.inf, 50.0)
    with np.errstate(all="ignore"):
        cert = eb.no_event_certificate(s, p, UE, lam, valid, k, q, horizon)[0]
    may = eb.may_keep_signs(s, p, UE, lam, valid, k, q)
    assert cert.sum() > 200
    assert np.all(may[cert])
    assert (~may).sum() > 0.3 * (~cert).sum()


def test_flow_curvature_bound_holds_where_modal_terms_cancel():
    """The flow's curvature bound ``C zn exp(max(mu, 0) s)`` is above ``|f''|`` of each event
    function at ``tau + s``, ``s`` in ``[0, 4 H_S]``, with ``f''`` from ``scipy.linalg.expm`` of
    the exact simulator's matrices (``d'' = (E z)_v``, ``d''' = (E^2 z)_v``); on lanes near the
    3pi/2 axis (``b_11 <= 1e-2``, large cancelling modal terms) it is far below the modal bound
    (:func:`eb.curvature_bound`) over a short window (``H_S / 10``)."""
    from scipy.linalg import expm

    from atlas.dynamics import modal_form as mf
    from atlas.dynamics import system as SY

    rng = np.random.default_rng(5)
    n = 16
    b1 = np.where(np.arange(n) < 8, 1.5 * math.pi - 10 ** rng.uniform(-4, -2, n),
                  rng.uniform(0, 2 * math.pi, n))  # fmt: skip
    b2 = rng.uniform(0, 2 * math.pi, n)
    k, q = np.tile((2.0, 1.0), (n, 1)), np.tile((0.3, 0.3), (n, 1))
    lanes = mf.Lanes.of(b1, b2, 0.3 * math.pi, k, q)
    tables = mf.modal_tables(lanes)
    mask = np.ones(n, int)  # SF: contact 1 closed, gap 2 driven by its force
    g = rng.normal(size=(n, 4)) * 1e-2
    ix = np.arange(n)
    P, U, lam, valid, H, ok = mf.segments(lanes, tables, ix, mask, g)
    d, v, acc, p, UE = eb.evaluate(P, U, lam, np.zeros(n))
    C, zn = eb.flow_curvature_bound(p, UE, lam, acc, H, k, q)
    mu = tables.mu[mask, ix]
    modal = eb.curvature_bound(p, UE, lam, 0.1 * H, k, q)
    narrower = 0
    for r in np.flatnonzero(ok):
        E = SY.build_system(b1[r], b2[r], 0.3 * math.pi, tuple(k[r]), tuple(q[r]), (1, 1), 1.0,
                            0.1).modes[1].E  # fmt: skip
        z1 = np.concatenate([g[r], [1.0]])
        for s in np.linspace(0, 4 * H[r], 9):
            z = expm(E * s) @ z1
            d2, d3 = (E @ z)[2:4], (E @ E @ z)[2:4]
            f2 = np.concatenate([d2, -k[r] * d2 - q[r] * d3])
            bound = C[r] * zn[r] * np.exp(max(mu[r], 0.0) * s)
            assert np.all(np.abs(f2) <= bound * (1 + 1e-9)), (r, s, f2, bound)
        short = C[r] * zn[r] * np.exp(max(mu[r], 0.0) * 0.1 * H[r])
        narrower += r < 8 and np.all(short < 1e-2 * modal[r, [1, 3]].min())
    assert narrower >= 4


def _random_segments(rng, n):
    """Random segments: gaps' quadratic parts ``p`` (n, 2, 3), modal terms ``UE`` (n, 2, 4) of
    growing, oscillating and decaying modes ``lam`` (n, 4), contact models ``k``, ``q`` (n, 2)."""
    re = rng.normal(size=(n, 2)) * 0.3
    im = np.abs(rng.normal(size=n)) * 2
    lam = np.stack([re[:, 0] + 1j * im, re[:, 0] - 1j * im, re[:, 1], -np.abs(re[:, 1]) - 0.1], 1)
    w1 = rng.normal(size=(n, 2)) + 1j * rng.normal(size=(n, 2))
    UE = np.stack([w1, w1.conj(), rng.normal(size=(n, 2)), rng.normal(size=(n, 2))], axis=2)
    UE *= rng.uniform(0.0, 0.5, (n, 1, 1))
    p = rng.normal(size=(n, 2, 3)) * np.array([1.0, 0.5, 0.2])
    k, q = rng.uniform(0.2, 2.0, (n, 2)), rng.uniform(0.0, 1.0, (n, 2))
    return p, UE, lam, k, q


def _event_values(p, UE, lam, k, q, x):
    """The event functions ``(d1, d2, phi1, phi2)`` (n, 4, m) at the times ``x`` (n, m), summed
    directly from the segment."""
    xx = x[:, None, :]
    e = np.exp(lam[:, None, :, None] * xx[:, :, None, :])  # (n, 1, 4, m)
    d = p[:, :, :1] + p[:, :, 1:2] * xx + p[:, :, 2:3] * xx**2 + (UE[..., None] * e).sum(2).real
    v = (
        p[:, :, 1:2]
        + 2 * p[:, :, 2:3] * xx
        + (UE[..., None] * lam[:, None, :, None] * e).sum(2).real
    )
    return np.concatenate([d, -k[..., None] * d - q[..., None] * v], axis=1)


def test_signed_curvature_brackets_are_never_wrong_on_random_segments():
    """:func:`eb.taylor_steps` on random segments and windows: a dense sampling (and the function
    at ``sigma_hi``) finds no sign change before ``sigma_lo`` and one by ``sigma_hi``; the
    ``sigma_lo`` is over 1.5 times the modal curvature bound's (:func:`eb.safe_steps`) on some
    of the functions that bound cuts below half the window."""
    rng = np.random.default_rng(17)
    n = 2000
    p, UE, lam, k, q = _random_segments(rng, n)
    W = 10 ** rng.uniform(-2, 0.5, n)
    f0 = _event_values(p, UE, lam, k, q, np.zeros((n, 1)))[:, :, 0]
    s = np.where(f0 > 0, 1.0, -1.0)
    h = 1e-6
    fh = _event_values(p, UE, lam, k, q, np.array([[-h, h]] * n))
    fp = (fh[:, :, 1] - fh[:, :, 0]) / (2 * h)
    f2, M3 = eb.second_and_third(p, UE, lam, W, k, q)
    A, Bd = np.maximum(s * f0, 0.0), s * fp
    lo, hi = eb.taylor_steps(A, Bd, s * f2, M3, W, 1e-6 * (np.abs(f2) + M3))
    x = np.linspace(0, 1, 201)[None, :] * lo.min(axis=1)[:, None]
    before = s[..., None] * _event_values(p, UE, lam, k, q, x)
    assert np.all(before[:, :, :-1] > -1e-9), np.argwhere(before[:, :, :-1] <= -1e-9)[:3]
    rr, cc = np.nonzero(np.isfinite(hi))
    assert rr.size > 250
    at_hi = _event_values(p[rr], UE[rr], lam[rr], k[rr], q[rr], hi[rr, cc][:, None])
    assert np.all(s[rr, cc] * at_hi[np.arange(rr.size), cc, 0] <= 1e-9)
    modal_lo, _ = eb.safe_steps(A, Bd, eb.curvature_bound(p, UE, lam, W, k, q))
    cut = modal_lo < 0.5 * W[:, None]
    assert cut.sum() > 1000 and (lo[cut] > 1.5 * modal_lo[cut]).mean() > 0.05


@pytest.mark.parametrize("n", [500, pytest.param(2000, marks=pytest.mark.slow)])
def test_keeps_sign_within_is_never_wrong_on_random_segments(n):
    """:func:`eb.keeps_sign_within` on ``n`` random segments and windows up to 30 (500 in CI,
    2,000 with ``-m slow``): wherever it holds, a dense sampling of the window finds no sign
    change; it holds on many."""
    rng = np.random.default_rng(19)
    p, UE, lam, k, q = _random_segments(rng, n)
    p[:, :, 0] += np.where(rng.random((n, 2)) < 0.5, 3.0, -3.0)  # far from the contact, mostly
    W = 10 ** rng.uniform(-1, 1.5, n)
    f0 = _event_values(p, UE, lam, k, q, np.zeros((n, 1)))[:, :, 0]
    s = np.where(f0 > 0, 1.0, -1.0)
    ok = eb.keeps_sign_within(s, p, UE, lam, k, q, W)
    assert 0.1 < ok.mean() < 0.9
    rr, cc = np.nonzero(ok)
    x = np.linspace(0, 1, 1001)[None, :] * W[rr][:, None]
    vals = (
        s[rr, cc][:, None]
        * _event_values(p[rr], UE[rr], lam[rr], k[rr], q[rr], x)[np.arange(rr.size), cc]
    )
    assert np.all(vals > 0)
