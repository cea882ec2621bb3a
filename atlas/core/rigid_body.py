"""A planar rigid body with two sliding point contacts: from masses and contacts to the atlas.

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

**Scalings that keep every verdict** (SPEC §1: verdicts depend only on ``beta1, beta2, alpha``,
``kappa``, ``q1_hat``, ``q2_hat``): mass ``(m, I, F, tau, k, c) -> lambda (m, I, F, tau, k, c)``
(``B -> B/lambda``); length ``(r, I, tau, speed) -> (lambda r, lambda^2 I, lambda tau,
sqrt(lambda) speed)`` (``B``, ``a`` unchanged); gravity ``(g, F, tau, speed) -> (lambda g,
lambda F, lambda tau, sqrt(lambda) speed)`` (``a -> lambda a``); contacts ``(k, c) -> (lambda k,
sqrt(lambda) c)``.

:func:`admissible_twist`, :func:`mobility` and :func:`free_acceleration` use only ``+ - * /`` on
their arguments, so they evaluate floats, numpy arrays and :class:`fractions.Fraction` alike (the
exact tier of the realisability audit).  One validation (:func:`check_body`, :func:`sliding_signs`
and the checks of the built-in geometries) serves :class:`Mechanism`, :func:`body_invariants` and
the mechanism atlases: every bad value is a one-line ``ValueError`` naming the parameter.  Layer 1:
numpy and JAX only.

**Built-in bodies** (classmethods): :meth:`Mechanism.ladder` (floor and wall; the classical
Painleve rod at its foot, threshold ``mu = 4/3``: P. Painleve 1905, F. Genot & B. Brogliato,
Eur. J. Mech. A 18 (1999) 653-677, A. R. Champneys & P. L. Varkonyi, IMA J. Appl. Math. 81 (2016)
538-568), :meth:`Mechanism.two_legged` (a chair or biped on a floor, the two-contact postures of
Y. Or & E. Rimon, Nonlinear Dyn. 67 (2012) 1647-1668) and :meth:`Mechanism.leaning_rod` (a rod on
the floor resting on a table edge: a ``body_side`` contact).  Their default numbers are
illustrative, except the ladder's 4-to-1 angle.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from fractions import Fraction
from functools import cached_property

import numpy as np

from atlas.core import checks
from atlas.core.contact_space import ContactSpace, verdict_names, verdicts_at

__all__ = [
    "Mechanism",
    "BODIES",
    "BODY_VERTEX",
    "BODY_SIDE",
    "CONTACT_KINDS",
    "admissible_twist",
    "jacobians",
    "sliding_signs",
    "twist",
    "check_body",
    "body_invariants",
    "mobility",
    "free_acceleration",
    "tangent",
    "verdicts_at",
    "verdict_names",
]

_TWO_PI = 2.0 * math.pi
#: contact kinds (module docstring): a body vertex on an environment surface, an environment
#: vertex on a body side
BODY_VERTEX, BODY_SIDE = "body_vertex", "body_side"
CONTACT_KINDS = (BODY_VERTEX, BODY_SIDE)
#: a sliding vector is tangent if its normal component is at most this fraction of its length
TANGENT_TOL = 1e-9


def _cross(u, v):
    return u[0] * v[1] - u[1] * v[0]


def _dot(u, v):
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
    u = tuple(_dot(tangent(n[j]), z[:2]) + _cross(r[j], tangent(n[j])) * z[2] for j in (0, 1))
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
        tuple(_dot(n[i], w[j]) / m + _cross(r[i], n[i]) * _cross(r[j], w[j]) / I for j in (0, 1))
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
        ai = -(_dot(n[i], acc) + _cross(r[i], n[i]) * tau / I - omega * omega * _dot(n[i], r[i]))
        if kinds[i] == BODY_SIDE:
            ai = ai + 2 * omega * u[i]
        out.append(ai)
    return tuple(out)


def _sub(u, v):
    return (u[0] - v[0], u[1] - v[1])


def _scale(k, u):
    return (k * u[0], k * u[1])


# --- validation (one-line errors naming the parameter; scalars or arrays) ------------------------


def _first(x, bad):
    return np.asarray(x)[bad].flat[0] if np.ndim(x) else x


def _real(name, v, *, low=None, high=None, open_low=False, open_high=False):
    """``v`` as float (or float64 array), finite and within the bounds; else a one-line error."""
    x = checks.real(name, v, finite=False)  # booleans, strings, complex numbers refused
    bad = ~np.isfinite(x)
    if np.any(bad):
        raise ValueError(f"{name}: must be finite, got {_first(x, bad)}")
    for bound, is_open, below, word in ((low, open_low, True, ">"), (high, open_high, False, "<")):
        if bound is None:
            continue
        if below:
            bad = x <= bound if is_open else x < bound
        else:
            bad = x >= bound if is_open else x > bound
        if np.any(bad):
            op = word if is_open else word + "="
            raise ValueError(f"{name}: must be {op} {_fmt_bound(bound)}, got {_first(x, bad)}")
    return float(x) if x.ndim == 0 else x


def _fmt_bound(b):
    return "pi/2" if b == math.pi / 2 else f"{b:g}"


def _vector(name, v):
    try:
        parts = tuple(v)
    except TypeError:
        raise ValueError(f"{name}: must be a 2-vector, got {v!r}") from None
    if len(parts) != 2:
        raise ValueError(f"{name}: must be a 2-vector, got {len(parts)} components")
    return tuple(_real(name, p) for p in parts)


def _unit(name, v):
    x, y = _vector(name, v)
    norm = np.hypot(x, y)
    if np.any(norm == 0.0):
        raise ValueError(f"{name}: normal has zero length")
    return (x / norm, y / norm) if np.ndim(norm) else (float(x / norm), float(y / norm))


def _sign_input(name, s, n):
    """``s_j = +-1``, or the sign along ``t_j`` of a sliding vector tangent to the surface."""
    if s is None:
        return None
    if np.ndim(s) == 0 and not isinstance(s, (tuple, list)):
        if isinstance(s, bool) or s not in (1, -1):
            raise ValueError(f"{name}: sliding sign must be +1 or -1, got {s!r}")
        return int(s)
    vec = _vector(name, s)
    along, off = _dot(vec, tangent(n)), _dot(vec, n)
    if np.ndim(along):
        raise ValueError(f"{name}: a sliding vector must be one vector, not arrays")
    if along == 0.0 or abs(off) > TANGENT_TOL * math.hypot(*vec):
        raise ValueError(
            f"{name}: sliding vector {tuple(float(c) for c in vec)} is not tangent to the surface "
            f"(normal component {float(off):.3g})"
        )
    return 1 if along > 0 else -1


def check_body(body: dict) -> dict:
    """Validated body parameters (scalars or broadcastable arrays), ``s2`` derived or checked.

    Keys: ``m, I`` [kg, kg m^2] ``> 0``; ``r1, r2`` [m] distinct; ``n1, n2`` nonzero (normalised);
    ``mu1, mu2 >= 0``; ``s1`` (``+-1`` or a tangent vector, default +1); ``s2`` (``None``: derived,
    :func:`sliding_signs`); ``kind1, kind2`` in :data:`CONTACT_KINDS` (default ``body_vertex``).
    Returns the same keys (plus ``rank1``: the contacts lie on one normal line); raises a one-line
    ``ValueError`` naming the first bad parameter.
    """
    out = {
        "m": _real("m", body["m"], low=0.0, open_low=True),
        "I": _real("I", body["I"], low=0.0, open_low=True),
    }
    for key in ("r1", "r2"):
        out[key] = _vector(key, body[key])
    for key in ("n1", "n2"):
        out[key] = _unit(key, body[key])
    same = np.logical_and(out["r1"][0] == out["r2"][0], out["r1"][1] == out["r2"][1])
    if np.any(same):
        raise ValueError(f"r2: contact coincides with r1 = {_point(out['r1'], same)}")
    for key in ("mu1", "mu2"):
        out[key] = _real(key, body.get(key, 0.0), low=0.0)
    for key in ("kind1", "kind2"):
        kind = body.get(key, BODY_VERTEX)
        if kind not in CONTACT_KINDS:
            raise ValueError(f"{key}: unknown contact kind {kind!r} ({', '.join(CONTACT_KINDS)})")
        out[key] = kind
    s1 = _sign_input("s1", body.get("s1", 1), out["n1"])
    s2 = _sign_input("s2", body.get("s2"), out["n2"])
    out["s1"], out["s2"], out["rank1"] = (
        s1,
        *sliding_signs((out["r1"], out["r2"]), (out["n1"], out["n2"]), s1, s2),
    )
    return out


def _point(r, mask):
    if np.ndim(mask):
        return tuple(float(np.broadcast_to(c, mask.shape)[mask].flat[0]) for c in r)
    return tuple(float(c) for c in r)


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
    ratio = lambda mask: float(_first(np.broadcast_to(u[1] / u[0], shape), mask))  # noqa: E731
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


# --- the body ----------------------------------------------------------------------------------


_BODY_KEYS = ("m", "I", "r1", "r2", "n1", "n2", "mu1", "mu2", "s1", "s2", "kind1", "kind2")


@dataclasses.dataclass(frozen=True)
class Mechanism:
    """A planar rigid body with two sliding point contacts under gravity (SI units).

    Parameters
    ----------
    m, I : float
        Mass [kg] and moment of inertia about the centre of mass [kg m^2], ``> 0``.
    r1, r2 : 2-vectors
        Contact positions relative to the centre of mass [m] (distinct).
    n1, n2 : 2-vectors
        Surface normals, pointing into the body (normalised here; nonzero).
    mu1, mu2 : float
        Coulomb friction coefficients [1], ``>= 0``.
    s1 : +1, -1 or 2-vector
        Sliding direction of contact 1: the sign of its tangential velocity along
        ``t_1 = (n_1y, -n_1x)``, or a vector along that velocity (tangent to the surface; stored as
        the sign).
    s2 : None, +1, -1 or 2-vector
        Sliding direction of contact 2.  ``None`` (default): derived from ``s1`` and the geometry
        (both contacts closed leave one twist, module docstring).  Given: checked, and an
        inadmissible pair is a ``ValueError`` naming ``s2``.  Required where the contacts lie on
        one normal line (two independent sliding speeds).
    kind1, kind2 : str
        ``"body_vertex"`` (a body vertex on an environment surface, default) or ``"body_side"`` (an
        environment vertex on a flat side of the body): the velocity terms of ``a`` differ.
    k1, k2 : float
        Contact stiffnesses [N/m], ``> 0``.  Without damping only ``kappa`` (their ratio weighted
        by ``|b_j|``) matters; with damping ``q1_hat, q2_hat`` scale with ``1/sqrt(k2)``, so the
        absolute stiffness matters too.
    c1, c2 : float
        Contact damping [N s/m], ``>= 0``.
    g, F : 2-vectors
        Gravity [m/s^2] (default ``(0, -9.81)``) and a constant external force [N] at the centre of
        mass.
    tau : float
        Constant external torque [N m].
    speed : float
        Sliding speed of contact 1 [m/s], ``>= 0``: the state's one speed along the admissible
        twist (:attr:`twist`, :attr:`omega`).  0 (default): the zero-speed limit, no velocity term
        in ``a``.
    name : str
        A label.
    """

    m: float
    I: float
    r1: tuple
    r2: tuple
    n1: tuple
    n2: tuple
    mu1: float = 0.0
    mu2: float = 0.0
    s1: object = 1
    s2: object = None
    kind1: str = BODY_VERTEX
    kind2: str = BODY_VERTEX
    k1: float = 1e5
    k2: float = 1e5
    c1: float = 0.0
    c2: float = 0.0
    g: tuple = (0.0, -9.81)
    F: tuple = (0.0, 0.0)
    tau: float = 0.0
    speed: float = 0.0
    name: str = "custom"
    _derived_s2: bool = dataclasses.field(default=False, init=False, repr=False, compare=False)

    def __post_init__(self):
        put = functools.partial(object.__setattr__, self)
        put("_derived_s2", self.s2 is None)
        body = check_body({k: getattr(self, k) for k in _BODY_KEYS})
        for key in _BODY_KEYS:
            put(key, body[key])
        for key in ("g", "F"):
            put(key, _vector(key, getattr(self, key)))
        for key in ("c1", "c2"):
            put(key, _real(key, getattr(self, key), low=0.0))
        for key in ("k1", "k2"):
            put(key, _real(key, getattr(self, key), low=0.0, open_low=True))
        put("tau", _real("tau", self.tau))
        put("speed", _real("speed", self.speed, low=0.0))
        if body["rank1"] and self.speed:
            raise ValueError(
                "speed: the contacts lie on one normal line (two independent sliding speeds); "
                "only the zero-speed state is defined"
            )

    # --- state ------------------------------------------------------------------------------

    @cached_property
    def _state(self):
        return twist(self._r, self._n, self.s1, self.speed)

    @property
    def twist(self) -> tuple:
        """``(v_x, v_y, omega)`` [m/s, m/s, rad/s] of the state (centre of mass, angular velocity)."""
        return self._state[0]

    @property
    def omega(self) -> float:
        """Angular velocity [rad/s] of the state."""
        return self._state[0][2]

    @property
    def sliding_speeds(self) -> tuple:
        """``(u1, u2)`` [m/s]: the contacts' sliding velocities along ``t_j`` (signs ``s1, s2``)."""
        return self._state[1]

    # --- matrices of eq. (1) ---------------------------------------------------------------

    @property
    def generalized_mass(self) -> np.ndarray:
        """``M = diag(m, m, I)`` of the coordinates ``(x_c, y_c, phi)``."""
        return np.diag([self.m, self.m, self.I])

    @property
    def normal_jacobian(self) -> np.ndarray:
        """Rows ``J_j = [n_jx, n_jy, r_j x n_j]``: ``d_j' = J_j x'`` [1, 1, m]."""
        return jacobians(self._r, self._n)[0]

    @property
    def tangent_jacobian(self) -> np.ndarray:
        """Rows ``[t_jx, t_jy, r_j x t_j]``: tangential velocity of contact ``j`` along ``t_j``."""
        return jacobians(self._r, self._n)[1]

    @cached_property
    def B(self) -> np.ndarray:
        """``B`` of eq. (1) [1/kg]: ``b_ij`` = gap ``i``'s response to a unit normal force at ``j``."""
        return np.array(mobility(self.m, self.I, self._r, self._n, self._mu, (self.s1, self.s2)))

    @cached_property
    def a(self) -> np.ndarray:
        """``a`` of eq. (1) [m/s^2] at the state (velocity terms by contact kind)."""
        acc = free_acceleration(
            self.m, self.I, self._r, self._n, self.g, self.F, self.tau, self.omega,
            self.sliding_speeds, (self.kind1, self.kind2),
        )  # fmt: skip
        return np.array(acc) + 0.0  # no -0.0

    @property
    def _r(self):
        return (self.r1, self.r2)

    @property
    def _n(self):
        return (self.n1, self.n2)

    @property
    def _mu(self):
        return (self.mu1, self.mu2)

    # --- invariants and verdicts -----------------------------------------------------------

    @cached_property
    def contact_space(self) -> ContactSpace:
        """The body's contact-space data (:class:`atlas.core.contact_space.ContactSpace`): ``B``,
        ``a``, ``k``, ``c``; the verdicts of every mechanism are taken from it."""
        return ContactSpace(self.B, self.a, k=(self.k1, self.k2), c=(self.c1, self.c2))

    @property
    def generalized_force(self) -> np.ndarray:
        """``Q = [m g + F; tau]`` [N, N, N m]: the generalised force without contact forces."""
        return np.array([self.m * self.g[0] + self.F[0], self.m * self.g[1] + self.F[1], self.tau])

    @cached_property
    def invariants(self) -> dict:
        """``beta1, beta2, alpha`` [rad, in [0, 2 pi)] and ``kappa, q1, q2`` [1] (SPEC §1)."""
        return self.contact_space.invariants()

    def verdicts(self, dtype="float64") -> dict:
        """Every verdict of the atlas at this body's invariants (see :func:`verdicts_at`)."""
        return self.contact_space.verdicts(dtype)

    def replace(self, **changes) -> Mechanism:
        """A copy with some parameters changed (validated again; a derived ``s2`` is derived
        again unless given)."""
        if self._derived_s2 and "s2" not in changes:
            changes["s2"] = None
        return dataclasses.replace(self, **changes)

    # --- built-in bodies -------------------------------------------------------------------

    @classmethod
    def ladder(cls, **kw):
        """A leaning ladder (:func:`ladder_body`; keyword arguments of that function or of the
        dataclass)."""
        return cls._built(ladder_body, kw)

    @classmethod
    def two_legged(cls, **kw):
        """A body on two legs on a floor (:func:`two_legged_body`)."""
        return cls._built(two_legged_body, kw)

    @classmethod
    def leaning_rod(cls, **kw):
        """A rod on the floor resting on a table edge (:func:`leaning_rod_body`)."""
        return cls._built(leaning_rod_body, kw)

    @classmethod
    def _built(cls, body, kw):
        names = body.__code__.co_varnames[: body.__code__.co_kwonlyargcount]
        geometry = {k: kw.pop(k) for k in list(kw) if k in names}
        return cls(**{**body(**geometry), **kw})


# --- built-in bodies: array-friendly geometry (numpy broadcasting over any parameter) ----------

_HALF_PI = math.pi / 2


def _angle_open(name, theta):
    return _real(name, theta, low=0.0, high=_HALF_PI, open_low=True, open_high=True)


def ladder_body(*, L=4.0, theta=math.acos(0.25), m=15.0, mu_floor=0.4, mu_wall=0.4) -> dict:
    """A uniform ladder (rod, ``I = m L^2 / 12``) on a floor (contact 1, its foot) leaning on a
    wall on its left (contact 2, its top), at ``theta`` [rad] in ``(0, pi/2)`` from the floor,
    ``L > 0`` [m], slipping down: the foot slides away from the wall (``s1 = +1`` along
    ``t1 = (1, 0)``), and then the top slides down (``s2 = +1`` along ``t2 = (0, -1)``, derived) while
    the ladder turns at ``omega = speed / (L sin theta)``.  Both contacts are body vertices.  Default
    geometry: the 4-to-1 rule for leaning ladders (foot one quarter of the length from the wall,
    ``cos theta = 1/4``, US OSHA 29 CFR 1926.1053(b)(5)(i)); mass and friction are illustrative.
    The foot alone has Painleve's paradox (``b11 < 0``) iff
    ``mu_floor > (1 + 3 cos^2) / (3 sin cos)``, at least 4/3 (at ``tan theta = 2``): the classical
    rod (Genot & Brogliato 1999)."""
    L = _real("L", L, low=0.0, open_low=True)
    theta = _angle_open("theta", theta)
    m = _real("m", m, low=0.0, open_low=True)
    mu_floor, mu_wall = _real("mu_floor", mu_floor, low=0.0), _real("mu_wall", mu_wall, low=0.0)
    c, s, half = np.cos(theta), np.sin(theta), L / 2
    return dict(
        m=m,
        I=m * L * L / 12,
        r1=(half * c, -half * s),
        r2=(-half * c, half * s),
        n1=(0.0, 1.0),
        n2=(1.0, 0.0),
        mu1=mu_floor,
        mu2=mu_wall,
        s1=1,
        name="ladder",
    )


def two_legged_body(*, d=0.2, h=0.5, m=5.0, I=None, mu1=0.3, mu2=0.3) -> dict:
    """A body on two legs on a floor (a chair, a two-legged rod, a biped's feet): leg 1 at
    ``(-d, -h)``, leg 2 at ``(+d, -h)`` from the centre of mass (``d > 0``, ``h >= 0`` [m]), both
    sliding along ``+x`` (leg 2 leads; the admissible twist is a translation, ``s2 = s1``).
    ``I`` defaults to a uniform ``2d x 2h`` plate, ``m (d^2 + h^2) / 3``.  The leading leg has
    Painleve's paradox (``b22 < 0``) iff ``mu2 h d > I/m + d^2`` (for the plate:
    ``mu2 > (4 d^2 + h^2) / (3 h d) >= 4/3``).  Illustrative numbers (a chair)."""
    d = _real("d", d, low=0.0, open_low=True)
    h = _real("h", h, low=0.0)
    m = _real("m", m, low=0.0, open_low=True)
    mu1, mu2 = _real("mu1", mu1, low=0.0), _real("mu2", mu2, low=0.0)
    if I is None:
        I = m * (d * d + h * h) / 3
    return dict(
        m=m,
        I=_real("I", I, low=0.0, open_low=True),
        r1=(-d, -h),
        r2=(d, -h),
        n1=(0.0, 1.0),
        n2=(0.0, 1.0),
        mu1=mu1,
        mu2=mu2,
        s1=1,
        name="two_legged",
    )


def leaning_rod_body(*, L=1.0, theta=math.pi / 6, e=0.25, m=1.0, mu_floor=0.5, mu_edge=0.5) -> dict:
    """A uniform rod (``I = m L^2 / 12``, ``L > 0`` [m]) with its lower end on the floor (contact 1,
    a body vertex) resting on a table edge (contact 2, an environment vertex on the rod's side:
    ``body_side``) at ``e`` [m] above the centre along the rod (``-L/2 < e < L/2``), at ``theta`` in
    ``(0, pi/2)`` from the floor, slipping down: the foot slides away (``+x``), and then the rod
    slides down over the edge (the edge's normal ``(sin, cos)`` is perpendicular to the rod, its
    tangent ``(cos, -sin)`` points down the rod: ``s2 = +1``, derived).  Illustrative numbers."""
    L = _real("L", L, low=0.0, open_low=True)
    theta = _angle_open("theta", theta)
    half = L / 2
    e = _real("e", e)
    off = np.abs(e) >= half
    if np.any(off):
        raise ValueError(
            f"e: the table edge must lie on the rod, -L/2 < e < L/2, got e = {_first(e, off)}"
        )
    m = _real("m", m, low=0.0, open_low=True)
    mu_floor, mu_edge = _real("mu_floor", mu_floor, low=0.0), _real("mu_edge", mu_edge, low=0.0)
    c, s = np.cos(theta), np.sin(theta)
    return dict(
        m=m,
        I=m * L * L / 12,
        r1=(half * c, -half * s),
        r2=(-e * c, e * s),
        n1=(0.0, 1.0),
        n2=(s, c),
        mu1=mu_floor,
        mu2=mu_edge,
        s1=1,
        kind2=BODY_SIDE,
        name="leaning_rod",
    )


def body_invariants(body: dict, k1=1e5, k2=1e5, c1=0.0, c2=0.0, speed=0.0, g=(0.0, -9.81)) -> dict:
    """Invariants (SPEC §1) of a body given as arrays (the geometry functions above): ``beta1,
    beta2, alpha`` [rad, in [0, 2 pi)], ``kappa, q1, q2`` [1], and ``B`` [1/kg], ``a`` [m/s^2] as
    ``b11 ... a2``, ``s2`` (derived), ``omega`` [rad/s]; every entry broadcasts over the
    parameters' shapes.  Validated like :class:`Mechanism` (:func:`check_body`); ``k1, k2`` [N/m],
    ``c1, c2`` [N s/m], ``speed`` [m/s] (contact 1), ``g`` [m/s^2]."""
    p = check_body(body)
    k1, k2 = (_real(k, v, low=0.0, open_low=True) for k, v in (("k1", k1), ("k2", k2)))
    c1, c2 = (_real(k, v, low=0.0) for k, v in (("c1", c1), ("c2", c2)))
    speed, g = _real("speed", speed, low=0.0), _vector("g", g)
    if np.any(p["rank1"] & (np.asarray(speed) != 0)):
        raise ValueError("speed: the contacts lie on one normal line; only speed = 0 is defined")
    r, n = (p["r1"], p["r2"]), (p["n1"], p["n2"])
    (b11, b12), (b21, b22) = mobility(
        p["m"], p["I"], r, n, (p["mu1"], p["mu2"]), (p["s1"], p["s2"])
    )
    (_vx, _vy, omega), u = twist(r, n, p["s1"], speed)
    kinds = (p["kind1"], p["kind2"])
    a1, a2 = free_acceleration(p["m"], p["I"], r, n, g, omega=omega, u=u, kinds=kinds)
    ang = lambda x, y: np.mod(np.arctan2(y, x), _TWO_PI) + 0.0  # noqa: E731
    nb1, nb2 = np.hypot(b11, b21), np.hypot(b12, b22)
    scale = np.sqrt(k2 * nb2)
    out = dict(beta1=ang(b11, b21), beta2=ang(b12, b22), alpha=ang(a1, a2))
    out.update(kappa=k1 * nb1 / (k2 * nb2), q1=c1 * nb1 / scale, q2=c2 * nb2 / scale)
    out.update(b11=b11, b12=b12, b21=b21, b22=b22, a1=a1, a2=a2, s2=p["s2"], omega=omega)
    return {k: np.asarray(v, np.float64) for k, v in out.items()}


BODIES = {"ladder": ladder_body, "two_legged": two_legged_body, "leaning_rod": leaning_rod_body}
