"""The audit: every counterexample is re-verified by the exact reference."""

import math

import pytest

from atlas.paper import audit


def test_issue_counterexample_class32():
    cx = audit.Counterexample(
        1.38541667 * math.pi,
        0.40625 * math.pi,
        0.1,
        1.0,
        0.01,
        {"consistent_II": 1, "stable_II": 0, "class_code": 32, "dominant_complex": True},
    )
    assert audit.verify_counterexample(cx)
    top = cx.eigenvalues[0]
    assert abs(top.imag) > 0.5 and top.real > 0.13


def test_ziegler_point():
    # neutral at q = 0, unstable for small equal damping (kappa = 0.5)
    b1, b2 = 2.142529475, 2.241091762
    assert audit.verify_counterexample(
        audit.Counterexample(b1, b2, 0.5, 0.0, 0.0, {"stable_SS": 2})
    )
    assert audit.verify_counterexample(
        audit.Counterexample(b1, b2, 0.5, 1e-6, 1e-6, {"stable_SS": 0})
    )


def test_wrong_expectation_is_not_verified():
    cx = audit.Counterexample(0.2 * math.pi, 0.65 * math.pi, 0.5, 0.0, 0.0, {"stable_SS": 2})
    assert not audit.verify_counterexample(cx)


def _check_claims(claims):
    cxs = [cx for c in claims for cx in c.counterexamples]
    assert cxs
    for cx in cxs:  # every counterexample re-verified from scratch by the exact reference
        fresh = audit.Counterexample(
            cx.beta1, cx.beta2, cx.kappa, cx.q1, cx.q2, dict(cx.expect), matrix=cx.matrix
        )
        assert audit.verify_counterexample(fresh), cx
    assert {c.status for c in claims} <= {"confirmed", "refuted", "imprecise"}
    text = audit.to_markdown(claims)
    assert "NOT verified" not in text
    by_id = {c.id: c for c in claims}
    # refuted / imprecise claims carry their evidence: a verified counterexample or a corrected text
    for c in claims:
        if c.status in ("refuted", "imprecise"):
            assert c.counterexamples or c.corrected, c.id
    # Table 2 and the audit agree, and Table 2 is dual-symmetric
    t2s = by_id["T2S"]
    assert t2s.data["vs_dual"] == []
    assert "II 15: paper stable, computed model-dependent" in t2s.data["vs_paper"]
    assert "II 32: paper stable, computed model-dependent" in t2s.data["vs_paper"]
    assert t2s.status == "refuted"
    assert "15, 32" in by_id["QD"].corrected
    # the new Sec. 6.2 claim is computed (and holds)
    assert by_id["S62"].status == "confirmed" and by_id["S62"].data["points"] > 10_000
    assert by_id["S62"].data["exact_disagreements"] == 0
    return by_id


def test_run_audit_ci_all_counterexamples_verified():
    """The CI-sized audit (not marked slow): every check runs, every counterexample re-verified."""
    _check_claims(audit.run_audit(ci=True))


@pytest.mark.slow
def test_run_audit_quick_all_counterexamples_verified():
    by_id = _check_claims(audit.run_audit(quick=True))
    assert by_id["T2S"].data["vs_search"] == []


# ---- statuses follow from the computation ----------------------------------------------------


def test_app_b_status_from_counts():
    c = audit._app_b(300)
    counts = c.data["counts"]
    # q1 = 0 with b11 > 0: neutral, so the claim's "negative real parts" fails on every such point
    assert counts["b>0, q=0"][0] > 0 and counts["b>0, q=0"][1] == 0
    assert counts["b>0, q>0"][0] == counts["b>0, q>0"][1] > 0
    assert counts["b<0"][0] == counts["b<0"][1] > 0
    assert c.status == "imprecise"


def test_mode_2x2_exact_against_closed_form():
    # l^2 + q b l + kappa b = 0: b = 0.5, kappa = 2, q = 0 -> +-i; q = 0.1 -> -0.025 +- i sqrt(1-0.025^2)
    r = audit.mode_2x2_exact(0.5, 2.0, 0.0)
    assert r["verdict_2x2"] == 2 and all(
        abs(abs(z) - 1) < 1e-12 and abs(z.real) < 1e-12 for z in r["roots"]
    )
    r = audit.mode_2x2_exact(0.5, 2.0, 0.1)
    assert r["verdict_2x2"] == 1
    assert all(abs(z.real + 0.025) < 1e-12 for z in r["roots"])
    r = audit.mode_2x2_exact(-0.5, 2.0, 0.1)  # roots (0.05 +- sqrt(0.0025 + 4)) / 2
    assert r["verdict_2x2"] == 0 and r["saddle"]
    assert abs(max(z.real for z in r["roots"]) - (0.05 + (0.0025 + 4) ** 0.5) / 2) < 1e-12
