"""SS stability over a box of contact models: for every model, for none, or depends (certified).

**The question.**  For one geometry (direction vectors ``b1 = (c1, s1)``, ``b2 = (c2, s2)``, SPEC §1)
and a box of models ``kappa in K``, ``q1 in Q1``, ``q2 in Q2`` (``K = (0, inf)`` or ``[lo, hi]``,
``Q_j = [0, inf)`` or ``[lo, hi]``; optionally ``q1 = q2 = q in Q``), is the SS equilibrium stable
for every model, unstable for every model, or does it depend on the model?  "Stable" is the
project's word for the ``stable_SS`` codes *stable or neutral* (neutral, the undamped ``q = 0``
case, is drawn as stable in Fig. 1 and counted so by ``model_dependent_SS``); "unstable" is the
code *unstable*.  The verdict is about the linearisation ``M`` of SS, like ``stable_SS``: it does
not involve ``alpha``, and SS consistency (a function of ``beta1, beta2, alpha`` only) is the same
for every model, so an atlas combines the two as it does for one model.

**The conditions** (:mod:`atlas.core.hurwitz`, with ``k1 = kappa``, ``k2 = 1``,
``D = det B = c1 s2 - s1 c2``, polynomials of :mod:`atlas.core.expressions`):

* ``D < 0``: ``a0 = kappa D < 0``, unstable for every model (a proof, no search).
* damped (``q != 0``), ``D > 0``: stable or neutral iff ``a3 > 0`` and ``G >= 0``, with
  ``a3 = c1 q1 + s2 q2``, ``G = s1 c2 m^2 + q1 q2 [X^2 + D a3 m]``, ``m = kappa q2 + q1``,
  ``X = kappa c1 - s2`` (degree 2 in ``kappa``, 3 in ``q1`` and in ``q2``).
* damped, ``D = 0``: ``p = l^2 (l^2 + a3 l + a2)``: neutral iff ``a3 >= 0`` and
  ``a2 = kappa c1 + s2 >= 0``, else unstable.
* undamped (``q = 0``, in the box when ``lo(Q1) = lo(Q2) = 0``), ``D >= 0``: neutral iff
  ``a2 = kappa c1 + s2 >= 0`` and ``disc = X^2 + 4 kappa s1 c2 >= 0``, else unstable.  The
  undamped point is a part of its own: the limit ``q -> 0`` of the damped conditions is not the
  undamped verdict (the destabilisation paradox of the README).

So the box is one or two *parts* (damped: 3 variables, or 2 with ``q1 = q2``, where ``a3 / q`` and
``G / q^2`` are used; undamped: ``kappa`` alone) and on each part "good" (stable or neutral) is a
conjunction of polynomial sign conditions.  Stable for every model = no bad model = each condition
holds on each part; unstable for every model = no good model = on each part, at every point, some
condition fails.  Both are proved by :func:`atlas.core.bernstein.prove_any` (exact Bernstein
coefficients after mapping each axis to ``[0, 1]``, ``kappa = t / (1 - t)`` on ``(0, inf)``,
``q = t / (1 - t)`` on ``[0, inf)``; the damped part leaves out its ``q = 0`` face and the open
ends, so strict signs there are never required).  "Depends" carries one model on each side.

**Tiers.**  (1) ``D < 0`` decided at once; (2) a fixed sample of models per geometry (floats, never
a decision): the best candidate of each side is checked by the exact tier
(:func:`atlas.core.exact.ss_hurwitz`), and two checked witnesses decide "depends"; (3) the missing
side is proved absent by Bernstein subdivision with a small budget, whose failing vertices are
exact counterexamples (witnesses, checked again by the exact tier); what remains is
``UNDECIDED`` until (4) the settlement repeats (3) with a large budget.  A witness is stored as the
float model the exact tier checked.  No tolerance decides anything.

For ``K = (0, inf)``, ``Q1 = Q2 = [0, inf)`` the result has a closed form (used by the tests as an
independent check): unstable for every model iff ``D < 0`` or (``c1 <= 0`` and ``s2 <= 0``); stable
for every model iff ``D >= 0``, ``c1 > 0``, ``s2 > 0`` and ``s1 c2 >= 0``; depends otherwise.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from fractions import Fraction

import numpy as np

from atlas.core import bernstein as bz
from atlas.core import exact
from atlas.core import expressions as ex
from atlas.core.verdicts import OverModels, Verdict

__all__ = [
    "ModelBox",
    "BoxResult",
    "model_box",
    "parse_model_box",
    "checked",
    "ss_over_models",
    "sample_models",
    "integers",
    "det_signs",
    "WITNESS_NAMES",
]

#: the witness results of :func:`ss_over_models`, besides the code ``ss_over_models``
WITNESS_NAMES = tuple(
    f"ss_witness_{side}_{v}" for side in ("stable", "unstable") for v in ("kappa", "q1", "q2")
)
_NEG = {"<0": ">=0", "<=0": ">0", ">0": "<=0", ">=0": "<0"}
_GOOD = (int(Verdict.STABLE), int(Verdict.NEUTRAL))
BUDGET, SETTLE_BUDGET = 48, 16384


@dataclasses.dataclass(frozen=True)
class ModelBox:
    """A box of contact models (module docstring): ``(lo, hi)`` per axis, ``hi = inf`` unbounded;
    ``kappa`` with ``lo = 0`` means ``kappa > 0``; ``equal``: ``q1 = q2`` (then ``q1 == q2``)."""

    kappa: tuple = (0.0, math.inf)
    q1: tuple = (0.0, math.inf)
    q2: tuple = (0.0, math.inf)
    equal: bool = False

    def __post_init__(self):
        """Every axis checked (:func:`_range`, a one-line ``ValueError`` naming it) and stored as
        ``(lo, hi)`` floats, however the box was made."""
        for name in ("kappa", "q1", "q2"):
            value = _range(name, getattr(self, name), kappa=name == "kappa")
            object.__setattr__(self, name, value)
        if not isinstance(self.equal, (bool, np.bool_)):
            raise ValueError(f"model_box: equal: expected True or False, got {_shown(self.equal)}")
        object.__setattr__(self, "equal", bool(self.equal))
        if self.equal and self.q1 != self.q2:
            raise ValueError("model_box: q: equal damping needs the same q1 and q2 ranges")

    @property
    def has_undamped(self) -> bool:
        return self.q1[0] == 0 and self.q2[0] == 0

    @property
    def has_damped(self) -> bool:
        return self.q1[1] > 0 or self.q2[1] > 0

    def __str__(self):
        """The box's text, exact: :func:`parse_model_box` of it gives this box back."""
        f = lambda r: f"{_exact(r[0])}:{_exact(r[1])}"  # noqa: E731
        qs = f"q={f(self.q1)}" if self.equal else f"q1={f(self.q1)},q2={f(self.q2)}"
        return f"kappa={f(self.kappa)},{qs}"


def _exact(x: float) -> str:
    """``x`` as short text that reads back as ``x`` exactly (``%g`` where that is exact)."""
    short = f"{x:g}"
    return short if float(short) == x else repr(float(x))


def _shown(value) -> str:
    """``value``'s repr where it is one short line, else its type (error messages stay one line)."""
    text = repr(value)
    return text if len(text) <= 60 and "\n" not in text else f"a {type(value).__name__}"


def _range(name: str, value, *, kappa: bool) -> tuple:
    """One axis ``(lo, hi)`` (or one number: a fixed value), checked: one-line ``ValueError``."""
    if isinstance(value, np.ndarray) and value.ndim <= 1:
        value = tuple(value.tolist()) if value.ndim else value.item()
    vals = value if isinstance(value, (tuple, list)) else (value, value)
    if len(vals) != 2 or any(isinstance(v, (bool, np.bool_, str, bytes)) for v in vals):
        raise ValueError(f"model_box: {name}: expected lo:hi or one number, got {_shown(value)}")
    try:
        lo, hi = (float(v) for v in vals)
    except (TypeError, ValueError):
        raise ValueError(f"model_box: {name}: expected real numbers, got {_shown(value)}") from None
    if math.isnan(lo) or math.isnan(hi):
        raise ValueError(f"model_box: {name}: NaN bound in {_shown(value)}")
    if lo < 0 or hi < 0:
        raise ValueError(f"model_box: {name}: bounds must be >= 0, got {_shown(value)}")
    if lo > hi:
        raise ValueError(f"model_box: {name}: reversed range {_exact(lo)}:{_exact(hi)}")
    if lo == math.inf:
        raise ValueError(f"model_box: {name}: the lower bound must be finite")
    if kappa and hi == 0:
        raise ValueError(f"model_box: {name}: empty (kappa > 0), got {_shown(value)}")
    return lo, hi


def model_box(kappa=None, q1=None, q2=None, q=None) -> ModelBox:
    """A checked :class:`ModelBox`; an axis not given is its whole range (``kappa > 0``,
    ``q >= 0``); ``q`` sets ``q1 = q2`` (equal damping) and excludes ``q1``, ``q2``."""
    whole = (0.0, math.inf)
    k = whole if kappa is None else _range("kappa", kappa, kappa=True)
    if q is not None:
        if q1 is not None or q2 is not None:
            raise ValueError("model_box: q: give q (equal damping) or q1/q2, not both")
        r = _range("q", q, kappa=False)
        return ModelBox(k, r, r, True)
    r1 = whole if q1 is None else _range("q1", q1, kappa=False)
    r2 = whole if q2 is None else _range("q2", q2, kappa=False)
    return ModelBox(k, r1, r2, False)


def parse_model_box(text: str) -> ModelBox:
    """``"kappa=0.01:100,q1=0:1,q2=0:1"`` (or ``q=lo:hi`` for equal damping; ``inf`` allowed as an
    upper bound; one number fixes the axis) as a :class:`ModelBox`."""
    out: dict = {}
    for item in (text or "").split(","):
        key, eq, val = item.strip().partition("=")
        if not eq or key not in ("kappa", "q1", "q2", "q"):
            raise ValueError(
                f"model_box: expected kappa=lo:hi,q1=lo:hi,q2=lo:hi (or q=), got {item!r}"
            )
        if key in out:
            raise ValueError(f"model_box: {key}: given twice")
        parts = val.split(":")
        if len(parts) not in (1, 2):
            raise ValueError(f"model_box: {key}: expected lo:hi, got {val!r}")
        try:
            nums = [float(p) for p in parts]
        except ValueError:
            raise ValueError(f"model_box: {key}: expected numbers, got {val!r}") from None
        out[key] = tuple(nums) if len(nums) == 2 else nums[0]
    return model_box(**out)


def checked(value) -> ModelBox:
    """The one check of every entry point: a :class:`ModelBox` from itself, its text
    (:func:`parse_model_box`) or a dict of :func:`model_box` keywords; anything else, a bad
    axis or an unknown key is a one-line ``ValueError`` naming the parameter (the CLI's
    message)."""
    if isinstance(value, ModelBox):
        return value
    if isinstance(value, str):
        return parse_model_box(value)
    if isinstance(value, dict):
        unknown = set(value) - {"kappa", "q1", "q2", "q"}
        if unknown:
            raise ValueError(
                f"model_box: unknown axes {sorted(map(str, unknown))} (kappa, q1, q2, q)"
            )
        return model_box(**value)
    raise ValueError(f"model_box: expected a ModelBox, a dict or text, got {_shown(value)}")


# --- the pieces of the box and their conditions, exactly -------------------------------------------


@dataclasses.dataclass(frozen=True, eq=False)
class _Piece:
    """A box in its own variables: ``axes`` (:class:`atlas.core.bernstein.Axis`), faces left out
    (``patterns``), ``kind`` (``undamped``, ``rect``: ``(kappa, q1, q2)`` or ``(kappa, q)``,
    ``corner``: ``(kappa, r, u)`` with ``q1 = r u``, ``q2 = r (1 - u)``)."""

    kind: str
    axes: tuple
    patterns: tuple = ()


def _axis(lo, hi, open_lo=False):
    return bz.Axis(lo, None if hi == math.inf else hi, open_lo)


@functools.lru_cache(maxsize=16)
def _pieces(box: ModelBox) -> tuple:
    """The parts of the box (module docstring) as pieces.  The damped part of a 3-variable box
    whose ``q`` ranges both start at 0 is the corner ``q1 + q2 <= h`` in ``(kappa, r, u)`` (where
    ``G / r^2`` has no zero at ``r = 0``, unlike ``G`` at ``q = 0``) and two rectangles
    ``q1 >= h/2`` and ``q1 <= h/2, q2 >= h/2``: they cover it."""
    K = _axis(*box.kappa, open_lo=box.kappa[0] == 0)
    out = (_Piece("undamped", (K,)),) if box.has_undamped else ()
    if not box.has_damped:
        return out
    (l1, h1), (l2, h2) = box.q1, box.q2
    if box.equal:
        return out + (_Piece("rect", (K, _axis(l1, h1)), ({1: 0},) if l1 == 0 else ()),)
    if l1 > 0 or l2 > 0:
        return out + (_Piece("rect", (K, _axis(l1, h1), _axis(l2, h2))),)
    if h1 == 0 or h2 == 0:
        return out + (_Piece("rect", (K, _axis(l1, h1), _axis(l2, h2)), ({1: 0, 2: 0},)),)
    h = min([v for v in (h1, h2) if v < math.inf] or [1.0])
    half = Fraction(h) / 2
    return out + (
        _Piece("corner", (K, bz.Axis(0, h), bz.Axis(0, 1)), ({1: 0},)),
        _Piece("rect", (K, _axis(half, h1), _axis(0, h2))),
        _Piece("rect", (K, _axis(0, half), _axis(half, h2))),
    )


def _variables(piece: _Piece, box: ModelBox, n: int):
    """``(k1, q1, q2, power)``: the model as polynomials in the piece's variables (of ``n``), and
    the power of the damping scale (``q``, ``r``) divided out of ``a3`` (``G``: twice that)."""
    P = bz.Poly
    k1 = P.var(0, n)
    if piece.kind == "corner":
        r, u = P.var(1, n), P.var(2, n)
        return k1, r * u, r + (-1) * r * u, 1
    if box.equal:
        return k1, P.var(1, n), P.var(1, n), 1
    return k1, P.var(1, n), P.var(2, n), 0


@functools.lru_cache(maxsize=64)
def _template(piece: _Piece, box: ModelBox, name: str) -> bz.Template:
    """The condition ``name`` (``a2u``, ``disc``, ``a3``, ``G``) of ``piece`` as a polynomial in
    the piece's variables whose coefficients are polynomials in ``c1, s1, c2, s2``, written in
    the Bernstein basis of the piece once (:class:`atlas.core.bernstein.Template`)."""
    n = len(piece.axes)
    tot = n + 4
    c1, s1, c2, s2 = (bz.Poly.var(n + i, tot) for i in range(4))
    one = Fraction(1)
    if piece.kind == "undamped":
        k1, q1, q2, e = bz.Poly.var(0, tot), None, None, 0
    else:
        k1, q1, q2, e = _variables(piece, box, tot)
    if name == "a2u":
        p = ex.a2_undamped(k1, c1, one, s2, sub=bz.sub)
    elif name == "disc":
        p = ex.disc_undamped(k1, c1, one, s2, s1, c2, sub=bz.sub)
    elif name == "a3":
        p = ex.a3(c1, s2, q1, q2, sub=bz.sub).divide_var(1, e)
    else:
        D = ex.det(c1, s1, c2, s2, sub=bz.sub)
        p = ex.G(c1, s1, c2, s2, k1, one, q1, q2, D, sub=bz.sub).divide_var(1, 2 * e)
    return bz.Template(p, piece.axes)


def integers(gf) -> tuple[list, int]:
    """The direction components as integers over one power of two ``N`` (exact)."""
    ratios = [float(v).as_integer_ratio() for v in gf]
    N = max(d for _, d in ratios)
    return [a * (N // d) for a, d in ratios], N


def _conditions(gf, box: ModelBox, piece: _Piece):
    """``[(coefficients, kind, implied_by)]`` whose conjunction is "stable or neutral" on
    ``piece`` (integer Bernstein coefficients; ``implied_by``: conditions that together imply
    it, tried first), or ``None`` where no model is (``D < 0``)."""
    ints, N = integers(gf)
    c1, s1, c2, s2 = ints
    D = c1 * s2 - s1 * c2
    if D < 0:
        return None
    at = lambda name: _template(piece, box, name).at(ints, N)  # noqa: E731
    nonneg_s1c2 = (np.full((1,) * len(piece.axes), s1 * c2, dtype=object), ">=0")
    if piece.kind == "undamped":
        # disc = X^2 + 4 kappa s1 c2 with kappa > 0
        return [(at("a2u"), ">=0", None), (at("disc"), ">=0", [nonneg_s1c2])]
    a3 = at("a3")
    if D == 0:
        return [(a3, ">=0", None), (at("a2u"), ">=0", None)]
    # G = s1 c2 m^2 + q1 q2 X^2 + D q1 q2 a3 m with m, q1 q2 >= 0 and D > 0
    return [(a3, ">0", None), (at("G"), ">=0", [nonneg_s1c2, (a3, ">=0")])]


def _model(piece: _Piece, x) -> tuple[float, float, float]:
    """Float ``(kappa, q1, q2)`` of an exact point of a piece (correctly rounded: stays in it)."""
    if piece.kind == "undamped":
        return float(x[0]), 0.0, 0.0
    if piece.kind == "corner":
        return float(x[0]), float(x[1] * x[2]), float(x[1] * (1 - x[2]))
    return float(x[0]), float(x[1]), float(x[-1])


def _is_good(gf, m) -> bool | None:
    """The exact tier's verdict on model ``m``: ``True`` stable or neutral, ``False`` unstable."""
    v = exact.ss_hurwitz(*gf, *m)
    return None if v is None else v in _GOOD


def _holds_everywhere(piece, task, budget):
    """:func:`atlas.core.bernstein.prove_any` on one piece."""
    return bz.prove_any(task, list(piece.axes), piece.patterns, budget)


def _prove(gf, box: ModelBox, side: str, budget: int):
    """Prove no model of ``side`` (``good`` / ``bad``) exists in the box: ``("proved", None)``,
    ``("witness", model)`` (checked by the exact tier) or ``("unknown", None)``."""
    status = "proved"
    for piece in _pieces(box):
        conds = _conditions(gf, box, piece)
        if conds is None:
            if side == "good":
                continue
            return "unknown", None  # every model of the part is bad: the search finds one
        if side == "good":
            tasks = [([(p, _NEG[k]) for p, k, _ in conds], None)]
        else:
            tasks = [([(p, k)], imp) for p, k, imp in conds]
        for task, implied_by in tasks:
            if implied_by and all(
                _holds_everywhere(piece, [c], budget)[0] == "proved" for c in implied_by
            ):
                continue
            res, t = _holds_everywhere(piece, task, budget)
            if res == "counterexample":
                m = _model(piece, bz.point_of(piece.axes, t))
                if _is_good(gf, m) is (side == "good"):
                    return "witness", m
                res = "unknown"
            if res == "unknown":
                status = "unknown"
    return status, None


# --- the sample search (floats: candidates only) --------------------------------------------------


def _samples(lo: float, hi: float, open_lo: bool) -> np.ndarray:
    """Sample values of one axis inside ``[lo, hi]`` (never a decision: candidates)."""
    if lo == hi:
        return np.array([lo])
    vals = [] if open_lo else [lo]
    if hi == math.inf:
        vals += [lo + 2.0**e for e in range(-24, 25, 3)]
    else:
        vals += list(lo + (hi - lo) * np.linspace(0, 1, 9)[1:])
        if lo > 0:
            vals += list(np.geomspace(lo, hi, 9))
        else:
            vals += [hi * 2.0**e for e in range(-24, 0, 3)]
    return np.unique(np.clip(np.array(vals), lo, hi))


def sample_models(box: ModelBox, fine: bool):
    """The sample models of the box, as flat ``(kappa, q1, q2)`` arrays (``fine``: every sample
    value, else about every third)."""
    pick = (lambda v: v) if fine else (lambda v: np.unique(np.append(v[::3], v[-1])))  # noqa: E731
    k = pick(_samples(*box.kappa, open_lo=box.kappa[0] == 0))
    q1 = pick(_samples(*box.q1, False))
    if box.equal:
        K, Q = np.meshgrid(k, q1, indexing="ij")
        return K.ravel(), Q.ravel(), Q.ravel()
    K, Q1, Q2 = np.meshgrid(k, q1, pick(_samples(*box.q2, False)), indexing="ij")
    return K.ravel(), Q1.ravel(), Q2.ravel()


def _dense_axis(rng, lo: float, hi: float, n: int) -> np.ndarray:
    """``n`` seeded values of one axis inside ``[lo, hi]``, spread over many scales."""
    if lo == hi:
        return np.full(n, lo)
    if hi == math.inf:
        return lo + np.exp2(rng.uniform(-60, 60, n))
    top = hi * np.exp2(rng.uniform(-40, 0, n)) if lo == 0 else np.geomspace(lo, hi, n)
    vals = np.where(rng.random(n) < 0.5, rng.uniform(lo, hi, n), rng.permutation(top))
    vals[::9] = lo
    return np.clip(vals, lo, hi)


def dense_models(box: ModelBox, n: int = 4096):
    """``n`` seeded models of the box over many scales (the last search for witnesses;
    candidates only), as flat ``(kappa, q1, q2)`` arrays."""
    rng = np.random.default_rng(20261128)
    k = _dense_axis(rng, *box.kappa, n)
    k = np.where(k > 0, k, box.kappa[1] if box.kappa[1] < math.inf else 1.0)
    q1 = _dense_axis(rng, *box.q1, n)
    q2 = q1 if box.equal else _dense_axis(rng, *box.q2, n)
    return k, q1, q2


def _score(c1, s1, c2, s2, kappa, q1, q2):
    """A float margin, > 0 roughly where a model is stable or neutral (candidates only)."""
    D = c1 * s2 - s1 * c2
    one = np.ones_like(kappa)
    rel = lambda f, *a: f(*a, sub=np.subtract) / np.maximum(f(*map(np.abs, a), sub=np.add), 1e-300)  # noqa: E731
    a3 = rel(ex.a3, c1, s2, q1, q2)
    G = rel(ex.G, c1, s1, c2, s2, kappa, one, q1, q2, D)
    a2 = rel(ex.a2_undamped, kappa, c1, one, s2)
    disc = rel(ex.disc_undamped, kappa, c1, one, s2, s1, c2)
    damped = (q1 > 0) | (q2 > 0)
    good = np.where(damped, np.minimum(a3, np.where(D > 0, G, a2)), np.minimum(a2, disc))
    return np.where(D < 0, -1.0, good)


def _search(geo, box: ModelBox, fine, chunk: int = 256):
    """Per geometry (rows of ``geo``), the sample models of largest and smallest score."""
    K, Q1, Q2 = dense_models(box) if fine == "dense" else sample_models(box, fine)
    best = np.empty((len(geo), 2), dtype=np.int64)
    for i in range(0, len(geo), chunk):
        g = [geo[i : i + chunk, j, None] for j in range(4)]
        s = _score(*g, K[None], Q1[None], Q2[None])
        best[i : i + chunk, 0] = np.argmax(s, axis=1)
        best[i : i + chunk, 1] = np.argmin(s, axis=1)
    return [(K[j], Q1[j], Q2[j]) for j in best[:, 0]], [(K[j], Q1[j], Q2[j]) for j in best[:, 1]]


# --- the driver -------------------------------------------------------------------------------------


def _decide(gf, box: ModelBox, good, bad, budget: int):
    """Code and witnesses of one geometry from its checked witnesses and proofs."""
    if good is None:
        st, good = _prove(gf, box, "good", budget)
        if st == "proved":
            return int(OverModels.UNSTABLE), None, None
    if bad is None:
        st, bad = _prove(gf, box, "bad", budget)
        if st == "proved":
            return int(OverModels.STABLE), None, None
    if good is not None and bad is not None:
        return int(OverModels.DEPENDS), good, bad
    return int(OverModels.UNDECIDED), good, bad


def det_signs(geo: np.ndarray) -> np.ndarray:
    """Exact signs of ``D = c1 s2 - s1 c2`` per row: the float difference where it exceeds its
    rounding bound, exact rationals elsewhere."""
    c1, s1, c2, s2 = geo.T
    d = c1 * s2 - s1 * c2
    bound = 4 * np.finfo(np.float64).eps * (np.abs(c1 * s2) + np.abs(s1 * c2)) + 1e-300
    sign = np.where(np.abs(d) > bound, np.sign(d), 2).astype(np.int8)
    for i in np.flatnonzero(sign == 2):
        a, b, c, e = (Fraction(float(v)) for v in geo[i])
        sign[i] = (a * e > b * c) - (a * e < b * c)
    return sign


def _by_signs(geo: np.ndarray, sd: np.ndarray) -> np.ndarray:
    """Codes proven by signs alone, for every box (``UNDECIDED`` elsewhere): ``D < 0``: unstable;
    ``D > 0``, ``c1 <= 0``, ``s2 <= 0``: ``a3 <= 0`` (damped) and ``a2 = kappa c1 + s2 <= 0``
    (undamped; ``= 0`` only with ``c1 = s2 = 0``, then ``disc = -4 kappa D < 0``): unstable;
    ``D > 0``, ``c1 > 0``, ``s2 > 0``, ``s1 c2 >= 0``: ``a3 > 0``, every term of ``G`` and of
    ``disc`` ``>= 0``, ``a2 > 0``: stable or neutral."""
    c1, s1, c2, s2 = geo.T
    code = np.full(len(geo), int(OverModels.UNDECIDED), np.int8)
    code[(sd == -1) | ((sd == 1) & (c1 <= 0) & (s2 <= 0))] = int(OverModels.UNSTABLE)
    code[(sd == 1) & (c1 > 0) & (s2 > 0) & (np.sign(s1) * np.sign(c2) >= 0)] = int(
        OverModels.STABLE
    )
    return code


def _verify(geo: np.ndarray, models) -> np.ndarray:
    """``True`` (stable or neutral), ``False`` (unstable) of model ``models[i]`` at ``geo[i]``:
    the certified float kernel (:func:`atlas.core.hurwitz.ss_verdict`, in the shared shape
    buckets: one program for every number of points), the exact tier where it
    leaves a point undecided."""
    import jax  # noqa: PLC0415 - JAX only when witnesses are checked

    from atlas.core import buckets, hurwitz  # noqa: PLC0415

    m = np.asarray(models, np.float64).reshape(-1, 3)
    n = len(m)
    undecided = int(Verdict.UNDECIDED)
    if n and jax.config.jax_enable_x64:  # shape buckets: the programs of every other caller
        v = buckets.call(hurwitz.ss_verdict_jit, *np.hstack([geo, m]).T)
    else:  # no float64 in JAX here: the exact tier for all
        v = np.full(n, undecided, np.int8)
    for i in np.flatnonzero(v == undecided):
        v[i] = exact.ss_hurwitz(*geo[i].tolist(), *m[i].tolist())
    return np.isin(v, _GOOD)


def _witnesses(geo: np.ndarray, box: ModelBox) -> list:
    """Per geometry, ``(good, bad)``: checked sample models (``None`` where none was found): a
    coarse sample first, the fine one where a side is missing, then :func:`dense_models`."""
    found = [[None, None] for _ in range(len(geo))]
    todo = np.arange(len(geo))
    for fine in (False, True, "dense"):
        if not len(todo):
            break
        good_m, bad_m = _search(geo[todo], box, fine)
        is_good, is_bad = _verify(geo[todo], good_m), ~_verify(geo[todo], bad_m)
        for n, i in enumerate(todo):
            found[i][0] = found[i][0] or (tuple(map(float, good_m[n])) if is_good[n] else None)
            found[i][1] = found[i][1] or (tuple(map(float, bad_m[n])) if is_bad[n] else None)
        todo = np.array([i for i in todo if None in found[i]], dtype=np.int64)
    return found


def ss_over_models(c1, s1, c2, s2, box: ModelBox, *, settle: bool = True) -> dict:
    """Certified SS verdict over the model ``box`` (module docstring) for broadcastable direction
    components: ``ss_over_models`` (:class:`atlas.core.verdicts.OverModels` codes, int8) and the
    :data:`WITNESS_NAMES` (float64, NaN where the code is not ``DEPENDS``).  ``settle=False`` leaves
    what the small budget did not decide ``UNDECIDED``.  ``.stats`` of the result: counts."""
    box = checked(box)
    arrs = np.broadcast_arrays(*(np.asarray(v, np.float64) for v in (c1, s1, c2, s2)))
    shape = arrs[0].shape
    geo = np.stack([a.ravel() for a in arrs], axis=1)
    code = _by_signs(geo, det_signs(geo))
    wit = np.full((len(geo), 6), np.nan)
    open_idx = np.flatnonzero(code == int(OverModels.UNDECIDED))
    stats = {"points": len(geo), "by_signs": len(geo) - len(open_idx), "undecided_before": 0}
    found = _witnesses(geo[open_idx], box)
    for n, i in enumerate(open_idx):
        gf = tuple(geo[i].tolist())
        good, bad = found[n]
        c, w_good, w_bad = _decide(gf, box, good, bad, BUDGET)
        if c == int(OverModels.UNDECIDED):
            stats["undecided_before"] += 1
            if settle:
                c, w_good, w_bad = _decide(gf, box, w_good, w_bad, SETTLE_BUDGET)
        code[i] = c
        if c == int(OverModels.DEPENDS):
            wit[i] = (*w_good, *w_bad)
    stats["undecided_after"] = int(np.sum(code == int(OverModels.UNDECIDED)))
    out = BoxResult({"ss_over_models": code.reshape(shape)})
    out.update({name: wit[:, j].reshape(shape) for j, name in enumerate(WITNESS_NAMES)})
    out.stats = stats
    return out


class BoxResult(dict):
    """The results, with the run's counts in ``.stats``."""

    stats: dict
