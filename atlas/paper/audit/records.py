"""The audit's records: a claim of the paper with its status and evidence, and the points behind it."""

from __future__ import annotations

from dataclasses import dataclass, field

from atlas.core.verdicts import Verdict

#: verdict codes (:class:`atlas.core.verdicts.Verdict`) as plain ints, as the kernels return them
U, S, N = int(Verdict.UNSTABLE), int(Verdict.STABLE), int(Verdict.NEUTRAL)

#: the statuses a claim can get
STATUSES = ("confirmed", "refuted", "imprecise")


@dataclass
class Counterexample:
    """A point ``(beta1, beta2)`` [rad] with ``kappa, q1, q2`` [1] and the exact facts it shows.

    ``expect`` maps names to required exact values: ``stable_SS``, ``consistent_II``, ``stable_II``
    (verdict codes), ``class_code``, ``negBK_det``/``negBK_tr``/``negBK_disc`` (signs of det, trace,
    discriminant of ``-BK``), ``negative_real_root`` (bool), ``dominant_complex`` (bool).
    """

    beta1: float
    beta2: float
    kappa: float
    q1: float
    q2: float
    expect: dict
    note: str = ""
    eigenvalues: list = field(default_factory=list)
    verified: bool | None = None
    #: "M" (the 4x4 SS matrix (8)/(9)), or "SF" / "FS" (the 2x2 matrix (7) of that mode)
    matrix: str = "M"


@dataclass
class Claim:
    """A claim of the paper (``id``, ``section``, ``statement``) and what the computation found."""

    id: str
    section: str
    statement: str
    status: str  # confirmed / refuted / imprecise
    evidence: str
    corrected: str = ""
    counterexamples: list = field(default_factory=list)
    data: dict = field(default_factory=dict)  # machine-readable counts behind the status


@dataclass
class Finding:
    """What one check found: the part of a :class:`Claim` that the computation decides."""

    status: str
    evidence: str
    corrected: str = ""
    counterexamples: list = field(default_factory=list)
    data: dict = field(default_factory=dict)
