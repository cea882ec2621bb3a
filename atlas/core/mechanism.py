"""A planar rigid body with two sliding point contacts: from masses and contacts to the atlas.

**Derivation** (paper Sec. 2, eq. (1)).  The body has generalised coordinates ``x = (x_c, y_c, phi)``
(centre of mass [m], angle [rad]) and generalised mass ``M = diag(m, m, I)``.  Contact ``j`` is the
body point at ``r_j`` [m] (world frame, relative to the centre of mass) touching a fixed surface whose
unit normal ``n_j`` points from the surface into the body; its unit tangent is ``n_j`` turned by
-90 degrees, ``t_j = (n_jy, -n_jx)``, and the contact slides along ``s_j t_j`` (``s_j = +-1``).  The gap
``d_j = n_j . p_j + const`` of the contact point ``p_j`` has

    d_j'' = J_j x'' - omega^2 n_j . r_j,          J_j = [n_jx, n_jy, r_j x n_j]   (contact Jacobian)

with ``u x v = u_x v_y - u_y v_x`` and ``omega`` the angular velocity.  The contact pushes the body
with ``f_j w_j``, ``w_j = n_j - mu_j s_j t_j`` (normal component 1, Coulomb friction ``mu_j`` against
the sliding), i.e. with the generalised force ``f_j W_j``, ``W_j = [w_j; r_j x w_j]``.  With gravity
``g``, a constant force ``F`` and torque ``tau``, ``M x'' = sum_j f_j W_j + [m g + F; tau]`` turns the
two gap equations into eq. (1), ``d'' = B f - a``, with

    b_ij = J_i M^-1 W_j = n_i . w_j / m + (r_i x n_i)(r_j x w_j) / I                      [1/kg]
    a_i  = -(n_i . (g + F/m) + (r_i x n_i) tau / I - omega^2 n_i . r_i)                 [m/s^2]

(``b_ij``: response of gap ``i`` to a unit normal force at contact ``j``, SPEC §1).  The contacts are
Kelvin-Voigt springs, ``f_j = -k_j d_j - c_j d_j'`` [N] (eq. (6) unscaled), so the damping of eq. (8)
is ``Q = diag(c)`` and the invariants are those of :func:`atlas.core.mechanics.invariants` with
``q_j = c_j``.

**Scalings that keep every verdict** (SPEC §1: verdicts depend only on ``beta1, beta2, alpha``,
``kappa``, ``q1_hat``, ``q2_hat``): mass ``(m, I, F, tau, k, c) -> lambda (m, I, F, tau, k, c)``
(``B -> B/lambda``); length ``(r, I, tau, omega) -> (lambda r, lambda^2 I, lambda tau,
omega/sqrt(lambda))`` (``B``, ``a`` unchanged); gravity ``(g, F, tau, omega) -> (lambda g, lambda F,
lambda tau, sqrt(lambda) omega)`` (``a -> lambda a``); contacts ``(k, c) -> (lambda k, sqrt(lambda) c)``.

:func:`mobility` and :func:`free_acceleration` use only ``+ - * /`` on their arguments, so they
evaluate floats, numpy arrays and :class:`fractions.Fraction` alike (the exact tier of the
realisability audit).  Layer 1: numpy and JAX only.

**Built-in bodies** (classmethods): :meth:`Mechanism.ladder` (floor and wall; the classical
Painleve rod at its foot, threshold ``mu = 4/3``: P. Painleve 1905, F. Genot & B. Brogliato,
Eur. J. Mech. A 18 (1999) 653-677, A. R. Champneys & P. L. Varkonyi, IMA J. Appl. Math. 81 (2016)
538-568), :meth:`Mechanism.two_legged` (a chair or biped on a floor, the two-contact postures of
Y. Or & E. Rimon, Nonlinear Dyn. 67 (2012) 1647-1668) and :meth:`Mechanism.leaning_rod` (a rod on
the floor resting on a table edge).  Their default numbers are illustrative, except the ladder's
4-to-1 angle.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from functools import cached_property

import jax
import numpy as np

from atlas.core import mechanics as mech
from atlas.core import points
from atlas.core.verdicts import UNDECIDED_CODE, Verdict

__all__ = [
    "Mechanism",
    "BODIES",
    "body_invariants",
    "mobility",
    "free_acceleration",
    "tangent",
    "verdicts_at",
    "VERDICT_NAMES",
]

#: the atlas outputs a single mechanism has (SPEC §2; the ``model_dependent_*`` reductions need
#: several model samples and are not among them)
VERDICT_NAMES = (
    "class_code",
    "subclass_code",
    "consistent_FF",
    "consistent_SF",
    "consistent_FS",
    "consistent_SS",
    "stable_SF",
    "consistent_IF",
    "stable_FS",
    "consistent_FI",
    "cc_possible",
) + points.SPECTRAL_NAMES
_TWO_PI = 2.0 * math.pi


def _cross(u, v):
    return u[0] * v[1] - u[1] * v[0]


def _dot(u, v):
    return u[0] * v[0] + u[1] * v[1]


def tangent(n):
    """Unit tangent ``t = (n_y, -n_x)`` of a unit normal ``n`` (``n`` turned by -90 degrees)."""
    return (n[1], -n[0])


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


def free_acceleration(m, I, r, n, g, F=(0, 0), tau=0, omega=0):
    """``a`` of eq. (1) [m/s^2]: minus the gap accelerations without contact forces, ``(a1, a2)``."""
    acc = (g[0] + F[0] / m, g[1] + F[1] / m)
    return tuple(
        -(_dot(n[i], acc) + _cross(r[i], n[i]) * tau / I - omega * omega * _dot(n[i], r[i]))
        for i in (0, 1)
    )


def _sub(u, v):
    return (u[0] - v[0], u[1] - v[1])


def _scale(k, u):
    return (k * u[0], k * u[1])


# --- validation (one-line errors naming the parameter) -------------------------------------------


def _number(name, v, *, low=None, strict=False):
    try:
        x = float(v)
    except (TypeError, ValueError):
        raise ValueError(f"{name}: cannot interpret {v!r} as a number") from None
    if not math.isfinite(x):
        raise ValueError(f"{name}: must be finite, got {v!r}")
    if low is not None and (x <= low if strict else x < low):
        raise ValueError(f"{name}: must be {'>' if strict else '>='} {low}, got {x}")
    return x


def _vector(name, v):
    try:
        parts = tuple(v)
    except TypeError:
        raise ValueError(f"{name}: must be a 2-vector, got {v!r}") from None
    if len(parts) != 2:
        raise ValueError(f"{name}: must be a 2-vector, got {len(parts)} components")
    return tuple(_number(name, p) for p in parts)


def _unit(name, v):
    x, y = _vector(name, v)
    norm = math.hypot(x, y)
    if norm == 0.0:
        raise ValueError(f"{name}: normal has zero length")
    return (x / norm, y / norm)


def _sliding(name, s, n):
    """``s_j = +-1``, or the sign of a given sliding direction along ``t_j``."""
    if isinstance(s, (int, float)) and not isinstance(s, bool):
        if s not in (1, -1):
            raise ValueError(f"{name}: sliding sign must be +1 or -1, got {s!r}")
        return int(s)
    along = _dot(_vector(name, s), tangent(n))
    if along == 0.0:
        raise ValueError(f"{name}: sliding direction is normal to the surface")
    return 1 if along > 0 else -1


# --- the body ----------------------------------------------------------------------------------


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
    s1, s2 : +1, -1 or 2-vector
        Sliding direction of each contact: the sign of its tangential velocity along
        ``t_j = (n_jy, -n_jx)``, or a vector along that velocity (stored as the sign).
    k1, k2 : float
        Contact stiffnesses [N/m], ``> 0``.  Only ``kappa`` (their ratio, weighted by ``|b_j|``)
        matters.
    c1, c2 : float
        Contact damping [N s/m], ``>= 0``.
    g, F : 2-vectors
        Gravity [m/s^2] (default ``(0, -9.81)``) and a constant external force [N] at the centre of
        mass.
    tau : float
        Constant external torque [N m].
    omega : float
        Angular velocity [rad/s] (its centripetal term enters ``a``; 0: the body only translates).
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
    s2: object = 1
    k1: float = 1e5
    k2: float = 1e5
    c1: float = 0.0
    c2: float = 0.0
    g: tuple = (0.0, -9.81)
    F: tuple = (0.0, 0.0)
    tau: float = 0.0
    omega: float = 0.0
    name: str = "custom"

    def __post_init__(self):
        put = functools.partial(object.__setattr__, self)
        put("m", _number("m", self.m, low=0.0, strict=True))
        put("I", _number("I", self.I, low=0.0, strict=True))
        for key in ("r1", "r2", "g", "F"):
            put(key, _vector(key, getattr(self, key)))
        for key in ("n1", "n2"):
            put(key, _unit(key, getattr(self, key)))
        if self.r1 == self.r2:
            raise ValueError(f"r2: contact coincides with r1 = {self.r1}")
        for key in ("mu1", "mu2", "c1", "c2"):
            put(key, _number(key, getattr(self, key), low=0.0))
        for key in ("k1", "k2"):
            put(key, _number(key, getattr(self, key), low=0.0, strict=True))
        put("tau", _number("tau", self.tau))
        put("omega", _number("omega", self.omega))
        put("s1", _sliding("s1", self.s1, self.n1))
        put("s2", _sliding("s2", self.s2, self.n2))

    # --- matrices of eq. (1) ---------------------------------------------------------------

    @property
    def generalized_mass(self) -> np.ndarray:
        """``M = diag(m, m, I)`` of the coordinates ``(x_c, y_c, phi)``."""
        return np.diag([self.m, self.m, self.I])

    @property
    def normal_jacobian(self) -> np.ndarray:
        """Rows ``J_j = [n_jx, n_jy, r_j x n_j]``: ``d_j' = J_j x'`` [1, 1, m]."""
        return np.array([[*n, _cross(r, n)] for r, n in zip(self._r, self._n)])

    @property
    def tangent_jacobian(self) -> np.ndarray:
        """Rows ``[t_jx, t_jy, r_j x t_j]``: tangential velocity of contact ``j`` along ``t_j``."""
        return np.array([[*tangent(n), _cross(r, tangent(n))] for r, n in zip(self._r, self._n)])

    @cached_property
    def B(self) -> np.ndarray:
        """``B`` of eq. (1) [1/kg]: ``b_ij`` = gap ``i``'s response to a unit normal force at ``j``."""
        return np.array(mobility(self.m, self.I, self._r, self._n, self._mu, (self.s1, self.s2)))

    @cached_property
    def a(self) -> np.ndarray:
        """``a`` of eq. (1) [m/s^2]."""
        acc = free_acceleration(
            self.m, self.I, self._r, self._n, self.g, self.F, self.tau, self.omega
        )
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
    def invariants(self) -> dict:
        """``beta1, beta2, alpha`` [rad, in [0, 2 pi)] and ``kappa, q1, q2`` [1] (SPEC §1)."""
        B, a = self.B, self.a
        if not (a[0] or a[1]):
            raise ValueError("a: the free acceleration is zero, alpha is undefined")
        out = {
            "beta1": _angle(B[0, 0], B[1, 0]),
            "beta2": _angle(B[0, 1], B[1, 1]),
            "alpha": _angle(a[0], a[1]),
        }
        b1, b2 = math.hypot(B[0, 0], B[1, 0]), math.hypot(B[0, 1], B[1, 1])
        out.update(mech.invariants(self.k1, self.k2, self.c1, self.c2, b1, b2))
        return out

    def verdicts(self, dtype="float64") -> dict:
        """Every verdict of the atlas at this body's invariants (see :func:`verdicts_at`)."""
        inv = self.invariants
        res = verdicts_at(**inv, dtype=dtype)
        return {k: v[()] for k, v in res.items()}

    def replace(self, **changes) -> Mechanism:
        """A copy with some parameters changed (validated again)."""
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


def ladder_body(*, L=4.0, theta=math.acos(0.25), m=15.0, mu_floor=0.4, mu_wall=0.4) -> dict:
    """A uniform ladder (rod, ``I = m L^2 / 12``) on a floor (contact 1, its foot) leaning on a
    wall on its left (contact 2, its top), at ``theta`` [rad] from the floor, slipping down: the
    foot slides away from the wall (``s1 = +1`` along ``t1 = (1, 0)``), the top slides down
    (``s2 = +1`` along ``t2 = (0, -1)``).  Default geometry: the 4-to-1 rule for leaning ladders
    (foot one quarter of the length from the wall, ``cos theta = 1/4``, US OSHA 29 CFR
    1926.1053(b)(5)(i)); mass and friction are illustrative.  The foot alone has Painleve's paradox
    (``b11 < 0``) iff ``mu_floor > (1 + 3 cos^2) / (3 sin cos)``, at least 4/3 (at
    ``tan theta = 2``): the classical rod (Genot & Brogliato 1999)."""
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
        s2=1,
        name="ladder",
    )


def two_legged_body(*, d=0.2, h=0.5, m=5.0, I=None, mu1=0.3, mu2=0.3) -> dict:
    """A body on two legs on a floor (a chair, a two-legged rod, a biped's feet): leg 1 at
    ``(-d, -h)``, leg 2 at ``(+d, -h)`` from the centre of mass, both sliding along ``+x`` (leg 2
    leads).  ``I`` defaults to a uniform ``2d x 2h`` plate, ``m (d^2 + h^2) / 3``.  The leading leg
    has Painleve's paradox (``b22 < 0``) iff ``mu2 h d > I/m + d^2`` (for the plate:
    ``mu2 > (4 d^2 + h^2) / (3 h d) >= 4/3``).  Illustrative numbers (a chair)."""
    if I is None:
        I = m * (d * d + h * h) / 3
    return dict(
        m=m,
        I=I,
        r1=(-d, -h),
        r2=(d, -h),
        n1=(0.0, 1.0),
        n2=(0.0, 1.0),
        mu1=mu1,
        mu2=mu2,
        s1=1,
        s2=1,
        name="two_legged",
    )


def leaning_rod_body(*, L=1.0, theta=math.pi / 6, e=0.25, m=1.0, mu_floor=0.5, mu_edge=0.5) -> dict:
    """A uniform rod (``I = m L^2 / 12``) with its lower end on the floor (contact 1) resting on a
    table edge (contact 2) at distance ``e`` [m] above the centre along the rod, at ``theta`` from
    the floor, slipping down: the foot slides away (``+x``), the rod slides down over the edge (the
    edge's normal ``(sin, cos)`` is perpendicular to the rod, its tangent ``(cos, -sin)`` points
    down the rod: ``s2 = +1``).  Illustrative numbers."""
    c, s, half = np.cos(theta), np.sin(theta), L / 2
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
        s2=1,
        name="leaning_rod",
    )


def body_invariants(body: dict, k1=1e5, k2=1e5, c1=0.0, c2=0.0) -> dict:
    """Invariants (SPEC §1) of a body given as arrays (the geometry functions above): ``beta1,
    beta2, alpha`` [rad, in [0, 2 pi)], ``kappa, q1, q2`` [1], and ``B`` [1/kg], ``a`` [m/s^2] as
    ``b11 ... a2``; every entry broadcasts over the parameters' shapes.  ``g = (0, -9.81)``."""
    r, n = (body["r1"], body["r2"]), (body["n1"], body["n2"])
    (b11, b12), (b21, b22) = mobility(
        body["m"], body["I"], r, n, (body["mu1"], body["mu2"]), (body["s1"], body["s2"])
    )
    a1, a2 = free_acceleration(body["m"], body["I"], r, n, (0.0, -9.81))
    ang = lambda x, y: np.mod(np.arctan2(y, x), _TWO_PI) + 0.0  # noqa: E731
    nb1, nb2 = np.hypot(b11, b21), np.hypot(b12, b22)
    scale = np.sqrt(k2 * nb2)
    out = dict(beta1=ang(b11, b21), beta2=ang(b12, b22), alpha=ang(a1, a2))
    out.update(kappa=k1 * nb1 / (k2 * nb2), q1=c1 * nb1 / scale, q2=c2 * nb2 / scale)
    out.update(b11=b11, b12=b12, b21=b21, b22=b22, a1=a1, a2=a2)
    return {k: np.asarray(v, np.float64) for k, v in out.items()}


BODIES = {"ladder": ladder_body, "two_legged": two_legged_body, "leaning_rod": leaning_rod_body}


def _angle(x, y) -> float:
    """Direction angle of ``(x, y)`` in ``[0, 2 pi)`` [rad]."""
    t = math.atan2(y, x) + 0.0  # no -0.0
    return t + _TWO_PI if t < 0 else t


# --- verdicts at invariants --------------------------------------------------------------------


def _angle_codes(c1, s1, c2, s2, ca, sa):
    out = {"class_code": mech.class_code(c1, s1, c2, s2)}
    out["subclass_code"] = mech.subclass_code(c1, s1, c2, s2, ca, sa)
    out.update(
        {f"consistent_{k}": v for k, v in mech.consistent_modes(c1, s1, c2, s2, ca, sa).items()}
    )
    out["stable_SF"], out["consistent_IF"] = mech.stable_SF(c1), mech.consistent_IF(c1, s1)
    out["stable_FS"], out["consistent_FI"] = mech.stable_FS(s2), mech.consistent_FI(c2, s2)
    out["cc_possible"] = mech.cc_possible(c1, s2)
    return out


_angle_kernel = jax.jit(_angle_codes)
_CONSISTENCY = ("consistent_FF", "consistent_SF", "consistent_FS", "consistent_SS")


def _settle_codes(codes: dict, dirs: list) -> None:
    """Undecided class/subclass/Table 1 codes settled exactly (:func:`atlas.core.points.settle_codes`)."""
    undecided = {k: codes[k] == UNDECIDED_CODE for k in ("class_code", "subclass_code")}
    undecided.update({k: codes[k] == int(Verdict.UNDECIDED) for k in _CONSISTENCY})
    points.settle_codes(codes, undecided, *dirs)


def verdicts_at(beta1, beta2, alpha, kappa, q1, q2, *, dtype="float64") -> dict:
    """Every verdict of the atlas (:data:`VERDICT_NAMES`) at broadcastable invariants.

    The angles [rad] enter through :func:`atlas.core.mechanics.direction` in ``dtype``, exactly as
    in :func:`atlas.generate`; undecided codes are settled exactly.  Returns numpy arrays of the
    broadcast shape in the storage types of SPEC §2 (codes ``int8``/``int16``, Table 1, SF/FS
    stability, IF/FI, CC as ``bool``, spectral verdict flags ``int8``, the abscissa float).
    """
    dtype = np.dtype(dtype)
    args = [np.asarray(x, np.float64) for x in (beta1, beta2, alpha, kappa, q1, q2)]
    shape = np.broadcast_shapes(*(x.shape for x in args))
    args = [np.broadcast_to(x, shape) for x in args]
    dirs = [c for ang in args[:3] for c in mech.direction(ang, dtype)]
    codes = {k: np.array(v) for k, v in _angle_kernel(*dirs).items()}
    _settle_codes(codes, dirs)
    spec = points.spectral_points(*dirs[:4], *args[3:], dtype=dtype)
    out = {
        "class_code": codes["class_code"].astype(np.int8),
        "subclass_code": codes["subclass_code"].astype(np.int16),
    }
    for k in (*_CONSISTENCY, "consistent_IF", "consistent_FI", "cc_possible"):
        out[k] = codes[k] == 1
    for k in ("stable_SF", "stable_FS"):
        out[k] = codes[k] == int(Verdict.STABLE)
    out.update({k: np.asarray(spec[k]).reshape(shape) for k in points.SPECTRAL_NAMES})
    return {k: out[k] for k in VERDICT_NAMES}
