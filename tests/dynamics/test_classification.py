"""Outcome classification (atlas.dynamics.classification) of the paper's Fig. 2 panels and of an
impact without collision."""

import math

import numpy as np
import pytest

from atlas import dynamics as S

PI = math.pi
CASES = S.fig2_cases()


# --------------------------------------------------------------------------- Fig. 2 outcomes


def test_fig2a_growing_bouncing():
    # paper Sec. 6.4: "unboundedly growing oscillations, during which both legs repeatedly hit
    # the ground"; the growth is irregular, the amplitude limit (1e4 x scale) is hit by t = 400
    res = S.simulate(**dict(CASES["a"], t_end=400.0))
    assert S.classify(res) == S.Outcome.GROWING_BOUNCING
    assert set(res.contacts[[k == S.IMPACT for k in res.kinds]]) == {1, 2}


def test_fig2b_settles_ss():
    # paper: "the SS mode is stable, which is confirmed by the simulation" (q = 0: neutral)
    res = S.simulate(**dict(CASES["b"], t_end=20.0))
    assert res.n_events == 0
    assert S.classify(res) == S.Outcome.SETTLES_SS


def test_fig2c_growing_bouncing_then_bounded():
    # paper: inverse chattering despite the locally stable SS mode (growing bouncing).  Over
    # t <= 100 the bouncing is still growing (impact speeds); the longer run shows it saturating
    # (impact speeds stay ~6, |d1| ~ 36), i.e. the initial excursion 0.05 grew ~700 times: still
    # growing bouncing (grew and saturated), not a *small* sustained oscillation.
    res = S.simulate(**dict(CASES["c"], t_end=100.0))
    assert S.classify(res) == S.Outcome.GROWING_BOUNCING
    long = S.simulate(**dict(CASES["c"], t_end=1000.0))
    assert S.classify(long) == S.Outcome.GROWING_BOUNCING
    st = S.trajectory_stats(long)
    T = long.t_final
    mid = st.v_imp[(st.t_imp >= T / 3) & (st.t_imp < 2 * T / 3)].max()
    late = st.v_imp[st.t_imp >= 2 * T / 3].max()
    assert late < 1.25 * mid  # saturated: the speed test alone would not call it growing
    assert long.scale == pytest.approx(0.05)
    assert st.late_amplitude.max() > 100 * 0.05  # the amplitude test does


def test_fig2d_sustained_oscillation_single_contact_bouncing():
    # The caption of Fig. 2d ("sustained small amplitude oscillation with repeated impacts")
    # matches the simulation; Sec. 6.5's text (growing, simultaneous impacts) does not: contact 1
    # never lifts off, only contact 2 bounces, with impact speed saturating near 0.1.
    res = S.simulate(**dict(CASES["d"], t_end=100.0))
    assert S.classify(res) == S.Outcome.SUSTAINED_OSCILLATION
    lifts = res.contacts[[k == S.LIFTOFF for k in res.kinds]]
    assert set(lifts.tolist()) == {2}
    # small: gaps stay within a few resting penetrations |a| / (k1 |b1|) = 0.01 (paper eq. 6)
    assert res.scale == pytest.approx(0.01)
    assert S.trajectory_stats(res).late_amplitude.max() < 10 * 0.01


def test_fig2e_growing_bouncing_with_simultaneous_impacts():
    # The caption of Fig. 2e ("resembles inverse chattering, with repeated simultaneous impacts")
    # matches; Sec. 6.5's text (sustained microscopic oscillation) does not.  Each landing of
    # contact 2 is an impact at both contacts: contact 1 (sliding at its SS penetration) is pushed
    # in to > 10x its resting penetration and both contacts lift off within 0.5 time units.
    res = S.simulate(**dict(CASES["e"], t_end=100.0))
    assert S.classify(res) == S.Outcome.GROWING_BOUNCING
    kinds = np.array(res.kinds)
    imp2 = np.flatnonzero((kinds == S.IMPACT) & (res.contacts == 2) & (res.t_events > 20))
    lift1 = res.t_events[(kinds == S.LIFTOFF) & (res.contacts == 1)]
    lift2 = res.t_events[(kinds == S.LIFTOFF) & (res.contacts == 2)]
    assert imp2.size >= 5
    g = res.sample(np.linspace(0, res.t_final, 200_001))
    t = np.linspace(0, res.t_final, 200_001)
    for n in imp2:
        t_imp = res.t_events[n]
        d1_rest = res.states[n, 0]
        assert d1_rest < 0  # contact 1 in contact when contact 2 lands
        l2 = lift2[lift2 > t_imp][0]
        l1 = lift1[lift1 > t_imp][0]
        assert abs(l1 - l2) < 0.5
        window = (t > t_imp) & (t < l2)
        assert g[window, 0].min() < 10 * d1_rest


# --------------------------------------------------------------------------- impact without collision


def test_iwc_detected_if_mode():
    """IF (paper Sec. 4.3): b11 < 0 and b21 > 0: contact 1 pushed in, force -> +inf."""
    beta1 = 0.6 * PI  # b11 = cos < 0, b21 = sin > 0
    res = S.simulate(
        beta1, 0.25 * PI, 0.3 * PI, k=(1.0, 1.0), g0=(-1e-3, 1.0, -1e-3, 0.5), t_end=200
    )
    assert res.status == S.Status.DIVERGED
    assert S.classify(res) == S.Outcome.IWC
    assert res.mode_final == "SF"
