"""The point kernels: how each output of an atlas is computed, by name (SPEC §2).

A :class:`PointKernel` maps the inputs of the parameters it depends on to named raw results, point
by point.  Parameters enter through their direction components or model invariants
(:data:`PARAM_INPUTS`: ``beta1`` -> ``c1, s1``, ``beta2`` -> ``c2, s2``, ``alpha`` -> ``ca, sa``,
``model`` -> ``kappa, q1, q2``, all [1]).  ``fn`` is pure ``jax.numpy`` on broadcastable arrays
(jit-able, returns a dict of arrays); a kernel whose verdicts need tiers has a ``driver`` (the
certified path on broadcastable numpy inputs, :func:`atlas.core.points.spectral_points`), and one
whose codes floating point may leave undecided its exact reference: ``exact``, one point's codes
decided exactly (:mod:`atlas.core.settle` makes the kernel's ``settle`` from it, checked on a probe
point when declared), or a ``settle`` of whole arrays.  The
meaning of the raw codes is declared here: ``undecided`` (the code meaning undecided) and
``true_code`` (for a result stored as a boolean, the code stored as ``True``).

:data:`KERNELS` is the table the output registry (:mod:`atlas.data.outputs`) points into; every
builder runs these kernels: the atlas engine, :func:`atlas.core.rigid_body.verdicts_at`, the figures
and the explorer.  :func:`register` adds a kernel (checked at once: a bad declaration fails here,
not at first use).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Mapping
from types import MappingProxyType

from atlas.core import baseline, buckets, exact, hurwitz, points, warm
from atlas.core import contact_modes as mech
from atlas.core import settle as exact_settle
from atlas.core.verdicts import UNDECIDED_CODE, UNDECIDED_FLAG, Consistency, Verdict

__all__ = [
    "PointKernel",
    "KERNELS",
    "PARAM_INPUTS",
    "register",
    "unregister",
    "verdict_kernels",
    "jitted",
    "run",
    "settle",
]

#: the inputs each parameter contributes to a kernel, in argument order
PARAM_INPUTS: Mapping[str, tuple[str, ...]] = MappingProxyType(
    {
        "beta1": ("c1", "s1"),
        "beta2": ("c2", "s2"),
        "alpha": ("ca", "sa"),
        "model": ("kappa", "q1", "q2"),
    }
)
#: kinds of kernel: verdicts of the theory, or smooth display layers (margins)
KINDS = ("verdict", "display")


@dataclasses.dataclass(frozen=True, eq=False)
class PointKernel:
    """One kernel: ``fn(*inputs) -> {result: array}`` (module docstring).

    ``params``: the parameters, in :data:`PARAM_INPUTS` order.  ``results``: the names ``fn``
    returns.  ``undecided``: per result, the raw code meaning undecided (absent: always decided).
    ``true_code``: per boolean result, the raw code meaning ``True``.  ``driver``: certified tiers,
    ``driver(*inputs, names=, dtype=, resolve=, max_resolve=) -> {result: array}`` with its
    diagnostics in ``.stats``.  ``settle``: exact settlement, ``settle(codes, masks, *inputs)``
    replaces the codes where ``masks`` hold and returns its diagnostics.  ``exact``: the exact
    reference of one point, ``exact(*inputs) -> {result: code}`` on floats (``settle`` is made from
    it, :func:`atlas.core.settle.by_points`).  ``batches``: result sets computed together (default: all at once).
    ``kind``: ``"verdict"`` or ``"display"``.
    """

    name: str
    params: tuple[str, ...]
    results: tuple[str, ...]
    fn: Callable
    undecided: Mapping[str, int] = dataclasses.field(default_factory=dict)
    true_code: Mapping[str, int] = dataclasses.field(default_factory=dict)
    driver: Callable | None = None
    settle: Callable | None = None
    batches: tuple[tuple[str, ...], ...] = ()
    kind: str = "verdict"
    exact: Callable | None = None

    def __post_init__(self):
        put = lambda k, v: object.__setattr__(self, k, v)  # noqa: E731
        put("params", tuple(self.params))
        put("results", tuple(self.results))
        put("undecided", MappingProxyType(dict(self.undecided)))
        put("true_code", MappingProxyType(dict(self.true_code)))
        put("batches", tuple(tuple(b) for b in self.batches) or (self.results,))
        if self.exact is not None and self.settle is None:
            put("settle", exact_settle.by_points(self.exact))
        _check(self)

    @property
    def inputs(self) -> tuple[str, ...]:
        """The input names of ``fn`` and ``driver``, in argument order."""
        return tuple(c for p in self.params for c in PARAM_INPUTS[p])


def _check(k: PointKernel) -> None:
    """A one-line ``ValueError`` naming the first bad field of a kernel declaration."""
    where = f"kernel {k.name!r}"
    if not k.name.isidentifier():
        raise ValueError(f"name: {k.name!r} is not an identifier")
    order = list(PARAM_INPUTS)
    if not k.params or any(p not in PARAM_INPUTS for p in k.params):
        raise ValueError(f"params: {where} needs parameters among {', '.join(order)}")
    if sorted(k.params, key=order.index) != list(k.params) or len(set(k.params)) < len(k.params):
        raise ValueError(f"params: {where} lists its parameters out of order or twice")
    if not k.results or len(set(k.results)) < len(k.results):
        raise ValueError(f"results: {where} needs distinct result names")
    if not callable(k.fn):
        raise ValueError(f"fn: {where} has no kernel function")
    for field in ("undecided", "true_code"):
        extra = set(getattr(k, field)) - set(k.results)
        if extra:
            raise ValueError(f"{field}: {where} declares codes of unknown results {sorted(extra)}")
    flat = [r for b in k.batches for r in b]
    if sorted(flat) != sorted(k.results):
        raise ValueError(f"batches: {where} must split its results exactly once")
    if k.kind not in KINDS:
        raise ValueError(f"kind: {where} must be one of {', '.join(KINDS)}")
    if k.undecided and k.settle is None and k.driver is None:
        raise ValueError(
            f"settle: {where} can leave results undecided but cannot settle them (no exact)"
        )
    if k.exact is not None:
        _check_reference(k, where)


#: a point of general position at which a declared exact reference is tried (direction components
#: and model invariants [1], :data:`PARAM_INPUTS` names)
_PROBE = {"c1": 0.6, "s1": 0.8, "c2": -0.8, "s2": 0.6, "ca": 0.28, "sa": -0.96,
          "kappa": 0.5, "q1": 0.25, "q2": 0.125}  # fmt: skip


def _check_reference(k: PointKernel, where: str) -> None:
    """The exact reference answers for every result the kernel may leave undecided."""
    if not callable(k.exact):
        raise ValueError(f"exact: {where} declares an exact reference that is not callable")
    try:
        got = k.exact(*(_PROBE[i] for i in k.inputs))
    except Exception as e:
        raise ValueError(f"exact: {where}'s exact reference fails on a probe point: {e}") from None
    missing = [r for r in k.undecided if r not in got]
    if missing:
        raise ValueError(f"exact: {where}'s exact reference gives no {missing[0]!r}")


# --- the kernels of the atlas (pure jnp on broadcastable arrays) ---------------------------------


def _b1(c1, s1):
    return {"stable_SF": mech.stable_SF(c1), "consistent_IF": mech.consistent_IF(c1, s1)}


def _b2(c2, s2):
    return {"stable_FS": mech.stable_FS(s2), "consistent_FI": mech.consistent_FI(c2, s2)}


def _b1b2(c1, s1, c2, s2):
    return {"class_code": mech.class_code(c1, s1, c2, s2), "cc_possible": mech.cc_possible(c1, s2)}


def _b1b2a(c1, s1, c2, s2, ca, sa):
    out = {f"consistent_{k}": v for k, v in mech.consistent_modes(c1, s1, c2, s2, ca, sa).items()}
    out["subclass_code"] = mech.subclass_code(c1, s1, c2, s2, ca, sa)
    return out


def _spectral_eig(c1, s1, c2, s2, kappa, q1, q2):
    """The uncertified batched-``eig`` baseline (``method="eig"``)."""
    return baseline.eig_verdicts(c1, s1, c2, s2, kappa, q1, q2)


def _ss_margin(c1, s1, c2, s2, kappa, q1, q2):
    return {"margin_SS": hurwitz.ss_margin(c1, s1, c2, s2, kappa, q1, q2)}


_TABLE1 = tuple(f"consistent_{m}" for m in ("FF", "SF", "FS", "SS"))
_STABLE = int(Verdict.STABLE)
_CONSISTENT = int(Consistency.CONSISTENT)

#: every kernel, by name, in the order builders run them
KERNELS: dict[str, PointKernel] = {
    k.name: k
    for k in (
        PointKernel(
            "b1",
            ("beta1",),
            ("stable_SF", "consistent_IF"),
            _b1,
            true_code={"stable_SF": _STABLE, "consistent_IF": 1},
        ),
        PointKernel(
            "b2",
            ("beta2",),
            ("stable_FS", "consistent_FI"),
            _b2,
            true_code={"stable_FS": _STABLE, "consistent_FI": 1},
        ),
        PointKernel(
            "b1b2",
            ("beta1", "beta2"),
            ("class_code", "cc_possible"),
            _b1b2,
            undecided={"class_code": UNDECIDED_CODE},
            true_code={"cc_possible": 1},
            exact=exact.point_codes,
        ),
        PointKernel(
            "b1b2a",
            ("beta1", "beta2", "alpha"),
            (*_TABLE1, "subclass_code"),
            _b1b2a,
            undecided={"subclass_code": UNDECIDED_CODE, **dict.fromkeys(_TABLE1, UNDECIDED_FLAG)},
            true_code=dict.fromkeys(_TABLE1, _CONSISTENT),
            exact=exact.point_codes,
        ),
        PointKernel(
            "spectral",
            ("beta1", "beta2", "model"),
            points.SPECTRAL_NAMES,
            _spectral_eig,
            undecided=dict.fromkeys(points.SPECTRAL_NAMES[:3], UNDECIDED_FLAG),
            driver=points.spectral_points,
            batches=(("stable_SS",), ("consistent_II", "stable_II"), ("spectral_abscissa",)),
        ),
        PointKernel(
            "ss_margin", ("beta1", "beta2", "model"), ("margin_SS",), _ss_margin, kind="display"
        ),
    )
}


def register(kernel: PointKernel, *, replace: bool = False) -> PointKernel:
    """Add ``kernel`` to :data:`KERNELS` (checked when it was built); returns it."""
    if not isinstance(kernel, PointKernel):
        raise ValueError(f"kernel: expected a PointKernel, got {type(kernel).__name__}")
    if kernel.name in KERNELS and not replace:
        raise ValueError(f"name: kernel {kernel.name!r} is already registered")
    taken = {r: k.name for k in KERNELS.values() if k.name != kernel.name for r in k.results}
    clash = [r for r in kernel.results if r in taken]
    if clash:
        raise ValueError(f"results: {clash[0]!r} is already computed by kernel {taken[clash[0]]!r}")
    KERNELS[kernel.name] = kernel
    return kernel


def unregister(name: str) -> None:
    """Remove a kernel from :data:`KERNELS`."""
    KERNELS.pop(name)


def verdict_kernels(params=None) -> tuple[PointKernel, ...]:
    """The verdict kernels (whose parameters are among ``params``, if given), in table order."""
    return tuple(
        k
        for k in KERNELS.values()
        if k.kind == "verdict" and (params is None or set(k.params) <= set(params))
    )


def run(kernel: PointKernel, inputs: Mapping, names=None) -> dict:
    """The raw results ``names`` (default: all) of ``kernel`` as numpy arrays of the inputs'
    broadcast shape, from a mapping of broadcastable inputs (:data:`PARAM_INPUTS` names), run in
    shape buckets (:mod:`atlas.core.buckets`); uncertified codes are left undecided."""
    names = kernel.results if names is None else tuple(names)
    res = buckets.call(jitted(kernel), *(inputs[i] for i in kernel.inputs))
    return {k: res[k] for k in names}


def settle(kernel: PointKernel, codes: dict, inputs: Mapping) -> dict:
    """Settle exactly, in place, the undecided results of ``kernel`` among ``codes`` (arrays of
    one shape; ``inputs`` broadcast to it); returns the diagnostics ``resolved_points`` and
    ``exact_failures``."""
    masks = {k: codes[k] == u for k, u in kernel.undecided.items() if k in codes}
    if kernel.settle is None or not masks:
        return {"resolved_points": 0, "exact_failures": []}
    return kernel.settle(codes, masks, *(inputs[i] for i in kernel.inputs))


_JITTED: dict = {}


def jitted(kernel: PointKernel):
    """One jitted ``fn`` per kernel object (:class:`atlas.core.warm.Kernel`; every result
    returned, so callers asking for different subsets share one compilation)."""
    jk = _JITTED.get(kernel)
    if jk is None:
        jk = _JITTED[kernel] = warm.Kernel(kernel.fn)
    return jk
