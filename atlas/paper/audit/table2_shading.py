"""Table 2's background shading (SS and II stability words): the paper, the regenerated table, the
audit's wider search, and a class against its dual."""

from __future__ import annotations

from atlas.core import contact_modes
from atlas.paper.audit.appendix_c import issue_point
from atlas.paper.audit.printed import DUAL_MODES, SS_CURVED
from atlas.paper.audit.records import Counterexample, Finding, U
from atlas.paper.audit.registry import claim
from atlas.paper.audit.samples import fmt_classes, ss_word
from atlas.paper.tables import KAPPA_Q_SAMPLE, dual_kq


def paper_words() -> dict:
    """``{"SS"|"II": {class: word}}`` as Table 2 shades them (caption, Sec. 4.2)."""
    return {
        "SS": {
            c: "model-dependent" if c in SS_CURVED else ("stable" if c in (12, 42) else "unstable")
            for c in contact_modes.ALL_CLASSES
        },
        "II": {c: "unstable" if c == 25 else "stable" for c in contact_modes.ALL_CLASSES},
    }


def _search_words(ctx) -> dict:
    """The same words from the audit's samples (``-`` where II is never consistent)."""
    ii = {
        c: ctx.ii_stable_q0_consistent[c] | ctx.ii_stable_damped[c] | ctx.ii_stable_random[c]
        for c in contact_modes.ALL_CLASSES
    }
    return {
        "SS": dict(ctx.ss_word_all),
        "II": {c: ss_word(ii[c]) if ii[c] else "-" for c in contact_modes.ALL_CLASSES},
    }


def _dual_mismatches(rows) -> list[str]:
    out = []
    for c in contact_modes.ALL_CLASSES:
        d = rows[rows[c].dual]
        for m, md in DUAL_MODES:
            if rows[c].stability[m] != d.stability[md]:
                out.append(f"{c} {m} {rows[c].stability[m]} vs {d.cls} {md} {d.stability[md]}")
        if rows[c].II_stability != d.II_stability:
            out.append(f"{c} II {rows[c].II_stability} vs {d.cls} II {d.II_stability}")
    return out


def compare_shading(ctx) -> tuple[list, list, list]:
    """Differences of the regenerated Table 2 words: from the paper, from the search, from the dual."""
    rows, paper, search = ctx.rows, paper_words(), _search_words(ctx)
    table = {
        "SS": {c: rows[c].stability["SS"] for c in contact_modes.ALL_CLASSES},
        "II": {c: rows[c].II_stability for c in contact_modes.ALL_CLASSES},
    }
    vs_paper, vs_search = [], []
    for m in ("SS", "II"):
        for c in contact_modes.ALL_CLASSES:
            t = table[m][c]
            if t != "-" and t != paper[m][c]:
                vs_paper.append(f"{m} {c}: paper {paper[m][c]}, computed {t}")
            if t != search[m][c]:
                vs_search.append(f"{m} {c}: Table 2 {t}, search {search[m][c]}")
    return vs_paper, vs_search, _dual_mismatches(rows)


def _issue_points() -> list[Counterexample]:
    """The issue's class-32 point and its dual (class 15)."""
    user = issue_point()
    b1d, b2d = contact_modes.dual_angles(user.beta1, user.beta2)
    dual = Counterexample(
        float(b1d),
        float(b2d),
        *dual_kq(user.kappa, user.q1, user.q2),
        {"consistent_II": 1, "stable_II": U, "class_code": 15, "dominant_complex": True},
        "the dual of the class-32 point above (contacts swapped, kappa -> "
        "1/kappa, q1' = q2/sqrt(kappa), q2' = q1/sqrt(kappa))",
    )
    return [user, dual]


@claim(
    "T2S",
    "Table 2 (shading), Sec. 4.2, App. C",
    "Table 2's background: SS model-dependent (light) in 13, 14, 23, 31, 41, 46, stable "
    "(white) in 12, 42, unstable (dark) elsewhere; II unstable (dark) only in class 25 "
    "(caption), stable wherever else it is consistent.",
)
def table2_shading(ctx) -> Finding:
    vs_paper, vs_search, vs_dual = compare_shading(ctx)
    ii_paper = {int(x.split()[1].rstrip(":")) for x in vs_paper if x.startswith("II")}
    return Finding(
        "refuted" if vs_paper else "confirmed",
        "Table 2 regenerated over the class samples (closed under the dual map) x "
        f"{len(KAPPA_Q_SAMPLE)} (kappa, q1, q2) (closed under kappa -> 1/kappa, "
        "q1' = q2/sqrt(kappa), q2' = q1/sqrt(kappa); kappa 1e-5..1e5). Where the computed "
        "shading differs from the paper's, the computation wins: "
        + ("; ".join(vs_paper) or "no difference")
        + ". Table 2 vs this audit's wider search "
        "(class samples at Q = 0 and damped, random damped points): "
        + ("; ".join(vs_search) or "same words")
        + ". A class vs its dual (SF <-> FS): "
        + ("; ".join(vs_dual) or "same words for every mode")
        + ".",
        corrected=(
            "II is model-dependent (light) in classes "
            + fmt_classes(ii_paper)
            + " (consistent, but a complex pair can dominate with damping; see QD)."
            if ii_paper
            else ""
        ),
        counterexamples=_issue_points() if {15, 32} & ii_paper else [],
        data={"vs_paper": vs_paper, "vs_search": vs_search, "vs_dual": vs_dual},
    )
