"""The batched event-to-event engine (atlas.dynamics.fast_engine) against the exact simulator:
outcomes on sampled maps, the early decisions checked by continuing the trajectory with the
reference, the certificates and brackets against dense sampling, the Fig. 2 cases."""

import functools
import math

import numpy as np
import pytest
from samples import count_eig

from atlas import dynamics as S
from atlas.dynamics import fast_engine as F
from atlas.dynamics import modal_form as mf
from atlas.dynamics import stop_rule
from atlas.dynamics import substeps as SB
from atlas.dynamics import system as SY

PI = math.pi


def _reference(x1, x2, alpha, k, q, g0):
    return S.simulate_outcome(x1, x2, alpha, k=k, q=q, g0=g0, max_events=2000)


@functools.lru_cache(maxsize=4)
def _map(n, kappa, q, alpha):
    b1, b2 = S.outcome_grid(n)
    g0 = S.perturbed_initial_states(b1, b2, alpha, kappa)
    codes, res = F.outcomes(b1, b2, alpha, (kappa, 1.0), (q, q), g0, _reference)
    return b1, b2, g0, codes, res


@pytest.mark.parametrize(("n", "kappa", "q", "alpha"), [(9, 0.5, 0.0, 0.35 * PI),
                                                        (8, 2.0, 0.5, 0.2 * PI)])  # fmt: skip
def test_outcomes_match_the_exact_simulator(n, kappa, q, alpha):
    b1, b2, g0, codes, res = _map(n, kappa, q, alpha)
    ref = np.array([[int(_reference(x1, x2, alpha, (kappa, 1.0), (q, q), g0[i, j, 0])[0])
                     for j, x2 in enumerate(b2)] for i, x1 in enumerate(b1)])  # fmt: skip
    assert np.array_equal(codes[:, :, 0], ref)
    assert (res.decided_by > 0).mean() > 0.5  # most runs decided early


def test_degenerate_directions_stay_on_the_fast_path():
    """On grid directions where ``sin beta2`` or ``det B`` is a rounding residue (``beta2 = pi``,
    ``beta2 = beta1 + pi``), or exactly zero (``beta2 = 0``, ``beta1 = beta2``), the double
    eigenvalue is split by rounding or defective: the modal form is not used (condition ``~ 1e7``)
    and the closed form of the configuration is; the outcomes are the exact simulator's."""
    b = np.linspace(0, 2 * PI, 32, endpoint=False)
    cells = [(4, 16), (4, 20), (8, 0), (12, 12), (24, 0), (8, 8)]
    alpha, k, q = 0.35 * PI, (0.5, 1.0), (0.0, 0.0)
    g0 = np.array([S.perturbed_initial_states(b, b, alpha, 0.5)[c][0] for c in cells])
    b1, b2 = (b[list(c)] for c in zip(*cells, strict=True))
    tables = mf.modal_tables(mf.Lanes.of(b1, b2, alpha, k, q))
    assert not tables[2].ok[0] and tables[2].closed[0]  # FS at beta2 = pi: s2 = 1.2e-16
    assert not tables[3].ok[1] and tables[3].closed[1]  # SS at beta2 = beta1 + pi: det B ~ 1e-17
    res = F.run_batch(b1, b2, alpha, k, q, g0, reference=_reference)
    ref = [int(_reference(x1, x2, alpha, k, q, g)[0]) for x1, x2, g in zip(b1, b2, g0, strict=True)]
    assert res.code.tolist() == ref
    assert not np.any(res.decided_by == F.DECIDED_BY.index("fallback"))


def _continue(b1, b2, g0, res, kappa, q, alpha, how, t_more=400.0):
    """Runs of the exact simulator from the states where ``how`` decided (index into the
    flattened map)."""
    n2 = b2.size
    for x in np.flatnonzero(res.decided_by == F.DECIDED_BY.index(how)):
        i, j = divmod(int(x), n2)
        yield x, S.simulate(b1[i], b2[j], alpha, k=(kappa, 1.0), q=(q, q), g0=res.g_final[x],
                            t_end=t_more, max_events=100)  # fmt: skip


@pytest.mark.parametrize(("kappa", "q"), [(0.5, 0.0), (0.5, 0.5)])
def test_early_settle_is_confirmed_by_continuing_with_the_reference(kappa, q):
    """From the state where the fast engine declared ``settles_S``: no event ever, the same
    configuration, and the reference classifies the continuation as settled in it."""
    alpha = 0.35 * PI
    b1, b2, g0, codes, res = _map(10, kappa, q, alpha)
    runs = list(_continue(b1, b2, g0, res, kappa, q, alpha, "early_settle"))
    assert len(runs) >= 5
    for x, r in runs:
        assert r.n_events == 0
        assert int(S.classify(r)) == res.code[x]


def test_early_iwc_is_confirmed_by_continuing_with_the_reference():
    """From the state where the fast engine declared IWC: no event ever, the reference diverges
    with every active gap going to -inf (force to +inf) and calls it IWC."""
    kappa, q, alpha = 0.5, 0.0, 0.35 * PI
    b1, b2, g0, codes, res = _map(10, kappa, q, alpha)
    runs = list(_continue(b1, b2, g0, res, kappa, q, alpha, "early_iwc", t_more=2000.0))
    assert len(runs) >= 20
    for _, r in runs:
        assert r.n_events == 0
        assert r.status == S.Status.DIVERGED
        assert S.classify(r) == S.Outcome.IWC


@pytest.mark.parametrize("name", ["a", "b", "c", "d", "e"])
def test_fig2_cases_reproduced(name):
    """The fast engine on the Fig. 2 panels gives the reference's (and the paper's) outcome over
    the panel's horizon (atlas.paper.figures_dynamics.FIG2_T_END)."""
    from atlas.paper.figures_dynamics import FIG2_T_END

    p = S.fig2_cases()[name]
    expected = {"a": "GROWING_BOUNCING", "b": "SETTLES_SS", "c": "GROWING_BOUNCING",
                "d": "SUSTAINED_OSCILLATION", "e": "GROWING_BOUNCING"}[name]  # fmt: skip
    res = F.run_batch(p["beta1"], p["beta2"], p["alpha"], p["k"], p["q"], np.array([p["g0"]]),
                      t_end=FIG2_T_END[name], horizon_cap=1.0, max_events=100_000,
                      reference=_reference)  # fmt: skip
    assert S.Outcome(int(res.code[0])) == S.Outcome[expected]
    assert F.DECIDED_BY[res.decided_by[0]] != "fallback"


def test_locate_root_closes_a_certified_bracket_on_the_root():
    """d(t) = cos(t) - 0.3 as a segment (U = 1/2, 1/2 on lam = +-i): from brackets of several
    widths the returned upper end lies within xtol above the closed-form root acos(0.3), for the
    gap and for its force -k d - q d' (root of cos(t) - q sin(t) / k = 0.3)."""
    n = 6
    P = np.zeros((n, 2, 3))
    P[:, :, 0] = -0.3
    U = np.zeros((n, 2, 4), dtype=complex)
    U[:, :, :2] = 0.5
    lam = np.tile(np.array([1j, -1j, 0, 0]), (n, 1))
    k, q = np.full((n, 2), 2.0), np.full((n, 2), 0.5)
    root = math.acos(0.3)
    # the force -k d - q d' = -2 cos t - 0.5 (-sin t) + 0.6 = 0: 2 cos t - 0.5 sin t = 0.6
    A, phi = math.hypot(2.0, 0.5), math.atan2(0.5, 2.0)
    root_f = math.acos(0.6 / A) - phi
    a = np.array([0.0, 1.0, 1.26, 0.0, 0.5, 0.9])
    b = np.array([1.5, 1.3, 1.27, 1.4, 1.4, 1.1])
    j = np.array([0, 1, 0, 2, 3, 2])
    sj = np.array([1.0, 1.0, 1.0, -1.0, -1.0, -1.0])  # the force is negative before its root
    xtol = np.full(n, 1e-12)
    lo, got = F.locate_root(P, U, lam, np.zeros(n), a, b, j, sj, k, q, xtol)
    want = np.where(j < 2, root, root_f)
    assert np.all(got - lo <= xtol)
    assert np.all(got >= want - 1e-15)
    assert np.all(lo <= want + 1e-15)
    # cut short: a bracket of the root all the same
    lo, hi = F.locate_root(P, U, lam, np.zeros(n), a, b, j, sj, k, q, xtol, 2)
    assert np.all((lo <= want + 1e-15) & (hi >= want - 1e-15) & (lo >= a) & (hi <= b))


def test_iwc_aligned_many_on_closed_form_states():
    """SF of beta1 = 0.6 pi (b11 < 0): d1'' = |b11| d1 + const, eigenvalues +-sqrt(|b11|).
    A deviation along the growing eigenvector (1, lam) with d1 -> -inf and gap 2 open and opening
    is IWC; with a decaying component, with the deviation sent to +inf, or with gap 2 closing it
    is not; the batch (mixed with SS and FS states) gives each state's verdict."""
    sysm = SY.build_system(0.6 * PI, 0.25 * PI, 0.3 * PI, (1.0, 1.0), (0.0, 0.0), (1.0, 1.0), 1.0,
                          0.5)  # fmt: skip
    b11 = math.cos(0.6 * PI)
    lam = math.sqrt(-b11)
    d_eq = -math.cos(0.3 * PI) / b11
    on = [d_eq - 10, 1.0, -10 * lam, 0.5]
    mixed = [d_eq - 10 + 5, 1.0, -10 * lam - 5 * lam, 0.5]  # + 5 (1, -lam)
    wrong_way = [d_eq + 10, 1.0, 10 * lam, 0.5]
    closing = [d_eq - 10, 1.0, -10 * lam, -0.5]
    states = np.array([on, mixed, wrong_way, closing, on, on])
    mask = np.array([1, 1, 1, 1, 3, 2])
    E = np.stack([sysm.modes[m].E for m in mask])
    z_eq = np.stack([sysm.modes[m].z_eq for m in mask])
    got = SY.iwc_aligned_many(E, z_eq, mask, states, 1e-3)
    assert got[:4].tolist() == [True, False, False, False]
    for r in range(states.shape[0]):
        assert got[r] == SY.iwc_aligned(sysm, int(mask[r]), states[r], 1e-3)


@pytest.mark.parametrize(("n", "kappa", "q", "alpha"), [(9, 0.5, 0.0, 0.35 * PI),
                                                        (12, 2.0, 0.5, 0.2 * PI)])  # fmt: skip
def test_classify_many_matches_classify_stats(monkeypatch, n, kappa, q, alpha):
    """The array classification of the stopped runs equals classify_stats of each run's
    TrajectoryStats and System (light_system), through the horizon extensions."""
    seen = []
    lanes_of = {}
    modal, classify = F.modal_tables, F._classify_many

    def tables(lanes):
        out = modal(lanes)
        lanes_of[id(out)] = lanes
        return out

    def check(st, tabs, ix, width):
        codes = classify(st, tabs, ix, width)
        log = F._impact_log(st)
        for lane, code in zip(ix, codes, strict=True):
            sysm = mf.light_system(lanes_of[id(tabs)], tabs, lane)
            seen.append((int(code), int(S.classify_stats(F._stats(st, lane, sysm, log, width),
                                                         sysm))))  # fmt: skip
        return codes

    monkeypatch.setattr(F, "modal_tables", tables)
    monkeypatch.setattr(F, "_classify_many", check)
    b1, b2 = S.outcome_grid(n)
    g0 = S.perturbed_initial_states(b1, b2, alpha, kappa)
    F.outcomes(b1, b2, alpha, (kappa, 1.0), (q, q), g0, _reference)
    got, want = np.array(seen).T
    assert len(seen) >= 15
    assert len(set(want.tolist())) >= 3  # several classes exercised
    assert np.array_equal(got, want)


def test_twins_are_the_force_and_gap_of_an_undamped_contact():
    """phi_i = -k_i d_i - q_i d_i' is -k_i d_i exactly when q_i = 0 (the same roots): the twin of
    the first function is its partner only then, and only if monitored."""
    d, v, acc = np.array([[-0.3, 0.2]]), np.array([[0.7, -1.1]]), np.array([[2.0, 0.5]])
    f, _ = F.eb.event_functions(d, v, acc, np.array([[0.5, 1.0]]), np.array([[0.0, 0.3]]))
    assert f[0, 2] == -0.5 * d[0, 0] and f[0, 3] != -1.0 * d[0, 1]
    q = np.array([[0.0, 0.3], [0.0, 0.3], [0.0, 0.0], [0.0, 0.0]])
    mon = np.array([[1, 1, 1, 1], [1, 1, 1, 1], [1, 1, 1, 1], [1, 1, 0, 0]], dtype=bool)
    got = SB.twins(np.array([0, 3, 2, 1]), mon, q)
    want = np.zeros((4, 4), dtype=bool)
    want[0, 2] = want[2, 0] = True  # gap 1 <-> force 1 (q1 = 0); force 2 has q2 = 0.3
    assert np.array_equal(got, want)  # row 3: the force of an open gap is not monitored


def _lane(b1, b2, alpha, kappa, q, cell=None, **kw):
    """The fast engine's and the exact simulator's runs of one lane from the perturbed SS
    equilibrium of :func:`atlas.dynamics.perturbed_initial_states` (seed 0; of the cell ``(n, i,
    j)`` of ``outcome_grid(n)`` if given, where ``b1, b2`` are that cell's angles)."""
    if cell is None:
        g0 = S.perturbed_initial_states([b1], [b2], alpha, kappa)[0, 0, 0]
    else:
        n, i, j = cell
        g0 = S.perturbed_initial_states(*S.outcome_grid(n), alpha, kappa)[i, j, 0]
    fast = F.run_lanes(np.array([b1]), np.array([b2]), np.array([alpha]),
                       np.array([[kappa, 1.0]]), np.array([[q, q]]), g0[None])  # fmt: skip
    out, res = S.simulate_outcome(b1, b2, alpha, k=(kappa, 1.0), q=(q, q), g0=g0,
                                  max_events=2000, **kw)  # fmt: skip
    return fast, out, res


@pytest.mark.parametrize(("b1", "b2", "alpha", "kappa", "q", "cell", "expected"), [
    (*S.outcome_grid(32)[0][19:20], *S.outcome_grid(32)[1][4:5], 0.4 * PI, 0.02, 0.01,
     (32, 19, 4), "IWC"),
    (1.75185, 3.57682, 0.58641, 0.05946, 0.03685, None, "UNDETERMINED"),
    (0.0, 1.5 * PI, 0.3 * PI, 0.1, 0.05, None, "UNDETERMINED"),
])  # fmt: skip
def test_divergence_stop_is_located_as_in_the_exact_simulator(b1, b2, alpha, kappa, q, cell,
                                                               expected):  # fmt: skip
    """The divergence stops (aligned penetration, amplitude) located as events: both engines stop
    at the same time (to 1e-9 relative) with the same verdict, the exact simulator's verdict and
    stop unchanged at a 10 times finer sub-step (theta 0.05).  The first lane drifts without
    events into an aligned penetration (an independent solve_ivp oracle calls it IWC); the second
    passes the amplitude limit between the steps of either engine; in the third ``B`` is diagonal
    (up to the rounding of cos(1.5 pi)): contact 1 is decoupled, its gap is not driven to -inf
    along the growing eigenvector, so no IWC (early or at the stop) whatever the rounding."""
    fast, out, res = _lane(b1, b2, alpha, kappa, q, cell)
    _, out_fine, res_fine = _lane(b1, b2, alpha, kappa, q, cell, theta=0.05)
    assert out == out_fine == S.Outcome[expected]
    assert res.status == res_fine.status == S.Status.DIVERGED
    assert int(fast.code[0]) == int(out)
    assert F.DECIDED_BY[fast.decided_by[0]] == "stepped"  # its own stop, no early decision
    assert fast.t_final[0] == pytest.approx(res.t_final, rel=1e-9)
    assert res_fine.t_final == pytest.approx(res.t_final, rel=1e-9)


def test_near_defective_lane_is_sent_back_at_once():
    """beta1 = pi/2 + 1e-8 (kappa 5, q 1.5, beta2 0): the SF configuration has eigenvalues
    ``+-2.2e-4`` and an equilibrium ``~1.2e7`` whose modal amplitudes cancel to the O(1) gaps
    (evaluated with ~9 of 16 digits): the segment is flagged and the lane falls back to the exact
    simulator (it was stepped for minutes); at 1e-2 off the axis the same configuration stays on
    the fast path, and both lanes give the exact simulator's outcome (two runs each)."""
    alpha, k, q = 0.3 * PI, (5.0, 1.0), (1.5, 1.5)
    b1 = np.array([PI / 2 + 1e-8, PI / 2 + 1e-2])
    g = np.array([[1.0, 0.5, 0.0, 0.0]] * 2)  # contact 1 closed as in SF: d1 <= 0
    g[:, 0] = -0.1
    lanes = mf.Lanes.of(b1, np.zeros(2), alpha, k, q)
    tables = mf.modal_tables(lanes)
    P, U, *_ = mf.segments(lanes, tables, np.arange(2), np.array([1, 1]), g)
    assert F.cancels(P, U, g, np.ones(2)).tolist() == [True, False]
    g0 = S.perturbed_initial_states(b1, [0.0], alpha, 5.0, n_perturb=2)[:, 0].reshape(-1, 4)
    B1 = np.repeat(b1, 2)
    res = F.run_batch(B1, 0.0, alpha, k, q, g0, reference=_reference)
    ref = [int(_reference(x, 0.0, alpha, k, q, g)[0]) for x, g in zip(B1, g0, strict=True)]
    assert res.code.tolist() == ref
    fb = F.DECIDED_BY.index("fallback")
    # beta2 = 0: FS (b22 = 0, defective) in closed form; SF at 1e-8 off the axis is no rounding
    assert fb in res.decided_by[:2]
    assert res.decided_by[2] != fb and res.decided_by[3] != fb


@pytest.mark.parametrize("run", [0, 1])
def test_near_defective_lane_has_the_exact_simulators_verdict_at_a_finer_substep(run):
    """The near-defective lane (beta1 = pi/2 + 1e-8, beta2 0, kappa 5, q 1.5, alpha 0.3pi), both
    initial states: the exact simulator's verdict, stop and time (to 1e-9 relative) are the same
    at a 10 times finer sub-step (theta 0.05), and the fast engine gives that verdict."""
    alpha, k, q = 0.3 * PI, (5.0, 1.0), (1.5, 1.5)
    b1 = PI / 2 + 1e-8
    g0 = S.perturbed_initial_states([b1], [0.0], alpha, 5.0, n_perturb=2)[0, 0, run]
    out, res = S.simulate_outcome(b1, 0.0, alpha, k=k, q=q, g0=g0, max_events=2000)
    fine, res_fine = S.simulate_outcome(b1, 0.0, alpha, k=k, q=q, g0=g0, max_events=2000,
                                        theta=0.05)  # fmt: skip
    assert out == fine and res.status == res_fine.status and res.n_events == res_fine.n_events
    assert res_fine.t_final == pytest.approx(res.t_final, rel=1e-9)
    assert res_fine.n_steps > 5 * res.n_steps  # the finer sub-step was taken
    fast = F.run_batch(b1, 0.0, alpha, k, q, g0[None], reference=_reference)
    assert int(fast.code[0]) == int(out)


def test_a_fallback_lane_reports_the_exact_simulators_stop_time_state_and_events():
    """The near-defective lane above (beta1 = pi/2 + 1e-8, second initial state) falls back: its result carries the
    exact simulator's stop reason, final time, final state and event count in the fields a
    stepped lane fills (not only the verdict)."""
    alpha, k, q = 0.3 * PI, (5.0, 1.0), (1.5, 1.5)
    b1 = PI / 2 + 1e-8
    g0 = S.perturbed_initial_states([b1], [0.0], alpha, 5.0, n_perturb=2)[0, 0, 1]
    res = F.run_batch(b1, 0.0, alpha, k, q, g0[None], reference=_reference)
    assert F.DECIDED_BY[res.decided_by[0]] == "fallback"
    out, run = _reference(b1, 0.0, alpha, k, q, g0)
    assert F.STOPS[res.stop[0]] == run.status and res.code[0] == int(out)
    assert res.t_final[0] == run.t_final and res.n_events[0] == run.n_events > 0
    np.testing.assert_array_equal(res.g_final[0], run.g_final)


def test_a_stepped_lane_reports_its_stop():
    """A stepped lane's stop reason: the horizon (``t_end``) of the sustained oscillation of the
    paper's Fig. 2 map, where the exact simulator stops the same way."""
    alpha, kappa = 0.35 * PI, 0.5
    b1, b2 = S.outcome_grid(64)
    g0 = S.perturbed_initial_states(b1, b2, alpha, kappa)[2, 30, 0]
    res = F.run_batch(b1[2], b2[30], alpha, (kappa, 1.0), (0.0, 0.0), g0[None],
                      reference=_reference)  # fmt: skip
    _, run = _reference(b1[2], b2[30], alpha, (kappa, 1.0), (0.0, 0.0), g0)
    assert F.DECIDED_BY[res.decided_by[0]] == "stepped"
    assert F.STOPS[res.stop[0]] == run.status


def test_a_gap_landing_on_the_amplitude_limit_steps_on():
    """A growing bouncing run of the Fig. 2 map (64^2 cell (2, 30)) reaches a state with a gap
    exactly at the amplitude limit (not past it: no stop); the engine steps past it instead of
    stalling there and handing the lane to the exact simulator, and gives its outcome."""
    alpha, kappa = 0.35 * PI, 0.5
    b1, b2 = S.outcome_grid(64)
    g0 = S.perturbed_initial_states(b1, b2, alpha, kappa)[2, 30, 0]
    res = F.run_batch(b1[2], b2[30], alpha, (kappa, 1.0), (0.0, 0.0), g0[None],
                      reference=_reference)  # fmt: skip
    assert F.DECIDED_BY[res.decided_by[0]] == "stepped"
    assert int(res.code[0]) == int(_reference(b1[2], b2[30], alpha, (kappa, 1.0), (0.0, 0.0),
                                              g0)[0]) == int(S.Outcome.GROWING_BOUNCING)  # fmt: skip


def test_no_lane_takes_more_than_ten_times_the_median_steps():
    """An 8 x 8 grid of the 0:2pi:8 directions (kappa 0.1, q 1.5, alpha 0.3pi) holds a long lane
    without events: at beta1 = 3pi/2, beta2 = pi/2 (det B = 0, a closed form) both gaps sink
    quadratically after one event until the horizon is doubled to 1200.  Event-free stretches
    are crossed in steps of up to LONG H_S (sampled H_S apart), so its steps, and every lane's,
    stay within 10 times the median lane's (counted, not timed); its outcome is the exact
    simulator's."""
    b = np.arange(8) * (PI / 4)
    B1, B2 = (x.ravel() for x in np.meshgrid(b, b, indexing="ij"))
    alpha, k, q = 0.3 * PI, (0.1, 1.0), (1.5, 1.5)
    g0 = S.perturbed_initial_states(b, b, alpha, 0.1)[:, :, 0].reshape(-1, 4)
    res = F.run_lanes(B1, B2, np.full(64, alpha), np.tile(k, (64, 1)), np.tile(q, (64, 1)), g0)
    long_ = 6 * 8 + 2
    assert (B1[long_], B2[long_]) == (b[6], b[2])
    assert res.t_final[long_] == 1200.0 and res.n_events[long_] <= 2
    assert res.steps.max() <= 10 * np.median(res.steps)
    assert int(res.code[long_]) == int(_reference(b[6], b[2], alpha, k, q, g0[long_])[0])


def test_an_oscillation_far_from_its_contacts_is_crossed_in_few_steps_per_event():
    """Lane (1, 21) of the 64 x 64 bench map (kappa 0.5, q 0, alpha 0.35pi): a sustained
    oscillation with about 100 impacts, run to t = 1200.  Between its events the gaps swing far
    from zero, so the curvature bound's sigma_lo cuts a step to 1-2 H_S of its 8 H_S window;
    up to 8 further certified safe steps under the same bound cross the window in one step, and
    a crossing certified where they stop is located in the same step: at most 1.9 steps per
    event (2.4 when it took the next step, 3.5 with a 4 H_S window and 4 safe steps, 8.2
    without).  Its outcome is the exact simulator's."""
    alpha, k, q = 0.35 * PI, (0.5, 1.0), (0.0, 0.0)
    b1, b2 = S.outcome_grid(64)
    g0 = S.perturbed_initial_states(b1, b2, alpha, 0.5)[1, 21, 0]
    res = F.run_lanes(b1[1:2], b2[21:22], np.full(1, alpha), np.array([k]), np.array([q]),
                      g0[None])  # fmt: skip
    assert res.t_final[0] == 1200.0 and res.n_events[0] >= 100
    assert res.steps[0] <= 1.9 * res.n_events[0]
    out, ref = _reference(b1[1], b2[21], alpha, k, q, g0)
    assert int(res.code[0]) == int(out) == int(S.Outcome.SUSTAINED_OSCILLATION)
    assert res.n_events[0] == ref.n_events


def test_a_step_with_an_event_after_its_safe_substeps_samples_the_amplitude_as_two_steps():
    """Cell (5, 99) of the paper's 256^2 outcome map (kappa 0.5, q 0, alpha 0.35pi): the late
    amplitude of gap 1 (26.83 in the exact simulator's samples) is 1.4 % above the growing-
    bouncing threshold 10 scale (26.46).  A step whose safe sub-steps end before a crossing
    located in the same step is sampled before and after their end, as the two steps it
    replaces, and keeps the exact simulator's verdict (sampled as one step: sustained
    oscillation)."""
    alpha, kappa = 0.35 * PI, 0.5
    b1, b2 = S.outcome_grid(256)
    g0 = S.perturbed_initial_states(b1, b2, alpha, kappa)[5, 99, 0]
    res = F.run_lanes(b1[5:6], b2[99:100], np.full(1, alpha), np.array([[kappa, 1.0]]),
                      np.zeros((1, 2)), g0[None])  # fmt: skip
    out, _ = _reference(b1[5], b2[99], alpha, (kappa, 1.0), (0.0, 0.0), g0)
    assert int(res.code[0]) == int(out) == int(S.Outcome.GROWING_BOUNCING)


@pytest.fixture(scope="module")
def random_46():
    """The 1,000 lanes of the random comparison (seed 46) by the fast engine, counting the
    segments it builds (one run shared by the tests of these lanes): ``(res, segments built)``."""
    from atlas.dynamics import engine_check as C

    built = [0]
    real = F.segments

    def counted(lanes, tables, ix, mask, g, closed=False):
        built[0] += ix.size
        return real(lanes, tables, ix, mask, g, closed=closed)

    L = C.random_lanes(46, 1000)
    k = np.stack([L.kappa, np.ones_like(L.kappa)], axis=1)
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(F, "segments", counted)
        res = F.run_lanes(L.beta1, L.beta2, L.alpha, k, np.stack([L.q, L.q], axis=1), L.g0)
    return res, built[0]


def test_an_event_that_keeps_the_configuration_keeps_its_segment(random_46):
    """The lanes of the random comparison (seed 46): about a third of their events (a force
    changing sign beside an open gap, a gap crossing with its force) leave the contact
    configuration as it was, and the same closed form goes on: fewer segments are built (at the
    lanes' starts and at configuration changes, counted per lane) than the lanes have events
    (3,779 segments for 4,421 events; on the first 300, 1,504 for 1,326 when every event started
    one)."""
    res, built = random_46
    assert built < res.n_events.sum()


def test_lanes_over_ten_times_the_median_are_event_heavy_at_under_two_steps_per_event(random_46):
    """The 1,000 lanes of the random comparison (seed 46), counted (not timed): a lane over 10
    times the median lane's steps has at least 40 events, each costing a step or two (under 1.8
    steps per event).  Before the sub-steps passed crossings certified beyond their window,
    took a crossing their last step landed on, and overlapping brackets were closed together,
    13 lanes were over: one without events (106 steps), one at 4 steps per event (26 events),
    the others up to 2.25."""
    res, _ = random_46
    over = res.steps > 10 * np.median(res.steps)
    assert np.all(res.n_events[over] >= 40)
    assert np.all(res.steps[over] < 1.8 * res.n_events[over])


def test_free_flight_entered_leaving_settles_before_a_later_amplitude_stop():
    """A lane of the random comparison (seed 45, lane 1652: beta1 = pi/2, beta2 = 3pi/2, det B =
    0, its perturbed SS equilibrium ~1e16) enters free flight at t = 237.6 with both gaps opening
    and accelerating away: the exact simulator stops there as settled (settles_FF) at its next
    sub-step; the fast engine, stepping on, used to reach the amplitude limit first (t = 277.6,
    undetermined)."""
    from atlas.dynamics import engine_check as C

    lanes = C.random_lanes(45, 2000)
    i = 1652
    k, q = (lanes.kappa[i], 1.0), (lanes.q[i], lanes.q[i])
    res = F.run_lanes(*(np.array([x[i]]) for x in (lanes.beta1, lanes.beta2, lanes.alpha)),
                      np.array([k]), np.array([q]), lanes.g0[i : i + 1])  # fmt: skip
    out, run = S.simulate_outcome(lanes.beta1[i], lanes.beta2[i], lanes.alpha[i], k=k, q=q,
                                  g0=lanes.g0[i], max_events=2000)  # fmt: skip
    assert run.status == S.Status.SETTLED and out == S.Outcome.SETTLES_FF
    assert int(res.code[0]) == int(out)


def test_a_divergence_within_rounding_takes_the_exact_simulators_verdict():
    """A lane of the random comparison (seed 46, lane 183) diverges one event in with a gap at
    +3e-16 (fast) or -3e-16 (exact) beside one at -4.5e5: IWC or not is a rounding residue, which
    both engines flag; the lane gets the exact simulator's outcome and keeps the flag."""
    from atlas.dynamics import engine_check as C

    lanes = C.random_lanes(46, 2000)
    i = 183
    k, q = (lanes.kappa[i], 1.0), (lanes.q[i], lanes.q[i])
    res = F.run_batch(lanes.beta1[i], lanes.beta2[i], lanes.alpha[i], k, q,
                      lanes.g0[i : i + 1], reference=_reference)  # fmt: skip
    out, run = _reference(lanes.beta1[i], lanes.beta2[i], lanes.alpha[i], k, q, lanes.g0[i])
    assert run.status == S.Status.DIVERGED and stop_rule.run_within_rounding(run)
    assert int(res.code[0]) == int(out) and res.within_rounding[0]


def test_lanes_where_modal_terms_cancel_step_by_the_size_of_their_curvature():
    """Three lanes that run into penetration (IWC) near a degenerate direction: beta1 0.009 from
    3pi/2 (random comparison seed 46, lane 9), beta2 on 3pi/2 (lane 286) and the 64^2 bench map's
    cell (29, 29) (beta1 ~ beta2, det B small).  Their modal terms are large and cancel, so the
    modal curvature bound is 1e2-1e4 times |f''| and cut steps to ~1e-3 H_S (104, 226 and 188
    steps); the flow's bound (:func:`atlas.dynamics.event_bounds.flow_curvature_bound`) within a
    shorter window sets the step instead: at most 30 steps each (counted, not timed), and the
    exact simulator's outcome."""
    from atlas.dynamics import engine_check as C

    L = C.random_lanes(46, 1000)
    b1, b2 = S.outcome_grid(64)
    g0 = S.perturbed_initial_states(b1, b2, 0.35 * PI, 0.5)[29, 29, 0]
    cases = [(L.beta1[i], L.beta2[i], L.alpha[i], (L.kappa[i], 1.0), (L.q[i], L.q[i]), L.g0[i])
             for i in (9, 286)] + [(b1[29], b2[29], 0.35 * PI, (0.5, 1.0), (0.0, 0.0), g0)]  # fmt: skip
    for x1, x2, alpha, k, q, g in cases:
        res = F.run_lanes(np.array([x1]), np.array([x2]), np.array([alpha]), np.array([k]),
                          np.array([q]), g[None])  # fmt: skip
        assert res.steps[0] <= 30, (x1, x2, res.steps[0])
        assert int(res.code[0]) == int(_reference(x1, x2, alpha, k, q, g)[0]) == int(S.Outcome.IWC)


def test_no_lane_takes_more_steps_than_its_events_and_time_allow():
    """The lane bound in events and time, counted (not timed) on 300 lanes of the random
    comparison (seed 46): every lane takes at most 10 times the median lane's steps, plus 2 per
    event, plus one per ``4 H_S`` of its run (``H_S`` the shortest of its configurations; the step
    window of an oscillation between events).  Lanes with 44-120 events take more than 10 times
    the median lane, as each event costs a step or two; the lanes near the 3pi/2 axis whose
    modal terms cancel (lanes 9 and 286, 104 and 226 steps for 3 and 2 events before the
    flow's curvature bound) broke this bound."""
    from atlas.dynamics import engine_check as C

    L = C.random_lanes(46, 1000)
    sel = np.arange(300)
    k = np.stack([L.kappa, np.ones_like(L.kappa)], axis=1)[sel]
    q = np.stack([L.q, L.q], axis=1)[sel]
    res = F.run_lanes(L.beta1[sel], L.beta2[sel], L.alpha[sel], k, q, L.g0[sel])
    H = mf.modal_tables(mf.Lanes.of(L.beta1[sel], L.beta2[sel], L.alpha[sel], k, q)).H.min(axis=0)
    ok = res.decided_by != 3
    steps, events, t = res.steps[ok], res.n_events[ok], res.t_final[ok]
    bound = 10 * np.median(steps) + 2 * events + t / (4 * H[ok])
    assert np.all(steps <= bound), np.flatnonzero(steps > bound)
    assert ok.mean() >= 0.98


def test_stops_and_their_classification_reuse_the_tables_eigenvectors(monkeypatch):
    """Lanes of the random comparison (seed 46) stepped to the aligned-penetration stop (lanes 21,
    95, 119: IWC) or to a divergence within rounding (lane 183, sent to the exact simulator) are
    checked, located, classified and tested for rounding with the eigenvectors of their modal
    tables: no ``geev`` beyond the tables' own (counted per matrix), and the exact simulator's
    verdicts."""
    from atlas.dynamics import engine_check as C

    L = C.random_lanes(46, 2000)
    sel = np.array([21, 95, 119, 183])
    k, q = np.stack([L.kappa[sel], np.ones(sel.size)], 1), np.stack([L.q[sel]] * 2, 1)
    args = (L.beta1[sel], L.beta2[sel], L.alpha[sel], k, q)
    seen = count_eig(monkeypatch)
    mf.modal_tables(mf.Lanes.of(*args))
    tables_only = seen[0]
    res = F.run_lanes(*args, L.g0[sel])
    assert seen[0] == 2 * tables_only
    monkeypatch.undo()
    assert res.decided_by.tolist() == [0, 0, 0, 3]
    assert res.code[:3].tolist() == [int(S.Outcome.IWC)] * 3
    for j, i in enumerate(sel[:3]):
        out = _reference(L.beta1[i], L.beta2[i], L.alpha[i], tuple(k[j]), tuple(q[j]), L.g0[i])
        assert int(out[0]) == int(S.Outcome.IWC), i


def test_a_crossing_certified_beyond_the_window_does_not_stop_the_safe_substeps():
    """A lane of the random comparison (seed 46, lane 979: beta1 = 3pi/2, beta2 = pi/2, det B =
    0, its perturbed SS equilibrium ~1e16) has no event in its 150 time units: gap 2 oscillates
    about -1e15 while gap 1 drifts slowly towards its contact, its crossing certified ~190 H_S
    ahead, far beyond the step window.  That crossing no longer stops the safe sub-steps, so
    the oscillation is crossed in steps of the window: at most 30 steps (106 when every step
    ended at gap 2's sigma_lo), and the exact simulator's outcome."""
    from atlas.dynamics import engine_check as C

    L = C.random_lanes(46, 1000)
    i = 979
    assert (L.beta1[i], L.beta2[i]) == (1.5 * PI, 0.5 * PI)
    k, q = (L.kappa[i], 1.0), (L.q[i], L.q[i])
    res = F.run_lanes(L.beta1[i : i + 1], L.beta2[i : i + 1], L.alpha[i : i + 1], np.array([k]),
                      np.array([q]), L.g0[i : i + 1])  # fmt: skip
    out, run = _reference(L.beta1[i], L.beta2[i], L.alpha[i], k, q, L.g0[i])
    assert res.n_events[0] == run.n_events == 0
    assert res.steps[0] <= 30
    assert int(res.code[0]) == int(out)


def _random_lane(seed, i):
    """Lane ``i`` of the random comparison (1,000 lanes, ``seed``) by the fast engine, and the
    exact simulator's ``(outcome, run)`` of it."""
    from atlas.dynamics import engine_check as C

    L = C.random_lanes(seed, 1000)
    k, q = (L.kappa[i], 1.0), (L.q[i], L.q[i])
    res = F.run_lanes(L.beta1[i : i + 1], L.beta2[i : i + 1], L.alpha[i : i + 1], np.array([k]),
                      np.array([q]), L.g0[i : i + 1])  # fmt: skip
    return res, _reference(L.beta1[i], L.beta2[i], L.alpha[i], k, q, L.g0[i])


def test_safe_substeps_ending_on_a_crossing_take_it_as_the_event():
    """A lane of the random comparison (seed 46, lane 377: q = 0, growing bouncing, 179 events):
    its gaps fall back in free flight, an exact quadratic whose curvature bound is its own, so a
    safe sub-step's sigma_lo lands on the root.  The step takes it as its event (the next step
    took it, with a step of length 0): at most 0.75 steps per event (167 steps, 0.93, before;
    twin crossings of an undamped contact count two events), and the exact simulator's
    outcome and events."""
    res, (out, run) = _random_lane(46, 377)
    assert res.n_events[0] == run.n_events == 179
    assert res.steps[0] <= 0.75 * res.n_events[0]
    assert int(res.code[0]) == int(out) == int(S.Outcome.GROWING_BOUNCING)


def test_a_gap_and_its_force_crossing_close_together_are_located_in_one_step():
    """A lane of the random comparison (seed 47, lane 169: q = 0.0047, a sustained oscillation
    with 119 events): at each release the force of the lightly damped contact crosses zero
    ~2e-3 H_S before its gap, their certified brackets overlap, and neither could be located
    alone (the step went to the smaller sigma_lo, twice an event).  Both roots are located in
    the same step and the earlier is the event: at most 1.1 steps per event (268 steps, 2.25,
    before), and the exact simulator's outcome and events."""
    res, (out, run) = _random_lane(47, 169)
    assert res.n_events[0] == run.n_events == 119
    assert res.steps[0] <= 1.1 * res.n_events[0]
    assert int(res.code[0]) == int(out) == int(S.Outcome.SUSTAINED_OSCILLATION)


def test_a_gap_curving_away_from_its_contact_is_bracketed_by_its_signed_curvature():
    """A lane of the random comparison (seed 46, lane 489: kappa 0.05, q 0.23, 117 events): each
    period a lifted gap rises towards its contact and turns back before it (its force crosses
    first).  Under a bound of ``|f''|`` (about twice the true curvature) each step assumed it
    curved towards the contact, ~4 steps per approach; the signed curvature at the step's start
    (:func:`atlas.dynamics.event_bounds.taylor_steps`) takes the approach in about one: at most
    1.15 steps per event (198 steps, 1.69, before), and the exact simulator's outcome and
    events."""
    res, (out, run) = _random_lane(46, 489)
    assert res.n_events[0] == run.n_events == 117
    assert res.steps[0] <= 1.15 * res.n_events[0]
    assert int(res.code[0]) == int(out)


def test_an_oscillation_far_from_its_contacts_is_crossed_in_long_windows():
    """A lane of the random comparison (seed 47, lane 604: kappa 9.1, q 0.05): both contacts
    closed, a slowly growing oscillation (about 1/10 of the gaps) with no event for 148 time
    units.  Its functions keep their signs over the long window by the size of their terms
    (:func:`atlas.dynamics.event_bounds.keeps_sign_within`): the 140 time units to ``t_end =
    140`` take at most 8 steps (40 steps of the 8 H_S window before), with no event, as in the
    exact simulator."""
    from atlas.dynamics import engine_check as C

    L = C.random_lanes(47, 1000)
    i = 604
    k, q = (L.kappa[i], 1.0), (L.q[i], L.q[i])
    res = F.run_lanes(L.beta1[i : i + 1], L.beta2[i : i + 1], L.alpha[i : i + 1], np.array([k]),
                      np.array([q]), L.g0[i : i + 1], t_end=140.0)  # fmt: skip
    run = S.simulate(L.beta1[i], L.beta2[i], L.alpha[i], k=k, q=q, g0=L.g0[i], t_end=140.0)
    assert res.n_events[0] == run.n_events == 0
    assert res.steps[0] <= 8


@pytest.mark.parametrize(("seed", "n", "lane", "old"), [(44, 200, 13, 33), (45, 1000, 925, 30)])
def test_a_divergence_with_no_event_reaches_its_stop_in_few_steps(seed, n, lane, old):
    """Random lanes on an axis (beta2 = 3pi/2; beta1 = pi) whose SS configuration has a growing
    real mode and no event: the gap sinks to the deep-penetration stop (verdict undetermined, not
    aligned).  The growth cap cut their steps to one doubling each (``old`` steps); past it, where
    no event and no limit can come (a proven bound), one step reaches the limit: few steps
    (counted), the exact simulator's verdict, stop reason and stop time (to the location's
    tolerance)."""
    from atlas.dynamics import engine_check

    L = engine_check.random_lanes(seed, n)
    b1, b2, alpha, kappa, q, g0 = (x[lane] for x in (L.beta1, L.beta2, L.alpha, L.kappa, L.q,
                                                     L.g0))  # fmt: skip
    res = F.run_lanes([b1], [b2], [alpha], [[kappa, 1.0]], [[q, q]], g0[None])
    out, run = _reference(b1, b2, alpha, (kappa, 1.0), (q, q), g0)
    assert run.n_events == res.n_events[0] == 0
    assert F.DECIDED_BY[res.decided_by[0]] == "stepped" and res.steps[0] <= 6 < old
    assert int(res.code[0]) == int(out) and F.STOPS[res.stop[0]] == run.status
    assert abs(res.t_final[0] - run.t_final) <= 1e-10
