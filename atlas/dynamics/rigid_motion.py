"""A planar :class:`~atlas.core.rigid_body.Mechanism` followed in time while its closed contacts
slide (the rigid sliding mode: SS with both contacts, S with one), to the first state where that
mode ends (paper Sec. 6.2, spontaneous transitions).

**Motion.**  The body moves with the chosen contacts closed (``contacts``: both, or one of them,
the other ignored): contact forces ``f* = B^-1 a`` (``d'' = 0``, eq. (1); one contact:
``f* = a1 / b11``) and ``M x'' = Q + W^T f*`` (``W`` rows ``J_n,j - mu_j s_j J_t,j``).  ``B`` and ``a``
are those of the closed contacts (:class:`~atlas.core.contact_space.ContactSpace`, one contact its
first-class case) from the closed forms of :mod:`atlas.core.rigid_body` at the body's configuration
and twist.  The geometry follows the body: a ``body_vertex`` is a body-fixed point ``R(phi) r_j``
on its fixed surface (normal ``n_j``); a ``body_side`` contact sits at the fixed environment vertex
``e_j`` (``r_j = e_j - x_c``) with the body's normal ``R(phi) n_j``.  At every evaluation the twist
is projected on the admissible twists (the null space of the closed contacts' ``J_n``: a line for
two contacts, :func:`~atlas.core.rigid_body.admissible_twist`, a plane for one), which removes the
integrator's drift off the constraint.  Classical Runge-Kutta of step ``dt`` [s], halved where
``det B`` would change by more than a tenth of itself in a step (near a singular ``B`` the forces
change on the time ``det B / (det B)'``, so the steps shrink with it).

**Events** (first one ends the motion): a contact force ``f*_j`` reaches zero (the mode stops
being consistent: contact ``j`` lifts off), a sliding speed reaches zero (a contact sticks), ``det
B`` reaches zero (``"B singular"``; one contact: ``b11 = 0``, Painleve's point, beyond which
sliding is inconsistent and a jam (IWC) consistent, :func:`~atlas.core.contact_space.
single_contact_verdicts`; reported once the step falls below ``1e-12`` s), or ``t_end``.  The
other event times are located by bisection on the step (``1e-12`` s).  Checked against closed
forms: the frictionless ladder leaves the wall at ``sin(theta) = (2/3) sin(theta0)``; Painleve's
rod (uniform, on its tip) reaches ``b11 = 0`` at the root of ``1 + 3 cos(theta) (cos(theta) -
mu sin(theta)) = 0``; at ``mu = 2``, ``a1 -> 0`` as ``b11^0.34`` (``f*`` diverges, integrably):
it reaches Painleve's point ``a = b = 0`` rather than lifting off.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from atlas.core.contact_space import ContactSpace
from atlas.core.rigid_body import BODY_VERTEX, Mechanism, free_acceleration, jacobians, mobility

__all__ = ["Motion", "follow"]


@dataclasses.dataclass(frozen=True)
class Motion:
    """``t`` [s], ``x`` (n, 3) configurations ``(x_c, y_c, phi)`` [m, m, rad] relative to the
    start, ``v`` (n, 3) twists, ``forces`` (n, k) ``f*`` [N] of the ``k`` closed ``contacts``;
    ``event`` (``"lift-off of contact j"``, ``"contact j sticks"``, ``"B singular"``, ``"t_end"``)
    at ``t[-1]``; ``space`` the closed contacts' :class:`ContactSpace` just before it (``B``,
    ``a``, verdicts)."""

    t: np.ndarray
    x: np.ndarray
    v: np.ndarray
    forces: np.ndarray
    contacts: tuple
    event: str
    space: ContactSpace


@dataclasses.dataclass(frozen=True)
class _Sliding:
    """The body, its closed contacts (0-based ``idx``) and the sliding signs at the start."""

    body: Mechanism
    idx: tuple
    s0: tuple

    def state(self, y):
        """``(twist, space, W, u)`` at ``y = (x_c, y_c, phi, v_x, v_y, omega)``: the projected
        twist, the closed contacts' contact space, their ``W`` rows and sliding speeds."""
        b, idx = self.body, list(self.idx)
        r, n = _geometry(b, y)
        Jn, Jt = (J[idx] for J in jacobians(r, n))
        v = y[3:] - np.linalg.pinv(Jn) @ (Jn @ y[3:])
        u = jacobians(r, n)[1] @ v
        s = tuple(int(np.sign(uj)) or s0 for uj, s0 in zip(u, self.s0))
        mu = np.array([b.mu1, b.mu2])
        B = np.array(mobility(b.m, b.I, r, n, mu, s))[np.ix_(idx, idx)]
        acc = free_acceleration(b.m, b.I, r, n, b.g, b.F, b.tau, v[2], u, (b.kind1, b.kind2))
        names = tuple(str(j + 1) for j in idx)
        space = ContactSpace(B, np.array(acc)[idx] + 0.0, names=names)
        W = Jn - (mu * s)[idx][:, None] * Jt
        return v, space, W, u[idx]

    def rates(self, y):
        """``(y', watched)``: the motion's derivative and ``(f*, u, det B)`` (module docstring)."""
        v, space, W, u = self.state(y)
        f = np.linalg.solve(space.B, space.a)
        b = self.body
        acc = np.linalg.solve(b.generalized_mass, b.generalized_force + W.T @ f)
        return np.concatenate([v, acc]), (f, u, np.linalg.det(space.B))


def _rot(phi, p):
    c, s = math.cos(phi), math.sin(phi)
    return (c * p[0] - s * p[1], s * p[0] + c * p[1])


def _geometry(start, y):
    """Contact positions and normals of both contacts at ``y`` (module docstring)."""
    xc, phi = y[:2], y[2]
    r, n = [], []
    for r0, n0, kind in ((start.r1, start.n1, start.kind1), (start.r2, start.n2, start.kind2)):
        if kind == BODY_VERTEX:
            r.append(_rot(phi, r0))
            n.append(n0)
        else:
            r.append((r0[0] - xc[0], r0[1] - xc[1]))
            n.append(_rot(phi, n0))
    return r, n


def _step(sl, y, h):
    """One Runge-Kutta step, its end's watched quantities, and whether a stage reversed a sliding
    velocity (the friction would flip inside the step: a contact sticks before its end)."""
    k1, w1 = sl.rates(y)
    k2, w2 = sl.rates(y + h / 2 * k1)
    k3, w3 = sl.rates(y + h / 2 * k2)
    k4, w4 = sl.rates(y + h * k3)
    y_new = y + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    flips = np.any([np.sign(w[1]) * np.sign(w1[1]) < 0 for w in (w2, w3, w4)], axis=0)
    return y_new, sl.rates(y_new)[1], flips


def _crossed(sl, y, h, w0):
    """``(y_new, w_new, crossed)``: the step and which of ``det B``, ``f*_j``, ``u_j`` changed
    sign (``det B`` first: ``f*`` changes sign through infinity there, not through zero)."""
    y_new, w_new, flips = _step(sl, y, h)
    changed = lambda new, old: (np.sign(new) != np.sign(old)) & (old != 0)  # noqa: E731
    sing = changed(w_new[2], w0[2])
    crossed = np.concatenate([[sing], changed(w_new[0], w0[0]) & ~sing, flips | changed(*(
        w[1] for w in (w_new, w0)))])  # fmt: skip
    return y_new, w_new, crossed


def _contacts(body, contacts, twist):
    """Validated ``contacts`` (1-based) and the start state (module docstring)."""
    contacts = tuple(contacts)
    if not contacts or len(set(contacts)) != len(contacts) or not set(contacts) <= {1, 2}:
        raise ValueError(f"contacts: one or both of 1, 2, got {contacts}")
    v = np.array(body.twist if twist is None else twist, dtype=np.float64)
    if v.shape != (3,) or not np.all(np.isfinite(v)):
        raise ValueError(f"twist: must be a finite (v_x, v_y, omega), got {twist!r}")
    idx = tuple(j - 1 for j in contacts)
    y = np.concatenate([np.zeros(3), v])
    r, n = _geometry(body, y)
    off = jacobians(r, n)[0][list(idx)] @ v
    scale = np.max(np.abs(v)) * max(1.0, *np.abs(np.concatenate(r)))
    if np.any(np.abs(off) > 1e-9 * scale):
        raise ValueError(f"twist: opens or closes a closed contact (normal speeds {off.tolist()})")
    return _Sliding(body, idx, (body.s1, body.s2)), y


def follow(body: Mechanism, t_end=1.0, dt=1e-3, *, contacts=(1, 2), twist=None) -> Motion:
    """Follow ``body`` from its state with ``contacts`` (1-based: ``(1, 2)``, ``(1,)`` or
    ``(2,)``) closed and sliding until an event or ``t_end`` [s] (module docstring).  ``dt`` [s]
    the Runge-Kutta step; ``twist`` the initial ``(v_x, v_y, omega)`` [m/s, m/s, rad/s] (default
    the body's; it must keep the closed contacts closed).  A contact at rest slides in the body's
    direction ``s_j``."""
    if not (t_end > 0 and dt > 0):
        raise ValueError(f"t_end, dt: must be > 0, got {t_end}, {dt}")
    sl, y = _contacts(body, contacts, twist)
    y[3:] = sl.state(y)[0]
    w = sl.rates(y)[1]
    ts, ys, fs, event, t = [0.0], [y.copy()], [w[0]], "t_end", 0.0
    lift, stick = ([f"lift-off of contact {j}" for j in contacts],
                   [f"contact {j} sticks" for j in contacts])  # fmt: skip
    names = ["B singular", *lift, *stick]
    h = dt
    while t < t_end - 1e-15:
        try:
            h, (y_new, w_new, crossed) = _controlled(sl, y, min(dt, t_end - t, 4 * h), w)
            if h < 1e-12:
                event = "B singular"
                break
            if np.any(crossed):
                h, crossed = _bisect(sl, y, h, w)
                y_new, w_new, _ = _crossed(sl, y, h, w)
                event = names[int(np.argmax(crossed))]
        except np.linalg.LinAlgError:
            event = "B singular"
            break
        y, w, t = y_new, w_new, t + h
        ts.append(t), ys.append(y.copy()), fs.append(w[0])
        if event != "t_end":
            break
    ys = np.array(ys)
    space = sl.state(y)[1]
    return Motion(np.array(ts), ys[:, :3], ys[:, 3:], np.array(fs), contacts, event, space)


def _controlled(sl, y, h, w0):
    """The step (at most ``h``, halved as needed) over which ``det B`` changes by at most a tenth of
    itself, and its :func:`_crossed`: near a singular ``B`` the forces ``f* = B^-1 a`` change on
    the time ``det B / (det B)'``, so the steps shrink with it (``B singular`` once below
    ``1e-12`` s)."""
    while True:
        out = _crossed(sl, y, h, w0)
        if abs(out[1][2] - w0[2]) <= 0.1 * abs(w0[2]) or h < 1e-12:
            return h, out
        h /= 2


def _bisect(sl, y, h, w0):
    """The longest step (to 1e-12 s) over which no watched quantity changes sign, and which
    change sign just beyond it."""
    lo, hi, crossed = 0.0, h, None
    while hi - lo > 1e-12:
        mid = (lo + hi) / 2
        c = _crossed(sl, y, mid, w0)[2]
        if np.any(c):
            hi, crossed = mid, c
        else:
            lo = mid
    if crossed is None:
        crossed = _crossed(sl, y, hi, w0)[2]
    return lo, crossed
