"""The kinematics of a planar rigid body with two sliding point contacts: twists, Jacobians,
``B`` and ``a`` of eq. (1).

**Derivation** (paper Sec. 2, eq. (1)).  The body has generalised coordinates ``x = (x_c, y_c, phi)``
(centre of mass [m], angle [rad]), generalised mass ``M = diag(m, m, I)`` and twist
``x' = (v, omega)``.  Contact ``j`` is at ``r_j`` [m] (world frame, relative to the centre of mass)
with unit normal ``n_j`` pointing into the body and unit tangent ``t_j = (n_jy, -n_jx)`` (``n_j``
turned by -90 degrees).  With ``u x v = u_x v_y - u_y v_x``, the body point at the contact moves
with ``v + omega x r_j``: normal speed ``d_j' = J_j x'``, ``J_j = [n_jx, n_jy, r_j x n_j]``, and
sliding speed ``u_j = T_j x'``, ``T_j = [t_jx, t_jy, r_j x t_j]`` [m/s].

**Admissible sliding.**  Both contacts closed means ``J x' = 0``: two constraints on three
velocities.  Where ``J`` has rank 2 the twists form the line spanned by
``z = J_1 x J_2`` (:func:`admissible_twist`), so ``(u1, u2) = sigma (T_1 z, T_2 z)``: the geometry
fixes the sliding directions ``s_j = sign(u_j)`` up to one common flip.  :class:`Mechanism` takes
``s1`` and derives ``s2`` (a given ``s2`` is checked, and an inadmissible pair is refused with a
one-line error naming ``s2``).  Degenerate geometries: a contact whose sliding speed vanishes along
the admissible twist cannot slide while both contacts stay closed, and is refused; where ``J`` has
rank 1 (the two contacts on one normal line) the twists form a plane, ``u1`` and ``u2`` are
independent, and ``s2`` must be given (only the zero-speed state is defined there).  The signs are
decided exactly (float evaluation where ``|u_j|`` exceeds ``1e-12 * 12 max |r|``, far above its
rounding error, rational arithmetic on the float inputs otherwise).

**State.**  The body's state is its configuration and one speed along the admissible twist:
``speed`` = ``|u1|`` [m/s], the sliding speed of contact 1 (twist ``speed s1 z / u1``, angular
velocity :attr:`Mechanism.omega`).  ``speed = 0`` is the zero-speed limit (a body starting to slide;
the directions are those of the twist): every velocity term of ``a`` vanishes.

**Contact kinds and the gap's second derivative** (no contact force; ``acc = g + F/m``):

* ``"body_vertex"``: a body vertex on a fixed environment surface (the normal is fixed in the
  world).  ``d_j = n_j . p_j + const``, so ``d_j'' = J_j x'' - omega^2 n_j . r_j``.
* ``"body_side"``: a fixed environment vertex (a table edge) on a flat side of the body (the
  normal turns with the body, ``n_j' = omega x n_j``, and the contact point moves over the side).
  ``d_j = n_j . (q_j - e_j)`` for the body point ``q_j`` at the vertex ``e_j``:
  ``d_j'' = J_j x'' - omega^2 n_j . r_j - 2 omega u_j`` (the transport term ``2 n_j' . q_j'``).

The contact pushes the body with ``f_j w_j``, ``w_j = n_j - mu_j s_j t_j`` (Coulomb friction
against the sliding), i.e. with the generalised force ``f_j W_j``, ``W_j = [w_j; r_j x w_j]``.
With gravity ``g``, a constant force ``F`` and torque ``tau``, ``M x'' = sum_j f_j W_j + [m g + F;
tau]`` turns the two gap equations into eq. (1), ``d'' = B f - a``, with

    b_ij = J_i M^-1 W_j = n_i . w_j / m + (r_i x n_i)(r_j x w_j) / I                      [1/kg]
    a_i  = -(n_i . acc + (r_i x n_i) tau / I - omega^2 n_i . r_i - [body_side] 2 omega u_i)  [m/s^2]

(``b_ij``: response of gap ``i`` to a unit normal force at contact ``j``, SPEC §1).  The contacts are
Kelvin-Voigt springs, ``f_j = -k_j d_j - c_j d_j'`` [N] (eq. (6) unscaled), so the damping of eq. (8)
is ``Q = diag(c)`` and the invariants are those of :func:`atlas.core.contact_modes.invariants` with
``q_j = c_j``.

:func:`admissible_twist`, :func:`mobility` and :func:`free_acceleration` use only ``+ - * /`` on
their arguments, so they evaluate floats, numpy arrays and :class:`fractions.Fraction` alike (the
exact tier of the realisability audit).  Layer 1: numpy only.
"""

from __future__ import annotations

from fractions import Fraction

import numpy as np

__all__ = [
    "BODY_VERTEX",
    "BODY_SIDE",
    "CONTACT_KINDS",
    "tangent",
    "admissible_twist",
    "jacobians",
    "mobility",
    "free_acceleration",
    "sliding_signs",
    "twist",
]

#: contact kinds (module docstring): a body vertex on an environment surface, an environment
#: vertex on a body side
BODY_VERTEX, BODY_SIDE = "body_vertex", "body_side"
CONTACT_KINDS = (BODY_VERTEX, BODY_SIDE)


def _cross(u, v):
    return u[0] * v[1] - u[1] * v[0]


def dot(u, v):
    """``u . v`` of 2-vectors."""
    return u[0] * v[0] + u[1] * v[1]


def tangent(n):
    """Unit tangent ``t = (n_y, -n_x)`` of a unit normal ``n`` (``n`` turned by -90 degrees)."""
    return (n[1], -n[0])


def admissible_twist(r, n):
    """``z = J_1 x J_2`` (spans the twists ``(v_x, v_y, omega)`` keeping both contacts closed where
    it is nonzero) and the sliding speeds ``(u1, u2) = (T_1 z, T_2 z)`` along it (module
    docstring); ``z = 0`` iff the contacts lie on one normal line (rank-1 ``J``)."""
    c1, c2 = _cross(r[0], n[0]), _cross(r[1], n[1])
    z = (
        n[0][1] * c2 - c1 * n[1][1],
        c1 * n[1][0] - n[0][0] * c2,
        n[0][0] * n[1][1] - n[0][1] * n[1][0],
    )
    u = tuple(dot(tangent(n[j]), z[:2]) + _cross(r[j], tangent(n[j])) * z[2] for j in (0, 1))
    return z, u


def jacobians(r, n):
    """``(J_n, J_t)``: rows ``[n_jx, n_jy, r_j x n_j]`` and ``[t_jx, t_jy, r_j x t_j]`` of the contacts
    at ``r`` [m] with unit normals ``n`` (module docstring): ``d' = J_n x'``, ``u = J_t x'``."""
    rows = lambda e: np.array([[*e(nj), _cross(rj, e(nj))] for rj, nj in zip(r, n)])  # noqa: E731
    return rows(lambda nj: nj), rows(tangent)


def mobility(m, I, r, n, mu, s):
    """``B`` of eq. (1) [1/kg] as ``((b11, b12), (b21, b22))``.

    ``r = (r1, r2)`` contact positions [m], ``n = (n1, n2)`` unit normals, ``mu = (mu1, mu2)``,
    ``s = (s1, s2)`` sliding signs along ``t_j`` (module docstring).
    """
    w = [_sub(n[j], _scale(mu[j] * s[j], tangent(n[j]))) for j in (0, 1)]
    return tuple(
        tuple(dot(n[i], w[j]) / m + _cross(r[i], n[i]) * _cross(r[j], w[j]) / I for j in (0, 1))
        for i in (0, 1)
    )


def free_acceleration(
    m, I, r, n, g, F=(0, 0), tau=0, omega=0, u=(0, 0), kinds=(BODY_VERTEX, BODY_VERTEX)
):
    """``a`` of eq. (1) [m/s^2]: minus the gap accelerations without contact forces, ``(a1, a2)``.

    ``omega`` [rad/s] and the sliding speeds ``u`` [m/s] of the state (:func:`twist`); ``kinds``
    the contact kinds (:data:`CONTACT_KINDS`: a ``body_side`` contact has the transport term
    ``2 omega u_j``, module docstring).
    """
    acc = (g[0] + F[0] / m, g[1] + F[1] / m)
    out = []
    for i in (0, 1):
        ai = -(dot(n[i], acc) + _cross(r[i], n[i]) * tau / I - omega * omega * dot(n[i], r[i]))
        if kinds[i] == BODY_SIDE:
            ai = ai + 2 * omega * u[i]
        out.append(ai)
    return tuple(out)


def _sub(u, v):
    return (u[0] - v[0], u[1] - v[1])


def _scale(k, u):
    return (k * u[0], k * u[1])


def first_bad(x, bad):
    """The first value of ``x`` where ``bad`` holds (``x`` itself for a scalar): for error messages."""
    return np.asarray(x)[bad].flat[0] if np.ndim(x) else x


def _exact(x) -> Fraction:
    return Fraction(float(x))


def sliding_signs(r, n, s1, s2=None):
    """``(s2, rank1)``: the sliding sign of contact 2 admissible with ``s1`` (module docstring).

    ``r``, ``n``: contact positions [m] and unit normals (floats or broadcastable arrays); the
    signs of ``u_j`` along :func:`admissible_twist` are exact.  ``s2 = None`` derives it; a given
    ``s2`` is checked.  Raises a one-line ``ValueError`` for an inadmissible pair (``s2``), a contact
    that cannot slide (``s1``/``s2``), or a rank-1 geometry without ``s2``.
    """
    z, u = admissible_twist(r, n)
    scale = 12.0 * np.max(np.abs(np.array(np.broadcast_arrays(*r[0], *r[1]))), axis=0)
    shape = np.broadcast_shapes(*(np.shape(x) for x in (*z, *u, scale)))
    sign = [np.broadcast_to(np.sign(uj), shape).astype(int) for uj in u]
    rank1 = np.zeros(shape, bool)
    near = (np.abs(u[0]) <= 1e-12 * scale) | (np.abs(u[1]) <= 1e-12 * scale)
    near = np.broadcast_to(near, shape)
    if np.any(near):
        sign = [s.copy() for s in sign]
        comps = [np.broadcast_to(c, shape) for c in (*r[0], *r[1], *n[0], *n[1])]
        for idx in zip(*np.nonzero(near)) if shape else [()]:
            x = [_exact(c[idx]) for c in comps]
            ze, ue = admissible_twist((x[0:2], x[2:4]), (x[4:6], x[6:8]))
            rank1[idx] = not any(ze)
            for j in (0, 1):
                sign[j][idx] = (ue[j] > 0) - (ue[j] < 0)
    ratio = lambda mask: float(first_bad(np.broadcast_to(u[1] / u[0], shape), mask))  # noqa: E731
    if np.any(rank1):
        if s2 is None:
            raise ValueError(
                "s2: the contacts lie on one normal line, so the twist space is 2-D and the "
                "sliding speeds are independent: give s2"
            )
        full = ~rank1
    else:
        full = np.ones(shape, bool)
    for j in (0, 1):
        stuck = full & (sign[j] == 0)
        if np.any(stuck):
            raise ValueError(
                f"s{j + 1}: contact {j + 1} cannot slide while both contacts stay closed (its "
                "sliding speed along the admissible twist is zero)"
            )
    derived = s1 * sign[0] * sign[1]
    if s2 is None:
        out = derived
    else:
        bad = full & (derived != s2)
        if np.any(bad):
            raise ValueError(
                f"s2: inadmissible pair (s1, s2) = ({s1}, {s2}): with both contacts closed the "
                f"sliding speeds are tied, u2/u1 = {ratio(bad):.4g}, so s2 = {-s2} for s1 = {s1}"
            )
        out = np.broadcast_to(s2, shape)
    if not shape:
        return int(out), bool(rank1)
    return out.astype(int), rank1


def twist(r, n, s1, speed):
    """``((v_x, v_y, omega), (u1, u2))`` of the state with contact 1 sliding at ``speed`` [m/s]
    (``>= 0``) in direction ``s1`` along the admissible twist (:func:`admissible_twist`; a contact
    that cannot slide is refused by :func:`sliding_signs` first).  ``speed = 0``: all zero."""
    z, u = admissible_twist(r, n)
    with np.errstate(invalid="ignore", divide="ignore"):
        k = np.where(np.asarray(speed) == 0, 0.0, np.asarray(speed) * s1 / np.asarray(u[0]))
    if np.ndim(k) == 0:
        k = float(k)
    return tuple(k * c for c in z), (k * u[0], k * u[1])
