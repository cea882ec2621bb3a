"""Scenes: which parameters of an atlas vary, over which values, and which outputs are wanted.

A :class:`Scene` holds one entry per parameter of the data contract (SPEC §2):

========  =====  ============================================================================
name      units  meaning
========  =====  ============================================================================
beta1     rad    direction angle of ``b1`` (paper Sec. 2)
beta2     rad    direction angle of ``b2``
alpha     rad    direction angle of ``a`` (only the consistency outputs need it)
kappa     1      stiffness ratio ``k1 |b1| / (k2 |b2|)`` (SPEC §1; the paper's Fig. 1 uses 0.5)
q         1      dimensionless damping ``q1_hat = q2_hat = q`` (SPEC §1)
q1, q2    1      the two damping invariants varied separately (instead of ``q``)
========  =====  ============================================================================

Each entry is a *scalar* (a fixed parameter: a scalar coordinate and a global attribute of the
atlas) or a *range* (a dimension of the atlas, even when it has a single value).  Ranges are written

* ``"START:STOP:N"`` -- ``N`` values linearly spaced, both ends included.  **Angles over a full
  turn** (``STOP - START == 2 pi``) exclude the endpoint, because ``STOP`` is the same direction as
  ``START`` (``numpy.linspace(..., endpoint=False)``);
* ``"log:START:STOP:N"`` -- ``N`` values geometrically spaced, both ends included (``START > 0``);
* ``"V1,V2,..."`` -- explicit values, strictly increasing (CF coordinate variables are monotonic);
* a number or a 1-D array (an array is a range, a number is a scalar).

Any number may carry a ``pi`` suffix: ``"0.2pi"``, ``"pi"``, ``"-pi/2"`` is *not* accepted, write
``"-0.5pi"``.  Physical parameters ``k_j > 0``, ``q_j >= 0``, ``|b_j| > 0`` are converted to the
invariants by :func:`invariants` / :meth:`Scene.from_physical`.

Every invalid input raises :class:`ValueError` with a one-line message that starts with the name of
the parameter (``"kappa: must be > 0, got -1"``).
"""

from __future__ import annotations

import dataclasses
import math
from functools import cached_property

import numpy as np

from atlas.core import checks
from atlas.core.contact_modes import invariants  # noqa: F401  (re-exported: SPEC §3 physical entry)
from atlas.data.outputs import OUTPUTS, atlas_outputs, default_outputs, reductions

__all__ = [
    "Scene",
    "Axis",
    "parse_values",
    "invariants",
    "BUILTIN_SCENES",
    "builtin",
]

TWO_PI = 2.0 * math.pi
ANGLES = ("beta1", "beta2", "alpha")


def _parse_number(text: str, name: str) -> float:
    """A float, optionally with a ``pi`` suffix (``"0.2pi"``, ``"pi"``, ``"-1.5pi"``; keywords are
    case-sensitive: ``"2PI"`` is refused)."""
    t = text.strip()
    if t.lower().lstrip("+-") in ("nan", "inf", "infinity"):
        raise ValueError(f"{name}: must be finite, got {text.strip()!r}")
    if t.endswith("pi"):
        head = t[:-2].strip().rstrip("*").strip()
        if head in ("", "+"):
            return math.pi
        if head == "-":
            return -math.pi
        try:
            return float(head) * math.pi
        except ValueError:
            pass
        raise ValueError(f"{name}: cannot parse {text.strip()!r} as a number")
    try:
        return float(t)
    except ValueError:
        raise ValueError(f"{name}: cannot parse {text.strip()!r} as a number") from None


def parse_values(spec, name: str):
    """Parse one parameter specification into ``(values, is_dim)``.

    Returns a 1-D float64 array and ``True`` for a range, or a 0-d float64 array and ``False`` for a
    scalar.  See the module docstring for the syntax.
    """
    if isinstance(spec, str):
        text = spec.strip()
        if not text:
            raise ValueError(f"{name}: empty value")
        if text.startswith("log:"):
            parts = text[4:].split(":")
            if len(parts) != 3:
                raise ValueError(f"{name}: expected log:START:STOP:N, got {text!r}")
            start, stop = (_parse_number(p, name) for p in parts[:2])
            n = _parse_count(parts[2], name)
            if start <= 0 or stop <= 0:
                raise ValueError(f"{name}: log range needs START > 0 and STOP > 0, got {text!r}")
            _check_order(start, stop, n, name, text)
            vals = np.geomspace(start, stop, n) if n > 1 else np.array([start])
            return _finish(vals, True, name)
        if ":" in text:
            parts = text.split(":")
            if len(parts) != 3:
                raise ValueError(f"{name}: expected START:STOP:N, got {text!r}")
            start, stop = (_parse_number(p, name) for p in parts[:2])
            n = _parse_count(parts[2], name)
            _check_order(start, stop, n, name, text)
            full_turn = name in ANGLES and math.isclose(stop - start, TWO_PI, rel_tol=1e-12)
            if n == 1:
                vals = np.array([start])
            else:
                vals = np.linspace(start, stop, n, endpoint=not full_turn)
            return _finish(vals, True, name)
        if "," in text:
            items = [p for p in text.split(",")]
            if items and items[-1].strip() == "":
                items = items[:-1]  # "0.5," is a one-value range
            if not items:
                raise ValueError(f"{name}: empty list")
            vals = np.array([_parse_number(p, name) for p in items], dtype=np.float64)
            return _finish(vals, True, name)
        return _finish(np.array(_parse_number(text, name)), False, name)
    arr = checks.real(name, spec, finite=False)
    if arr.ndim == 0:
        return _finish(arr, False, name)
    if arr.ndim != 1:
        raise ValueError(f"{name}: expected a scalar or a 1-D array, got shape {arr.shape}")
    if arr.size == 0:
        raise ValueError(f"{name}: empty range")
    return _finish(arr.copy(), True, name)


def _parse_count(text: str, name: str) -> int:
    try:
        n = int(text.strip())
    except ValueError:
        raise ValueError(f"{name}: N must be an integer, got {text.strip()!r}") from None
    if n < 1:
        raise ValueError(f"{name}: empty range (N = {n})")
    from atlas.data.limits import available_memory  # noqa: PLC0415 - limits imports the tiles

    return checks.axis_size(name, n, available_memory())


def _check_order(start, stop, n, name, text):
    if stop < start:
        raise ValueError(f"{name}: reversed range (STOP < START) in {text!r}")
    if stop == start and n > 1:
        raise ValueError(f"{name}: empty range (START == STOP with N = {n}) in {text!r}")


def _finish(vals: np.ndarray, is_dim: bool, name: str):
    vals = np.asarray(vals, dtype=np.float64)
    if not np.all(np.isfinite(vals)):
        raise ValueError(f"{name}: must be finite (NaN or inf given)")
    if is_dim and vals.size > 1 and not np.all(np.diff(vals) > 0):
        raise ValueError(f"{name}: values must be strictly increasing")
    if name in ("kappa", "q", "q1", "q2"):
        checks.model_values(name, vals)  # one rule for the command line and the API
    return vals, is_dim


@dataclasses.dataclass(frozen=True)
class Axis:
    """One parsed scene parameter: ``values`` (1-D for a dimension, 0-d for a scalar)."""

    name: str
    values: np.ndarray
    is_dim: bool
    spec: str

    @property
    def size(self) -> int:
        return int(self.values.size)


@dataclasses.dataclass(frozen=True, eq=False)
class Scene:
    """Parameters of an atlas and the outputs wanted (see the module docstring for the syntax).

    Parameters
    ----------
    beta1, beta2 : str, float or array
        Direction angles of ``b1``, ``b2`` [rad].  Default: 256 values over ``[0, 2 pi)``.
    alpha : str, float, array or None
        Direction angle of ``a`` [rad]; ``None`` (default): the scene has no ``alpha`` and the
        consistency outputs (``subclass_code``, ``consistent_FF`` ...) are not available.
    kappa : str, float or array
        ``k1 |b1| / (k2 |b2|)`` [1], ``> 0``.  Default 0.5 (the paper's Fig. 1).
    q : str, float, array or None
        ``q1_hat = q2_hat`` [1], ``>= 0``.  Default 0 (Fig. 1) unless ``q1``/``q2`` are given.
    q1, q2 : str, float, array or None
        The damping invariants varied separately; give both (or neither) and no ``q``.
    outputs : sequence of str or None
        Subset of :func:`atlas.data.outputs.atlas_outputs`; ``None`` = every output of the default set
        (:func:`atlas.data.outputs.default_outputs`) the scene can compute (the
        consistency outputs need ``alpha``, the ``model_dependent_*`` reductions need ``kappa`` or
        ``q`` varied over more than one value).
    name : str
        Name of the scene (an attribute of the atlas).
    """

    beta1: object = "0:2pi:256"
    beta2: object = "0:2pi:256"
    alpha: object = None
    kappa: object = 0.5
    q: object = None
    q1: object = None
    q2: object = None
    outputs: object = None
    name: str = "custom"

    def __post_init__(self):
        if (self.q1 is None) != (self.q2 is None):
            missing = "q2" if self.q2 is None else "q1"
            raise ValueError(f"{missing}: q1 and q2 must be given together")
        if self.q1 is not None and self.q is not None:
            raise ValueError("q: give either q or q1 and q2, not both")
        if isinstance(self.outputs, str):
            object.__setattr__(self, "outputs", _split_outputs(self.outputs))
        _ = self.axes, self.output_names  # validate eagerly

    # --- parsed view ---------------------------------------------------------------------------

    @cached_property
    def axes(self) -> dict[str, Axis]:
        """Parsed parameters in canonical order (``beta1 beta2 alpha kappa q`` or ``... q1 q2``)."""
        raw = {"beta1": self.beta1, "beta2": self.beta2, "alpha": self.alpha, "kappa": self.kappa}
        if self.q1 is not None:
            raw.update(q1=self.q1, q2=self.q2)
        else:
            raw["q"] = 0.0 if self.q is None else self.q
        out = {}
        for key, spec in raw.items():
            if spec is None:
                if key in ("beta1", "beta2", "kappa"):
                    raise ValueError(f"{key}: required")
                continue
            vals, is_dim = parse_values(spec, key)
            text = spec if isinstance(spec, str) else _describe(vals)
            out[key] = Axis(key, vals, is_dim, text)
        return out

    @property
    def model_names(self) -> tuple[str, ...]:
        """The spectral (model) parameters: ``("kappa", "q")`` or ``("kappa", "q1", "q2")``."""
        return ("kappa", "q1", "q2") if "q1" in self.axes else ("kappa", "q")

    @property
    def dims(self) -> tuple[str, ...]:
        """All dimensions of the atlas, in canonical order."""
        return tuple(k for k, a in self.axes.items() if a.is_dim)

    @property
    def shape(self) -> dict[str, int]:
        return {k: self.axes[k].size for k in self.dims}

    def depends(self, output: str) -> tuple[str, ...]:
        """Parameters an output depends on (scalar or varied), canonical order."""
        dep = []
        for d in OUTPUTS[output].depends:
            dep.extend(self.model_names if d == "model" else (d,))
        return tuple(dep)

    def output_dims(self, output: str) -> tuple[str, ...]:
        """The dimensions an output spans: the varied parameters it depends on (SPEC §2)."""
        return tuple(d for d in self.depends(output) if self.axes[d].is_dim)

    @property
    def model_varied(self) -> bool:
        """True if some model parameter takes more than one value (model dependence is defined)."""
        return any(self.axes[m].is_dim and self.axes[m].size > 1 for m in self.model_names)

    def available(self, output: str) -> str | None:
        """``None`` if the scene can compute ``output``, else the reason."""
        if "alpha" in OUTPUTS[output].depends and "alpha" not in self.axes:
            return "needs alpha (give an alpha value or range)"
        if output in reductions() and not self.model_varied:
            return "needs kappa or q varied over more than one value"
        return None

    @cached_property
    def output_names(self) -> tuple[str, ...]:
        """The outputs to compute, in registry order (:func:`atlas.data.outputs.atlas_outputs`)."""
        every = atlas_outputs()
        if self.outputs is None:
            return tuple(o for o in default_outputs() if self.available(o) is None)
        wanted = list(self.outputs)
        if not wanted:
            raise ValueError("outputs: empty list")
        for o in wanted:
            if o not in every:
                known = ", ".join(every)
                raise ValueError(f"outputs: unknown variable {o!r} (known: {known})")
            why = self.available(o)
            if why:
                raise ValueError(f"outputs: {o} {why}")
        return tuple(o for o in every if o in wanted)

    def points(self, output: str | None = None) -> int:
        """Number of points of an output (default: of the largest output)."""
        outs = [output] if output else list(self.output_names)
        return max(int(np.prod([self.axes[d].size for d in self.output_dims(o)])) for o in outs)

    def fixed(self) -> dict[str, float]:
        """The scalar (not varied) parameters."""
        return {k: float(a.values) for k, a in self.axes.items() if not a.is_dim}

    def describe(self) -> str:
        """One line: ``name: beta1=0:2pi:512; beta2=...; kappa=0.5; q=0``."""
        parts = [f"{k}={a.spec}" for k, a in self.axes.items()]
        return f"{self.name}: " + "; ".join(parts)

    def replace(self, **changes) -> Scene:
        """A copy with some fields changed (validated again)."""
        if "q1" in changes or "q2" in changes:
            changes.setdefault("q", None)
        if changes.get("q") is not None:
            changes.setdefault("q1", None)
            changes.setdefault("q2", None)
        return dataclasses.replace(self, **changes)

    @classmethod
    def from_physical(cls, *, k1, k2, q1=0.0, q2=0.0, b1=1.0, b2=1.0, **kw) -> Scene:
        """A scene with the model fixed by physical parameters (see :func:`invariants`)."""
        inv = invariants(k1, k2, q1, q2, b1, b2)
        if inv["q1"] == inv["q2"]:
            return cls(kappa=inv["kappa"], q=inv["q1"], **kw)
        return cls(kappa=inv["kappa"], q1=inv["q1"], q2=inv["q2"], **kw)


def _split_outputs(text: str) -> tuple[str, ...]:
    return tuple(o.strip() for o in text.split(",") if o.strip())


def _describe(vals: np.ndarray) -> str:
    if vals.ndim == 0:
        return repr(float(vals))
    if vals.size <= 6:
        return ",".join(repr(float(v)) for v in vals)
    return f"{vals.size} values in [{float(vals[0])!r}, {float(vals[-1])!r}]"


#: built-in scenes (see :func:`builtin`)
BUILTIN_SCENES: dict[str, dict] = {
    # the paper's Fig. 1: beta1-beta2 plane, kappa = 0.5, q = 0
    "fig1": dict(beta1="0:2pi:512", beta2="0:2pi:512", kappa=0.5, q=0.0),
    # the same plane over a small sample of models: the model-dependent boundaries of Fig. 1
    "fig1-model": dict(
        beta1="0:2pi:512", beta2="0:2pi:512", kappa="0.1,0.5,2,10", q="0,0.05,0.5,2"
    ),
    # dense 4-D atlas (raise the counts from the CLI for larger runs)
    "atlas4d": dict(
        beta1="0:2pi:256", beta2="0:2pi:256", kappa="log:0.01:100:9", q="log:0.001:10:9"
    ),
}


def builtin(name: str, **overrides) -> Scene:
    """A built-in scene (``fig1``, ``fig1-model``, ``atlas4d``), optionally with fields replaced."""
    if name not in BUILTIN_SCENES:
        raise ValueError(f"scene: unknown scene {name!r} (known: {', '.join(BUILTIN_SCENES)})")
    fields = dict(BUILTIN_SCENES[name])
    if overrides.get("q1") is not None or overrides.get("q2") is not None:
        fields.pop("q", None)
    if overrides.get("q") is not None:
        fields.pop("q1", None)
        fields.pop("q2", None)
    fields.update({k: v for k, v in overrides.items() if v is not None})
    return Scene(name=name, **fields)
