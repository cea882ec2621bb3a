"""Sec. 4.3, 5.2, 6.2: consistency over subclasses, the IF/FI conditions, the cone condition, where II
consistency is model-dependent, and the CC necessary condition."""

from __future__ import annotations

import numpy as np

from atlas.core import contact_modes, exact
from atlas.core.verdicts import Consistency
from atlas.paper.audit.printed import MODES, PAPER_TABLE2
from atlas.paper.audit.records import Finding
from atlas.paper.audit.registry import claim
from atlas.paper.audit.samples import PI, directions, fmt_classes
from atlas.paper.tables import class_kernel, padded


def dense_alpha(class_points: dict, blocks: int):
    """Subclass codes and Table 1 consistency of every class-sample system at ``720 * blocks``
    shifted values of alpha (the kernel and shapes of Table 2: each class's sample padded to
    the largest, :func:`atlas.paper.tables.padded`).

    Returns ``(subclass, {mode: consistency}, inputs)``, flat over (system, alpha); ``inputs`` are
    the rows ``(c1, s1, c2, s2, cos alpha, sin alpha)`` for an exact re-check.
    """
    subs, conss, spots = [], {m: [] for m in MODES}, []
    size = max(len(p) for p in class_points.values())
    for c in contact_modes.ALL_CLASSES:
        p = class_points[c]
        c1, s1, c2, s2 = (np.asarray(v)[:, None] for v in directions(p[:, 0], p[:, 1]))
        pad = [padded(v, size) for v in (c1, s1, c2, s2)]
        ii, jj = np.meshgrid(np.arange(len(p)), np.arange(720), indexing="ij")
        for blk in range(blocks):
            al = (np.arange(720) + (blk + 0.5) / blocks) * (2 * PI / 720)
            ca, sa = (np.asarray(v)[None, :] for v in contact_modes.direction(al))
            _, sub, cons = class_kernel(*pad, ca, sa)
            subs.append(np.asarray(sub)[: len(p)].ravel())
            for m in conss:
                conss[m].append(np.asarray(cons[m])[: len(p)].ravel())
            cols = [np.asarray(v)[ii, 0] for v in (c1, s1, c2, s2)]
            cols += [np.asarray(v)[0, jj] for v in (ca, sa)]
            spots.append(np.stack([x.ravel() for x in cols], -1))
    cons = {m: np.concatenate(v) for m, v in conss.items()}
    return np.concatenate(subs), cons, np.concatenate(spots)


def exact_disagreements(sub, cons, inputs, n: int, seed: int = 62) -> int:
    """Of ``n`` seeded random points, how many the exact rational codes disagree with."""
    pick = np.random.default_rng(seed).choice(len(inputs), n, replace=False)
    bad = 0
    for k in pick:
        e = exact.point_codes(*(float(x) for x in inputs[k]))
        bad += int(
            e["subclass_code"] != sub[k] or any(e[f"consistent_{m}"] != cons[m][k] for m in cons)
        )
    return bad


def _varying(sub, cons) -> list[str]:
    """``"<mode> in <subclass>"`` for every subclass where a mode has both verdicts."""
    valid = sub > 0
    out = []
    for m in MODES:
        vals, codes = cons[m][valid], sub[valid]
        lo = np.zeros(1000, bool)
        hi = np.zeros(1000, bool)
        np.logical_or.at(lo, codes[vals == 0], True)
        np.logical_or.at(hi, codes[vals == 1], True)
        out += [f"{m} in {k}" for k in np.flatnonzero(lo & hi)]
    return out


@claim(
    "S62",
    "Sec. 6.2, Sec. 4.2",
    "The consistency of a contact mode never changes in the interior of a subclass "
    "(and stability, which does not depend on a, is the same for every subclass of a "
    "class).",
)
def subclass_consistency(ctx) -> Finding:
    ctx.say("Sec. 6.2: consistency inside each subclass (dense alpha)")
    sub, cons, inputs = dense_alpha(ctx.class_points, ctx.sizes.alpha_blocks)
    ex_bad = exact_disagreements(sub, cons, inputs, ctx.sizes.n_exact62)
    t1 = ctx.table1_points  # plus the T1 random points (uniform beta1, beta2, alpha)
    sub = np.concatenate([sub, t1.subclass.ravel()])
    cons = {m: np.concatenate([cons[m], t1.consistent[m].ravel()]) for m in cons}
    valid = sub > 0
    n_und = int(sum(np.sum(cons[m][valid] == Consistency.UNDECIDED) for m in cons))
    varying = _varying(sub, cons)
    n_sys = sum(len(p) for p in ctx.class_points.values())
    n62 = int(valid.sum())
    return Finding(
        "confirmed" if not varying and not ex_bad and not n_und else "refuted",
        f"{n_sys} class-sample systems x {720 * ctx.sizes.alpha_blocks} values of alpha, plus "
        f"{t1.subclass.size} uniform random (beta1, beta2, alpha): {n62} points off the ties; "
        f"Table 1 consistency of FF, SS, SF, FS per subclass code (all 144), certified kernels: "
        f"subclass-mode pairs with both verdicts: {', '.join(varying) or 'none'}; undecided: "
        f"{n_und}. Exact rational re-check (atlas.core.exact.point_codes) of "
        f"{ctx.sizes.n_exact62} of the points: {ex_bad} disagreements. Stability needs no check "
        "over alpha: M and matrix (7) do not contain a.",
        data={"varying": varying, "exact_disagreements": ex_bad, "points": n62},
    )


def _mark(flags) -> str:
    f = set(np.asarray(flags).tolist())
    return "x" if f == {True} else ("-" if f == {False} else "(x)")


def if_fi_marks(class_points: dict) -> tuple[dict, dict]:
    """IF/FI markers per class: ``(as printed, corrected)``.

    As printed: IF iff b11 < 0 and b12 > 0, FI 'analogous' (b22 < 0 and b21 > 0); corrected: b21
    for IF (the force at contact 1 lifts contact 2) and b12 for FI.
    """
    text, fixed = {}, {}
    for c in contact_modes.ALL_CLASSES:
        p = class_points[c]
        c1, s1, c2, s2 = directions(p[:, 0], p[:, 1])
        text[c] = (_mark((c1 < 0) & (c2 > 0)), _mark((s2 < 0) & (s1 > 0)))
        fixed[c] = (_mark((c1 < 0) & (s1 > 0)), _mark((s2 < 0) & (c2 > 0)))
    return text, fixed


def _against_printed(marks: dict, what: str) -> list[str]:
    out = []
    for c, want in ((c, row[5:7]) for c, row in PAPER_TABLE2.items()):
        if marks[c] != want:
            out.append(
                f"{c}: {what} gives IF {marks[c][0]}, FI {marks[c][1]}; paper's table IF "
                f"{want[0]}, FI {want[1]}"
            )
    return out


@claim(
    "IF",
    "Sec. 4.3; Table 2 col. 6-7",
    "IF is consistent iff b11 < 0 and b12 > 0 (FI analogous); IF/FI are stable whenever "
    "consistent.",
)
def if_fi(ctx) -> Finding:
    text, fixed = if_fi_marks(ctx.class_points)
    typo, corr_bad = _against_printed(text, "text"), _against_printed(fixed, "corrected")
    # stability: b11 < 0 makes matrix (7) a saddle (real positive dominant root): claim B1's count
    b_neg = ctx.matrix7.counts["b<0"]
    if corr_bad or b_neg[0] - b_neg[1]:
        status = "refuted"
    else:
        status = "imprecise" if typo else "confirmed"
    unprinted = (c for c in contact_modes.ALL_CLASSES if c not in PAPER_TABLE2)
    return Finding(
        status,
        "Against the paper's own printed Table 2 columns 6-7 (16 rows), on the class samples: "
        "with b12 > 0 as printed (FI: b21 > 0) the columns differ in "
        + ("; ".join(typo) or "no row")
        + ". With b21 > 0 for IF and b12 > 0 for FI (the "
        "sentence's 'the force at contact 1 lifts up contact 2' and the definition of b_ij) "
        "they differ in " + ("; ".join(corr_bad) or "no row") + "; the 8 unprinted rows "
        "then give "
        + ", ".join(f"{c}: {fixed[c][0]}/{fixed[c][1]}" for c in unprinted)
        + f" (IF/FI). Stability: matrix (7) with b11 < 0 is a saddle (real positive dominant "
        f"root) on {b_neg[1]} of {b_neg[0]} exact random points (claim B1).",
        corrected="IF consistent iff b11 < 0 and b21 > 0; FI iff b22 < 0 and b12 > 0."
        if status == "imprecise"
        else "",
        data={"text_mismatches": len(typo), "corrected_mismatches": len(corr_bad)},
    )


def cone_classes(class_points: dict) -> set:
    """Classes where the cone of b1, b2 meets the open third quadrant at some sample point."""
    t = np.linspace(0, 1, 41)[1:-1]
    out = set()
    for c in contact_modes.ALL_CLASSES:
        p = class_points[c]
        c1, s1, c2, s2 = directions(p[:, 0], p[:, 1])
        x = c1[:, None] * t + c2[:, None] * (1 - t)
        y = s1[:, None] * t + s2[:, None] * (1 - t)
        if np.any((x < 0) & (y < 0)):
            out.add(c)
    return out


@claim(
    "CONE",
    "Sec. 4.3",
    "The cone of b1, b2 meets the open third quadrant in classes 14, 15, 24, 25, 33, 34, "
    "35, 43 and their duals; this is necessary (not sufficient) for II consistency.",
)
def cone(ctx) -> Finding:
    cone_any = cone_classes(ctx.class_points)
    listed = {14, 15, 24, 25, 33, 34, 35, 43}
    duals = {ctx.rows[c].dual for c in listed}
    ii_any = {c for c in contact_modes.ALL_CLASSES if 1 in ctx.ii_consistent_any(c)}
    nec_bad = [c for c in ii_any if c not in cone_any]
    return Finding(
        "confirmed" if cone_any == listed | duals and not nec_bad else "refuted",
        f"Classes whose cone meets the third quadrant: {fmt_classes(cone_any)} (listed + "
        f"duals: {fmt_classes(listed | duals)}). Classes with II consistent anywhere "
        f"(Q = 0, damped, random): {fmt_classes(ii_any)}; outside the cone classes: "
        f"{fmt_classes(nec_bad)}. Necessity also follows algebraically: B (K + l Q) x = "
        "-l^2 x with x in the open first quadrant. Not sufficient: 14, 24, 31, 36 are only "
        "partly II-consistent.",
    )


@claim(
    "IIMD",
    "Sec. 4.3",
    "Whether II is consistent depends on B, K, Q in classes 14, 24 and their duals; "
    "elsewhere it is decided by the class.",
)
def ii_model_dependent(ctx) -> Finding:
    mixed = {c for c in contact_modes.ALL_CLASSES if len(ctx.ii_consistent_any(c)) > 1}
    return Finding(
        "confirmed" if mixed == {14, 24, 31, 36} else "refuted",
        f"Classes with both II verdicts (Q = 0, damped samples, random damped search): "
        f"{fmt_classes(mixed)}.",
    )


@claim(
    "CC",
    "Sec. 5.2, Table 2 col. 9",
    "The CC necessary condition (b11 > 0, b22 > 0) fails in 18 of the 24 classes.",
)
def cc_condition(ctx) -> Finding:
    cc = [c for c in contact_modes.ALL_CLASSES if ctx.rows[c].CC == "?"]
    part = [c for c in contact_modes.ALL_CLASSES if ctx.rows[c].CC == "(?)"]
    return Finding(
        "confirmed" if len(cc) == 6 and not part else "refuted",
        f"Condition holds throughout classes {fmt_classes(cc)} ({len(cc)}), fails "
        f"throughout {24 - len(cc) - len(part)}, partly in {fmt_classes(part)}. Paper's "
        "printed '?' rows: 11, 12, 13, 42, 43 (41 is among the rows missing from the text).",
    )
