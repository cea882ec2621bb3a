"""The one definition of verdict codes.

Every place that needs the codes (kernels, the exact reference, CF flag attributes, plot colours
and legends) reads them from here (SPEC §1-2).  A set of codes is declared once as a
:class:`Codes`: each value with its CF flag meaning, its label in words and its colour, and which
value means undecided; its enumeration (:attr:`Codes.enum`, e.g. :class:`Verdict`) and its CF flag
attributes (:meth:`Codes.flag_attrs`) are generated from that declaration, which is checked when
it is made (a value without a meaning, a meaning twice, an undecided code that is no value ...).
"""

from __future__ import annotations

import dataclasses
import enum
import re
from functools import cached_property

import numpy as np

__all__ = [
    "Code",
    "Codes",
    "Verdict",
    "Consistency",
    "OverModels",
    "VERDICT",
    "CONSISTENCY",
    "OVER_MODELS",
    "over_models_codes",
    "is_over_models",
    "flag_attrs",
    "UNDECIDED_FLAG",
    "UNDECIDED_CODE",
    "UNKNOWN_SIGN",
    "UNDECIDED_COLOR",
]

# The three encodings of "floating point could not certify this" (SPEC §2); nothing else in the
# package spells them as literals.
#: a verdict flag (:class:`Verdict`, :class:`Consistency`) that is undecided
UNDECIDED_FLAG = 3
#: an integer code array (``class_code``, ``subclass_code``) whose value is undecided
UNDECIDED_CODE = -1
#: a certified sign (-1, 0, +1) that could not be certified (:mod:`atlas.core.signs`)
UNKNOWN_SIGN = 2

#: the colour of an undecided value, whatever the output
UNDECIDED_COLOR = "#e41a1c"
_HEX = re.compile(r"#[0-9a-fA-F]{6}")


@dataclasses.dataclass(frozen=True)
class Code:
    """One stored value: ``meaning`` is its CF flag meaning (one word), ``label`` its words in
    legends and the inspector (default: the meaning with spaces), ``color`` ``#rrggbb`` (``None``:
    the explorer's palette picks one), ``damped_label`` its words on a map of a damped model
    (``q1`` or ``q2`` > 0) where they differ."""

    value: int
    meaning: str
    label: str | None = None
    color: str | None = None
    damped_label: str | None = None


class _Coded(enum.IntEnum):
    """Base of the generated enumerations: each member knows its label and colour."""

    @property
    def label(self) -> str:
        return type(self)._codes_.code(int(self)).label

    @property
    def color(self) -> str | None:
        return type(self)._codes_.code(int(self)).color


@dataclasses.dataclass(frozen=True, eq=False)
class Codes:
    """The values of one coded output, declared once (module docstring).

    ``name``: the enumeration's class name.  ``codes``: :class:`Code` entries (or ``(value,
    meaning[, label[, color]])`` tuples), in legend order.  ``undecided``: the value meaning
    undecided (``None``: always decided).  ``doc``: the enumeration's docstring.
    """

    name: str
    codes: tuple
    undecided: int | None = None
    doc: str = ""

    def __post_init__(self):
        codes = tuple(c if isinstance(c, Code) else Code(*c) for c in self.codes)
        codes = tuple(
            dataclasses.replace(c, label=c.meaning.replace("_", " ")) if c.label is None else c
            for c in codes
        )
        object.__setattr__(self, "codes", codes)
        _check_codes(self)

    def code(self, value: int) -> Code:
        """The declaration of ``value`` (``ValueError`` for a value it does not declare)."""
        for c in self.codes:
            if c.value == value:
                return c
        raise ValueError(f"{value} is not a code of {self.name}")

    @property
    def values(self) -> tuple[int, ...]:
        return tuple(c.value for c in self.codes)

    @cached_property
    def enum(self) -> type[enum.IntEnum]:
        """The enumeration of the values, members named by their meanings in capitals."""
        members = [(c.meaning.upper(), c.value) for c in self.codes]
        cls = _Coded(self.name, members, module=__name__)
        cls._codes_ = self
        cls.__doc__ = self.doc or f"The codes of {self.name}."
        return cls

    def flag_attrs(self, long_name: str, dtype=np.int8) -> dict:
        """CF flag attributes (``long_name``, ``flag_values``, ``flag_meanings``)."""
        return {
            "long_name": long_name,
            "flag_values": np.array(self.values, dtype=dtype),
            "flag_meanings": " ".join(c.meaning for c in self.codes),
        }


def _check_codes(c: Codes) -> None:
    """A one-line ``ValueError`` naming the first bad entry of a :class:`Codes` declaration."""
    where = f"codes {c.name!r}"
    if not c.codes:
        raise ValueError(f"codes: {where} declares no value")
    values = [x.value for x in c.codes]
    if len(set(values)) < len(values):
        raise ValueError(f"codes: {where} declares a value twice")
    for x in c.codes:
        if not isinstance(x.value, int) or isinstance(x.value, bool):
            raise ValueError(f"codes: {where} has a non-integer value {x.value!r}")
        if not isinstance(x.meaning, str) or not x.meaning.isidentifier():
            raise ValueError(f"meaning: {where} has no one-word meaning for value {x.value}")
        if x.color is not None and not _HEX.fullmatch(str(x.color)):
            raise ValueError(f"color: {where} value {x.value} needs a colour '#rrggbb'")
    meanings = [x.meaning.upper() for x in c.codes]
    if len(set(meanings)) < len(meanings):
        raise ValueError(f"meaning: {where} declares a meaning twice")
    if c.undecided is not None and c.undecided not in values:
        raise ValueError(f"undecided: {where} declares undecided {c.undecided}, which is no value")


#: stability verdict of a contact mode or of an impact without collision
VERDICT = Codes(
    "Verdict",
    (
        Code(0, "unstable", color="#f7f7f7"),
        Code(1, "stable", color="#525252"),
        Code(2, "neutral", "neutral (q = 0)", "#969696", damped_label="neutral (Re = 0)"),
        Code(UNDECIDED_FLAG, "undecided", color=UNDECIDED_COLOR),
    ),
    undecided=UNDECIDED_FLAG,
    doc="""Stability verdict of a contact mode or of an impact without collision.

    ``NEUTRAL`` means no eigenvalue with positive real part but some on the imaginary axis (the
    ``q = 0`` case of the paper's Fig. 1, drawn there as stable).  ``UNDECIDED`` is emitted only by
    the fast kernels where floating point cannot certify a sign; the exact reference never emits it.
    """,
)
Verdict = VERDICT.enum

#: consistency verdict (``consistent_II`` and the certified consistency flags)
CONSISTENCY = Codes(
    "Consistency",
    (
        Code(0, "inconsistent", color="#f7f7f7"),
        Code(1, "consistent", color="#4292c6"),
        Code(UNDECIDED_FLAG, "undecided", color=UNDECIDED_COLOR),
    ),
    undecided=UNDECIDED_FLAG,
    doc="Consistency verdict (for ``consistent_II`` and the certified consistency flags).",
)
Consistency = CONSISTENCY.enum


def over_models_codes(name: str, no: str, yes: str, doc: str = "") -> Codes:
    """The codes of a verdict over a box of contact models (:mod:`atlas.core.model_box`):
    ``0`` = ``no`` for every model, ``1`` = ``yes`` for every model, ``2`` depends on the model
    (a witness model on each side), ``3`` undecided; the values and colours of every such output
    (:func:`is_over_models`), the words its own."""
    return Codes(
        name,
        (
            Code(0, no, f"{no} for every model", "#f7f7f7"),
            Code(1, yes, f"{yes} for every model", "#525252"),
            Code(2, "depends", "depends on the model", "#fdae6b"),
            Code(UNDECIDED_FLAG, "undecided", color=UNDECIDED_COLOR),
        ),
        undecided=UNDECIDED_FLAG,
        doc=doc,
    )


def is_over_models(codes: Codes | None) -> bool:
    """Whether ``codes`` are those of a verdict over a box of models (:func:`over_models_codes`)."""
    return (
        codes is not None
        and codes.values == (0, 1, 2, UNDECIDED_FLAG)
        and codes.code(2).meaning == "depends"
        and codes.undecided == UNDECIDED_FLAG
    )


#: verdict over a box of contact models (:mod:`atlas.core.model_box`)
OVER_MODELS = over_models_codes(
    "OverModels",
    "unstable",
    "stable",
    """Verdict over a box of contact models (:mod:`atlas.core.model_box`): the SS mode is stable
    (neutral counted as stable, as :data:`Verdict.NEUTRAL` is drawn in Fig. 1) for every model of
    the box, unstable for every model, or depends on the model (witnesses on both sides).""",
)
OverModels = OVER_MODELS.enum


def flag_attrs(codes, long_name: str) -> dict:
    """CF flag attributes (``flag_values``, ``flag_meanings``, ``long_name``) of a :class:`Codes`
    or of an enumeration (meanings: the member names in lower case)."""
    if isinstance(codes, Codes):
        return codes.flag_attrs(long_name)
    members = list(codes)
    return {
        "long_name": long_name,
        "flag_values": np.array([int(m) for m in members], dtype=np.int8),
        "flag_meanings": " ".join(m.name.lower() for m in members),
    }
