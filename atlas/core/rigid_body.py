"""A planar rigid body with two sliding point contacts: from masses and contacts to the atlas.

:class:`Mechanism` holds a body (masses, contact positions and normals, friction, the sliding
directions, the contact model and the state) and gives ``B`` and ``a`` of eq. (1), the invariants
and every verdict.  The mechanics are in :mod:`atlas.core.body_kinematics` (the derivation: twists,
Jacobians, ``B``, ``a``, the contact kinds), the one validation in :mod:`atlas.core.body_checks`,
the built-in bodies in the registry :mod:`atlas.core.bodies` (``Mechanism.<name>(**kw)`` for every
registered body, e.g. :meth:`Mechanism.ladder`); their names are re-exported here.

**Scalings that keep every verdict** (SPEC §1: verdicts depend only on ``beta1, beta2, alpha``,
``kappa``, ``q1_hat``, ``q2_hat``): mass ``(m, I, F, tau, k, c) -> lambda (m, I, F, tau, k, c)``
(``B -> B/lambda``); length ``(r, I, tau, speed) -> (lambda r, lambda^2 I, lambda tau,
sqrt(lambda) speed)`` (``B``, ``a`` unchanged); gravity ``(g, F, tau, speed) -> (lambda g,
lambda F, lambda tau, sqrt(lambda) speed)`` (``a -> lambda a``); contacts ``(k, c) -> (lambda k,
sqrt(lambda) c)``.

One validation (:func:`check_body`, :func:`sliding_signs` and the declared ranges of the built-in
bodies' parameters) serves :class:`Mechanism`, :func:`body_invariants` and the mechanism atlases:
every bad value is a one-line ``ValueError`` naming the parameter.  Layer 1: numpy and JAX only.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from functools import cached_property

import numpy as np

from atlas.core import bodies
from atlas.core.bodies import BODIES, ladder_body, leaning_rod_body, two_legged_body
from atlas.core.body_checks import TANGENT_TOL, check_body
from atlas.core.body_checks import real as _real
from atlas.core.body_checks import vector as _vector
from atlas.core.body_kinematics import (
    BODY_SIDE,
    BODY_VERTEX,
    CONTACT_KINDS,
    admissible_twist,
    free_acceleration,
    jacobians,
    mobility,
    sliding_signs,
    tangent,
    twist,
)
from atlas.core.contact_space import ContactSpace, verdict_names, verdicts_at

__all__ = [
    "Mechanism",
    "BODIES",
    "BODY_VERTEX",
    "BODY_SIDE",
    "CONTACT_KINDS",
    "TANGENT_TOL",
    "admissible_twist",
    "jacobians",
    "sliding_signs",
    "twist",
    "tangent",
    "check_body",
    "body_invariants",
    "mobility",
    "free_acceleration",
    "ladder_body",
    "two_legged_body",
    "leaning_rod_body",
    "verdicts_at",
    "verdict_names",
]

_TWO_PI = 2.0 * math.pi


class _Bodies(type):
    """``Mechanism.<name>(**kw)`` for every body of the registry :data:`atlas.core.bodies.BODIES`."""

    def __getattr__(cls, name):
        if name in bodies.BODIES:
            return functools.partial(cls.built, name)
        raise AttributeError(f"type object {cls.__name__!r} has no attribute {name!r}")

    def __dir__(cls):
        return sorted(set(super().__dir__()) | set(bodies.BODIES))


_BODY_KEYS = ("m", "I", "r1", "r2", "n1", "n2", "mu1", "mu2", "s1", "s2", "kind1", "kind2")


@dataclasses.dataclass(frozen=True)
class Mechanism(metaclass=_Bodies):
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
    def built(cls, body: str, **kw) -> Mechanism:
        """The registered body ``body`` (:data:`atlas.core.bodies.BODIES`; also
        ``Mechanism.<body>(**kw)``): keyword arguments are its parameters (checked against their
        declared ranges) or fields of the dataclass."""
        b = bodies.BODIES.get(body)
        if b is None:
            raise ValueError(f"body: unknown {body!r} (built-in: {', '.join(bodies.BODIES)})")
        geometry = {k: kw.pop(k) for k in list(kw) if k in b.params}
        return cls(**{**b(**geometry), **kw})


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
