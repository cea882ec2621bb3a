"""The body registry: every built-in rigid body is one declaration (:class:`Body`).

A body declares its geometry function (keyword-only parameters -> the parameters of
:class:`atlas.core.rigid_body.Mechanism`: ``m, I, r1, r2, n1, n2, mu1, mu2, s1`` and optionally
``s2, kind1, kind2, name``), each parameter with its units, meaning and range (:class:`Param`), its
physical axes (:class:`Axis`: default range, units, long name, the parameters it sets) and a
description.  From it come ``Mechanism.<name>(**kw)``, the mechanism scene of
:func:`atlas.mechanism_atlas` and ``atlas mechanism NAME`` (choices, help, stored units) and the
README's list (checked by a test).  :func:`register` checks a declaration completely when it is
made (a parameter without units or meaning, an axis setting an unknown parameter or with other
units, a taken name, a geometry that does not build a valid body at its defaults): one line naming
the field.

**Built-in bodies**: ``ladder`` (floor and wall; the classical Painleve rod at its foot, threshold
``mu = 4/3``: P. Painleve 1905, F. Genot & B. Brogliato, Eur. J. Mech. A 18 (1999) 653-677, A. R.
Champneys & P. L. Varkonyi, IMA J. Appl. Math. 81 (2016) 538-568), ``two_legged`` (a chair or biped
on a floor, the two-contact postures of Y. Or & E. Rimon, Nonlinear Dyn. 67 (2012) 1647-1668) and
``leaning_rod`` (a rod on the floor resting on a table edge: a ``body_side`` contact).  Their
default numbers are illustrative, except the ladder's 4-to-1 angle.  Layer 1: numpy only.
"""

from __future__ import annotations

import dataclasses
import inspect
import math
from collections.abc import Callable, Mapping
from types import MappingProxyType
from typing import NamedTuple

import numpy as np

from atlas.core.body_checks import check_body, real
from atlas.core.body_kinematics import BODY_SIDE

__all__ = ["Param", "Axis", "Body", "BODIES", "MODEL", "DERIVED", "register", "unregister"]


@dataclasses.dataclass(frozen=True)
class Param:
    """A parameter of a body: ``units`` (UDUNITS, ``"1"``: dimensionless), ``meaning`` (its
    ``long_name`` in a mechanism atlas) and its range ``low`` .. ``high`` (``None``: unbounded;
    ``open_low``/``open_high``: the bound excluded), checked before the geometry runs."""

    units: str
    meaning: str
    low: float | None = None
    high: float | None = None
    open_low: bool = False
    open_high: bool = False

    def check(self, name: str, value):
        """``value`` as a float (or array) within the range; else a one-line error naming ``name``."""
        bounds = dataclasses.asdict(self)
        del bounds["units"], bounds["meaning"]
        return real(name, value, **bounds)


class Axis(NamedTuple):
    """A physical axis of a body's atlas: ``default`` range (``atlas.data.scene.parse_values``
    syntax), ``units``, ``long_name`` and the body parameters it sets (one value for all)."""

    default: str
    units: str
    long_name: str
    sets: tuple[str, ...]


#: the contact model and the state of every mechanism atlas: units, meaning, default (SI)
MODEL: Mapping[str, tuple[str, str, float]] = MappingProxyType(
    {
        "k1": ("N m-1", "stiffness of contact 1", 1e5),
        "k2": ("N m-1", "stiffness of contact 2", 1e5),
        "c1": ("N s m-1", "damping of contact 1", 0.0),
        "c2": ("N s m-1", "damping of contact 2", 0.0),
        "g": ("m s-2", "gravitational acceleration (along -y)", 9.81),
        "speed": ("m s-1", "sliding speed of contact 1 (0: the zero-speed limit)", 0.0),
    }
)
#: what a mechanism atlas stores of the built body besides its parameters: units, meaning
DERIVED: Mapping[str, tuple[str, str]] = MappingProxyType(
    {
        "m": ("kg", "mass"),
        "I": ("kg m2", "moment of inertia about the centre of mass"),
        "s1": ("1", "sliding direction of contact 1 along its tangent (n turned by -90 degrees)"),
        "s2": (
            "1",
            "sliding direction of contact 2 (admissible: derived from s1 and the geometry)",
        ),
    }
)


@dataclasses.dataclass(frozen=True, eq=False)
class Body:
    """One built-in body (module docstring).  ``geometry``: keyword-only parameters, each with a
    default, -> the :class:`~atlas.core.rigid_body.Mechanism` parameters (numpy broadcasting over
    any parameter); ``params``: a :class:`Param` for each of them; ``axes``: name ->
    :class:`Axis`; ``description``: one sentence.  Calling the body validates the given parameters
    by their ranges and returns the geometry's dict."""

    name: str
    geometry: Callable
    params: Mapping[str, Param]
    axes: Mapping[str, Axis]
    description: str

    def __post_init__(self):
        object.__setattr__(self, "params", MappingProxyType(dict(self.params)))
        axes = {k: Axis(*v) for k, v in dict(self.axes).items()}
        object.__setattr__(self, "axes", MappingProxyType(axes))

    @property
    def body(self) -> str:
        """The body's name (a mechanism scene names its body)."""
        return self.name

    @property
    def defaults(self) -> dict:
        """The geometry's default parameter values."""
        sig = inspect.signature(self.geometry).parameters
        return {k: sig[k].default for k in self.params}

    def __call__(self, **kw) -> dict:
        unknown = sorted(set(kw) - set(self.params))
        if unknown:
            raise ValueError(
                f"{unknown[0]}: not a parameter of {self.name} ({', '.join(self.params)})"
            )
        checked = {k: v if v is None else self.params[k].check(k, v) for k, v in kw.items()}
        return {"name": self.name, **self.geometry(**checked)}


#: every built-in body, by name, in declaration order
BODIES: dict[str, Body] = {}


def _check(b: Body) -> None:
    """A one-line ``ValueError`` naming the first incomplete or inconsistent field of ``b``."""
    where = f"body {b.name!r}"
    if not b.name.isidentifier() or b.name.startswith("_"):
        raise ValueError(f"name: {b.name!r} is not a public identifier")
    if b.name in BODIES:
        raise ValueError(f"name: body {b.name!r} is already registered")
    if not callable(b.geometry):
        raise ValueError(f"geometry: {where} has no geometry function")
    sig = inspect.signature(b.geometry).parameters
    kw = [k for k, p in sig.items() if p.kind is p.KEYWORD_ONLY]
    if len(kw) != len(sig) or any(sig[k].default is inspect.Parameter.empty for k in kw):
        raise ValueError(f"geometry: {where} takes keyword-only parameters with defaults")
    for k in kw:
        p = b.params.get(k)
        if not isinstance(p, Param) or not str(p.units).strip() or not str(p.meaning).strip():
            raise ValueError(f"params: {where}'s parameter {k!r} needs units and a meaning")
    extra = sorted(set(b.params) - set(kw))
    if extra:
        raise ValueError(f"params: {where} declares {extra[0]!r}, not a geometry parameter")
    clash = sorted(set(kw) & set(MODEL))
    if clash:
        raise ValueError(f"params: {where}'s {clash[0]!r} is a contact-model parameter")
    _check_axes(b, where)
    if not str(b.description).strip():
        raise ValueError(f"description: {where} needs a description")
    try:
        check_body(b(**b.defaults))
    except Exception as e:
        raise ValueError(f"geometry: {where} at its defaults: {e}") from None


def _check_axes(b: Body, where: str) -> None:
    if not b.axes:
        raise ValueError(f"axes: {where} needs at least one axis")
    for a, ax in b.axes.items():
        if not a.isidentifier() or a in MODEL:
            raise ValueError(f"axes: {where}'s axis {a!r} is not a free name")
        if not ax.sets or any(s not in b.params for s in ax.sets):
            raise ValueError(f"axes: {where}'s axis {a!r} sets unknown parameters {ax.sets}")
        if any(b.params[s].units != ax.units for s in ax.sets):
            raise ValueError(f"axes: {where}'s axis {a!r} in {ax.units!r} sets other units")
        if not str(ax.long_name).strip():
            raise ValueError(f"axes: {where}'s axis {a!r} needs a long_name")


def register(body: Body) -> Body:
    """Declare ``body`` (checked completely, module docstring); returns it."""
    if not isinstance(body, Body):
        raise ValueError(f"body: expected a Body, got {type(body).__name__}")
    _check(body)
    BODIES[body.name] = body
    return body


def unregister(name: str) -> None:
    """Remove a body from :data:`BODIES`."""
    BODIES.pop(name)


# --- the built-in bodies -------------------------------------------------------------------------

_HALF_PI = math.pi / 2
_LENGTH = Param("m", "length of the body", 0.0, open_low=True)
_MASS = Param("kg", "mass", 0.0, open_low=True)
_ANGLE = Param("rad", "angle of the body from the floor", 0.0, _HALF_PI, True, True)


def _mu(where: str) -> Param:
    return Param("1", f"friction coefficient at {where}", 0.0)


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
    )


def two_legged_body(*, d=0.2, h=0.5, m=5.0, I=None, mu1=0.3, mu2=0.3) -> dict:
    """A body on two legs on a floor (a chair, a two-legged rod, a biped's feet): leg 1 at
    ``(-d, -h)``, leg 2 at ``(+d, -h)`` from the centre of mass (``d > 0``, ``h >= 0`` [m]), both
    sliding along ``+x`` (leg 2 leads; the admissible twist is a translation, ``s2 = s1``).
    ``I`` defaults to a uniform ``2d x 2h`` plate, ``m (d^2 + h^2) / 3``.  The leading leg has
    Painleve's paradox (``b22 < 0``) iff ``mu2 h d > I/m + d^2`` (for the plate:
    ``mu2 > (4 d^2 + h^2) / (3 h d) >= 4/3``).  Illustrative numbers (a chair)."""
    if I is None:
        I = m * (d * d + h * h) / 3
    return dict(
        m=m, I=I, r1=(-d, -h), r2=(d, -h), n1=(0.0, 1.0), n2=(0.0, 1.0), mu1=mu1, mu2=mu2, s1=1
    )


def leaning_rod_body(*, L=1.0, theta=math.pi / 6, e=0.25, m=1.0, mu_floor=0.5, mu_edge=0.5) -> dict:
    """A uniform rod (``I = m L^2 / 12``, ``L > 0`` [m]) with its lower end on the floor (contact 1,
    a body vertex) resting on a table edge (contact 2, an environment vertex on the rod's side:
    ``body_side``) at ``e`` [m] above the centre along the rod (``-L/2 < e < L/2``), at ``theta`` in
    ``(0, pi/2)`` from the floor, slipping down: the foot slides away (``+x``), and then the rod
    slides down over the edge (the edge's normal ``(sin, cos)`` is perpendicular to the rod, its
    tangent ``(cos, -sin)`` points down the rod: ``s2 = +1``, derived).  Illustrative numbers."""
    half = L / 2
    off = np.abs(e) >= half
    if np.any(off):
        bad = np.asarray(e)[off].flat[0] if np.ndim(e) else e
        raise ValueError(f"e: the table edge must lie on the rod, -L/2 < e < L/2, got e = {bad}")
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
    )


_THETA = "0.02pi:0.48pi:181"
_MU = "0:2:201"

register(
    Body(
        "ladder",
        ladder_body,
        {"L": _LENGTH, "theta": _ANGLE, "m": _MASS, "mu_floor": _mu("the floor"),
         "mu_wall": _mu("the wall")},
        {"theta": Axis(_THETA, "rad", "ladder angle from the floor", ("theta",)),
         "mu": Axis(_MU, "1", "friction coefficient (floor and wall)", ("mu_floor", "mu_wall"))},
        "a uniform ladder on a floor leaning on a wall, slipping down (Mechanism.ladder)",
    )
)  # fmt: skip
register(
    Body(
        "two_legged",
        two_legged_body,
        {"d": Param("m", "half the distance between the legs", 0.0, open_low=True),
         "h": Param("m", "height of the centre of mass above the feet", 0.0),
         "m": _MASS,
         "I": Param("kg m2", "moment of inertia about the centre of mass", 0.0, open_low=True),
         "mu1": _mu("contact 1"), "mu2": _mu("contact 2")},
        {"h": Axis("0.05:2:196", "m", "height of the centre of mass above the feet", ("h",)),
         "mu": Axis(_MU, "1", "friction coefficient (both legs)", ("mu1", "mu2"))},
        "a body on two legs (at +-0.2 m) sliding on a floor (Mechanism.two_legged)",
    )
)  # fmt: skip
register(
    Body(
        "leaning_rod",
        leaning_rod_body,
        {"L": _LENGTH, "theta": _ANGLE,
         "e": Param("m", "position of the table edge along the rod, above its centre"),
         "m": _MASS, "mu_floor": _mu("the floor"), "mu_edge": _mu("the table edge")},
        {"theta": Axis(_THETA, "rad", "rod angle from the floor", ("theta",)),
         "mu": Axis(_MU, "1", "friction coefficient (floor and edge)", ("mu_floor", "mu_edge"))},
        "a rod on a floor resting on a table edge, slipping down (Mechanism.leaning_rod)",
    )
)  # fmt: skip
