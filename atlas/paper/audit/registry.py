"""The one registry of the paper's claims (:data:`CLAIMS`) and :func:`run_audit`.

A check is a function of a :class:`~atlas.paper.audit.context.Context` returning a
:class:`~atlas.paper.audit.records.Finding`; ``@claim(id, section, statement)`` registers it, in
report order.  Calling a registered claim on a context returns the :class:`Claim` record with every
counterexample re-verified by the exact reference.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass

from atlas.paper.audit.context import Context
from atlas.paper.audit.records import Claim, Finding
from atlas.paper.audit.verify import verify_counterexample


@dataclass(frozen=True)
class ClaimCheck:
    """A claim of the paper (``id``, ``section``, ``statement``) and the check that decides it."""

    id: str
    section: str
    statement: str
    check: Callable[[Context], Finding]

    def __call__(self, ctx: Context) -> Claim:
        f = self.check(ctx)
        c = Claim(
            self.id,
            self.section,
            self.statement,
            f.status,
            f.evidence,
            f.corrected,
            f.counterexamples,
            f.data,
        )
        for cx in c.counterexamples:
            verify_counterexample(cx)
        return c


#: id -> :class:`ClaimCheck`, in report order
CLAIMS: dict[str, ClaimCheck] = {}


def claim(id: str, section: str, statement: str):
    """Decorator: register ``check(ctx) -> Finding`` as the claim ``id`` of ``section``."""

    def register(check):
        if id in CLAIMS:
            raise ValueError(f"id: claim {id!r} registered twice")
        CLAIMS[id] = ClaimCheck(id, section, statement, check)
        return CLAIMS[id]

    return register


def run_audit(
    quick: bool = False,
    progress=None,
    rows=None,
    ci: bool = False,
    select: Iterable[str] | str | None = None,
    context: Context | None = None,
) -> list[Claim]:
    """Check the paper's claims; returns a list of :class:`Claim` (counterexamples verified).

    ``quick``: 8 class-sample points per class, 2^14 random points; ``ci`` (implies quick): the
    smallest size that still runs every check (4 per class, 2^12 random points, every 4th damped
    (kappa, q1, q2) of the class-sample search) -- for the CI test; the default is the full audit.
    ``select``: claim ids to run (default all, in report order); only the samples they need are
    computed.  ``context``: a :class:`Context` to reuse (its sizes win over ``quick``/``ci``).
    """
    ctx = context if context is not None else Context(quick, ci, progress, rows)
    ids = list(CLAIMS) if select is None else [select] if isinstance(select, str) else list(select)
    unknown = [i for i in ids if i not in CLAIMS]
    if unknown:
        raise ValueError(f"select: unknown claim ids {unknown} (known: {', '.join(CLAIMS)})")
    claims = [CLAIMS[i](ctx) for i in ids]
    ctx.say(f"audit done in {ctx.elapsed():.1f} s")
    return claims
