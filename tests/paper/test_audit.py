"""The audit: every counterexample is re-verified by the exact reference."""

import math
from dataclasses import replace

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


def _check_claim(c):
    """Status known; counterexamples re-verified from scratch by the exact reference; refuted and
    imprecise claims carry their evidence (a verified counterexample or a corrected statement)."""
    assert c.status in ("confirmed", "refuted", "imprecise"), c.id
    for cx in c.counterexamples:
        fresh = audit.Counterexample(
            cx.beta1, cx.beta2, cx.kappa, cx.q1, cx.q2, dict(cx.expect), matrix=cx.matrix
        )
        assert audit.verify_counterexample(fresh), cx
    assert "NOT verified" not in audit.to_markdown([c])
    if c.status in ("refuted", "imprecise"):
        assert c.counterexamples or c.corrected, c.id


def _check_t2s(c):  # Table 2 and the audit agree, and Table 2 is dual-symmetric
    assert c.data["vs_dual"] == []
    assert "II 15: paper stable, computed model-dependent" in c.data["vs_paper"]
    assert "II 32: paper stable, computed model-dependent" in c.data["vs_paper"]
    assert c.status == "refuted"


def _check_s62(c):  # the new Sec. 6.2 claim is computed (and holds)
    assert c.status == "confirmed" and c.data["points"] > 10_000
    assert c.data["exact_disagreements"] == 0


def _check_qd(c):  # the corrected Q3 names the classes Table 2 shades model-dependent
    assert "15, 32" in c.corrected


#: what a claim must show beyond :func:`_check_claim`, by id
SPECIFIC = {"T2S": _check_t2s, "QD": _check_qd, "S62": _check_s62}


def _check_claims(claims):
    assert [c.id for c in claims] == list(audit.CLAIMS)
    assert any(c.counterexamples for c in claims)
    for c in claims:
        _check_claim(c)
        if c.id in SPECIFIC:
            SPECIFIC[c.id](c)
    return {c.id: c for c in claims}


@pytest.mark.e2e
@pytest.mark.parametrize("claim_id", list(audit.CLAIMS))
def test_claim_ci(paper_run, claim_id):
    """Each claim of the session's CI-sized ``atlas paper`` run (``paper_run``, conftest.py): its
    status, evidence and counterexamples re-verified from scratch."""
    assert [c.id for c in paper_run.claims] == list(audit.CLAIMS)
    (c,) = [c for c in paper_run.claims if c.id == claim_id]
    _check_claim(c)
    if claim_id in SPECIFIC:
        SPECIFIC[claim_id](c)


def test_one_claim_computes_only_its_samples():
    ctx = audit.Context(ci=True)
    audit.run_audit(select="Z", context=ctx)  # the Ziegler band needs no shared sample
    assert ctx.computed() == set()
    audit.run_audit(select="T1", context=ctx)
    assert ctx.computed() == {"table1_points"}
    audit.run_audit(select="S144", context=ctx)  # 144 subclasses: Table 1 points + rigid bodies
    assert ctx.computed() == {"table1_points", "realisations"}


def test_select_unknown_claim():
    with pytest.raises(ValueError, match="select: unknown claim ids \\['T9'\\]"):
        audit.run_audit(select=["T1", "T9"])


@pytest.mark.slow
def test_run_audit_quick_all_counterexamples_verified():
    by_id = _check_claims(audit.run_audit(quick=True))
    assert by_id["T2S"].data["vs_search"] == []


# ---- statuses follow from the computation ----------------------------------------------------


def test_app_b_status_from_counts():
    ctx = audit.Context(sizes=replace(audit.Sizes.of(ci=True), n_matrix7=300))
    c = audit.CLAIMS["B1"](ctx)
    assert ctx.computed() == {"matrix7"}
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


def test_dense_alpha_calls_the_class_kernel_with_one_shape(monkeypatch):
    """Sec. 6.2's dense alpha pads each class's sample to the largest, as Table 2 does: one
    argument shape (one program) for every class, not one per sample size (7 or 8 points here);
    the codes are still those of each real point (exact re-check)."""
    from atlas.paper.audit import consistency
    from atlas.paper.tables import class_samples

    pts = class_samples(96, 8)
    assert {len(p) for p in pts.values()} == {7, 8}
    shapes, real = [], consistency.class_kernel

    def recording(*args):
        shapes.append(tuple(a.shape for a in args))
        return real(*args)

    monkeypatch.setattr(consistency, "class_kernel", recording)
    sub, cons, inputs = consistency.dense_alpha(pts, 1)
    assert set(shapes) == {((8, 1),) * 4 + ((1, 720),) * 2}
    assert len(sub) == len(inputs) == 720 * sum(len(p) for p in pts.values())
    assert consistency.exact_disagreements(sub, cons, inputs, 300) == 0


def test_app_c_q1_over_every_model(monkeypatch):
    """C1w is decided by the proved whole-model-space map: confirmed as computed, refuted by one
    class-12 cell that depends on the model, not confirmed with an undecided cell."""
    from atlas.core.verdicts import OverModels
    from atlas.paper import figure_models

    ctx = audit.Context(ci=True)
    assert audit.CLAIMS["C1w"](ctx).status == "confirmed"
    real = figure_models.model_dependence_map
    n = figure_models.N_MODELS[2]
    i = int(n * 0.1)  # beta1 = beta2 - 0.2 pi ~ 0.2 pi, 0.4 pi: class 12
    for flip, status in ((OverModels.DEPENDS, "refuted"), (OverModels.UNDECIDED, "imprecise")):

        def mutated(n, box="kappa=0:inf", flip=flip):
            ds = real(n, box)
            ds["ss_over_models"][i, 2 * i] = int(flip)
            return ds

        monkeypatch.setattr(figure_models, "model_dependence_map", mutated)
        c = audit.CLAIMS["C1w"](audit.Context(ci=True))  # a context computes its map once
        assert c.status == status
        assert f"12: stable for every model, {flip.label};" in c.evidence


def test_app_c_q2_q3_over_every_model(monkeypatch):
    """C2w (II consistency over every model) is confirmed as computed and refuted by one point
    of class 12 said consistent; C3w is refuted by an exactly verified witness in class 15 or 32
    (II consistent, a complex pair dominant), as the audit's class-32 point shows."""
    from atlas.paper import tables

    ctx = audit.Context(ci=True)
    c2 = audit.CLAIMS["C2w"](ctx)
    assert c2.status == "confirmed", c2.evidence
    c3 = audit.CLAIMS["C3w"](ctx)
    assert c3.status == "refuted" and c3.counterexamples
    assert all(cx.verified for cx in c3.counterexamples)
    assert {cx.expect["class_code"] for cx in c3.counterexamples} <= {15, 32}
    real = tables.over_models_codes

    def mutated(pts, dtype="float64"):
        out = real(pts, dtype)
        if tables.contact_modes.class_code(*out[0]["geometry"]) == 12:
            out[0] = dict(out[0], ii_consistent_over_models=1)
        return out

    monkeypatch.setattr(tables, "over_models_codes", mutated)
    assert audit.CLAIMS["C2w"](ctx).status == "refuted"
