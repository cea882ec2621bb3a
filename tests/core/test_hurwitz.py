"""The SS kernel (:mod:`atlas.core.hurwitz`) where XLA's arithmetic is not IEEE op-by-op
arithmetic: XLA on CPU reads subnormal inputs as zero (denormals-are-zero), jitted or not.
References: Routh-Hurwitz in exact rationals of the float inputs.  The op-by-op cases run by hand:
``python -m pytest -m slow tests/core/test_hurwitz.py``."""

from fractions import Fraction

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from atlas.core import hurwitz, points
from atlas.core.verdicts import Verdict

#: subnormal damping: XLA reads it as zero (an undamped, neutral system), IEEE does not
Q_SUBNORMAL = 1e-310

#: the op-by-op case (``jax.disable_jit``; the package runs this kernel only jitted): ``slow``
OP_BY_OP = pytest.param(False, marks=pytest.mark.slow)

#: points ``(beta1, beta2)`` [rad] at kappa 0.5 where any positive damping ``q1`` is stable
STABLE_POINTS = [(0.3, 1.2), (0.2, 0.9), (0.1, 0.5)]


def exact_ss_stable(c1, s1, c2, s2, kappa, q1, q2) -> bool:
    """Liénard-Chipart of ``p(l) = det(l^2 I + B (K + l Q))`` (paper eq. 9), ``B = [b1 b2]``,
    ``K = diag(kappa, 1)``, in exact rationals: ``True`` iff every root has ``Re < 0``."""
    c1, s1, c2, s2, k1, q1, q2 = (Fraction(float(v)) for v in (c1, s1, c2, s2, kappa, q1, q2))
    d = c1 * s2 - s1 * c2
    a3, a2 = c1 * q1 + s2 * q2, c1 * k1 + s2 + d * q1 * q2
    a1, a0 = d * (k1 * q2 + q1), d * k1
    h2 = a3 * a2 - a1
    return min(a3, a2, a1, a0, h2, a1 * h2 - a3 * a3 * a0) > 0


def _inputs(b1, b2, q1):
    return [np.float64(v) for v in (np.cos(b1), np.sin(b1), np.cos(b2), np.sin(b2), 0.5, q1, 0.0)]


@pytest.mark.parametrize("jitted", [True, OP_BY_OP], ids=["jit", "op-by-op"])
def test_subnormal_damping_is_never_certified_undamped(jitted):
    """``q1 = 1e-310 > 0`` is damping: the system is stable (exactly), and the kernel must say so
    or stay undecided; reading the subnormal as zero certified "neutral" (the undamped verdict)."""
    fn = jax.jit(hurwitz.ss_verdict) if jitted else hurwitz.ss_verdict
    for b1, b2 in STABLE_POINTS:
        x = _inputs(b1, b2, Q_SUBNORMAL)
        assert exact_ss_stable(*x)
        if jitted:
            got = int(fn(*map(jnp.asarray, x)))
        else:
            with jax.disable_jit():
                got = int(fn(*map(jnp.asarray, x)))
        assert got in (int(Verdict.STABLE), int(Verdict.UNDECIDED)), (b1, b2, got)


def test_subnormal_damping_settles_to_the_exact_verdict():
    """Through the certified driver (kernel, then the exact tier): stable, as exactly."""
    x = np.array([_inputs(b1, b2, Q_SUBNORMAL) for b1, b2 in STABLE_POINTS]).T
    got = points.spectral_points(*x, names=("stable_SS",))["stable_SS"]
    assert (got == int(Verdict.STABLE)).all(), got


def exact_ss_unstable(c1, s1, c2, s2, kappa, q1, q2) -> bool:
    """``True`` iff ``p`` (as in :func:`exact_ss_stable`) certainly has a root with ``Re > 0``: a
    negative coefficient, or positive ones with ``H2 < 0`` or ``H3 < 0`` (sign changes in the
    first column of the Routh array)."""
    c1, s1, c2, s2, k1, q1, q2 = (Fraction(float(v)) for v in (c1, s1, c2, s2, kappa, q1, q2))
    d = c1 * s2 - s1 * c2
    a3, a2 = c1 * q1 + s2 * q2, c1 * k1 + s2 + d * q1 * q2
    a1, a0 = d * (k1 * q2 + q1), d * k1
    h2 = a3 * a2 - a1
    if min(a3, a2, a1, a0) < 0:
        return True
    return min(a3, a2, a1, a0) > 0 and (h2 < 0 or a1 * h2 - a3 * a3 * a0 < 0)


@pytest.mark.parametrize("jitted", [True, OP_BY_OP], ids=["jit", "op-by-op"])
def test_equal_damping_sum_flushed_to_zero_keeps_the_verdict(jitted):
    """Equal damping reads ``sign(a3) = sign(c1 + s2)`` from one rounded sum.  XLA flushes a
    subnormal sum to zero (``3e-308 - 2.9e-308`` gives 0 under jit), so that sign can be 0 where
    it is not; but ``|c1|, |s2| < 2^-1021`` forces ``|s1 c2| ~ 1``: ``det B < 0`` is unstable, and
    ``det B > 0`` has ``G ~ s1 c2 m^2 < 0``, unstable whatever ``a3``'s sign.  The verdict is the
    exact one on the worst such inputs, jitted and op-by-op."""
    flushed = jax.jit(jnp.add)(jnp.asarray(3e-308), jnp.asarray(-2.9e-308))
    assert float(flushed) == 0 and Fraction(3e-308) + Fraction(-2.9e-308) != 0
    cases = [(3e-308, 1.0, -1.0, -2.9e-308), (-3e-308, 1.0, -1.0, 2.9e-308)]
    cases += [(c1, -s1, -c2, s2) for c1, s1, c2, s2 in cases]
    for c1, s1, c2, s2 in cases:
        for q in (1e-3, 0.3, 5.0):
            x = [np.float64(v) for v in (c1, s1, c2, s2, 0.5, q, q)]
            assert exact_ss_unstable(*x)
            if jitted:
                got = int(jax.jit(hurwitz.ss_verdict)(*map(jnp.asarray, x)))
            else:
                with jax.disable_jit():
                    got = int(hurwitz.ss_verdict(*map(jnp.asarray, x)))
            assert got in (int(Verdict.UNSTABLE), int(Verdict.UNDECIDED)), (x, got)
