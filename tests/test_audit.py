"""The audit: every counterexample is re-verified by the exact reference."""

import math

import pytest

from atlas import audit


def test_issue_counterexample_class32():
    cx = audit.Counterexample(1.38541667 * math.pi, 0.40625 * math.pi, 0.1, 1.0, 0.01,
                              {"consistent_II": 1, "stable_II": 0, "class_code": 32,
                               "dominant_complex": True})
    assert audit.verify_counterexample(cx)
    top = cx.eigenvalues[0]
    assert abs(top.imag) > 0.5 and top.real > 0.13


def test_ziegler_point():
    # neutral at q = 0, unstable for small equal damping (kappa = 0.5)
    b1, b2 = 2.142529475, 2.241091762
    assert audit.verify_counterexample(audit.Counterexample(b1, b2, 0.5, 0.0, 0.0, {"stable_SS": 2}))
    assert audit.verify_counterexample(audit.Counterexample(b1, b2, 0.5, 1e-6, 1e-6,
                                                            {"stable_SS": 0}))


def test_wrong_expectation_is_not_verified():
    cx = audit.Counterexample(0.2 * math.pi, 0.65 * math.pi, 0.5, 0.0, 0.0, {"stable_SS": 2})
    assert not audit.verify_counterexample(cx)


@pytest.mark.slow
def test_run_audit_quick_all_counterexamples_verified():
    claims = audit.run_audit(quick=True)
    cxs = [cx for c in claims for cx in c.counterexamples]
    assert cxs
    for cx in cxs:
        fresh = audit.Counterexample(cx.beta1, cx.beta2, cx.kappa, cx.q1, cx.q2, dict(cx.expect))
        assert audit.verify_counterexample(fresh), cx
    assert {c.status for c in claims} <= {"confirmed", "refuted", "imprecise"}
    text = audit.to_markdown(claims)
    assert "NOT verified" not in text
