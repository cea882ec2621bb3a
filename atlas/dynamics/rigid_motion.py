"""A planar :class:`~atlas.core.rigid_body.Mechanism` followed in time while both contacts slide
(the rigid SS mode), to the first state where that mode ends (paper Sec. 6.2, spontaneous
transitions).

**Motion.**  The body moves from its state with both contacts closed: contact forces
``f* = B^-1 a`` (``d'' = 0``, eq. (1)) and ``M x'' = Q + W^T f*`` (``W`` rows
``J_n,j - mu_j s_j J_t,j``).  The geometry follows the body: a ``body_vertex`` is a body-fixed point
``R(phi) r_j`` on its fixed surface (normal ``n_j``); a ``body_side`` contact sits at the fixed
environment vertex ``e_j`` (``r_j = e_j - x_c``) with the body's normal ``R(phi) n_j``.  At every
evaluation the velocity is taken along the admissible twist (:func:`~atlas.core.rigid_body.
admissible_twist`; the projection removes the integrator's drift off the constraint), and the
Mechanism there gives ``B`` and ``a``.  Classical Runge-Kutta of step ``dt`` [s].

**Events** (first one ends the motion): a contact force ``f*_j`` reaches zero (SS stops being
consistent: contact ``j`` lifts off, the other slides on), a sliding speed reaches zero (a contact
sticks), ``B`` singular, or ``t_end``.  The event time is located by bisection on the step
(``1e-12`` s).  Checked against the frictionless ladder's closed form
``sin(theta) = (2/3) sin(theta0)``.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from atlas.core.rigid_body import BODY_VERTEX, Mechanism, admissible_twist

__all__ = ["Motion", "follow"]


@dataclasses.dataclass(frozen=True)
class Motion:
    """``t`` [s], ``x`` (n, 3) configurations ``(x_c, y_c, phi)`` [m, m, rad] relative to the
    start, ``v`` (n, 3) twists, ``forces`` (n, 2) ``f*`` [N]; ``event`` (``"lift-off of contact
    j"``, ``"contact j sticks"``, ``"B singular"``, ``"t_end"``) at ``t[-1]``; ``body`` the
    Mechanism at the end."""

    t: np.ndarray
    x: np.ndarray
    v: np.ndarray
    forces: np.ndarray
    event: str
    body: Mechanism


def _rot(phi, p):
    c, s = math.cos(phi), math.sin(phi)
    return (c * p[0] - s * p[1], s * p[0] + c * p[1])


def _body_at(start, y):
    """The Mechanism at state ``y = (x_c, y_c, phi, v_x, v_y, omega)`` (module docstring)."""
    xc, phi = y[:2], y[2]
    r, n = [], []
    for r0, n0, kind in ((start.r1, start.n1, start.kind1), (start.r2, start.n2, start.kind2)):
        if kind == BODY_VERTEX:
            r.append(_rot(phi, r0))
            n.append(n0)
        else:
            r.append((r0[0] - xc[0], r0[1] - xc[1]))
            n.append(_rot(phi, n0))
    z, u = admissible_twist(r, n)
    k = float(np.dot(y[3:], z) / np.dot(z, z))
    u1 = k * u[0]
    s1 = start.s1 if u1 == 0 else (1 if u1 > 0 else -1)
    return start.replace(r1=r[0], r2=r[1], n1=n[0], n2=n[1], s1=s1, speed=abs(u1))


def _rates(start, y):
    """``(y', f*, body)``: the SS motion's derivative, its contact forces, the body."""
    body = _body_at(start, y)
    f = np.linalg.solve(body.B, body.a)
    W = body.normal_jacobian - np.diag([body.mu1 * body.s1, body.mu2 * body.s2]) @ (
        body.tangent_jacobian
    )
    acc = np.linalg.solve(body.generalized_mass, body.generalized_force + W.T @ f)
    return np.concatenate([body.twist, acc]), f, body


def _step(start, y, h):
    """One Runge-Kutta step and whether a stage reversed a sliding velocity (the friction would
    flip inside the step: a contact sticks before its end)."""
    k1, _, b1 = _rates(start, y)
    k2, _, b2 = _rates(start, y + h / 2 * k1)
    k3, _, b3 = _rates(start, y + h / 2 * k2)
    k4, _, b4 = _rates(start, y + h * k3)
    u0 = np.sign(b1.sliding_speeds)
    flips = [np.sign(b.sliding_speeds) * u0 < 0 for b in (b2, b3, b4)]
    return y + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4), np.any(flips, axis=0)


def _watch(start, y):
    """The contact forces ``f*`` (an event where one changes sign) and the sliding velocities."""
    _, f, body = _rates(start, y)
    return np.asarray(f), np.asarray(body.sliding_speeds)


def _crossed(start, y, h, f0):
    """``(y_new, f_new, crossed)``: the step and which of ``f1, f2, u1, u2`` changed sign."""
    y_new, flips = _step(start, y, h)
    f_new, u_new = _watch(start, y_new)
    _, u0 = _watch(start, y)
    lift = (np.sign(f_new) != np.sign(f0)) & (f0 != 0)
    stick = flips | ((np.sign(u_new) != np.sign(u0)) & (u0 != 0))
    return y_new, f_new, np.concatenate([lift, stick])


def follow(body: Mechanism, t_end=1.0, dt=1e-3) -> Motion:
    """Follow ``body`` from its state in the SS mode until an event or ``t_end`` [s] (module
    docstring).  ``dt`` [s] the Runge-Kutta step."""
    if not (t_end > 0 and dt > 0):
        raise ValueError(f"t_end, dt: must be > 0, got {t_end}, {dt}")
    y = np.array([0.0, 0.0, 0.0, *body.twist])
    f, _ = _watch(body, y)
    ts, xs, fs, event, t = [0.0], [y.copy()], [f], "t_end", 0.0
    names = ("lift-off of contact 1", "lift-off of contact 2", "contact 1 sticks",
             "contact 2 sticks")  # fmt: skip
    while t < t_end - 1e-15:
        h = min(dt, t_end - t)
        try:
            y_new, f_new, crossed = _crossed(body, y, h, f)
            if np.any(crossed):
                h = _bisect(body, y, h, f)
                y_new, f_new, _ = _crossed(body, y, h, f)
                event = names[int(np.argmax(crossed))]
        except np.linalg.LinAlgError:
            event = "B singular"
            break
        y, f, t = y_new, f_new, t + h
        ts.append(t), xs.append(y.copy()), fs.append(f)
        if event != "t_end":
            break
    xs = np.array(xs)
    return Motion(np.array(ts), xs[:, :3], xs[:, 3:], np.array(fs), event, _body_at(body, y))


def _bisect(body, y, h, f0):
    """The longest step (to 1e-12 s) over which no watched quantity changes sign."""
    lo, hi = 0.0, h
    while hi - lo > 1e-12:
        mid = (lo + hi) / 2
        if np.any(_crossed(body, y, mid, f0)[2]):
            hi = mid
        else:
            lo = mid
    return lo
