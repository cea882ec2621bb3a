"""Sec. 4.2 and App. B: stability of the sliding modes -- matrix (7), where SS stability is
model-dependent, and Fig. 1's undamped boundaries against vanishing damping (Ziegler)."""

from __future__ import annotations

import numpy as np

from atlas.core import contact_modes
from atlas.paper.audit.context import KAPPAS_Q0
from atlas.paper.audit.printed import SS_CURVED
from atlas.paper.audit.records import Counterexample, Finding, N, S, U
from atlas.paper.audit.registry import claim
from atlas.paper.audit.samples import PI, directions, first, fmt_classes


def _matrix7_points(m) -> list[Counterexample]:
    """SF and FS points with ``b_jj > 0, q_j = 0`` (neutral) if any, and an SF saddle (``b11 < 0``)."""
    cxs = []
    if "b>0, q=0" in m.failing:
        i = int(np.flatnonzero((m.b11 > 0) & (m.q == 0))[0])
        cxs.append(
            Counterexample(
                float(m.beta[i]),
                0.25 * PI,
                float(m.kappa[i]),
                0.0,
                0.0,
                {"verdict_2x2": N, "saddle": False},
                "SF, b11 > 0, q1 = 0: matrix (7) has purely imaginary roots",
                matrix="SF",
            )
        )
        cxs.append(
            Counterexample(
                0.25 * PI,
                float(m.beta[i]) % PI,
                1.0,
                0.0,
                0.0,
                {"verdict_2x2": N},
                "FS, b22 > 0, q2 = 0",
                matrix="FS",
            )
        )
    j = int(np.flatnonzero(m.b11 < 0)[0])
    cxs.append(
        Counterexample(
            float(m.beta[j]),
            0.25 * PI,
            float(m.kappa[j]),
            float(m.q[j] or 1.0),
            0.0,
            {"verdict_2x2": U, "saddle": True, "dominant_real_positive": True},
            "SF, b11 < 0: a saddle (the claim's own case, for reference)",
            matrix="SF",
        )
    )
    return cxs


@claim(
    "B1",
    "Sec. 4.2, App. B",
    "Matrix (7): det = b11 k1, trace = -b11 q1; b11 > 0 gives two eigenvalues with negative "
    "real parts (SF stable), b11 < 0 a saddle (SF unstable); FS analogous.",
)
def matrix7(ctx) -> Finding:
    m = ctx.matrix7
    fail = {key: v[0] - v[1] for key, v in m.counts.items()}
    if fail["b<0"] or fail["b>0, q>0"] or m.kernel_mismatches:
        status = "refuted"
    elif fail["b>0, q=0"]:
        status = "imprecise"
    else:
        status = "confirmed"
    return Finding(
        status,
        f"{m.beta.size} random (beta1, kappa = 10^U(-6, 6), q1 = 0 for half of them, else "
        "10^U(-4, 3)), matrix (7) in scaled time [[0, 1], [-kappa b11, -q1 b11]] decided in exact "
        "rational arithmetic: points / points where the claim holds: "
        + "; ".join(f"{key}: {v[1]} of {v[0]}" for key, v in m.counts.items())
        + f". The kernel used by Fig. 1 and Table 2 (SF stable iff b11 > 0) disagrees with "
        f"sign(b11) on {m.kernel_mismatches} points. For b11 > 0 and q1 = 0 the trace is 0 and the "
        "roots are +-i sqrt(kappa b11): neutral, not asymptotically stable. FS is the same matrix "
        "with b22, k2, q2 (see the FS point below).",
        corrected="SF is asymptotically stable iff b11 > 0 and q1 > 0; for b11 > 0, q1 = 0 it is "
        "neutral (a centre), drawn as stable in Fig. 1; b11 < 0 is a saddle for every "
        "q1 >= 0."
        if status == "imprecise"
        else "",
        counterexamples=_matrix7_points(m),
        data={"counts": m.counts, "kernel_mismatches": m.kernel_mismatches},
    )


@claim(
    "SS6",
    "Sec. 4.2, 6.2, 6.3; App. C Q1",
    "SS stability has (K, Q-dependent) boundaries inside classes 13, 14, 23, 31, 41, 46 "
    "only; elsewhere it is decided by the class (straight boundaries).",
)
def ss_model_dependent(ctx) -> Finding:
    R, RD = ctx.random, ctx.random_damped
    mixed0 = {c for c, w in ctx.ss_word_q0.items() if w == "model-dependent"}
    mixed_all = {c for c, w in ctx.ss_word_all.items() if w == "model-dependent"}
    cxs = []
    for c in sorted(mixed_all - set(SS_CURVED)):
        for st in (S, U):
            i = first((R.cls == c) & (R.v["stable_SS"] == st) & RD)
            if i is not None:
                cxs.append(R.point(i, {"stable_SS": st, "class_code": c}))
    ok = mixed0 == set(SS_CURVED) and mixed_all == set(SS_CURVED)
    return Finding(
        "confirmed" if ok else "refuted",
        f"Classes with both verdicts at Q = 0 (kappa in {KAPPAS_Q0}): {fmt_classes(mixed0)}. "
        f"Adding the damped samples and {int(RD.sum())} damped random points (q1 != q2, "
        f"ratios to 1e6, kappa 1e-6..1e6): {fmt_classes(mixed_all)}. Per-class words: "
        + ", ".join(f"{c}: {ctx.ss_word_all[c]}" for c in contact_modes.ALL_CLASSES)
        + ".",
        counterexamples=cxs,
    )


def ziegler_band(kappa: float = 0.5, n: int = 700):
    """A point of the band between Fig. 1's neutral boundary and the vanishing-damping boundary.

    On an ``n x n`` grid of ``(beta1, beta2)`` [rad]: points with disc > 0 (neutral at q = 0) but
    ``S1 C2 (1 + kappa)^2 + (kappa C1 - S2)^2 < 0`` (unstable for all small equal damping), with
    det > 0 and kappa C1 + S2 > 0.  Returns ``(beta1, beta2)`` of the deepest such point (or
    ``None``) and the band's area fraction of the torus.
    """
    bb = np.linspace(0.01, 2 * PI - 0.01, n)
    B1g, B2g = np.meshgrid(bb, bb, indexing="ij")
    C1, S1, C2, S2 = directions(B1g, B2g)
    disc = (kappa * C1 - S2) ** 2 + 4 * kappa * S1 * C2
    glim = S1 * C2 * (1 + kappa) ** 2 + (kappa * C1 - S2) ** 2
    det = C1 * S2 - S1 * C2
    cand = (disc > 1e-3) & (glim < -1e-3) & (det > 0) & (kappa * C1 + S2 > 0)
    area = float(cand.mean())
    if not cand.any():
        return None, area
    i, j = np.unravel_index(np.argmax(np.where(cand, np.minimum(disc, -glim), -1)), cand.shape)
    return (float(B1g[i, j]), float(B2g[i, j])), area


def _ziegler_points(b, k) -> list[Counterexample]:
    cxs = [
        Counterexample(*b, k, q, q, {"stable_SS": st}, f"q1 = q2 = {q:g}")
        for q, st in ((0.0, N), (1e-2, U), (1e-4, U), (1e-8, U))
    ]
    return cxs + [
        Counterexample(
            *b, k, 1e-6 * r, 1e-6, {"stable_SS": U}, f"unequal small damping q1/q2 = {r:g}"
        )
        for r in (1e-3, 1e3)
    ]


@claim(
    "Z",
    "Fig. 1, Sec. 4.2, App. C (Q != 0)",
    "Fig. 1 is drawn at q1 = q2 = 0 and the Q = 0 answers 'remain true' for Q != 0; "
    "neutral (q = 0) points are drawn as stable.",
)
def ziegler(ctx) -> Finding:
    k = 0.5
    b, area = ziegler_band(k)
    zcx = _ziegler_points(b, k) if b is not None else []
    return Finding(
        "refuted" if zcx else "confirmed",
        "Small-damping (Ziegler) destabilisation: with q1 = q2 = q -> 0+, G/q^2 -> "
        "S1 C2 (1 + kappa)^2 + (kappa C1 - S2)^2, whereas the q = 0 neutral boundary is "
        "(kappa C1 - S2)^2 + 4 kappa S1 C2 = 0; they differ by S1 C2 (1 - kappa)^2 unless "
        f"kappa = 1. At kappa = 0.5 the band between the two curves covers {100 * area:.2f}% "
        "of the (beta1, beta2) torus: neutral at q = 0 (shaded stable in Fig. 1) but unstable "
        "for every small equal damping. With unequal damping the limit is "
        "S1 C2 (kappa r + 1)^2 / r... i.e. it depends on r = q1/q2 "
        "(G/q2^2 -> S1 C2 (kappa + r)^2 + r (kappa C1 - S2)^2), so the q -> 0 limit of the "
        "stability region is itself model-dependent.",
        corrected="Fig. 1's dashed SS curves are the undamped neutral-stability boundaries; the "
        "boundary of asymptotic stability for vanishing damping is "
        "S1C2 (kappa + r)^2 + r (kappa C1 - S2)^2 = 0 with r = q1/q2 (for r = 1: "
        "S1C2 (1 + kappa)^2 + (kappa C1 - S2)^2 = 0).",
        counterexamples=zcx,
    )
