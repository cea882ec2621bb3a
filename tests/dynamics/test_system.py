"""The compliant system (atlas.dynamics.system): SS equilibrium and the mode matrices against the
equations they come from (paper eqs. 1, 6-8)."""

import math

import numpy as np
import pytest
import scipy.linalg

from atlas.dynamics import system


def test_ss_equilibrium_balances_eq1():
    """At d*: f = -K d* > 0 and d'' = B f - a = 0 (paper eq. 1 with the contact law eq. 6)."""
    beta1, beta2, alpha, k = 0.05 * math.pi, 0.65 * math.pi, 0.35 * math.pi, (100.0, 200.0)
    d = system.ss_equilibrium(beta1, beta2, alpha, k=k)
    B = np.array([[math.cos(beta1), math.cos(beta2)], [math.sin(beta1), math.sin(beta2)]])
    f = -np.array(k) * d
    assert np.all(f > 0)
    np.testing.assert_allclose(B @ f, [math.cos(alpha), math.sin(alpha)], rtol=0, atol=1e-15)


def test_ss_equilibrium_none_when_inconsistent():
    # a = b1 - b2 (alpha between beta1 and -beta2): B^-1 a = (1, -1) has a negative force
    b1, b2 = np.array([1.0, 0.0]), np.array([0.0, 1.0])
    a = b1 - b2
    alpha = math.atan2(a[1], a[0])
    assert system.ss_equilibrium(0.0, 0.5 * math.pi, alpha, a_norm=float(np.hypot(*a))) is None


def test_modes_match_eq7_and_expm():
    """E_S of each mode: d'' = -B K_S d - B Q_S d' - a (paper eqs. 7, 8), and Phi = expm(E h)."""
    beta1, beta2, alpha = 0.15 * math.pi, 1.07 * math.pi, 0.2 * math.pi
    k, q = np.array([100.0, 200.0]), np.array([20.0, 20.0])
    sysm = system.build_system(beta1, beta2, alpha, k, q, (1.0, 1.0), 1.0, 0.5)
    B = np.array([[math.cos(beta1), math.cos(beta2)], [math.sin(beta1), math.sin(beta2)]])
    a = np.array([math.cos(alpha), math.sin(alpha)])
    for mask, name in enumerate(("FF", "SF", "FS", "SS")):
        mode = sysm.modes[mask]
        assert system.mode_name(mask) == name
        act = np.diag([float(c == "S") for c in name])
        g = np.array([-0.01, 0.02, 0.3, -0.4])
        acc = -B @ act @ (k * g[:2]) - B @ act @ (q * g[2:]) - a
        np.testing.assert_allclose(mode.E[2:4] @ np.append(g, 1.0), acc, rtol=1e-14)
        np.testing.assert_allclose(mode.Phi, scipy.linalg.expm(mode.E * mode.h), rtol=1e-12)


def test_bad_theta_names_parameter():
    with pytest.raises(ValueError, match="theta"):
        system.build_system(0.1, 2.0, 0.5, (1.0, 1.0), (0.0, 0.0), (1.0, 1.0), 1.0, 1.5)


@pytest.mark.parametrize(
    "kw, name",
    [
        ({"k": (1.0,)}, "k"),
        ({"q": (0, 0, 0)}, "q"),
        ({"k": 1 + 1j}, "k"),
        ({"beta1": True}, "beta1"),
    ],
)
def test_build_system_refuses_bad_parameters(kw, name):
    args = dict(beta1=0.3, beta2=1.2, alpha=2.0, k=(1.0, 2.0), q=(0.0, 0.0), b_norm=1.0)
    args.update(a_norm=1.0, theta=1.0)
    args.update(kw)
    with pytest.raises(ValueError, match=f"^{name}[: ]"):
        system.build_system(**args)
