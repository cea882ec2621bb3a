"""The outputs of an atlas and the coordinates they span: the one registry (SPEC §2).

An *output* is a data variable of the Datasets the package builds: the atlas of
:func:`atlas.data.engine.generate`, the mechanism atlases (:mod:`atlas.data.body_atlas`), the
explorer's map (:func:`atlas.explore.maps.compute_map`) and the Fig. 1 map
(:func:`atlas.paper.figures.stability_map`).  Each is declared here once, in the style of xclim's
indicators: the parameters it depends on, *how it is computed*, its stored type, its stored values
(``codes``: each value's CF meaning, label and colour and the undecided value, from which the CF
flags, the enumeration, the explorer's key and the inspector's words are generated), whether it is
in the default set, and its other CF attributes.  :data:`COORDS` holds the attributes of the
coordinates.  How to add one: ``docs/extending.md``.

How an output is computed is one of

* ``kernel``: its point kernel, by name in :data:`atlas.core.kernels.KERNELS` or given (the kernel's
  inputs follow from ``depends``; the meaning of its raw codes, undecided and ``True``, is declared
  with the kernel).  Every builder runs the kernels of the outputs it is asked for;
* ``needs`` + ``state``: a reduction over the model samples of kernel results (model dependence:
  ``state`` maps the needed raw results to a bit set of decided states per sample);
* ``computed_by``: a display layer computed by one named function (not part of an atlas).

:func:`register` checks a declaration completely (unknown kernel, parameters that disagree with the
kernel's, a stored type that disagrees with its codes, a value without a meaning, an undecided
code other than the kernel's, a float without units ...): a bad output fails when it is declared,
in one line, not when it is first computed.
"""

from __future__ import annotations

import colorsys
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
    CONSISTENCY,
    OVER_MODELS,
    UNDECIDED_CODE,
    UNDECIDED_COLOR,
    UNDECIDED_FLAG,
    VERDICT,
    Code,
    Codes,
    Consistency,
    Verdict,
    over_models_codes,
)

__all__ = [
    "Output",
    "OUTPUTS",
    "COORDS",
    "register",
    "unregister",
    "atlas_outputs",
    "default_outputs",
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
#: CF flag attributes an output does not spell: they are generated from its ``codes``
FLAG_KEYS = ("flag_values", "flag_meanings")


@dataclasses.dataclass(frozen=True)
class Output:
    """One output variable, declared once (module docstring).

    ``depends``: parameters, ``"model"`` standing for the scene's spectral parameters (``kappa,
    q`` or ``kappa, q1, q2``).  ``storage``: ``"bool"``, ``"int8"``, ``"int16"`` or ``"float"``
    (the working dtype).  ``attrs``: CF attributes (``long_name``, ``units`` of a float, a
    ``comment``); the flag attributes are generated from ``codes``.  ``codes``: the stored values
    of a boolean or integer output (:class:`atlas.core.verdicts.Codes`: meaning, label and colour
    of each value and the undecided value; a boolean's are ``0, 1``), the source of its CF flags,
    its enumeration (:attr:`enum`) and the explorer's key and labels.  ``kernel``: its point
    kernel (a name in :data:`atlas.core.kernels.KERNELS`, or a new
    :class:`atlas.core.kernels.PointKernel`, registered with it).  ``needs``, ``state``: a
    reduction of kernel results over the model samples.  ``computed_by``: the function computing a display layer.
    ``in_atlas``: :func:`atlas.generate` can compute it (``outputs=``).  ``default``: it is in the
    default set (generate without ``outputs``, the Fig. 1 map, the mechanism files, the
    inspector); a new output joins it only by saying so.  ``raw``: the codes of its kernel's raw
    values where they say more than the stored ones (a boolean stored from a verdict: neutral,
    undecided), the inspector's words for them.
    """

    name: str
    depends: tuple[str, ...]
    storage: str
    attrs: Mapping
    kernel: str | kernels.PointKernel | None = None
    needs: tuple[str, ...] = ()
    state: Callable | None = None
    computed_by: str | None = None
    codes: Codes | None = None
    in_atlas: bool = True
    default: bool = False
    raw: Codes | None = None

    @property
    def enum(self) -> type | None:
        """The enumeration of the stored values of an integer output, generated from ``codes``
        (members with ``label`` and ``color``); ``None`` for booleans and floats."""
        return None if self.codes is None or self.storage == "bool" else self.codes.enum

    @property
    def undecided(self) -> int | None:
        """The raw code meaning undecided (``None``: never undecided): the kernel's (a boolean's
        raw code is not stored), else the declared ``codes``'."""
        if self.kernel is not None:
            return kernels.KERNELS[self.kernel].undecided.get(self.name)
        return None if self.codes is None else self.codes.undecided

    @property
    def true_code(self) -> int | None:
        """For a boolean output computed by a kernel, the raw code stored as ``True``."""
        return (
            None if self.kernel is None else kernels.KERNELS[self.kernel].true_code.get(self.name)
        )


# --- codes and CF attributes ---------------------------------------------------------------------


def _bool(false: str, true: str) -> Codes:
    """The codes of a boolean output: ``0`` = ``false``, ``1`` = ``true`` (CF flag meanings)."""
    return Codes("Bool", ((0, false), (1, true)))


def _attrs(long_name: str, comment: str | None = None) -> dict:
    return {"long_name": long_name, **({"comment": comment} if comment else {})}


def _numbered(name: str, colors: Mapping[int, str], prefix: str) -> Codes:
    """Integer codes: ``-1`` undecided, ``0`` degenerate, then ``prefix_v`` for each value ``v``
    of ``colors`` (labelled ``prefix v``, in its colour)."""
    return Codes(
        name,
        (
            Code(UNDECIDED_CODE, "undecided", color=UNDECIDED_COLOR),
            Code(0, "degenerate", color="#ffffff"),
            *(Code(v, f"{prefix}_{v}", f"{prefix} {v}", c) for v, c in colors.items()),
        ),
        undecided=UNDECIDED_CODE,
    )


#: shade of subclass ``ijk`` by ``k`` (negative: mixed towards black, positive: towards white)
_SHADES = (-0.5, -0.32, -0.14, 0.14, 0.32, 0.5)


def _subclass_colors() -> dict[int, str]:
    """subclass ``ijk`` -> colour: the class ``ij`` (the ``i``-th of Table 2) takes the ``7 i``-th
    of 24 hues (105 degrees apart; saturation 0.75, value 0.85), shaded by ``k`` (k = 1..3 darker,
    4..6 lighter), so the subclasses of one class read as one family (144 shades pairwise
    distinct, which shades of the class colours are not)."""
    out = {}
    n = len(mech.ALL_CLASSES)
    for i, c in enumerate(mech.ALL_CLASSES):
        hue = np.array(colorsys.hsv_to_rgb((7 * i % n) / n, 0.75, 0.85))
        for k, t in enumerate(_SHADES, 1):
            rgb = hue * (1 - abs(t)) + (t > 0) * abs(t)  # towards white (t > 0) or black
            out[10 * c + k] = "#" + "".join(format(round(float(v) * 255), "02x") for v in rgb)
    return out


_B1B2 = ("beta1", "beta2")
_B1B2A = ("beta1", "beta2", "alpha")
_SPECTRAL = ("beta1", "beta2", "model")


def _table1(mode: str) -> Output:
    return Output(
        f"consistent_{mode}",
        _B1B2A,
        "bool",
        _attrs(f"consistency of the {mode} contact mode (paper Table 1, Appendix A)"),
        kernel="b1b2a",
        codes=_bool("inconsistent", "consistent"),
        default=True,
        raw=CONSISTENCY,
    )


def _sliding(name: str, param: str, kernel: str, b: str) -> Output:
    return Output(
        name,
        (param,),
        "bool",
        _attrs(
            f"stability of the {name[-2:]} contact mode (paper Sec. 4.2)",
            f"stable iff {b} > 0; {b} = 0 (neutral) is stored as not_stable",
        ),
        kernel=kernel,
        codes=_bool("not_stable", "stable"),
        default=True,
        raw=VERDICT,
    )


def _impact(name: str, param: str, kernel: str, cond: str) -> Output:
    return Output(
        name,
        (param,),
        "bool",
        _attrs(
            f"consistency of the {name[-2:]} impact without collision (paper Sec. 4.3)",
            f"consistent iff {cond}; stable whenever consistent",
        ),
        kernel=kernel,
        codes=_bool("inconsistent", "consistent"),
        default=True,
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
        _attrs(long_name, comment),
        needs=needs,
        state=state,
        codes=_bool("model_independent", "model_dependent"),
        default=True,
    )


def _geometry_outputs() -> list[Output]:
    """Class codes and the Table 1 / Sec. 4-5 flags: functions of the geometry alone."""
    return [
        Output(
            "class_code",
            _B1B2,
            "int8",
            _attrs("class code ij (rank of beta1, beta2; paper Sec. 3)"),
            kernel="b1b2",
            codes=_numbered("ClassCode", mech.CLASS_COLORS, "class"),
            default=True,
        ),
        Output(
            "subclass_code",
            _B1B2A,
            "int16",
            _attrs("subclass code ijk (rank of alpha; paper Sec. 3)"),
            kernel="b1b2a",
            codes=_numbered("SubclassCode", _subclass_colors(), "subclass"),
            default=True,
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
            _attrs(
                "CC inverse chattering possible (paper Sec. 5.2)",
                "necessary condition b11 > 0 and b22 > 0",
            ),
            kernel="b1b2",
            codes=_bool("impossible", "possible"),
            default=True,
        ),
    ]


def _spectral_outputs() -> list[Output]:
    """The certified verdicts on the eigen-structure of ``M`` and their model dependence."""
    return [
        Output(
            "stable_SS",
            _SPECTRAL,
            "int8",
            _attrs(
                "stability verdict of the SS contact mode (eigenvalues of M, eq. 9)",
                "neutral: no eigenvalue with Re > 0, some with Re = 0 (q = 0; Fig. 1 stable)",
            ),
            kernel="spectral",
            codes=VERDICT,
            default=True,
        ),
        Output(
            "consistent_II",
            _SPECTRAL,
            "int8",
            _attrs("consistency of the II impact without collision (Sec. 4.3)"),
            kernel="spectral",
            codes=CONSISTENCY,
            default=True,
        ),
        Output(
            "stable_II",
            _SPECTRAL,
            "int8",
            _attrs(
                "stability verdict of the II impact without collision (Sec. 4.3)",
                "stable iff the strictly dominant eigenvalue of M is a II eigenvalue",
            ),
            kernel="spectral",
            codes=VERDICT,
            default=True,
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
            default=True,
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
        _attrs(
            "SS stability over every model of the model box (proven)",
            "stable: stable or neutral for every model; unstable: for every model; "
            "depends: a certified witness model on each side (ss_witness_*)",
        ),
        computed_by=_OVER_MODELS,
        codes=OVER_MODELS,
        in_atlas=False,
    )
    return [code, *witness, *_ii_over_models_outputs()]


_II_OVER_MODELS = "atlas.data.over_models.add_ii_over_models"
_II_WHAT = {"ii_consistent_over_models": "consistency", "ii_stable_over_models": "stability"}


def _ii_over_models_outputs() -> list[Output]:
    """Certified II consistency and stability over a box of models (on request: ``model_box``)."""
    out = []
    for name, (yes, no) in II_SIDES.items():
        prefix = name.removesuffix("_over_models")
        out.append(
            Output(
                name,
                _B1B2,
                "int8",
                _attrs(
                    f"II {_II_WHAT[name]} over every model of the box (proven)",
                    f"{yes}: for every model of the box; {no}: for every model; depends: a "
                    f"certified witness model on each side ({prefix}_witness_*)",
                ),
                computed_by=_II_OVER_MODELS,
                codes=over_models_codes(f"{name.title().replace('_', '')}", no, yes),
                in_atlas=False,
            )
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
    _check_codes(o, where)
    how = [o.kernel is not None, bool(o.needs) or o.state is not None, o.computed_by is not None]
    if sum(how) != 1:
        raise ValueError(
            f"kernel: {where} must declare exactly one of kernel, needs + state, computed_by"
        )
    if o.raw is not None and o.kernel is None:
        raise ValueError(f"raw: {where} declares raw codes but has no kernel")
    if o.kernel is not None:
        _check_kernel(o, where)
    elif how[1]:
        _check_reduction(o, where)
    elif o.in_atlas:
        raise ValueError(f"computed_by: {where} has no kernel, so it cannot be an atlas output")
    if o.default and not o.in_atlas:
        raise ValueError(f"default: {where} is in the default set, so it must be an atlas output")


def _check_codes(o: Output, where: str) -> None:
    """Units of a float, the codes of a boolean or integer output."""
    if o.storage == "float":
        if "units" not in o.attrs:
            raise ValueError(f"attrs: {where} is a float and needs units")
        if o.codes is not None:
            raise ValueError(f"codes: {where} is a float and has no codes")
        return
    if not isinstance(o.codes, Codes):
        raise ValueError(
            f"codes: {where} is stored as {o.storage} and needs its codes "
            "(atlas.core.verdicts.Codes: each value with its meaning)"
        )
    if o.storage == "bool" and o.codes.values != (0, 1):
        raise ValueError(f"codes: {where} is a boolean, its codes are 0 and 1")
    info = np.iinfo(np.int8 if o.storage == "bool" else o.storage)
    if any(not info.min <= v <= info.max for v in o.codes.values):
        raise ValueError(f"codes: {where} declares a value outside {o.storage}")
    flags = _flags(o)
    for k in FLAG_KEYS:
        if k in o.attrs and not np.array_equal(o.attrs[k], flags[k]):
            raise ValueError(f"attrs: {where} declares {k}; its flags come from its codes")


def _flags(o: Output) -> dict:
    dtype = np.int8 if o.storage == "bool" else np.dtype(o.storage)
    flags = o.codes.flag_attrs(o.attrs["long_name"], dtype)
    return {k: flags[k] for k in FLAG_KEYS}


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
    if o.raw is not None and (
        not isinstance(o.raw, Codes) or u not in (None, o.raw.undecided)
        or k.true_code.get(o.name, o.raw.values[0]) not in o.raw.values
    ):  # fmt: skip
        raise ValueError(f"raw: {where} declares raw codes that disagree with kernel {o.kernel!r}")
    if o.storage not in ("bool", "float") and u != o.codes.undecided:
        raise ValueError(
            f"undecided: {where} declares undecided {o.codes.undecided}, "
            f"its kernel {o.kernel!r} leaves {u}"
        )


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


#: kernels registered by the declaration of an output (:func:`register` with a kernel object)
_OWN_KERNELS: set[str] = set()


def register(output: Output) -> Output:
    """Declare ``output`` (checked completely, module docstring); returns the stored copy, whose
    ``attrs`` hold the CF flags generated from its codes.  ``kernel`` may be a
    :class:`atlas.core.kernels.PointKernel` object: it is registered with the output (one
    declaration for a new kernel and its output)."""
    if not isinstance(output, Output):
        raise ValueError(f"output: expected an Output, got {type(output).__name__}")
    if output.name in OUTPUTS:
        raise ValueError(f"name: output {output.name!r} is already registered")
    if isinstance(output.kernel, kernels.PointKernel):
        return _register_with_kernel(output)
    o = dataclasses.replace(
        output, depends=tuple(output.depends), needs=tuple(output.needs),
        attrs=MappingProxyType(dict(output.attrs)),
    )  # fmt: skip
    _check(o)
    if o.codes is not None:
        rest = {k: v for k, v in o.attrs.items() if k not in ("long_name", *FLAG_KEYS)}
        attrs = {"long_name": o.attrs["long_name"], **_flags(o), **rest}
        o = dataclasses.replace(o, attrs=MappingProxyType(attrs))
    OUTPUTS[o.name] = o
    return o


def _register_with_kernel(output: Output) -> Output:
    k = output.kernel
    if kernels.KERNELS.get(k.name) is not k:
        kernels.register(k)
        _OWN_KERNELS.add(k.name)
    try:
        return register(dataclasses.replace(output, kernel=k.name))
    except ValueError:
        if k.name in _OWN_KERNELS and not in_kernel(k.name, atlas_only=False):
            kernels.unregister(k.name)
            _OWN_KERNELS.discard(k.name)
        raise


def unregister(name: str) -> None:
    """Remove an output from :data:`OUTPUTS` (and a kernel registered with it that no other
    output uses)."""
    k = OUTPUTS.pop(name).kernel
    if k in _OWN_KERNELS and not in_kernel(k, atlas_only=False):
        kernels.unregister(k)
        _OWN_KERNELS.discard(k)


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
    """The outputs :func:`atlas.generate` can compute, in the order of the Dataset."""
    return tuple(n for n, o in OUTPUTS.items() if o.in_atlas)


def default_outputs() -> tuple[str, ...]:
    """The default set: the atlas outputs computed when none are named (``default``)."""
    return tuple(n for n, o in OUTPUTS.items() if o.in_atlas and o.default)


def kernel_outputs(*, atlas_only: bool = False) -> tuple[str, ...]:
    """The outputs computed by a point kernel, in registry order."""
    return tuple(
        n for n, o in OUTPUTS.items() if o.kernel is not None and (o.in_atlas or not atlas_only)
    )


def verdict_outputs() -> tuple[str, ...]:
    """The verdicts of one point: the outputs of the default set computed by a verdict kernel
    (the reductions over model samples need several samples), in registry order."""
    return tuple(
        n
        for n in default_outputs()
        if OUTPUTS[n].kernel is not None and kernels.KERNELS[OUTPUTS[n].kernel].kind == "verdict"
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
