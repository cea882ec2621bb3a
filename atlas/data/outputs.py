"""The outputs of an atlas and the coordinates they span: the one registry (SPEC §2).

An *output* is a data variable of the Datasets the package builds: the atlas of
:func:`atlas.data.engine.generate`, the explorer's map (:func:`atlas.explore.maps.compute_map`)
and the Fig. 1 map (:func:`atlas.paper.figures.stability_map`).  Each is defined here once: the
parameters it depends on, the kernel group that computes it, its stored type, its CF attributes
and the raw code that means *undecided*.  :data:`COORDS` holds the attributes of the coordinates.

Kernel groups (the outputs of a group share their parameters and one jitted kernel):

===================  ==================================  =========================================
group                parameters                          computed by
===================  ==================================  =========================================
``b1``, ``b2``       ``beta1`` / ``beta2``               :mod:`atlas.core.mechanics`
``b1b2``             ``beta1, beta2``                    :mod:`atlas.core.mechanics`
``b1b2a``            ``beta1, beta2, alpha``             :mod:`atlas.core.mechanics` (Table 1)
``spectral``         ``beta1, beta2`` + model            :func:`atlas.core.points.spectral_points`
``model_dependence``  ``beta1, beta2`` (over the model)   reduction of ``spectral`` results
``margin``           ``beta1, beta2`` + model            smooth margins for display (not in atlases)
===================  ==================================  =========================================
"""

from __future__ import annotations

import dataclasses
from types import MappingProxyType

import numpy as np

from atlas.core import mechanics as mech
from atlas.core.verdicts import (
    UNDECIDED_CODE,
    UNDECIDED_FLAG,
    Consistency,
    Verdict,
    flag_attrs,
)

__all__ = [
    "Output",
    "OUTPUTS",
    "ATLAS_OUTPUTS",
    "GROUPS",
    "COORDS",
    "coord_attrs",
    "variable_attrs",
    "storage_dtype",
    "to_storage",
    "undecided",
    "in_group",
]

#: kernel groups of an atlas, in the order the engine computes them
GROUPS = ("b1", "b2", "b1b2", "b1b2a", "spectral", "model_dependence")


@dataclasses.dataclass(frozen=True)
class Output:
    """One output variable.

    ``depends``: parameters, ``"model"`` standing for the scene's spectral parameters (``kappa,
    q`` or ``kappa, q1, q2``).  ``storage``: ``"bool"``, ``"int8"``, ``"int16"`` or ``"float"``
    (the working dtype).  ``undecided``: the raw kernel code meaning undecided (``None``: never
    undecided).  ``true_code``: for a boolean output, the raw code stored as ``True``.
    ``needs``: kernel results a reduction reads.  ``in_atlas``: part of :func:`atlas.generate`.
    """

    name: str
    depends: tuple[str, ...]
    group: str
    storage: str
    attrs: MappingProxyType
    undecided: int | None = None
    true_code: int | None = None
    needs: tuple[str, ...] = ()
    in_atlas: bool = True


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
_B1B2A = ("beta1", "beta2", "alpha")
_SPECTRAL = ("beta1", "beta2", "model")


def _table1(mode: str) -> Output:
    return Output(
        f"consistent_{mode}",
        _B1B2A,
        "b1b2a",
        "bool",
        _bool_flags(
            f"consistency of the {mode} contact mode (paper Table 1, Appendix A)",
            "inconsistent",
            "consistent",
        ),
        undecided=UNDECIDED_FLAG,
        true_code=int(Consistency.CONSISTENT),
    )


def _sliding(name: str, param: str, group: str, b: str) -> Output:
    return Output(
        name,
        (param,),
        group,
        "bool",
        _bool_flags(
            f"stability of the {name[-2:]} contact mode (paper Sec. 4.2)",
            "not_stable",
            "stable",
            f"stable iff {b} > 0; {b} = 0 (neutral) is stored as not_stable",
        ),
        true_code=int(Verdict.STABLE),
    )


def _impact(name: str, param: str, group: str, cond: str) -> Output:
    return Output(
        name,
        (param,),
        group,
        "bool",
        _bool_flags(
            f"consistency of the {name[-2:]} impact without collision (paper Sec. 4.3)",
            "inconsistent",
            "consistent",
            f"consistent iff {cond}; stable whenever consistent",
        ),
        true_code=1,
    )


def _model_dependent(mode: str, long_name: str, comment: str, needs) -> Output:
    return Output(
        f"model_dependent_{mode}",
        ("beta1", "beta2"),
        "model_dependence",
        "bool",
        _bool_flags(long_name, "model_independent", "model_dependent", comment),
        needs=needs,
    )


def _geometry_outputs() -> list[Output]:
    """Class codes and the Table 1 / Sec. 4-5 flags: functions of the geometry alone."""
    return [
        Output(
            "class_code",
            ("beta1", "beta2"),
            "b1b2",
            "int8",
            _code_flags(
                "class code ij (rank of beta1, beta2; paper Sec. 3)",
                list(mech.ALL_CLASSES),
                "class",
                np.int8,
            ),
            undecided=UNDECIDED_CODE,
        ),
        Output(
            "subclass_code",
            _B1B2A,
            "b1b2a",
            "int16",
            _code_flags(
                "subclass code ijk (rank of alpha; paper Sec. 3)", _SUBCLASSES, "subclass", np.int16
            ),
            undecided=UNDECIDED_CODE,
        ),
        *(_table1(m) for m in ("FF", "SF", "FS", "SS")),
        _sliding("stable_SF", "beta1", "b1", "b11"),
        _impact("consistent_IF", "beta1", "b1", "b11 < 0 and b21 > 0"),
        _sliding("stable_FS", "beta2", "b2", "b22"),
        _impact("consistent_FI", "beta2", "b2", "b22 < 0 and b12 > 0"),
        Output(
            "cc_possible",
            ("beta1", "beta2"),
            "b1b2",
            "bool",
            _bool_flags(
                "CC inverse chattering possible (paper Sec. 5.2)",
                "impossible",
                "possible",
                "necessary condition b11 > 0 and b22 > 0",
            ),
            true_code=1,
        ),
    ]


def _spectral_outputs() -> list[Output]:
    """The certified verdicts on the eigen-structure of ``M`` and their model dependence."""
    return [
        Output(
            "stable_SS",
            _SPECTRAL,
            "spectral",
            "int8",
            _verdict_flags(
                "stability verdict of the SS contact mode (eigenvalues of M, eq. 9)",
                "neutral: no eigenvalue with Re > 0, some with Re = 0 (q = 0; Fig. 1 stable)",
            ),
            undecided=UNDECIDED_FLAG,
        ),
        Output(
            "consistent_II",
            _SPECTRAL,
            "spectral",
            "int8",
            flag_attrs(Consistency, "consistency of the II impact without collision (Sec. 4.3)"),
            undecided=UNDECIDED_FLAG,
        ),
        Output(
            "stable_II",
            _SPECTRAL,
            "spectral",
            "int8",
            _verdict_flags(
                "stability verdict of the II impact without collision (Sec. 4.3)",
                "stable iff the strictly dominant eigenvalue of M is a II eigenvalue",
            ),
            undecided=UNDECIDED_FLAG,
        ),
        Output(
            "spectral_abscissa",
            _SPECTRAL,
            "spectral",
            "float",
            {
                "long_name": "spectral abscissa of M: max real part of its eigenvalues",
                "units": "1",
                "comment": "time scaled by contact 2 (unit 1/sqrt(k2 |b2|)); approximate, "
                "not certified",
            },
        ),
        _model_dependent(
            "SS",
            "SS stability verdict varies over the model samples (kappa, q)",
            "more than one decided verdict over the samples; neutral counted as stable",
            ("stable_SS",),
        ),
        _model_dependent(
            "II",
            "II verdict varies over the model samples (kappa, q)",
            "more than one decided state among inconsistent, consistent-unstable, "
            "consistent-stable over the samples",
            ("consistent_II", "stable_II"),
        ),
    ]


def _margin_outputs() -> list[Output]:
    """Display layers: smooth margins whose zero contours are drawn as boundaries."""
    return [
        Output(
            "margin_SS",
            _SPECTRAL,
            "margin",
            "float",
            {
                "long_name": "smooth SS stability margin (zero contour drawn as the SS boundary)",
                "units": "1",
            },
            in_atlas=False,
        ),
        Output(
            "margin_II_consistent",
            _SPECTRAL,
            "margin",
            "float",
            {"long_name": "scaled discriminant (zero where II consistency changes)", "units": "1"},
            in_atlas=False,
        ),
        Output(
            "margin_II_stable",
            _SPECTRAL,
            "margin",
            "float",
            {"long_name": "Re(l_II) - max Re(other roots)", "units": "1"},
            in_atlas=False,
        ),
    ]


def _registry() -> dict[str, Output]:
    outs = _geometry_outputs() + _spectral_outputs() + _margin_outputs()
    return {o.name: dataclasses.replace(o, attrs=MappingProxyType(o.attrs)) for o in outs}


#: every output, by name (atlas outputs first, in SPEC §2 order)
OUTPUTS: dict[str, Output] = _registry()
#: the outputs of :func:`atlas.generate`, in the order of the Dataset
ATLAS_OUTPUTS: tuple[str, ...] = tuple(n for n, o in OUTPUTS.items() if o.in_atlas)

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


def in_group(group: str, *, atlas_only: bool = True) -> tuple[str, ...]:
    """Outputs of a kernel group, in registry order."""
    return tuple(
        n for n, o in OUTPUTS.items() if o.group == group and (o.in_atlas or not atlas_only)
    )


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
