"""Realisability audit: each of the 144 subclasses by one rigid body under its weight.

The paper (Sec. 3) claims that "a single planar rigid body with two contacts, and its own weight as
external load can belong to any of the subclasses if the positions and directions of contacts as
well as the friction coefficients are chosen appropriately".  :func:`search` checks the claim on a
stated set of bodies with *rational* parameters:

* ``m = 1`` kg, ``I = 1`` kg m^2 (radius of gyration 1 m: only ``r / sqrt(I/m)`` matters),
  gravity ``g = (0, -981/100)`` m/s^2, no external force or torque, the zero-speed state (a body
  starting to slide: no velocity term in ``a``);
* contact positions ``r_j`` on the grid ``[-3, 3]^2`` m with step 1/4 m;
* normals ``n_j``: the 4 axis directions and the 56 rational unit vectors ``(+-p/h, +-q/h)``,
  ``(+-q/h, +-p/h)`` of the primitive Pythagorean triples with ``h <= 41`` (60 directions, gaps
  <= 12.7 degrees);
* friction ``mu_j in {0, 1/10, ..., MU_MAX}`` (``MU_MAX = 2``) and ``s1 = +-1``; **``s2`` is the
  admissible one**: with both contacts closed a rigid body has one line of twists, and the sliding
  directions are tied (:func:`atlas.core.rigid_body.admissible_twist`); bodies where a contact cannot
  slide are left out.

Random bodies from this set (fixed seed) are classified in float64 by the package's own certified
kernels (:func:`atlas.core.contact_modes.subclass_code`); for each subclass the body farthest from every
boundary of the subclass is kept (``margin``: sine of the smallest angle between the direction of
``b1``, ``b2`` or ``a`` and the axes or another of them).  Every kept example is then re-verified in
exact rational arithmetic: the admissible sliding signs from the exact twist (:func:`admissible`),
``B`` and ``a`` of eq. (1) on :class:`fractions.Fraction` inputs by
:func:`atlas.core.rigid_body.mobility` / :func:`~atlas.core.rigid_body.free_acceleration`, and the
codes by :func:`atlas.core.exact.point_codes` on integer (hence exactly representable) multiples of
the columns of ``B`` and of ``a``.

**A richer system for the rest** (:data:`WHEEL`): the same body with a *driven wheel* at contact 2
-- a wheel of radius ``rho > 0`` whose hub is fixed to the body at ``r2 + rho n2`` (on the contact
normal) and which a motor spins at a constant rate relative to the body.  The wheel's gap is the
hub's distance to the surface minus ``rho``, a body-fixed point with the same Jacobian row
``J_2`` (``(r2 + rho n2) x n2 = r2 x n2``), and a contact force at the rim acts on the composite as a
force at ``r2``; a constant spin adds no torque.  So ``B`` and ``a`` (composite ``m``, ``I``) are
those of eq. (1) above at zero body speed, while the rim slides at ``u2 = u2_body + rho spin``: the
motor sets ``s2`` independently of ``s1`` (contact 1 must still slide along the body's twist).  The
subclasses a rigid body does not reach in the searched set are searched with free ``s2`` and
verified exactly the same way.

No impossibility argument is needed when every subclass has a verified example; a subclass without
one is reported as "none found in the searched set" (the search is not a proof of impossibility),
except where an argument applies.  The one known here: **without friction** (``mu1 = mu2 = 0``)
``B = J M^-1 J^T`` is symmetric positive definite (``b12 = b21``, ``b11, b22, det B > 0``), so ``b1``
and ``b2`` lie in the first quadrant with ``beta1 < beta2`` (class 12) or ``b1`` in the fourth and
``b2`` in the second with ``beta2 < beta1*`` (class 42): only the 12 subclasses of
:data:`FRICTIONLESS_CLASSES` exist, every other subclass needs friction.
"""

from __future__ import annotations

import dataclasses
import math
import time
from fractions import Fraction
from typing import NamedTuple

import numpy as np

from atlas.core import contact_modes as mech
from atlas.core import exact
from atlas.core.rigid_body import Mechanism, admissible_twist, free_acceleration, mobility

__all__ = [
    "ALL_SUBCLASSES",
    "MU_MAX",
    "FRICTIONLESS_CLASSES",
    "RIGID",
    "WHEEL",
    "Realisation",
    "admissible",
    "search",
    "exact_codes",
    "mechanism",
    "markdown",
]

#: the 144 subclass codes ijk (SPEC §1)
ALL_SUBCLASSES = tuple(10 * c + k for c in mech.ALL_CLASSES for k in range(1, 7))
MU_MAX = Fraction(2)
#: the systems searched (module docstring): a rigid body (admissible sliding), and the same body
#: with a driven wheel at contact 2 (``s2`` free)
RIGID, WHEEL = "rigid body", "rigid body + driven wheel at contact 2"
#: the only classes a body without friction can be in (module docstring)
FRICTIONLESS_CLASSES = (12, 42)
_MU_STEP = Fraction(1, 10)
_R_MAX, _R_STEP = 3, Fraction(1, 4)
_G = (Fraction(0), Fraction(-981, 100))
_TRIPLES = (
    (3, 4, 5),
    (5, 12, 13),
    (8, 15, 17),
    (7, 24, 25),
    (20, 21, 29),
    (12, 35, 37),
    (9, 40, 41),
)


def _normals() -> tuple[tuple[Fraction, Fraction], ...]:
    """The searched rational unit normals (module docstring)."""
    out = {(Fraction(1), Fraction(0)), (Fraction(0), Fraction(1))}
    out |= {(Fraction(-1), Fraction(0)), (Fraction(0), Fraction(-1))}
    for p, q, h in _TRIPLES:
        for x, y in ((p, q), (q, p)):
            for sx in (1, -1):
                for sy in (1, -1):
                    out.add((Fraction(sx * x, h), Fraction(sy * y, h)))
    return tuple(sorted(out, key=lambda n: math.atan2(n[1], n[0])))


NORMALS = _normals()


@dataclasses.dataclass(frozen=True)
class Realisation:
    """One subclass's outcome: an exactly verified body, or none in the searched set.

    ``params``: the :class:`~atlas.core.rigid_body.Mechanism` parameters (``m, I, r1, r2, n1, n2,
    mu1, mu2, s1, s2, g``) as Fractions, or ``None``; ``system``: :data:`RIGID` or :data:`WHEEL`;
    ``verified``: ``(s1, s2)`` is admissible for ``system`` and the exact subclass code of
    ``params`` is ``subclass``; ``margin``: sine of the angular distance to the nearest boundary of
    the subclass (float64); ``impossible``: an impossibility argument for the searched set, if one
    applies.
    """

    subclass: int
    params: dict | None
    verified: bool
    margin: float
    note: str
    impossible: str | None = None
    system: str | None = None

    @property
    def found(self) -> bool:
        return self.params is not None


def _sample(rng, n: int, mu_max: Fraction) -> dict:
    """``n`` random bodies of the searched set, as integer indices."""
    steps = int(_R_MAX / _R_STEP)
    ix = {f"r{j}": rng.integers(-steps, steps + 1, size=(n, 2)) for j in (1, 2)}
    ix.update({f"n{j}": rng.integers(0, len(NORMALS), size=n) for j in (1, 2)})
    ix.update({f"mu{j}": rng.integers(0, int(mu_max / _MU_STEP) + 1, size=n) for j in (1, 2)})
    ix.update({f"s{j}": rng.choice(np.array([1, -1]), size=n) for j in (1, 2)})
    return ix


def _sliding(ix: dict, system: str):
    """``(s2, ok)``: the sliding sign of contact 2 (admissible for a rigid body, the sampled one
    with the wheel) and where the sample is usable: contact 1 slides (and, for a rigid body,
    contact 2), ``|u_j|`` clear of zero (the kept examples are verified exactly)."""
    nrm = np.array(NORMALS, dtype=float)
    r = tuple(tuple(ix[f"r{j}"][:, k] * float(_R_STEP) for k in (0, 1)) for j in (1, 2))
    n = tuple(tuple(nrm[ix[f"n{j}"], k] for k in (0, 1)) for j in (1, 2))
    _z, (u1, u2) = admissible_twist(r, n)
    ok = np.abs(u1) > 1e-9
    if system == WHEEL:
        return ix["s2"], ok
    return ix["s1"] * np.sign(u1).astype(int) * np.sign(u2).astype(int), ok & (np.abs(u2) > 1e-9)


def _floats(ix: dict, s2):
    """``(b1, b2, a)`` as float64 ``(x, y)`` arrays of the sampled bodies."""
    nrm = np.array(NORMALS, dtype=float)
    r = tuple(tuple(ix[f"r{j}"][:, k] * float(_R_STEP) for k in (0, 1)) for j in (1, 2))
    n = tuple(tuple(nrm[ix[f"n{j}"], k] for k in (0, 1)) for j in (1, 2))
    mu = tuple(ix[f"mu{j}"] * float(_MU_STEP) for j in (1, 2))
    B = mobility(1.0, 1.0, r, n, mu, (ix["s1"], s2))
    a = free_acceleration(1.0, 1.0, r, n, tuple(float(x) for x in _G))
    return (B[0][0], B[1][0]), (B[0][1], B[1][1]), a


def _unit(v):
    norm = np.hypot(v[0], v[1])
    with np.errstate(invalid="ignore", divide="ignore"):
        return v[0] / norm, v[1] / norm


def _classify(ix: dict, system: str):
    """Certified float64 subclass codes (-1/0 where undecided/degenerate/unusable), margins and
    the sliding signs ``s2``."""
    s2, usable = _sliding(ix, system)
    b1, b2, a = (_unit(v) for v in _floats(ix, s2))
    ok = usable & np.isfinite(b1[0]) & np.isfinite(b2[0]) & np.isfinite(a[0])
    ok &= np.any(ix["r1"] != ix["r2"], axis=1)  # distinct contacts (a valid Mechanism)
    b1, b2, a = ([np.where(ok, c, 1.0) for c in v] for v in (b1, b2, a))
    code = np.asarray(mech.subclass_code(*b1, *b2, *a)).astype(int)
    code = np.where(ok, code, 0)
    cross = lambda u, v: np.abs(u[0] * v[1] - u[1] * v[0])  # noqa: E731
    parts = [np.abs(c) for c in (*b1, *b2, *a)] + [cross(b1, b2), cross(b1, a), cross(b2, a)]
    return code, np.min(parts, axis=0), s2


def _params(ix: dict, i: int, s2) -> dict:
    """Exact (Fraction) Mechanism parameters of sample ``i``."""
    out = {"m": Fraction(1), "I": Fraction(1), "g": _G}
    for j in (1, 2):
        out[f"r{j}"] = tuple(int(v) * _R_STEP for v in ix[f"r{j}"][i])
        out[f"n{j}"] = NORMALS[int(ix[f"n{j}"][i])]
        out[f"mu{j}"] = int(ix[f"mu{j}"][i]) * _MU_STEP
    out["s1"], out["s2"] = int(ix["s1"][i]), int(s2[i])
    return out


def _integer_direction(v) -> tuple[int, int]:
    """A positive integer multiple of a rational 2-vector, reduced, exactly representable as floats."""
    den = math.lcm(v[0].denominator, v[1].denominator)
    x, y = int(v[0] * den), int(v[1] * den)
    gcd = math.gcd(x, y) or 1
    x, y = x // gcd, y // gcd
    if max(abs(x), abs(y)) >= 2**53:
        raise ValueError("params: rational components too large for an exact float")
    return x, y


def admissible(params: dict, system: str = RIGID) -> bool:
    """Exactly: can ``system`` (:data:`RIGID`, :data:`WHEEL`) slide with ``(s1, s2)``?

    The sliding speeds along the body's twist line (:func:`atlas.core.rigid_body.admissible_twist`,
    in :class:`~fractions.Fraction` arithmetic): a rigid body needs ``u1, u2 != 0`` and
    ``s2 = s1 sign(u1 u2)``; with the wheel contact 1 must slide (``u1 != 0``), ``s2`` is free.
    Contacts on one normal line (a 2-D twist space) admit every pair.
    """
    z, (u1, u2) = admissible_twist((params["r1"], params["r2"]), (params["n1"], params["n2"]))
    if not any(z):
        return True
    if system == WHEEL:
        return u1 != 0
    return u1 != 0 and u2 != 0 and params["s2"] == params["s1"] * (1 if u1 * u2 > 0 else -1)


def exact_codes(params: dict) -> dict:
    """Exact class/subclass codes and Table 1 consistency of a body with rational parameters.

    ``B`` and ``a`` (eq. 1) in :class:`~fractions.Fraction` arithmetic; the codes depend only on the
    directions of ``b1``, ``b2``, ``a``, which :func:`atlas.core.exact.point_codes` ranks exactly.
    """
    p = {k: v for k, v in params.items()}
    r, n, mu, s = (p["r1"], p["r2"]), (p["n1"], p["n2"]), (p["mu1"], p["mu2"]), (p["s1"], p["s2"])
    for key, v in (("n1", n[0]), ("n2", n[1])):
        if v[0] * v[0] + v[1] * v[1] != 1:
            raise ValueError(f"{key}: must be an exact rational unit vector")
    B = mobility(p["m"], p["I"], r, n, mu, s)
    a = free_acceleration(p["m"], p["I"], r, n, p["g"])
    vecs = [(B[0][0], B[1][0]), (B[0][1], B[1][1]), a]
    if any(v == (0, 0) for v in vecs):
        return {"class_code": 0, "subclass_code": 0}
    dirs = [float(c) for v in vecs for c in _integer_direction(v)]
    return exact.point_codes(*dirs)


def mechanism(params: dict, **kw) -> Mechanism:
    """The float :class:`~atlas.core.rigid_body.Mechanism` of exact parameters (``kw``: k, c, name)."""
    return Mechanism(**{k: _as_float(v) for k, v in params.items()}, **kw)


def _as_float(v):
    if isinstance(v, tuple):
        return tuple(float(x) for x in v)
    return v if v is None or isinstance(v, int) else float(v)


def _best(code, margin, s2, best: dict, ix: dict) -> None:
    """Keep, per subclass, the sample with the largest margin (in place)."""
    order = np.lexsort((-margin, code))
    first = np.ones(order.size, bool)
    first[1:] = code[order][1:] != code[order][:-1]
    for i in order[first]:
        c = int(code[i])
        if c > 0 and (c not in best or margin[i] > best[c][0]):
            best[c] = (float(margin[i]), _params(ix, i, s2))


def search(
    samples: int = 1 << 19,
    *,
    seed: int = 0,
    mu_max=MU_MAX,
    chunk: int = 1 << 17,
) -> Search:
    """Per subclass, a verified realisation (a rigid body, else the body with a driven wheel) or
    "none found in the searched set".

    Parameters
    ----------
    samples : int
        Random bodies drawn from the searched set (module docstring).
    seed : int
        Seed of :func:`numpy.random.default_rng` (the result is deterministic).
    mu_max : Fraction or str
        Largest friction coefficient searched (a multiple of 1/10; default 2).

    Returns
    -------
    Search
        ``found``: ``{subclass code: Realisation}`` for all 144 subclasses, in Table 2 order;
        ``stats``: ``samples``, ``mu_max``, ``seconds_search``, ``seconds_verify``, ``found``,
        ``verified`` and ``rigid`` / ``wheel`` (subclasses verified per system).
    """
    if samples < 1:
        raise ValueError(f"samples: must be >= 1, got {samples}")
    mu_max = Fraction(mu_max)
    if mu_max < 0 or mu_max % _MU_STEP:
        raise ValueError(f"mu_max: must be a non-negative multiple of 1/10, got {mu_max}")
    t0 = time.perf_counter()
    best = {RIGID: _search(RIGID, samples, seed, mu_max, chunk), WHEEL: {}}
    if mu_max > 0 and len(best[RIGID]) < len(ALL_SUBCLASSES):  # without friction s2 is moot
        best[WHEEL] = _search(WHEEL, samples, seed, mu_max, chunk)
    t1 = time.perf_counter()
    out = {c: _verify(c, best, samples, mu_max) for c in ALL_SUBCLASSES}
    stats = dict(
        samples=samples,
        mu_max=mu_max,
        seconds_search=t1 - t0,
        seconds_verify=time.perf_counter() - t1,
        found=sum(r.found for r in out.values()),
        verified=sum(r.verified for r in out.values()),
        **{k: sum(r.verified and r.system == s for r in out.values()) for k, s in _SYSTEMS},
    )
    return Search(out, stats)


class Search(NamedTuple):
    """What :func:`search` returns: the realisations ``found`` and the search's ``stats``."""

    found: dict
    stats: dict


def _search(system: str, samples: int, seed: int, mu_max: Fraction, chunk: int) -> dict:
    """``{subclass: (margin, params)}``: the best sample of ``system`` per subclass."""
    rng, best = np.random.default_rng(seed), {}
    for start in range(0, samples, chunk):
        ix = _sample(rng, min(chunk, samples - start), mu_max)
        _best(*_classify(ix, system), best, ix)
    return best


_SYSTEMS = (("rigid", RIGID), ("wheel", WHEEL))


def _verify(code: int, best: dict, samples: int, mu_max: Fraction) -> Realisation:
    hits = [(system, best[system][code]) for _k, system in _SYSTEMS if code in best[system]]
    if not hits:
        if mu_max == 0 and code // 10 not in FRICTIONLESS_CLASSES:
            why = "impossible without friction: B symmetric positive definite (classes 12, 42 only)"
            return Realisation(code, None, False, 0.0, why, why)
        note = f"none found in the searched set ({samples} bodies); no impossibility argument known"
        return Realisation(code, None, False, 0.0, note)
    system, (margin, params) = hits[0]
    got = exact_codes(params)["subclass_code"]
    if got != code or not admissible(params, system):  # pragma: no cover - a guard
        return Realisation(code, params, False, margin, "exact check failed", system=system)
    return Realisation(code, params, True, margin, "verified exactly", system=system)


def _fmt(v) -> str:
    if isinstance(v, tuple):
        return "(" + ", ".join(_fmt(x) for x in v) + ")"
    return str(v)


def markdown(result: dict, stats: dict | None = None) -> str:
    """A Markdown section: the counts per system and one row per subclass (body parameters,
    system, margin)."""
    found = sum(r.verified for r in result.values())
    per = {s: sum(r.verified and r.system == s for r in result.values()) for _k, s in _SYSTEMS}
    mu_max = (stats or {}).get("mu_max", MU_MAX)
    lines = [
        "## Realisability of the 144 subclasses by one rigid body under its weight",
        "",
        f"{per[RIGID]} / {len(result)} subclasses realised by one rigid body whose two contacts"
        " slide as a rigid body can (s2 follows from s1 and the geometry: both contacts closed"
        f" leave one line of twists); {per[WHEEL]} more by the body with a driven wheel at"
        f" contact 2 (s2 set by the motor); {len(result) - found} not found.  Each example is"
        " re-verified exactly (rational arithmetic: the sliding signs from the exact twist, B, a"
        " and the subclass code).",
        f"Searched set: m = 1 kg, I = 1 kg m^2, g = (0, -9.81) m/s^2, r_j in [-3, 3]^2 m (step 1/4),"
        f" {len(NORMALS)} rational unit normals, mu_j in [0, {mu_max}] (step 1/10),"
        " s1 = +-1, zero-speed state (no velocity term), no other load.",
    ]
    if stats:
        lines.append(f"{stats['samples']} bodies searched.")  # seconds: atlas.paper.runlog
    lines += ["", "| subclass | r1 | r2 | n1 | n2 | mu1 | mu2 | s1 | s2 | system | margin | note |"]
    lines.append("|---|---|---|---|---|---|---|---|---|---|---|---|")
    keys = ("r1", "r2", "n1", "n2", "mu1", "mu2", "s1", "s2")
    for code, r in result.items():
        cells = [_fmt(r.params[k]) for k in keys] if r.found else ["-"] * len(keys)
        cells.append(r.system or "-")
        lines.append(f"| {code} | " + " | ".join(cells) + f" | {r.margin:.3f} | {r.note} |")
    return "\n".join(lines) + "\n"
