"""The modal form of the contact configurations (atlas.dynamics.modal_form): the condition bound
against constructed singular values, the tables of a grid against lane-by-lane tables, the
closed-form segments against the matrix exponential of the configuration."""

import math

import numpy as np
import pytest

from atlas.dynamics import modal_form as mf
from atlas.dynamics import system as SY

PI = math.pi


def _with_singular_values(rng, s):
    """Complex matrices ``U diag(s) Vh`` (m, na, na) with random unitary ``U``, ``Vh``."""
    m, na = s.shape
    z = rng.normal(size=(2, m, na, na)) + 1j * rng.normal(size=(2, m, na, na))
    U, Vh = np.linalg.qr(z[0])[0], np.linalg.qr(z[1])[0]
    return U @ (s[:, :, None] * Vh)


@pytest.mark.parametrize("na", [2, 4])
def test_cond_bound_is_above_the_condition_and_within_na_of_it(na):
    """``cond(V) = s_max / s_min`` by construction (1 to 1e12): the bound is never below it and
    at most ``na`` times it while the inverse is accurate."""
    rng = np.random.default_rng(1)
    cond = 10.0 ** rng.uniform(0, 12, 400)
    s = np.sqrt(cond)[:, None] ** rng.uniform(-1, 1, (400, na))
    s[:, 0], s[:, -1] = np.sqrt(cond), 1 / np.sqrt(cond)  # s_max / s_min = cond
    V = _with_singular_values(rng, s)
    bound = mf.cond_bound(V, np.linalg.inv(V))
    assert np.all(bound >= cond * (1 - 1e-9))  # rounding of the constructed singular values
    fine = cond < 1e8
    assert np.all(bound[fine] <= na * cond[fine] * 1.01)


def test_cond_bound_does_not_trust_a_wrong_inverse():
    """A unitary ``V`` (condition 1) with ``W = 0.3 V^-1``: ``|V|_F |W|_F = 0.6`` alone would
    pass below the condition; the residual ``W V - I`` raises the bound (or makes it infinite)."""
    rng = np.random.default_rng(2)
    for na in (2, 4):
        V = _with_singular_values(rng, np.ones((20, na)))
        bound = mf.cond_bound(V, 0.3 * np.linalg.inv(V))
        assert np.all(bound >= 1.0)
    V = np.array([[[1.0, 1.0], [1.0, 1.0]]])  # singular: no finite bound
    assert mf.cond_bound(V + 0j, np.zeros((1, 2, 2), complex))[0] == np.inf


def test_grid_tables_equal_lane_by_lane_tables():
    """Tables of a grid with repeated lanes (each distinct subsystem solved once) are bitwise
    those of every lane solved alone, degenerate directions (not ``ok``) included."""
    b = np.linspace(0, 2 * PI, 8, endpoint=False)
    b1, b2 = np.repeat(b, 8), np.tile(b, 8)
    b1, b2 = np.concatenate([b1, b1[:5]]), np.concatenate([b2, b2[:5]])  # repeated lanes
    k, q, alpha = (0.5, 1.0), (0.3, 0.0), 0.35 * PI
    grid = mf.modal_tables(mf.Lanes.of(b1, b2, alpha, k, q))
    assert not grid[3].ok.all()  # beta2 = beta1 + pi is on the grid
    for r in range(b1.size):
        alone = mf.modal_tables(mf.Lanes.of(b1[r], b2[r], alpha, k, q))
        for tab, one in zip(grid, alone, strict=True):
            for name in ("lam", "valid", "V", "W", "d_eq", "H", "ok", "E"):
                x, y = getattr(tab, name)[r], getattr(one, name)[0]
                assert x.tobytes() == y.tobytes(), (r, tab.mask, name)


@pytest.mark.parametrize("q", [0.0, 0.4])
def test_segments_follow_the_matrix_exponential(q):
    """The closed-form gaps and velocities of a segment in each configuration equal ``expm(E_S
    t) (g, 1)`` of the exact simulator's matrices (paper eqs. 7, 8) at several times."""
    rng = np.random.default_rng(3)
    n = 24
    b1, b2 = rng.uniform(0, 2 * PI, n), rng.uniform(0, 2 * PI, n)
    lanes = mf.Lanes.of(b1, b2, 0.3 * PI, (0.5, 1.0), q)
    tables = mf.modal_tables(lanes)
    g = rng.normal(size=(n, 4))
    mask = np.arange(n) % 4
    P, U, lam, valid, H, ok = mf.segments(lanes, tables, np.arange(n), mask, g)
    for r in np.flatnonzero(ok):
        sysm = SY.build_system(b1[r], b2[r], 0.3 * PI, (0.5, 1.0), (q, q), (1, 1), 1.0, 0.1)
        E = sysm.modes[mask[r]].E
        for t in (0.0, 0.37, 1.9):
            z = SY.expm(E * t) @ np.concatenate([g[r], [1.0]])
            e = np.exp(lam[r] * t)
            d = P[r, :, 0] + P[r, :, 1] * t + P[r, :, 2] * t**2 + (U[r] * e).sum(axis=1).real
            v = P[r, :, 1] + 2 * P[r, :, 2] * t + (U[r] * lam[r] * e).sum(axis=1).real
            scale = 1 + np.abs(z[:4]).max()
            np.testing.assert_allclose(np.concatenate([d, v]), z[:4], atol=1e-9 * scale)
    assert ok.sum() >= n - 2


#: degenerate directions: (beta1, beta2, configuration) with b_ii = 0 exactly (beta2 = 0) or by
#: rounding (beta1 = pi / 2, beta2 = pi), det B = 0 exactly (beta1 = beta2) or by rounding
#: (beta2 = beta1 + pi)
_DEGENERATE = [(0.3 * PI, 0.0, 2), (PI / 2, 0.7 * PI, 1), (1.1 * PI, PI, 2), (1.5 * PI, -0.2 * PI, 1),
               (0.6 * PI, 0.6 * PI, 3), (0.25 * PI, 1.25 * PI, 3), (1.75 * PI, 0.75 * PI, 3)]  # fmt: skip


@pytest.mark.parametrize("q", [0.0, 0.6])
@pytest.mark.parametrize(("beta1", "beta2", "mask"), _DEGENERATE)
def test_closed_segments_follow_the_matrix_exponential(beta1, beta2, mask, q):
    """In the defective and near-defective configurations of degenerate directions (condition
    ``~1e8`` or a singular ``B_SS``: not ``ok``) the closed form (``closed``) gives the gaps and
    velocities of ``scipy.linalg.expm(E_S t) (g, 1)`` of the unperturbed matrices to 1e-11 of the
    state over ``t <= 6`` (the rounding-level entry of ``B`` set to zero changes them by
    ``~1e-16 t^2``)."""
    from scipy.linalg import expm

    k = (0.4, 1.0)
    lanes = mf.Lanes.of(beta1, beta2, 0.3 * PI, k, q)
    tables = mf.modal_tables(lanes)
    assert not tables[mask].ok[0] and tables[mask].closed[0]
    rng = np.random.default_rng(mask)
    g = rng.normal(size=(1, 4))
    P, U, lam, valid, H, ok = mf.segments(lanes, tables, np.zeros(1, int), np.array([mask]), g,
                                          closed=True)  # fmt: skip
    assert ok[0] and P.shape == (1, 2, 5)
    E = SY.build_system(beta1, beta2, 0.3 * PI, k, (q, q), (1, 1), 1.0, 0.1).modes[mask].E
    powers = np.arange(5)
    for t in (0.0, 0.37, 1.9, 6.0):
        z = expm(E * t) @ np.concatenate([g[0], [1.0]])
        e = np.exp(lam[0] * t)
        d = P[0] @ t**powers + (U[0] * e).sum(axis=1).real
        v = P[0, :, 1:] @ (powers[1:] * t ** powers[:-1]) + (U[0] * lam[0] * e).sum(axis=1).real
        np.testing.assert_allclose(np.concatenate([d, v]), z[:4], atol=1e-11 * np.abs(z).max())


def test_closed_tables_keep_the_exact_simulators_eigenvalues_and_equilibria():
    """The tables of closed configurations hold what :func:`atlas.dynamics.system.build_system`
    computes from the unperturbed ``B`` (the classification and the stop rule read them)."""
    for beta1, beta2, mask in _DEGENERATE:
        tables = mf.modal_tables(mf.Lanes.of(beta1, beta2, 0.3 * PI, (0.4, 1.0), 0.6))
        mode = SY.build_system(beta1, beta2, 0.3 * PI, (0.4, 1.0), (0.6, 0.6), (1, 1), 1.0,
                               0.1).modes[mask]  # fmt: skip
        na = mode.eig.size
        assert np.array_equal(tables.lam[mask, 0, :na], mode.eig)
        want = np.full(2, np.nan) if mode.z_eq is None else mode.z_eq[:2]
        assert np.array_equal(tables.d_eq[mask, 0], want, equal_nan=True)


@pytest.mark.parametrize("q", [0.0, 0.5])
def test_log_norm_bounds_the_weighted_flow(q):
    """``|D expm(A t) D^-1|_2 <= exp(mu t)`` (the logarithmic norm's bound, Dahlquist) for the
    flows ``A`` of every configuration of random directions and of near-defective ones (near the
    3pi/2 axis and det B = 0), with ``D = diag(1, 1, 1 / w, 1 / w)``, ``w = 1 / H_S``; the norm of
    the exponential from ``scipy.linalg.expm`` of the exact simulator's matrices."""
    from scipy.linalg import expm

    rng = np.random.default_rng(11)
    b1 = np.concatenate([rng.uniform(0, 2 * PI, 12), [1.5 * PI - 1e-2, 1.5 * PI + 1e-6, 0.4]])
    b2 = np.concatenate([rng.uniform(0, 2 * PI, 12), [0.7 * PI, 0.2 * PI, 0.4 + PI + 1e-7]])
    k = (0.3, 1.0)
    tables = mf.modal_tables(mf.Lanes.of(b1, b2, 0.3 * PI, k, q))
    n_tight = 0
    for r in range(b1.size):
        sysm = SY.build_system(b1[r], b2[r], 0.3 * PI, k, (q, q), (1, 1), 1.0, 0.1)
        for mask in range(4):
            A = sysm.modes[mask].E[:4, :4]
            w = 1.0 / tables.H[mask, r]
            D = np.diag([1.0, 1.0, 1.0 / w, 1.0 / w])
            mu = tables.mu[mask, r]
            for t in (0.1 / w, 1.0 / w, 4.0 / w):
                norm = np.linalg.norm(D @ expm(A * t) @ np.linalg.inv(D), 2)
                assert norm <= np.exp(mu * t) * (1 + 1e-12), (r, mask, t, norm, mu)
                n_tight += norm >= 0.5 * np.exp(mu * t)
    assert n_tight > 0  # not vacuous


def _counting(monkeypatch, name):
    """Count the matrices passed to ``numpy.linalg.<name>`` (a list of one int)."""
    seen = [0]
    real = getattr(np.linalg, name)

    def counted(a, *args, **kwargs):
        seen[0] += int(np.prod(np.shape(a)[:-2], dtype=int))
        return real(a, *args, **kwargs)

    monkeypatch.setattr(np.linalg, name, counted)
    return seen


def test_tables_keep_geevs_eigenvectors_for_the_alignment_test():
    """``tables.eig(m, lanes)`` is bitwise what ``numpy.linalg.eig`` gives for each lane's active
    subsystem alone (complex), also where the modal form is not ``ok`` (``det B = 0`` on the
    grid) or closed, so the IWC alignment test needs no eigen-decomposition of its own."""
    b = np.linspace(0, 2 * PI, 8, endpoint=False)
    b1, b2 = np.repeat(b, 8), np.tile(b, 8)
    tables = mf.modal_tables(mf.Lanes.of(b1, b2, 0.35 * PI, (0.5, 1.0), (0.3, 0.0)))
    assert not tables[3].ok.all() and tables.closed.any()
    for m in (1, 2, 3):
        sub = [i for i in range(2) if m >> i & 1]
        sub += [i + 2 for i in sub]
        w, V = tables.eig(m, np.arange(b1.size))
        for r in range(b1.size):
            w1, V1 = np.linalg.eig(tables.E[m, r][np.ix_(sub, sub)])
            assert w[r].tobytes() == w1.astype(complex).tobytes(), (m, r)
            assert V[r].tobytes() == V1.astype(complex).tobytes(), (m, r)


def test_log_norm_once_per_distinct_flow(monkeypatch):
    """On an ``n x n`` grid the flows of FF, SF (beta1 alone), FS (beta2 alone) and SS get one
    logarithmic norm per distinct matrix (bitwise: an inactive column of ``E`` holds ``-b_ij * 0``,
    a zero signed as ``-b_ij``, 4 sign patterns per column): at most ``n^2 + 2 (4n) + 16``
    symmetric eigenproblems, not ``4 n^2``; each lane's ``mu`` is bitwise :func:`mf.log_norm` of
    its own flow."""
    n = 12
    b = np.linspace(0.1, 2 * PI, n, endpoint=False)
    lanes = mf.Lanes.of(np.repeat(b, n), np.tile(b, n), 0.35 * PI, (0.5, 1.0), (0.2, 0.2))
    seen = _counting(monkeypatch, "eigvalsh")
    tables = mf.modal_tables(lanes)
    assert seen[0] <= n * n + 8 * n + 16 < 4 * n * n
    for m in range(4):
        alone = mf.log_norm(tables.E[m], 1.0 / tables.H[m])
        assert tables.mu[m].tobytes() == alone.tobytes()
