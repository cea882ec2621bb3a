"""Exact re-verification of the audit's points: rational arithmetic and the high-precision reference
:func:`atlas.core.exact.point_spectral` (its eigenvalues are kept for the report)."""

from __future__ import annotations

from fractions import Fraction

import mpmath

from atlas.core import contact_modes, exact
from atlas.paper.audit.records import Counterexample, N, S, U


def _negbk_signs(c1, s1, c2, s2, kappa):
    """Signs of det, trace and discriminant of ``-BK``, in exact rational arithmetic."""
    C1, S1, C2, S2, K = (Fraction(float(v)) for v in (c1, s1, c2, s2, kappa))
    det = K * (C1 * S2 - S1 * C2)
    tr = -(K * C1 + S2)
    disc = tr * tr - 4 * det
    sg = lambda x: (x > 0) - (x < 0)  # noqa: E731
    return {"negBK_det": sg(det), "negBK_tr": sg(tr), "negBK_disc": sg(disc)}


def mode_2x2_exact(b_jj, kappa_j, q_j, dps: int = 50) -> dict:
    """Matrix (7) of a single sliding contact in scaled time, ``[[0, 1], [-kappa_j b_jj, -q_j b_jj]]``
    (SF: ``b11 = cos beta1``, ``kappa_1 = kappa``, ``q_1``; FS: ``b22 = sin beta2``, ``kappa_2 = 1``,
    ``q_2``), decided in exact rational arithmetic on the float inputs.

    Returns the roots (``dps`` digits), ``verdict_2x2`` (a :class:`Verdict` code from the roots:
    neutral iff the roots are exactly imaginary, i.e. ``det > 0`` and ``trace == 0``), ``saddle``
    (two real roots of opposite signs, exactly: ``det < 0``) and ``dominant_real_positive``.
    """
    b, k, q = (Fraction(float(v)) for v in (b_jj, kappa_j, q_j))
    det, tr = b * k, -b * q
    with mpmath.workdps(dps):
        roots = [
            complex(z)
            for z in mpmath.polyroots(
                [
                    1,
                    -mpmath.mpf(tr.numerator) / tr.denominator,
                    mpmath.mpf(det.numerator) / det.denominator,
                ],
                maxsteps=200,
                extraprec=2 * dps,
            )
        ]
    if det > 0 and tr == 0:
        verdict = N
    elif det == 0:
        verdict = U if tr > 0 else N
    else:
        top = max(z.real for z in roots)
        verdict = S if top < 0 else U
    disc = tr * tr - 4 * det
    return {
        "roots": roots,
        "verdict_2x2": int(verdict),
        "saddle": bool(det < 0),
        "dominant_real_positive": bool(disc >= 0 and (tr > 0 or det < 0)),
    }


def _verify_2x2(cx: Counterexample) -> bool:
    c1, _ = (float(v) for v in contact_modes.direction(cx.beta1))
    _, s2 = (float(v) for v in contact_modes.direction(cx.beta2))
    r = mode_2x2_exact(c1, cx.kappa, cx.q1) if cx.matrix == "SF" else mode_2x2_exact(s2, 1.0, cx.q2)
    cx.eigenvalues = sorted(r["roots"], key=lambda z: (-z.real, -z.imag))
    cx.verified = all(r[k] == v for k, v in cx.expect.items())
    return cx.verified


def verify_counterexample(cx: Counterexample) -> bool:
    """Re-verify ``cx`` with the exact reference; fills ``cx.eigenvalues`` and ``cx.verified``."""
    if cx.matrix in ("SF", "FS"):
        return _verify_2x2(cx)
    c1, s1 = (float(v) for v in contact_modes.direction(cx.beta1))
    c2, s2 = (float(v) for v in contact_modes.direction(cx.beta2))
    r = exact.point_spectral(c1, s1, c2, s2, cx.kappa, cx.q1, cx.q2)
    roots = r["roots"]
    cx.eigenvalues = sorted(roots, key=lambda z: (-z.real, -z.imag))
    facts = {k: r[k] for k in ("stable_SS", "consistent_II", "stable_II")}
    facts["class_code"] = exact.point_codes(c1, s1, c2, s2)["class_code"]
    facts.update(_negbk_signs(c1, s1, c2, s2, cx.kappa))
    scale = max(1.0, max(abs(z) for z in roots))
    facts["negative_real_root"] = any(abs(z.imag) <= 1e-12 * scale and z.real < 0 for z in roots)
    top = max(roots, key=lambda z: z.real)
    facts["dominant_complex"] = abs(top.imag) > 1e-9 * scale
    cx.verified = all(facts[k] == v for k, v in cx.expect.items())
    return cx.verified
