"""Sec. 6: the worked subclasses (152, 254, 261/262), 'nothing stable' ranges, Fig. 2's parameter
points, and how the SS boundary moves with K and Q."""

from __future__ import annotations

import numpy as np

from atlas.core import contact_modes, exact, warm
from atlas.core.hurwitz import ss_margin
from atlas.core.verdicts import Verdict
from atlas.paper.audit.printed import MODES
from atlas.paper.audit.records import Counterexample, Finding, N, S, U
from atlas.paper.audit.registry import claim
from atlas.paper.audit.samples import PI, first, fmt_classes
from atlas.paper.audit.verify import mode_2x2_exact


def consistent_in(rows, cls, k) -> list[str]:
    """Contact modes consistent in subclass ``10 cls + k`` (from Table 2's rows)."""
    return [m for m in MODES if k in rows[cls].subclasses[m]]


@claim(
    "S152",
    "Sec. 6",
    "In class 152 no contact mode is consistent; non-existence is "
    "resolved because one type of IWC is possible.",
)
def subclass_152(ctx) -> Finding:
    rows, R, v = ctx.rows, ctx.random, ctx.random.v
    m152 = consistent_in(rows, 15, 2)
    ii15 = sorted(Verdict(x).label for x in ctx.ii_stable_q0[15])
    ii15d = sorted(Verdict(x).label for x in ctx.ii_stable_damped[15] | ctx.ii_stable_random[15])
    i = first((R.cls == 15) & (v["stable_II"] == U) & (v["consistent_II"] == 1) & ctx.random_damped)
    expect = {"consistent_II": 1, "stable_II": U, "class_code": 15}
    cxs = (
        [R.point(i, expect, "class 15, damped: the only IWC is not stable")]
        if i is not None
        else []
    )
    ok = not m152 and rows[15].II == "x" and rows[15].IF == "-" and rows[15].FI == "-"
    return Finding(
        ("imprecise" if cxs else "confirmed") if ok else "refuted",
        f"Consistent modes in 152: {m152 or 'none'}; IF {rows[15].IF}, FI {rows[15].FI}, "
        f"II {rows[15].II}. II stability in class 15 at Q = 0: {ii15}; with damping: "
        f"{ii15d}. Where II is consistent but unstable (a complex pair dominates), the "
        "trajectory generically follows the dominant oscillatory mode, so the IWC does not "
        "resolve non-existence there.",
        corrected="In 152 no contact mode is consistent and II is always consistent; II is "
        "stable for Q = 0 but can be unstable with damping (see QD), so the "
        "resolution by an IWC is model-dependent.",
        counterexamples=cxs,
    )


@claim(
    "S254",
    "Sec. 6",
    "In class 254 all 4 contact modes are consistent but only 1 is stable; 2 types of IWC "
    "are consistent and stable.",
)
def subclass_254(ctx) -> Finding:
    r = ctx.rows[25]
    m254 = consistent_in(ctx.rows, 25, 4)
    stab = [m for m in m254 if r.stability[m] == "stable"]
    ok = len(m254) == 4 and stab == ["FF"] and r.IF == r.FI == "x"
    return Finding(
        "confirmed" if ok and r.II_stability == "unstable" else "refuted",
        f"Consistent: {m254}; stable: {stab}; IF {r.IF}, FI {r.FI} (stable when "
        f"consistent); II {r.II} but {r.II_stability} -- three IWC types are "
        "consistent, two of them stable.",
    )


@claim(
    "S26",
    "Sec. 6.1",
    "All systems in subclasses 261 and 262 have a unique consistent contact mode which is "
    "unstable, and IF and FI are stable there.",
)
def subclasses_261_262(ctx) -> Finding:
    rows, unique_unstable = ctx.rows, []
    for c in contact_modes.ALL_CLASSES:
        for kk in range(1, 7):
            m = consistent_in(rows, c, kk)
            if len(m) == 1 and rows[c].stability[m[0]] == "unstable":
                unique_unstable.append((10 * c + kk, m[0], rows[c].IF, rows[c].FI, rows[c].II))
    both = [u for u in unique_unstable if u[2] == "x" and u[3] == "x"]
    return Finding(
        "imprecise" if {u[0] for u in both} != {261, 262} else "confirmed",
        "Subclasses whose unique consistent mode is unstable throughout: "
        + ", ".join(f"{u[0]} ({u[1]}; IF {u[2]}, FI {u[3]}, II {u[4]})" for u in unique_unstable)
        + ". Those with IF and FI both consistent (hence stable): "
        + ", ".join(str(u[0]) for u in both)
        + ".",
        corrected="A unique, unstable consistent contact mode with stable IF and FI occurs in "
        "all of subclasses " + ", ".join(str(u[0]) for u in both) + " (SS in 261, "
        "262, 266; SF in 263; FS in 265), not only in 261 and 262.",
    )


def nothing_stable(P, rows, cls, k):
    """Points of ``P`` in class ``cls`` (mask ``sel``) and, per such point, whether nothing is
    stable in subclass ``10 cls + k``: no consistent mode or IWC stable (``ok``)."""
    r = rows[cls]
    sel = P.cls == cls
    ok = np.ones(sel.sum(), bool)
    for m in consistent_in(rows, cls, k):
        if m == "SS":
            ok &= ~np.isin(P.v["stable_SS"][sel], (S, N))
        elif r.stability[m] != "unstable":
            ok &= False
    if r.IF == "x" or r.FI == "x":
        ok &= False
    ok &= P.v["stable_II"][sel] != S
    return sel, ok


def _nothing_stable_subclasses(ctx):
    """Subclasses with 'nothing stable' points at kappa = 0.5, q = 0 and with damping, and up to two
    points of 132/142 at kappa = 0.5."""
    G05, rows = ctx.q0_half, ctx.rows
    found0, foundd, cxs = set(), set(), []
    for c in contact_modes.ALL_CLASSES:
        for kk in range(1, 7):
            sel, ok = nothing_stable(G05, rows, c, kk)
            if ok.any():
                found0.add(10 * c + kk)
                if 10 * c + kk in (132, 142) and len(cxs) < 2:
                    i = np.flatnonzero(sel)[np.flatnonzero(ok)[0]]
                    expect = {"stable_SS": U, "dominant_complex": True, "class_code": c}
                    note = f"subclass {10 * c + kk}, nothing stable, kappa = 0.5, q = 0"
                    cxs.append(G05.point(i, expect, note))
            sel, ok = nothing_stable(ctx.random, rows, c, kk)
            if (ok & ctx.random_damped[sel]).any():
                foundd.add(10 * c + kk)
            if nothing_stable(ctx.damped, rows, c, kk)[1].any():
                foundd.add(10 * c + kk)
    return found0, foundd, cxs


@claim(
    "S64",
    "Sec. 6.4-6.5, Fig. 1",
    "There are ranges within subclasses 132, 133, 142, 143 (inside the dashed curves) "
    "where no contact mode and no IWC is stable; there M has complex eigenvalues with "
    "positive real part.",
)
def nothing_stable_ranges(ctx) -> Finding:
    found0, foundd, cxs = _nothing_stable_subclasses(ctx)
    return Finding(
        "imprecise" if found0 != {132, 133, 142, 143} else "confirmed",
        f"At kappa = 0.5, q = 0, subclasses with such ranges: {fmt_classes(found0)}; with "
        f"damping (samples and random search, q1 != q2 included): {fmt_classes(foundd)}. "
        "The counterexample points below (exactly verified) have a complex dominant pair. "
        "The duals (subclasses of 31 and 41) have the same ranges by symmetry.",
        corrected="Ranges exist in subclasses 132, 133, 142, 143 and in their duals "
        f"({fmt_classes(found0 - {132, 133, 142, 143})}); they persist with damping.",
        counterexamples=cxs,
    )


#: Fig. 2's panels: beta1/pi, beta2/pi, alpha/pi, kappa, q_hat (q1 = q2)
FIG2 = {
    "a": (0.2, 0.65, 0.35, 0.5, 0.0),
    "b": (0.05, 0.65, 0.35, 0.5, 0.0),
    "d": (0.15, 1.07, 0.2, 0.5, 2**0.5),
    "e": (0.15, 1.1, 0.2, 0.5, 2**0.5),
}


def fig2_point(name: str):
    """Exact facts at a Fig. 2 panel: ``(subclass, consistent modes, verdicts, stable, text)``
    (neutral counted as stable, as in Fig. 1)."""
    b1, b2, al, kap, q = FIG2[name]
    c1, s1 = (float(v) for v in contact_modes.direction(b1 * PI))
    c2, s2 = (float(v) for v in contact_modes.direction(b2 * PI))
    ca, sa = (float(v) for v in contact_modes.direction(al * PI))
    codes = exact.point_codes(c1, s1, c2, s2, ca, sa)
    r = exact.point_spectral(c1, s1, c2, s2, kap, q, q)
    verdict = {
        "FF": S,
        "SS": r["stable_SS"],
        "SF": mode_2x2_exact(c1, kap, q)["verdict_2x2"],
        "FS": mode_2x2_exact(s2, 1.0, q)["verdict_2x2"],
    }
    cons = [m for m in MODES if codes[f"consistent_{m}"] == 1]
    iwc = [
        m
        for m, ok in (
            ("IF", c1 < 0 and s1 > 0),
            ("FI", s2 < 0 and c2 > 0),
            ("II", r["consistent_II"] == 1 and r["stable_II"] == S),
        )
        if ok
    ]
    stable = [m for m in cons if verdict[m] in (S, N)] + iwc
    text = (
        f"{name}: subclass {codes['subclass_code']}, consistent modes {cons} ("
        + ", ".join(f"{m} {Verdict(verdict[m]).label}" for m in cons)
        + f"), stable IWCs {iwc or 'none'}, SS abscissa {r['spectral_abscissa']:.4g}"
    )
    return codes["subclass_code"], cons, verdict, stable, text


@claim(
    "F2",
    "Sec. 6.4-6.5, Fig. 2 caption",
    "Fig. 2a (beta = 0.2 pi, 0.65 pi, q = 0) is in 132 with nothing stable; 2b "
    "(beta1 = 0.05 pi) has a stable SS mode; 2d, 2e (q = 20, k = 100, 200) lie in 142/143 "
    "with nothing stable.",
)
def fig2(ctx) -> Finding:
    ctx.say("Fig. 2 points, exact")
    facts = {name: fig2_point(name) for name in FIG2}
    wrong = []
    if facts["a"][0] != 132 or facts["a"][3]:
        wrong.append("a")
    wrong += [nm for nm in ("d", "e") if facts[nm][0] not in (142, 143) or facts[nm][3]]
    sub_b, cons_b, v_b = facts["b"][:3]
    if sub_b != 132 or "SS" not in cons_b or v_b["SS"] == U:
        wrong.append("b")
    neutral_b = v_b["SS"] == N
    status = "refuted" if wrong else "imprecise" if neutral_b else "confirmed"
    f2b = Counterexample(
        0.05 * PI,
        0.65 * PI,
        0.5,
        0.0,
        0.0,
        {"stable_SS": N, "class_code": 13},
        "Fig. 2b: SS neutral (purely imaginary spectrum), not asymptotically stable",
    )
    return Finding(
        status,
        "Exact reference at the caption's parameters (kappa = 0.5, q_hat = 20/sqrt(200) for "
        "d, e; neutral counted as stable as in Fig. 1): "
        + "; ".join(f[4] for f in facts.values())
        + f". Parts not as stated: {', '.join(wrong) or 'none'}."
        + (
            " Fig. 2b is undamped, so its SS mode is neutral (linearly a centre), not "
            "asymptotically stable."
            if neutral_b
            else ""
        ),
        corrected="Fig. 2b's SS mode is neutrally stable at q = 0 (asymptotically stable only "
        "with damping that keeps G > 0)."
        if status == "imprecise"
        else "",
        counterexamples=[f2b] if neutral_b else [],
        data={"not_as_stated": wrong},
    )


#: :func:`atlas.core.hurwitz.ss_margin` as one kept program (:func:`atlas.core.warm.jit`), not
#: some 80 operations dispatched one by one
_ss_margin = warm.jit(ss_margin)


def ss_crossings(kap, qa, qb, beta1=0.1 * PI, n=4001):
    """Zero crossings of the SS margin along ``beta1`` [rad], ``beta2`` in ``(pi/2, pi)`` [rad]."""
    b2 = np.linspace(0.5 * PI + 1e-3, PI - 1e-3, n)
    c1, s1 = contact_modes.direction(np.full_like(b2, beta1))
    c2, s2 = contact_modes.direction(b2)
    args = [np.asarray(v, np.float64) for v in (c1, s1, c2, s2, kap, qa, qb)]
    m = np.asarray(_ss_margin(*args))
    return b2[np.flatnonzero(np.diff(np.sign(m)) != 0)]


@claim(
    "S63",
    "Sec. 6.3, Fig. 1 caption",
    "The shapes of the SS stability boundaries inside classes 13, 14, 23, 31, 41, 46 "
    "depend on K, Q (and |b_j|): stability is model-dependent.",
)
def ss_boundary_moves(ctx) -> Finding:
    moves, crossings = [], []
    for kap, qa, qb in (
        (0.5, 0.0, 0.0),
        (2.0, 0.0, 0.0),
        (0.5, 0.1, 0.1),
        (0.5, 1.0, 1.0),
        (0.5, 1.0, 0.01),
    ):
        z = ss_crossings(kap, qa, qb)
        crossings.append(tuple(round(float(b), 4) for b in z))
        moves.append(
            f"kappa {kap:g}, q ({qa:g}, {qb:g}): beta2/pi = "
            + (", ".join(f"{b / PI:.4f}" for b in z) or "no crossing")
        )
    return Finding(
        "confirmed" if len(set(crossings)) > 1 else "refuted",
        "Zero crossings of the SS margin along beta1 = 0.1 pi, beta2 in (pi/2, pi) (class 13): "
        + "; ".join(moves)
        + ". Only kappa = k1|b1|/(k2|b2|) and q_j|b_j|/sqrt(k2|b2|) "
        "matter (SPEC invariants).",
    )
