"""The outputs of an atlas and the coordinates they span: the one registry (SPEC §2).

An *output* is a data variable of the Datasets the package builds: the atlas of
:func:`atlas.data.engine.generate`, the mechanism atlases (:mod:`atlas.data.body_atlas`), the
explorer's map (:func:`atlas.explore.maps.compute_map`) and the Fig. 1 map
(:func:`atlas.paper.figures.stability_map`).  Each is declared here once, in the style of xclim's
indicators: the parameters it depends on, *how it is computed*, its stored type and its CF
attributes.  :data:`COORDS` holds the attributes of the coordinates.

How an output is computed is one of

* ``kernel``: the name of its point kernel in :data:`atlas.core.kernels.KERNELS` (the kernel's
  inputs follow from ``depends``; the meaning of its raw codes, undecided and ``True``, is declared
  with the kernel).  Every builder runs the kernels of the outputs it is asked for;
* ``needs`` + ``state``: a reduction over the model samples of kernel results (model dependence:
  ``state`` maps the needed raw results to a bit set of decided states per sample);
* ``computed_by``: a display layer computed by one named function (not part of an atlas).

:func:`register` checks a declaration completely (unknown kernel, parameters that disagree with the
kernel's, a stored type that disagrees with its codes, CF flags that miss the undecided code ...):
a bad output fails when it is declared, not when it is first computed.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Mapping
from types import MappingProxyType

import numpy as np

from atlas.core import contact_modes as mech
from atlas.core import kernels
from atlas.core.ii_over_models import SIDES as II_SIDES
from atlas.core.ii_over_models import witness_names as ii_witness_names
from atlas.core.model_box import WITNESS_NAMES
from atlas.core.verdicts import (
    UNDECIDED_CODE,
    UNDECIDED_FLAG,
    Consistency,
    OverModels,
    Verdict,
    flag_attrs,
)

__all__ = [
    "Output",
    "OUTPUTS",
    "COORDS",
    "register",
    "unregister",
    "atlas_outputs",
    "kernel_outputs",
    "verdict_outputs",
    "reductions",
    "kernel_of",
    "coord_attrs",
    "variable_attrs",
    "storage_dtype",
    "to_storage",
    "undecided",
    "in_kernel",
]

STORAGE = ("bool", "int8", "int16", "float")


@dataclasses.dataclass(frozen=True)
class Output:
    """One output variable (module docstring).

    ``depends``: parameters, ``"model"`` standing for the scene's spectral parameters (``kappa,
    q`` or ``kappa, q1, q2``).  ``storage``: ``"bool"``, ``"int8"``, ``"int16"`` or ``"float"``
    (the working dtype).  ``attrs``: CF attributes.  ``kernel``: its point kernel
    (:data:`atlas.core.kernels.KERNELS`).  ``needs``, ``state``: a reduction of kernel results
    over the model samples.  ``computed_by``: the function computing a display layer.
    ``enum``: the verdict enumeration of stored flag values (colours, labels).  ``in_atlas``:
    part of :func:`atlas.generate`.
    """

    name: str
    depends: tuple[str, ...]
    storage: str
    attrs: Mapping
    kernel: str | None = None
    needs: tuple[str, ...] = ()
    state: Callable | None = None
    computed_by: str | None = None
    enum: type | None = None
    in_atlas: bool = True

    @property
    def undecided(self) -> int | None:
        """The raw code meaning undecided (``None``: never undecided)."""
        return (
            None if self.kernel is None else kernels.KERNELS[self.kernel].undecided.get(self.name)
        )

    @property
    def true_code(self) -> int | None:
        """For a boolean output computed by a kernel, the raw code stored as ``True``."""
        return (
            None if self.kernel is None else kernels.KERNELS[self.kernel].true_code.get(self.name)
        )


# --- CF attributes -------------------------------------------------------------------------------


def _bool_flags(long_name: str, false: str, true: str, comment: str | None = None) -> dict:
    out = {
        "long_name": long_name,
        "flag_values": np.array([0, 1], np.int8),
        "flag_meanings": f"{false} {true}",
    }
    if comment:
        out["comment"] = comment
    return out


def _code_flags(long_name: str, codes: list[int], prefix: str, dtype) -> dict:
    values = [UNDECIDED_CODE, 0] + codes
    meanings = ["undecided", "degenerate"] + [f"{prefix}_{c}" for c in codes]
    return {
        "long_name": long_name,
        "flag_values": np.array(values, dtype),
        "flag_meanings": " ".join(meanings),
    }


def _verdict_flags(long_name: str, comment: str) -> dict:
    return {**flag_attrs(Verdict, long_name), "comment": comment}


_SUBCLASSES = [10 * c + k for c in mech.ALL_CLASSES for k in range(1, 7)]
_B1B2 = ("beta1", "beta2")
_B1B2A = ("beta1", "beta2", "alpha")
_SPECTRAL = ("beta1", "beta2", "model")


def _table1(mode: str) -> Output:
    return Output(
        f"consistent_{mode}",
        _B1B2A,
        "bool",
        _bool_flags(
            f"consistency of the {mode} contact mode (paper Table 1, Appendix A)",
            "inconsistent",
            "consistent",
        ),
        kernel="b1b2a",
    )


def _sliding(name: str, param: str, kernel: str, b: str) -> Output:
    return Output(
        name,
        (param,),
        "bool",
        _bool_flags(
            f"stability of the {name[-2:]} contact mode (paper Sec. 4.2)",
            "not_stable",
            "stable",
            f"stable iff {b} > 0; {b} = 0 (neutral) is stored as not_stable",
        ),
        kernel=kernel,
    )


def _impact(name: str, param: str, kernel: str, cond: str) -> Output:
    return Output(
        name,
        (param,),
        "bool",
        _bool_flags(
            f"consistency of the {name[-2:]} impact without collision (paper Sec. 4.3)",
            "inconsistent",
            "consistent",
            f"consistent iff {cond}; stable whenever consistent",
        ),
        kernel=kernel,
    )


def _ss_states(res: dict) -> np.ndarray:
    """Decided SS states of one sample as bits: 1 stable (neutral counted as stable), 2 unstable."""
    v = res["stable_SS"]
    ok = (v == int(Verdict.STABLE)) | (v == int(Verdict.NEUTRAL))
    return np.where(ok, 1, np.where(v == int(Verdict.UNSTABLE), 2, 0))


def _ii_states(res: dict) -> np.ndarray:
    """Decided II states of one sample as bits: 1 inconsistent, 2 consistent-unstable,
    4 consistent-stable (0: undecided)."""
    c, s = res["consistent_II"], res["stable_II"]
    return np.where(
        (c == UNDECIDED_FLAG) | (s == UNDECIDED_FLAG),
        0,
        np.where(c == int(Consistency.INCONSISTENT), 1, np.where(s == int(Verdict.STABLE), 4, 2)),
    )


def _model_dependent(mode: str, long_name: str, comment: str, needs, state) -> Output:
    return Output(
        f"model_dependent_{mode}",
        _B1B2,
        "bool",
        _bool_flags(long_name, "model_independent", "model_dependent", comment),
        needs=needs,
        state=state,
    )


def _geometry_outputs() -> list[Output]:
    """Class codes and the Table 1 / Sec. 4-5 flags: functions of the geometry alone."""
    return [
        Output(
            "class_code",
            _B1B2,
            "int8",
            _code_flags(
                "class code ij (rank of beta1, beta2; paper Sec. 3)",
                list(mech.ALL_CLASSES),
                "class",
                np.int8,
            ),
            kernel="b1b2",
        ),
        Output(
            "subclass_code",
            _B1B2A,
            "int16",
            _code_flags(
                "subclass code ijk (rank of alpha; paper Sec. 3)", _SUBCLASSES, "subclass", np.int16
            ),
            kernel="b1b2a",
        ),
        *(_table1(m) for m in ("FF", "SF", "FS", "SS")),
        _sliding("stable_SF", "beta1", "b1", "b11"),
        _impact("consistent_IF", "beta1", "b1", "b11 < 0 and b21 > 0"),
        _sliding("stable_FS", "beta2", "b2", "b22"),
        _impact("consistent_FI", "beta2", "b2", "b22 < 0 and b12 > 0"),
        Output(
            "cc_possible",
            _B1B2,
            "bool",
            _bool_flags(
                "CC inverse chattering possible (paper Sec. 5.2)",
                "impossible",
                "possible",
                "necessary condition b11 > 0 and b22 > 0",
            ),
            kernel="b1b2",
        ),
    ]


def _spectral_outputs() -> list[Output]:
    """The certified verdicts on the eigen-structure of ``M`` and their model dependence."""
    return [
        Output(
            "stable_SS",
            _SPECTRAL,
            "int8",
            _verdict_flags(
                "stability verdict of the SS contact mode (eigenvalues of M, eq. 9)",
                "neutral: no eigenvalue with Re > 0, some with Re = 0 (q = 0; Fig. 1 stable)",
            ),
            kernel="spectral",
            enum=Verdict,
        ),
        Output(
            "consistent_II",
            _SPECTRAL,
            "int8",
            flag_attrs(Consistency, "consistency of the II impact without collision (Sec. 4.3)"),
            kernel="spectral",
            enum=Consistency,
        ),
        Output(
            "stable_II",
            _SPECTRAL,
            "int8",
            _verdict_flags(
                "stability verdict of the II impact without collision (Sec. 4.3)",
                "stable iff the strictly dominant eigenvalue of M is a II eigenvalue",
            ),
            kernel="spectral",
            enum=Verdict,
        ),
        Output(
            "spectral_abscissa",
            _SPECTRAL,
            "float",
            {
                "long_name": "spectral abscissa of M: max real part of its eigenvalues",
                "units": "1",
                "comment": "time scaled by contact 2 (unit 1/sqrt(k2 |b2|)); approximate, "
                "not certified",
            },
            kernel="spectral",
        ),
        _model_dependent(
            "SS",
            "SS stability verdict varies over the model samples (kappa, q)",
            "more than one decided verdict over the samples; neutral counted as stable",
            ("stable_SS",),
            _ss_states,
        ),
        _model_dependent(
            "II",
            "II verdict varies over the model samples (kappa, q)",
            "more than one decided state among inconsistent, consistent-unstable, "
            "consistent-stable over the samples",
            ("consistent_II", "stable_II"),
            _ii_states,
        ),
    ]


_FIGURE_MARGINS = "atlas.paper.figures.stability_map"


def _margin_outputs() -> list[Output]:
    """Display layers: smooth margins whose zero contours are drawn as boundaries."""
    return [
        Output(
            "margin_SS",
            _SPECTRAL,
            "float",
            {
                "long_name": "smooth SS stability margin (zero contour drawn as the SS boundary)",
                "units": "1",
            },
            kernel="ss_margin",
            in_atlas=False,
        ),
        Output(
            "margin_II_consistent",
            _SPECTRAL,
            "float",
            {"long_name": "scaled discriminant (zero where II consistency changes)", "units": "1"},
            computed_by=_FIGURE_MARGINS,
            in_atlas=False,
        ),
        Output(
            "margin_II_stable",
            _SPECTRAL,
            "float",
            {"long_name": "Re(l_II) - max Re(other roots)", "units": "1"},
            computed_by=_FIGURE_MARGINS,
            in_atlas=False,
        ),
    ]


_OVER_MODELS = "atlas.data.over_models.add_over_models"


def _over_models_outputs() -> list[Output]:
    """Certified SS verdicts over a box of models (on request: ``model_box``)."""
    witness = [
        Output(
            name,
            _B1B2,
            "float",
            {
                "long_name": f"{name.split('_')[-1]} of a model on the {name.split('_')[2]} side "
                "(ss_over_models = depends; checked by the exact tier)",
                "units": "1",
            },
            computed_by=_OVER_MODELS,
            in_atlas=False,
        )
        for name in WITNESS_NAMES
    ]
    code = Output(
        "ss_over_models",
        _B1B2,
        "int8",
        {
            **flag_attrs(OverModels, "SS stability over every model of the model box (proven)"),
            "comment": "stable: stable or neutral for every model; unstable: for every model; "
            "depends: a certified witness model on each side (ss_witness_*)",
        },
        computed_by=_OVER_MODELS,
        enum=OverModels,
        in_atlas=False,
    )
    return [code, *witness, *_ii_over_models_outputs()]


_II_OVER_MODELS = "atlas.data.over_models.add_ii_over_models"
_II_WHAT = {"ii_consistent_over_models": "consistency", "ii_stable_over_models": "stability"}


def _ii_over_models_outputs() -> list[Output]:
    """Certified II consistency and stability over a box of models (on request: ``model_box``)."""
    out = []
    for name, (yes, no) in II_SIDES.items():
        attrs = flag_attrs(OverModels, f"II {_II_WHAT[name]} over every model of the box (proven)")
        attrs["flag_meanings"] = f"{no} {yes} depends undecided"
        prefix = name.removesuffix("_over_models")
        attrs["comment"] = (
            f"{yes}: for every model of the box; {no}: for every model; depends: a certified "
            f"witness model on each side ({prefix}_witness_*)"
        )
        out.append(
            Output(
                name,
                _B1B2,
                "int8",
                attrs,
                computed_by=_II_OVER_MODELS,
                enum=OverModels,
                in_atlas=False,
            )  # fmt: skip
        )
        for w in ii_witness_names(name):
            side = w.removeprefix(f"{prefix}_witness_").rsplit("_", 1)[0]
            long_name = (
                f"{w.rsplit('_', 1)[1]} of a model on the {side} side ({name} = depends; "
                "certified by the point kernels)"
            )
            out.append(
                Output(
                    w,
                    _B1B2,
                    "float",
                    {"long_name": long_name, "units": "1"},
                    computed_by=_II_OVER_MODELS,
                    in_atlas=False,
                )  # fmt: skip
            )
    return out


# --- declaration ---------------------------------------------------------------------------------

#: every output, by name (atlas outputs first, in SPEC §2 order)
OUTPUTS: dict[str, Output] = {}


def _check(o: Output) -> None:
    """A one-line ``ValueError`` naming the first incomplete or inconsistent field of ``o``."""
    where = f"output {o.name!r}"
    if not o.name.isidentifier():
        raise ValueError(f"name: {o.name!r} is not an identifier")
    if not o.depends or any(d not in kernels.PARAM_INPUTS for d in o.depends):
        raise ValueError(
            f"depends: {where} needs parameters among {', '.join(kernels.PARAM_INPUTS)}"
        )
    if o.storage not in STORAGE:
        raise ValueError(f"storage: {where} must be one of {', '.join(STORAGE)}, got {o.storage!r}")
    if not o.attrs.get("long_name"):
        raise ValueError(f"attrs: {where} needs a long_name")
    if o.storage == "float" and "units" not in o.attrs:
        raise ValueError(f"attrs: {where} is a float and needs units")
    if "flag_values" in o.attrs and len(o.attrs["flag_meanings"].split()) != len(
        o.attrs["flag_values"]
    ):
        raise ValueError(f"attrs: {where} has as many flag_meanings as flag_values")
    how = [o.kernel is not None, bool(o.needs) or o.state is not None, o.computed_by is not None]
    if sum(how) != 1:
        raise ValueError(
            f"kernel: {where} must declare exactly one of kernel, needs + state, computed_by"
        )
    if o.kernel is not None:
        _check_kernel(o, where)
    elif how[1]:
        _check_reduction(o, where)
    elif o.in_atlas:
        raise ValueError(f"computed_by: {where} has no kernel, so it cannot be an atlas output")


def _check_kernel(o: Output, where: str) -> None:
    k = kernels.KERNELS.get(o.kernel)
    if k is None:
        raise ValueError(
            f"kernel: {where} names unknown kernel {o.kernel!r} "
            f"(known: {', '.join(kernels.KERNELS)})"
        )
    if o.name not in k.results:
        raise ValueError(f"kernel: {where} is not a result of kernel {o.kernel!r}")
    if tuple(o.depends) != k.params:
        raise ValueError(
            f"depends: {where} must depend on the parameters of kernel "
            f"{o.kernel!r}, {', '.join(k.params)}"
        )
    if (o.storage == "bool") != (o.name in k.true_code):
        raise ValueError(
            f"storage: {where} is stored as a boolean iff its kernel declares its true_code"
        )
    u = k.undecided.get(o.name)
    if u is not None and o.storage != "bool":
        flags = [int(v) for v in o.attrs.get("flag_values", ())]
        meanings = o.attrs.get("flag_meanings", "").split()
        if u not in flags or meanings[flags.index(u)] != "undecided":
            raise ValueError(f"attrs: {where} stores undecided code {u}, its flags must name it")


def _check_reduction(o: Output, where: str) -> None:
    if not o.needs or not callable(o.state):
        raise ValueError(f"state: {where} is a reduction and needs both needs and state")
    for n in o.needs:
        src = OUTPUTS.get(n)
        if src is None or src.kernel is None:
            raise ValueError(f"needs: {where} reads {n!r}, which is no kernel output")
        if "model" not in src.depends or set(o.depends) != set(src.depends) - {"model"}:
            raise ValueError(f"depends: {where} must be {n!r} reduced over the model")
    if o.storage != "bool":
        raise ValueError(f"storage: {where} is a reduction and is stored as a boolean")


def register(output: Output) -> Output:
    """Declare ``output`` (checked completely, module docstring); returns the stored copy."""
    if not isinstance(output, Output):
        raise ValueError(f"output: expected an Output, got {type(output).__name__}")
    if output.name in OUTPUTS:
        raise ValueError(f"name: output {output.name!r} is already registered")
    o = dataclasses.replace(
        output, depends=tuple(output.depends), needs=tuple(output.needs),
        attrs=MappingProxyType(dict(output.attrs)),
    )  # fmt: skip
    _check(o)
    OUTPUTS[o.name] = o
    return o


def unregister(name: str) -> None:
    """Remove an output from :data:`OUTPUTS`."""
    OUTPUTS.pop(name)


for _o in _geometry_outputs() + _spectral_outputs() + _margin_outputs() + _over_models_outputs():
    register(_o)

#: attributes of the coordinates (scene parameters, SPEC §1-2)
COORDS: dict[str, MappingProxyType] = {
    k: MappingProxyType(v)
    for k, v in {
        "beta1": dict(
            units="rad", long_name="direction angle of b1 (response of the gaps to contact 1)"
        ),
        "beta2": dict(
            units="rad", long_name="direction angle of b2 (response of the gaps to contact 2)"
        ),
        "alpha": dict(units="rad", long_name="direction angle of a (free relative acceleration)"),
        "kappa": dict(units="1", long_name="stiffness ratio k1 |b1| / (k2 |b2|)"),
        "q": dict(
            units="1", long_name="dimensionless damping q1_hat = q2_hat = q |b| / sqrt(k2 |b2|)"
        ),
        "q1": dict(units="1", long_name="dimensionless damping q1_hat = q1 |b1| / sqrt(k2 |b2|)"),
        "q2": dict(units="1", long_name="dimensionless damping q2_hat = q2 |b2| / sqrt(k2 |b2|)"),
    }.items()
}


# --- accessors -----------------------------------------------------------------------------------


def coord_attrs(name: str) -> dict:
    """A fresh copy of the attributes of coordinate ``name``."""
    return dict(COORDS[name])


def variable_attrs(name: str) -> dict:
    """A fresh copy of the CF attributes of output ``name`` (arrays copied too)."""
    return {k: v.copy() if isinstance(v, np.ndarray) else v for k, v in OUTPUTS[name].attrs.items()}


def atlas_outputs() -> tuple[str, ...]:
    """The outputs of :func:`atlas.generate`, in the order of the Dataset."""
    return tuple(n for n, o in OUTPUTS.items() if o.in_atlas)


def kernel_outputs(*, atlas_only: bool = False) -> tuple[str, ...]:
    """The outputs computed by a point kernel, in registry order."""
    return tuple(
        n for n, o in OUTPUTS.items() if o.kernel is not None and (o.in_atlas or not atlas_only)
    )


def verdict_outputs() -> tuple[str, ...]:
    """The verdicts of one point: the atlas outputs computed by a verdict kernel (the reductions
    over model samples need several samples), in registry order."""
    return tuple(
        n
        for n in kernel_outputs(atlas_only=True)
        if kernels.KERNELS[OUTPUTS[n].kernel].kind == "verdict"
    )


def reductions() -> tuple[str, ...]:
    """The atlas outputs reduced over the model samples (``needs`` + ``state``)."""
    return tuple(n for n, o in OUTPUTS.items() if o.needs and o.in_atlas)


def in_kernel(kernel: str, *, atlas_only: bool = True) -> tuple[str, ...]:
    """Outputs computed by ``kernel``, in registry order."""
    return tuple(
        n for n, o in OUTPUTS.items() if o.kernel == kernel and (o.in_atlas or not atlas_only)
    )


def kernel_of(name: str) -> kernels.PointKernel:
    """The point kernel of output ``name``; a one-line error for an output without one."""
    o = OUTPUTS.get(name)
    if o is None:
        raise ValueError(f"outputs: unknown output {name!r}")
    if o.kernel is None:
        how = "a reduction over the model samples" if o.needs else f"computed by {o.computed_by}"
        raise ValueError(f"outputs: {name} has no point kernel ({how})")
    return kernels.KERNELS[o.kernel]


def storage_dtype(name: str, dtype) -> np.dtype:
    """Stored numpy dtype of output ``name`` (``dtype``: the working float dtype)."""
    s = OUTPUTS[name].storage
    return np.dtype(dtype) if s == "float" else np.dtype(s)


def to_storage(name: str, codes: np.ndarray, dtype) -> np.ndarray:
    """Raw kernel results -> stored values (booleans: ``True`` iff the code is ``true_code``)."""
    o = OUTPUTS[name]
    codes = np.asarray(codes)
    if o.true_code is not None:
        return codes == o.true_code
    return codes.astype(storage_dtype(name, dtype))


def undecided(name: str, codes: np.ndarray) -> np.ndarray:
    """Mask of the raw kernel results of ``name`` that are undecided."""
    u = OUTPUTS[name].undecided
    codes = np.asarray(codes)
    return np.zeros(codes.shape, bool) if u is None else codes == u
