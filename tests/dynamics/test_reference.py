"""The exact simulator against an independent integrator (atlas.dynamics.reference: scipy
solve_ivp restarted at every event)."""

import numpy as np
import pytest

from atlas import dynamics as S

CASES = S.fig2_cases()


def _gap_events(t, kinds, contacts, states):
    m = np.array([k in (S.IMPACT, S.LIFTOFF) for k in kinds], dtype=bool)
    return t[m], [k for k, keep in zip(kinds, m, strict=True) if keep], contacts[m], states[m]


@pytest.mark.parametrize("name", list("abcde"))
def test_agrees_with_solve_ivp(name):
    """Gap events (impacts, lift-offs) and states agree with DOP853 at rtol 1e-12."""
    p = dict(CASES[name], t_end=10.0)
    res = S.simulate(**p)
    ref = S.simulate_solve_ivp(**p, method="DOP853", rtol=1e-12, atol=1e-15)
    t1, k1, c1, g1 = _gap_events(res.t_events, res.kinds, res.contacts, res.states)
    t2, k2, c2, g2 = _gap_events(ref["t_events"], ref["kinds"], ref["contacts"], ref["states"])
    assert k1 == k2
    np.testing.assert_array_equal(c1, c2)
    np.testing.assert_allclose(t1, t2, rtol=0, atol=1e-9)
    np.testing.assert_allclose(g1, g2, rtol=0, atol=1e-8)
    np.testing.assert_allclose(res.g_final, ref["g_final"], rtol=0, atol=1e-8)
