"""The one definition of verdict codes.

Every place that needs the codes (kernels, the exact reference, CF flag attributes, plot colours
and legends) reads them from here (SPEC §1-2).
"""

from __future__ import annotations

import enum

import numpy as np

__all__ = [
    "Verdict",
    "Consistency",
    "OverModels",
    "flag_attrs",
    "UNDECIDED_FLAG",
    "UNDECIDED_CODE",
    "UNKNOWN_SIGN",
]

# The three encodings of "floating point could not certify this" (SPEC §2); nothing else in the
# package spells them as literals.
#: a verdict flag (:class:`Verdict`, :class:`Consistency`) that is undecided
UNDECIDED_FLAG = 3
#: an integer code array (``class_code``, ``subclass_code``) whose value is undecided
UNDECIDED_CODE = -1
#: a certified sign (-1, 0, +1) that could not be certified (:mod:`atlas.core.signs`)
UNKNOWN_SIGN = 2


class Verdict(enum.IntEnum):
    """Stability verdict of a contact mode or of an impact without collision.

    ``NEUTRAL`` means no eigenvalue with positive real part but some on the imaginary axis (the
    ``q = 0`` case of the paper's Fig. 1, drawn there as stable).  ``UNDECIDED`` is emitted only by
    the fast kernels where floating point cannot certify a sign; the exact reference never emits it.
    """

    UNSTABLE = 0
    STABLE = 1
    NEUTRAL = 2
    UNDECIDED = UNDECIDED_FLAG

    @property
    def label(self) -> str:
        return _VERDICT_STYLE[self][0]

    @property
    def color(self) -> str:
        return _VERDICT_STYLE[self][1]


class Consistency(enum.IntEnum):
    """Consistency verdict (for ``consistent_II`` and the certified consistency flags)."""

    INCONSISTENT = 0
    CONSISTENT = 1
    UNDECIDED = UNDECIDED_FLAG

    @property
    def label(self) -> str:
        return _CONSISTENCY_STYLE[self][0]

    @property
    def color(self) -> str:
        return _CONSISTENCY_STYLE[self][1]


_VERDICT_STYLE = {
    Verdict.UNSTABLE: ("unstable", "#f7f7f7"),
    Verdict.STABLE: ("stable", "#525252"),
    Verdict.NEUTRAL: ("neutral (q = 0)", "#969696"),
    Verdict.UNDECIDED: ("undecided", "#e41a1c"),
}
_CONSISTENCY_STYLE = {
    Consistency.INCONSISTENT: ("inconsistent", "#f7f7f7"),
    Consistency.CONSISTENT: ("consistent", "#4292c6"),
    Consistency.UNDECIDED: ("undecided", "#e41a1c"),
}


def flag_attrs(codes: type[enum.IntEnum], long_name: str) -> dict:
    """CF flag attributes (``flag_values``, ``flag_meanings``, ``long_name``) for an enumeration."""
    members = list(codes)
    return {
        "long_name": long_name,
        "flag_values": np.array([int(m) for m in members], dtype=np.int8),
        "flag_meanings": " ".join(m.name.lower() for m in members),
    }


class OverModels(enum.IntEnum):
    """Verdict over a box of contact models (:mod:`atlas.core.model_box`): the SS mode is stable
    (neutral counted as stable, as :data:`Verdict.NEUTRAL` is drawn in Fig. 1) for every model of
    the box, unstable for every model, or depends on the model (witnesses on both sides)."""

    UNSTABLE = 0
    STABLE = 1
    DEPENDS = 2
    UNDECIDED = UNDECIDED_FLAG

    @property
    def label(self) -> str:
        return _OVER_MODELS_STYLE[self][0]

    @property
    def color(self) -> str:
        return _OVER_MODELS_STYLE[self][1]


_OVER_MODELS_STYLE = {
    OverModels.UNSTABLE: ("unstable for every model", "#f7f7f7"),
    OverModels.STABLE: ("stable for every model", "#525252"),
    OverModels.DEPENDS: ("depends on the model", "#fdae6b"),
    OverModels.UNDECIDED: ("undecided", "#e41a1c"),
}
