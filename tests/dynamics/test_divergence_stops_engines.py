"""The deep-penetration and non-finite stops of the divergence rule (atlas.dynamics.stop_rule)
reached on real runs of every engine: the exact simulator (``--engine numpy``), the event-to-event
NumPy engine (``fast``) and its JAX kernel (``jax``), each reporting the run as it stopped.

The deep-penetration lanes were found by a seeded scan of 1,500 random lanes through the NumPy
engine (2 of them stop there); the rule's limit is the documented ``-1e3 penetration_limit`` =
``-1e6 scale`` (``scale``: the run's length scale, the initial gaps or ``|a| / min k_i |b_i|``).
"""

import warnings

import numpy as np
import pytest

from atlas import dynamics as S
from atlas.dynamics import fast_engine as F
from atlas.dynamics.system import Outcome, Status

#: (beta1, beta2, alpha, kappa, q), g0: lanes whose active gap 1 runs past -1e6 scale unaligned
DEEP_LANES = [
    ((3.037405595837771, 4.667152195149329, 1.2489558857848695, 0.8224352033013632,
      7.572763526192105),
     (-0.003218356153364115, -0.01647948829576863, 0.002007511885818941, 0.0007949014920157781)),
    ((2.248760770572925, 4.173672892777783, 2.0077087276041947, 0.37601005826908285,
      0.0011666630122590324),
     (-0.007308605585121127, -0.02456262483546335, 0.038305201527362095, -0.01810433025471342)),
]  # fmt: skip
#: gaps of 1e300 and -1e300 at rest: the run overflows (a non-finite state) before any limit
HUGE_G0 = (1e300, -1e300, 0.0, 0.0)
STEPPED, FALLBACK = F.DECIDED_BY.index("stepped"), F.DECIDED_BY.index("fallback")


def _exact(params, g0):
    b1, b2, alpha, kappa, q = params
    return S.simulate_outcome(b1, b2, alpha, k=(kappa, 1.0), q=(q, q), g0=np.array(g0))


def _reference(b1, b2, alpha, k, q, g0):
    return S.simulate_outcome(b1, b2, alpha, k=k, q=q, g0=g0)


def _batch(engine, lanes, **kw):
    """One batch of ``lanes`` through ``engine.run_batch`` (the exact simulator for fallbacks)."""
    p = np.array([params for params, _ in lanes])
    g0 = np.array([g for _, g in lanes], dtype=float)
    k = np.stack([p[:, 3], np.ones(len(p))], axis=1)
    q = np.stack([p[:, 4], p[:, 4]], axis=1)
    return engine.run_batch(p[:, 0], p[:, 1], p[:, 2], k, q, g0, reference=_reference, **kw)


def _deep_limit(scale):
    return -1e6 * scale


@pytest.mark.parametrize("lane", range(len(DEEP_LANES)))
def test_exact_simulator_stops_at_the_deep_penetration_limit(lane):
    out, res = _exact(*DEEP_LANES[lane])
    assert res.status == Status.DIVERGED and out == Outcome.UNDETERMINED
    d = np.asarray(res.g_final[:2])
    assert np.isfinite(res.g_final).all() and d.max() < 0
    # located at the limit (not sampled past it): the deepest gap sits on -1e6 scale
    assert d.min() == pytest.approx(_deep_limit(res.scale), rel=1e-9)
    assert 0 < res.t_final < 150


def _check_deep(res, exact):
    for i, (_, run) in enumerate(exact):
        assert res.code[i] == int(Outcome.UNDETERMINED) and res.decided_by[i] == STEPPED
        assert res.t_final[i] == pytest.approx(run.t_final, rel=1e-9)
        assert res.g_final[i, :2].min() == pytest.approx(_deep_limit(run.scale), rel=1e-9)


def test_numpy_engine_stops_at_the_deep_penetration_limit_with_the_exact_simulator():
    _check_deep(_batch(F, DEEP_LANES), [_exact(*lane) for lane in DEEP_LANES])


@pytest.mark.slow  # compiles the JAX kernel (as every JAX-engine test but one map)
def test_jax_engine_stops_at_the_deep_penetration_limit_with_the_exact_simulator():
    from atlas.dynamics import jax_engine as J

    _check_deep(_batch(J, DEEP_LANES), [_exact(*lane) for lane in DEEP_LANES])


def test_exact_simulator_stops_at_a_non_finite_state():
    """... without a warning: the overflow is the stop, reported as such, under NumPy's default
    floating-point error handling (a warning, an error in this suite)."""
    with np.errstate(divide="warn", over="warn", under="ignore", invalid="warn"), \
            warnings.catch_warnings():  # fmt: skip
        warnings.simplefilter("error")
        out, res = _exact(DEEP_LANES[0][0], HUGE_G0)
    assert res.status == Status.DIVERGED and out == Outcome.UNDETERMINED
    assert not np.isfinite(res.g_final).all()
    assert 0 < res.t_final < 150  # the overflow, not the start or the horizon
    # stopped where the velocities overflow, before the gaps reach the deep limit (-1e306 here)
    d = np.asarray(res.g_final[:2])
    assert np.isfinite(d).all() and d.min() > 0.9 * _deep_limit(res.scale)


def _check_non_finite(res):
    """The fast engines do not step such a run: they hand it to the exact simulator (whose stop
    is checked above) and report its verdict, never one of their own (IWC, settled)."""
    assert res.decided_by[0] == FALLBACK and res.code[0] == int(Outcome.UNDETERMINED)
    assert not res.within_rounding[0]
    # with the exact simulator's stop, time and state (stopped past 0, before the horizon)
    assert F.STOPS[res.stop[0]] == Status.DIVERGED and 0 < res.t_final[0] < 150
    assert not np.isfinite(res.g_final[0]).all()


def test_numpy_engine_reports_a_non_finite_run_as_the_exact_simulator():
    _check_non_finite(_batch(F, [(DEEP_LANES[0][0], HUGE_G0)]))


@pytest.mark.slow
def test_jax_engine_reports_a_non_finite_run_as_the_exact_simulator():
    from atlas.dynamics import jax_engine as J

    _check_non_finite(_batch(J, [(DEEP_LANES[0][0], HUGE_G0)]))
