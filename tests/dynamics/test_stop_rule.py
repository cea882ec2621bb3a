"""The stop rule shared by both engines (atlas.dynamics.stop_rule): the limits, the located first
time on closed forms."""

import math

import numpy as np
from samples import count_eig

from atlas.dynamics import stop_rule as SR


def _free(n):
    """Inputs of ``stopped`` for ``n`` states in FF (no active contact: no alignment test)."""
    return np.zeros(n, dtype=int), np.zeros((n, 5, 5)), np.full((n, 5), np.nan)


def test_limits_of_the_rule():
    """Gap above 1e4 scale, any gap below -1e6 scale, or a NaN stops a run; inside, nothing."""
    mask, E, zq = _free(5)
    g = np.array([[1e4 - 1, 0, 0, 0], [1e4 + 1, 0, 0, 0], [0, -1e6 + 1, 0, 0],
                  [0, -1e6 - 1, 0, 0], [np.nan, 0, 0, 0]])  # fmt: skip
    amp, pen = SR.limits(np.ones(5))
    assert SR.stopped(g, mask, E, zq, amp, pen).tolist() == [False, True, False, True, True]


def test_locate_finds_the_first_crossing_of_the_amplitude_limit():
    """d(t) = exp(t) passes 1e4 at ln(1e4), and d(t) = 2e4 sin(t) at asin(1/2), whatever the
    start of the interval (the located time at most 2 xtol above the closed form)."""
    mask, E, zq = _free(3)
    amp, pen = SR.limits(np.ones(3))

    def state_at(tau, rows):
        d = np.where(rows == 0, np.exp(tau), 2e4 * np.sin(tau))
        return np.stack([d, 0 * d, 0 * d, 0 * d], axis=1)

    def holds(g, rows):
        return SR.stopped(g, mask[rows], E[rows], zq[rows], amp[rows], pen[rows])

    a = np.array([0.0, 0.0, 0.3])
    b = np.array([20.0, 2.5, 2.0])
    tau, g = SR.locate(state_at, holds, a, b, 1e-12)
    exact = [math.log(1e4), math.asin(0.5), math.asin(0.5)]
    assert np.all(tau >= exact) and np.all(tau <= np.array(exact) + 2e-12)
    assert np.all(g[:, 0] > 1e4)


def test_within_rounding_flags_a_verdict_that_hangs_on_a_rounding_digit():
    """SF of beta1 = 0.6 pi (``d1'' = |b11| d1 + const``, eigenvalues ``+-sqrt(|b11|)``): a state
    1e20 along the growing eigenvector is IWC with gap 2 open and opening; with gap 2 at 47 (a
    digit of 1e-18 of the state) the verdict flips with its sign: flagged.  Gap 2 at 1e15 (1e-5),
    a state off the eigenvector (not IWC whatever the sign) and FF are not."""
    from atlas.dynamics import system as SY

    sysm = SY.build_system(0.6 * math.pi, 0.25 * math.pi, 0.3 * math.pi, (1.0, 1.0), (0.0, 0.0),
                           (1.0, 1.0), 1.0, 0.5)  # fmt: skip
    mode = sysm.modes[1]
    lam = math.sqrt(-math.cos(0.6 * math.pi))
    X = 1e20
    base = [mode.z_eq[0] - X, 47.0, -lam * X, 1e3]
    g = np.array([base, [base[0], 1e15, base[2], 1e15], [base[0], 47.0, lam * X, 1e3], base])
    mask = np.array([1, 1, 1, 0])
    E, zq = np.broadcast_to(mode.E, (4, 5, 5)), np.broadcast_to(mode.z_eq, (4, 5))
    assert SY.iwc_aligned(sysm, 1, g[0], 1e-2) and SY.iwc_aligned(sysm, 1, g[1], 1e-2)
    assert not SY.iwc_aligned(sysm, 1, g[2], 1e-2)
    assert SR.within_rounding(g, mask, E, zq).tolist() == [True, False, False, False]


def test_a_verdict_within_rounding_goes_to_the_exact_simulator():
    """beta1 = pi, beta2 = 0 (``det B = -1.2e-16``: an SS 'equilibrium' at 7e16): both engines
    stop at t = 41.09 with d1 = -7.1e20, the free gap at 47 (fast) or -3e-4 (exact), rounding
    residues of the state; the fast engine said IWC, the exact simulator undetermined.  The lane
    is sent to the exact simulator and flagged (``within_rounding``)."""
    from atlas.dynamics import fast_engine as F
    from atlas.dynamics.outcome import simulate_outcome

    g0 = np.array([[-6.643684176097953e16, -7286426781335026.0, -689019560184056.4,
                    177319680430470.12]])  # fmt: skip
    args = (math.pi, 0.0, 0.9424777960769379)
    out, run = simulate_outcome(*args, k=(0.1, 1.0), q=(0.05, 0.05), g0=g0[0])
    res = F.run_batch(*args, (0.1, 1.0), (0.05, 0.05), g0,
                      reference=lambda *a, **kw: simulate_outcome(*a, **kw))  # fmt: skip
    assert int(res.code[0]) == int(out)
    assert F.DECIDED_BY[res.decided_by[0]] == "fallback"
    assert res.within_rounding[0] and SR.run_within_rounding(run)


def test_within_rounding_solves_each_states_eigenproblem_once(monkeypatch):
    """The rounding test of a divergence (lane 183 of the random comparison, seed 46: a gap at
    -3e-16 beside one at -4.5e5 in the exact simulator's run) tries the 16 signs of the small
    components on one eigen-decomposition of the configuration (LAPACK ``geev`` once, not 17
    times), with the verdict of the tests one by one: flagged."""
    from atlas import dynamics as S
    from atlas.dynamics import engine_check as C

    L = C.random_lanes(46, 2000)
    i = 183
    _, run = S.simulate_outcome(L.beta1[i], L.beta2[i], L.alpha[i], k=(L.kappa[i], 1.0),
                                q=(L.q[i], L.q[i]), g0=L.g0[i], max_events=2000)  # fmt: skip
    seen = count_eig(monkeypatch)
    assert SR.run_within_rounding(run)
    assert seen[0] == 1
