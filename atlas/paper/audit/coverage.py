"""The audit's own record (``META``): how many points it evaluated, what was left undecided."""

from __future__ import annotations

from atlas.paper.audit.records import Finding
from atlas.paper.audit.registry import claim


@claim("META", "-", "Audit coverage")
def coverage(ctx) -> Finding:
    G0, GD, R = ctx.q0, ctx.damped, ctx.random
    undecided = sum(P.v["n_undecided"] for P in (G0, GD, R))
    resolved = sum(P.v["n_resolved"] for P in (G0, GD, R))
    return Finding(
        "confirmed",
        f"Q = 0 class samples: {G0.b1.size} points; damped class samples: {GD.b1.size}; "
        f"random: {R.b1.size} ({int(ctx.random_damped.sum())} damped); undecided after exact "
        f"settling: {undecided} (settled exactly: {resolved}); quick = {ctx.quick}, "
        f"ci = {ctx.ci}.",
    )  # the seconds: the run log (atlas.paper.runlog)
