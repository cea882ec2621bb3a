"""App. C: Q1 (instability), Q2 (II consistency), Q3 (II stability) at ``Q = 0`` and with damping."""

from __future__ import annotations

import numpy as np

from atlas.core import contact_modes
from atlas.core import ii_over_models as iim
from atlas.core.verdicts import OverModels, Verdict
from atlas.paper import tables
from atlas.paper.audit.context import KAPPAS_Q0
from atlas.paper.audit.printed import SS_CURVED
from atlas.paper.audit.records import Counterexample, Finding, N, S, U
from atlas.paper.audit.registry import claim
from atlas.paper.audit.samples import PI, first, fmt_classes
from atlas.paper.audit.verify import verify_counterexample
from atlas.paper.tables import KAPPA_Q_SAMPLE

#: App. C, Q2 as printed: II consistent always in these classes, in some regions of P2_SOME
P2_ALWAYS = {15, 25, 32, 33, 34, 35, 43, 44}
P2_SOME = {14, 24}


def issue_point() -> Counterexample:
    """The class-32 point of the issue: II consistent, but a damped complex pair dominates."""
    return Counterexample(
        1.38541667 * PI,
        0.40625 * PI,
        0.1,
        1.0,
        0.01,
        {"consistent_II": 1, "stable_II": U, "class_code": 32, "dominant_complex": True},
        "reported in the issue: complex pair Re 0.1342 > II root 0.1297",
    )


def _q1_misses(ctx) -> list[Counterexample]:
    """A point the paper's Q1 test calls not unstable but is (class 13 if possible)."""
    R, nb = ctx.random, ctx.neg_bk
    miss = nb.clear & nb.unstable & ~((nb.det < 0) | (nb.tr > 0))
    i = first(miss & (R.cls == 13))
    i = first(miss) if i is None else i
    if i is None:
        return []
    expect = {
        "stable_SS": U,
        "negBK_det": 1,
        "negBK_tr": -1,
        "negBK_disc": -1,
        "dominant_complex": True,
    }
    return [R.point(i, expect, "det(-BK) > 0, tr(-BK) < 0, complex pair")]


@claim(
    "C1",
    "App. C, Q1 (Q = 0)",
    "Some eigenvalue of M has positive real part iff -BK has a positive eigenvalue, i.e. "
    "iff det(-BK) < 0 or tr(-BK) > 0.",
)
def q1_test(ctx) -> Finding:
    nb = ctx.neg_bk
    paper_pred = (nb.det < 0) | (nb.tr > 0)
    corr_pred = paper_pred | (nb.disc < 0)
    n_paper = int(np.sum((nb.unstable != paper_pred) & nb.clear))
    n_corr = int(np.sum((nb.unstable != corr_pred) & nb.clear))
    fig2a = Counterexample(
        0.2 * PI,
        0.65 * PI,
        0.5,
        0.0,
        0.0,
        {"stable_SS": U, "negBK_det": 1, "negBK_tr": -1, "negBK_disc": -1},
        "the paper's own Fig. 2a point",
    )
    fig2a_wrong = verify_counterexample(fig2a)
    return Finding(
        "refuted" if n_paper or fig2a_wrong else "confirmed",
        f"On {int(nb.clear.sum())} undamped random points away from ties, the paper's test "
        f"misclassifies {n_paper}; every miss is a complex pair of -BK (discriminant < 0 with "
        f"det > 0, tr < 0), whose square roots always include one with positive real part -- "
        f"the mode-coupling (flutter) instability that makes the curved dashed boundaries of "
        f"Fig. 1. The corrected test misclassifies {n_corr}.",
        corrected="For Q = 0, M has an eigenvalue with positive real part iff -BK has an "
        "eigenvalue off the half-line (-inf, 0]: det(-BK) < 0, or tr(-BK) > 0, or "
        "tr(-BK)^2 < 4 det(-BK).",
        counterexamples=_q1_misses(ctx) + ([fig2a] if fig2a_wrong else []),
        data={
            "points": int(nb.clear.sum()),
            "paper_test_misses": n_paper,
            "corrected_test_misses": n_corr,
        },
    )


@claim("C1a", "App. C, Q1 (Q = 0)", "Instability is impossible in classes 12 and 42.")
def q1_never_unstable(ctx) -> Finding:
    got = {c: ctx.ss_q0[c] for c in (12, 42)}
    return Finding(
        "confirmed" if all(U not in v for v in got.values()) else "refuted",
        f"Q = 0 verdicts over class samples x kappa {KAPPAS_Q0}: "
        + ", ".join(f"{c}: {sorted(Verdict(x).label for x in v)}" for c, v in got.items())
        + " (neutral, never asymptotically stable at Q = 0).",
    )


@claim(
    "C1b",
    "App. C, Q1 (Q = 0)",
    "Instability holds in some regions of classes 13, 14, 23, 31, 41, 46 and always in "
    "the other 16 classes.",
)
def q1_where_unstable(ctx) -> Finding:
    rest = [c for c in contact_modes.ALL_CLASSES if c not in SS_CURVED and c not in (12, 42)]
    bad_rest = [c for c in rest if ctx.ss_q0[c] != {U}]
    some = [c for c in SS_CURVED if ctx.ss_word_q0[c] == "model-dependent"]
    return Finding(
        "confirmed" if not bad_rest and len(some) == 6 else "refuted",
        f"Mixed in {fmt_classes(some)}; classes of the rest not always unstable: "
        f"{fmt_classes(bad_rest)}.",
    )


@claim(
    "C1c",
    "App. C, Q1 (Q = 0)",
    "The eigenvalues with non-positive real parts are always purely imaginary.",
)
def q1_imaginary(ctx) -> Finding:
    R, nb = ctx.random, ctx.neg_bk
    # eigenvalues at Q = 0: l = +-sqrt(mu), mu the eigenvalues of -BK (closed form, complex sqrt)
    sq = np.sqrt(nb.disc.astype(complex))
    lam = np.sqrt(np.stack([(nb.tr + sq) / 2, (nb.tr - sq) / 2], -1))
    scale = np.maximum(1.0, np.abs(lam).max(-1))
    off_axis = np.any(np.abs(lam.real) > 1e-7 * scale[:, None], -1)  # +-l: a root with Re < 0
    n_off = int(np.sum(off_axis & nb.clear))
    n_off_not_unstable = int(np.sum(off_axis & nb.clear & ~nb.unstable))
    n_unst0 = int(np.sum(nb.unstable & nb.clear))
    i = first(~ctx.random_damped & nb.unstable & (nb.disc > 1e-9) & (nb.det < -1e-9))
    status = "refuted" if n_off_not_unstable else "imprecise" if n_off else "confirmed"
    return Finding(
        status,
        f"On the {int(nb.clear.sum())} undamped random points away from ties (eigenvalues "
        f"l = +-sqrt(mu), mu those of -BK): {n_off} have an eigenvalue with Re l < 0 off the "
        f"imaginary axis; all of them are unstable points ({n_unst0} unstable in all; "
        f"off-axis roots at points that are not unstable: {n_off_not_unstable}). At Q = 0 the "
        "spectrum is symmetric under l -> -l, so the mirror image of an unstable eigenvalue "
        "has negative real part, e.g. a positive eigenvalue mu of -BK gives the real "
        "eigenvalue -sqrt(mu) < 0; when no eigenvalue has positive real part, all are purely "
        "imaginary.",
        corrected="At Q = 0, when no eigenvalue has positive real part, all eigenvalues are "
        "purely imaginary (neutral, never asymptotically stable)."
        if status == "imprecise"
        else "",
        counterexamples=[R.point(i, {"stable_SS": U, "negative_real_root": True})]
        if i is not None and n_off
        else [],
        data={"off_axis": n_off, "off_axis_not_unstable": n_off_not_unstable},
    )


@claim(
    "C2",
    "App. C, Q2 (Q = 0); Sec. 4.3",
    "A positive real eigenvalue with a same-sign eigenvector (II consistent) exists in "
    "classes 15, 25, 32-35, 43, 44; in some regions of 14, 24; nowhere else.",
)
def q2_ii_consistent(ctx) -> Finding:
    G0, ci0 = ctx.q0, ctx.ii_consistent_q0
    yes = {c for c, v in ci0.items() if v == {1}}
    some = {c for c, v in ci0.items() if v == {0, 1}}
    cxs = []
    for c in sorted(some - P2_SOME):
        for val in (1, 0):
            i = first((G0.cls == c) & (G0.v["consistent_II"] == val))
            if i is not None:
                cxs.append(G0.point(i, {"consistent_II": val, "class_code": c}))
    if (yes, some) == (P2_ALWAYS, P2_SOME):
        status = "confirmed"
    else:
        status = "imprecise" if yes == P2_ALWAYS and P2_SOME < some else "refuted"
    return Finding(
        status,
        f"Always: {fmt_classes(yes)}; in some regions: {fmt_classes(some)}; never: the "
        "rest. The dual classes 31 (of 14) and 36 (of 24) must behave like 14, 24 (swapping "
        "contacts maps the problem onto itself) and do; Sec. 4.3 says 'classes 14, 24 and "
        "their duals', Appendix C omits the duals.",
        corrected="Yes in 15, 25, 32-35, 43, 44; in some regions of 14, 24, 31, 36; no otherwise.",
        counterexamples=cxs,
    )


@claim(
    "C3",
    "App. C, Q3 (Q = 0); Table 2 (class 25)",
    "II stable ('dominant eigenvalue real with eigenvector in the positive quadrant') as "
    "for Q2, except class 25: two positive real eigenvalues, only the smaller has an "
    "appropriate eigenvector.",
)
def q3_ii_stable(ctx) -> Finding:
    G0, ci0, si0 = ctx.q0, ctx.ii_consistent_q0, ctx.ii_stable_q0
    st_yes = {c for c, v in si0.items() if v == {S}}
    st_some = {c for c, v in si0.items() if S in v and len(v) > 1}
    # class 25: two positive real roots, only the smaller II
    i = first((G0.cls == 25) & (G0.v["consistent_II"] == 1))
    expect = {"consistent_II": 1, "stable_II": U, "class_code": 25}
    c25 = [G0.point(i, expect, "II consistent but not stable")] if i is not None else []
    ok = st_yes == P2_ALWAYS - {25} and st_some <= P2_SOME | {31, 36}
    return Finding(
        "confirmed" if ok else "refuted",
        f"Always stable: {fmt_classes(st_yes)}; sometimes: {fmt_classes(st_some)}; class "
        f"25 stable_II values: {sorted(Verdict(x).label for x in si0[25])} with consistent "
        f"II {sorted(ci0[25])}. Eigenvalues of a class-25 point are listed below (two "
        "positive reals; the larger fails the eigenvector test).",
        counterexamples=c25,
    )


def _damped_changes(ctx):
    """Classes whose Q1 / Q2 / Q3 pattern changes with damping, and random points showing it."""
    R, RD, v = ctx.random, ctx.random_damped, ctx.random.v
    ss0, ci0 = ctx.ss_q0, ctx.ii_consistent_q0
    q1 = [c for c in contact_modes.ALL_CLASSES if ctx.ss_word_q0[c] != ctx.ss_word_all[c]]
    q2 = [c for c in contact_modes.ALL_CLASSES if ctx.ii_consistent_any(c) != ci0[c]]
    q3, cxs = [], []
    for c in q1:
        for st in (S, U):
            i = first((R.cls == c) & (v["stable_SS"] == st) & RD)
            if i is not None and st not in ss0[c] | ({S} if N in ss0[c] else set()):
                cxs.append(R.point(i, {"stable_SS": st, "class_code": c}))
    for c in q2:
        for val in (ctx.ii_consistent_damped[c] | ctx.ii_consistent_random[c]) - ci0[c]:
            i = first((R.cls == c) & (v["consistent_II"] == val) & RD)
            if i is not None:
                cxs.append(R.point(i, {"consistent_II": val, "class_code": c}))
    for c in contact_modes.ALL_CLASSES:
        base = ctx.ii_stable_q0_consistent[c]
        new = (ctx.ii_stable_damped[c] | ctx.ii_stable_random[c]) - base
        if not (new and base):
            continue
        q3.append(c)
        for val in new:
            i = first((R.cls == c) & (v["stable_II"] == val) & (v["consistent_II"] == 1) & RD)
            if i is not None:
                cx = R.point(i, {"consistent_II": 1, "stable_II": val, "class_code": c})
                if val == U:
                    cx.expect["dominant_complex"] = True
                    cx.note = "II consistent, but a complex pair dominates the II root"
                cxs.append(cx)
    return q1, q2, q3, cxs


def _over_models_by_class(ctx) -> tuple[dict, int]:
    """``{class: OverModels codes of its cells}`` on the whole-model-space map of ``atlas paper``'s
    size, and the cell count."""
    ds = ctx.models_map
    code = ds["ss_over_models"].values
    b = ds.beta1.values
    (c1, s1), (c2, s2) = contact_modes.direction(b[:, None]), contact_modes.direction(b[None, :])
    cls = np.broadcast_to(np.asarray(contact_modes.class_code(c1, s1, c2, s2)), code.shape)
    return {c: set(np.unique(code[cls == c]).tolist()) for c in contact_modes.ALL_CLASSES}, b.size


@claim(
    "C1w",
    "App. C (Q != 0), Q1",
    "The Q = 0 answer to Q1 remains true for every model (kappa > 0, q1, q2 >= 0): SS is never "
    "unstable in classes 12 and 42, always unstable in the 16 classes other than 13, 14, 23, 31, "
    "41, 46, and only in these six does it depend on the geometry and the model.",
)
def q1_every_model(ctx) -> Finding:
    seen, n = _over_models_by_class(ctx)
    st, un, dep = int(OverModels.STABLE), int(OverModels.UNSTABLE), int(OverModels.DEPENDS)
    rest = [c for c in seen if c not in SS_CURVED and c not in (12, 42)]
    undecided = [c for c, v in seen.items() if int(OverModels.UNDECIDED) in v or not v]
    bad = [c for c in (12, 42) if seen[c] & {un, dep}] + [c for c in rest if seen[c] & {st, dep}]
    bad += [c for c in SS_CURVED if dep not in seen[c] and c not in undecided]
    status = "refuted" if bad else "imprecise" if undecided else "confirmed"
    return Finding(
        status,
        f"ss_over_models (every region proved, atlas.core.model_box) on the {n}^2 offset grid "
        "of the Fig. 1 plane (fig1_models.png), per class: "
        + "; ".join(
            f"{c}: {', '.join(OverModels(x).label for x in sorted(v))}" for c, v in seen.items()
        )
        + f". Classes breaking the pattern: {fmt_classes(bad)}; with undecided cells or none: "
        f"{fmt_classes(undecided)}.",
    )


def _ii_over_models_by_class(ctx) -> tuple[dict, int]:
    """``{class: the points' over-models records}`` (:func:`atlas.paper.tables.over_models_codes`)
    at Table 2's class samples, and the points per class."""
    per = max(ctx.sizes.per_class, 8)
    samples = tables.class_samples(96, per)
    return {c: tables.over_models_codes(samples[c]) for c in contact_modes.ALL_CLASSES}, per


def _labels(records, name) -> str:
    return ", ".join(iim.label(name, x) for x in sorted({r[name] for r in records}))


@claim(
    "C2w",
    "App. C (Q != 0), Q2; Sec. 4.3",
    "The Q = 0 answer to Q2 remains true for every model (kappa > 0, q1, q2 >= 0): II is "
    "consistent in classes 15, 25, 32-35, 43, 44, in some cases in 14, 24 and their duals 31, 36 "
    "(here: depends on the model), never elsewhere.",
)
def q2_every_model(ctx) -> Finding:
    seen, per = _ii_over_models_by_class(ctx)
    name = "ii_consistent_over_models"
    yes, dep, no, und = (int(OverModels[k]) for k in ("STABLE", "DEPENDS", "UNSTABLE", "UNDECIDED"))
    want = {c: {yes} if c in P2_ALWAYS else {dep} if c in P2_SOME | {31, 36} else {no}
            for c in contact_modes.ALL_CLASSES}  # fmt: skip
    codes = {c: {r[name] for r in v} for c, v in seen.items()}
    bad = [c for c in codes if codes[c] - {und} and codes[c] - {und} != want[c]]
    open_ = [c for c in codes if und in codes[c]]
    return Finding(
        "refuted" if bad else "imprecise" if open_ else "confirmed",
        f"ii_consistent_over_models (atlas.core.ii_over_models: the geometry's signs, or a "
        f"witness model on each side, checked by the point kernels) at {per} points of each "
        "class (Table 2's samples), whole model space, per class: "
        + "; ".join(f"{c}: {_labels(v, name)}" for c, v in seen.items())
        + f". Classes breaking the pattern: {fmt_classes(bad)}; with undecided points: "
        f"{fmt_classes(open_)}.",
    )


def _ii_stability_counterexamples(seen) -> list[Counterexample]:
    """A consistent-but-unstable witness (exact tier) in each class where II stability depends."""
    out = []
    for c, recs in seen.items():
        for r in recs:
            if r["ii_stable_over_models"] == int(OverModels.DEPENDS) and tables.consistent_unstable(
                r
            ):
                k, q1, q2 = r["unstable_witness"]
                expect = {"consistent_II": 1, "stable_II": U, "class_code": c}
                out.append(Counterexample(*r["beta"], k, q1, q2, expect,
                                          "II consistent, not stable: a witness model of "
                                          "ii_stable_over_models"))  # fmt: skip
                break
    return out


@claim(
    "C3w",
    "App. C (Q != 0), Q3; Table 2",
    "The Q = 0 answer to Q3 remains true for every model (kappa > 0, q1, q2 >= 0): the dominant "
    "eigenvalue is an II root for every model in classes 15, 32-35, 43, 44; never in class 25.",
)
def q3_every_model(ctx) -> Finding:
    seen, per = _ii_over_models_by_class(ctx)
    name = "ii_stable_over_models"
    st, un = int(OverModels.STABLE), int(OverModels.UNSTABLE)
    cxs = _ii_stability_counterexamples({c: seen[c] for c in sorted(P2_ALWAYS - {25})})
    c25 = {r[name] for r in seen[25]}
    ok = {c for c in P2_ALWAYS - {25} if {r[name] for r in seen[c]} == {st}}
    open_ = sorted(P2_ALWAYS - {25} - ok - {int(x.expect["class_code"]) for x in cxs})
    refuted = bool(cxs) or c25 != {un}
    return Finding(
        "refuted" if refuted else "imprecise" if open_ else "confirmed",
        f"ii_stable_over_models at {per} points of each class (Table 2's samples), whole model "
        "space, per class: "
        + "; ".join(f"{c}: {_labels(seen[c], name)}" for c in sorted(P2_ALWAYS))
        + f". Proved stable for every model: {fmt_classes(sorted(ok))}; a model with II "
        f"consistent but a dominant complex pair: {fmt_classes([x.expect['class_code'] for x in cxs])}"
        f"; open (a sample never unstable, the proof over the unbounded model space not closed): "
        f"{fmt_classes(open_)}; class 25: {', '.join(OverModels(x).label for x in sorted(c25))}.",
        corrected="With damping II stability depends on the model in classes "
        + fmt_classes([x.expect["class_code"] for x in cxs])
        + " (a complex pair can overtake the II root); class 25 is unstable for every model."
        if cxs
        else "",
        counterexamples=cxs,
    )


@claim(
    "QD",
    "App. C (Q != 0)",
    "The answers to Q1-Q3 for Q = 0 remain true for Q != 0 (only the non-positive "
    "eigenvalues move off the imaginary axis).",
)
def q_damped(ctx) -> Finding:
    q1, q2, q3, cxs = _damped_changes(ctx)
    user = issue_point()
    return Finding(
        "refuted" if q1 or q2 or q3 or verify_counterexample(user) else "confirmed",
        f"Damped search: class samples x {len(KAPPA_Q_SAMPLE)} (kappa, q1, q2) and "
        f"{int(ctx.random_damped.sum())} random damped points. Q1 class pattern changes in: "
        f"{fmt_classes(q1)}; Q2 (II consistency) pattern changes in: "
        f"{fmt_classes(q2)}; Q3 (II stability where consistent) changes in: "
        f"{fmt_classes(q3)}. Independently of the class patterns, the SS boundary "
        "inside the six classes moves with (kappa, q1, q2) and its vanishing-damping limit "
        "differs from Q = 0 (claim Z).",
        corrected="Q1 and Q2 keep their class patterns (per the search); Q3 does not: with "
        "damping a complex pair can overtake the II root, so II stability is "
        f"model-dependent in classes {fmt_classes(q3)} (where Q = 0 "
        "gives 'stable').",
        counterexamples=[user] + cxs,
    )
