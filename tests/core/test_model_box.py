"""SS verdicts over a box of contact models against independent checks: the closed form of the
whole model space (worked by hand, module docstring), a dense sample of models through the exact
tier, single-model boxes against the exact tier, and the classes of the paper's Table 2."""

import math

import numpy as np
import pytest
from samples import per_class

from atlas.core import exact
from atlas.core import model_box as mb
from atlas.core.contact_modes import class_code, direction
from atlas.core.verdicts import OverModels, Verdict

U, S, DEP, UND = (int(v) for v in OverModels)
CURVED = (13, 14, 23, 31, 41, 46)


def _per_class(k: int = 2, seed: int = 7):
    return per_class(k, seed)


def _good(g, m) -> bool:
    return exact.ss_hurwitz(*g, *m) in (int(Verdict.STABLE), int(Verdict.NEUTRAL))


def _sample(box: mb.ModelBox):
    ks = np.geomspace(max(box.kappa[0], 1e-3), min(box.kappa[1], 1e3), 6)
    q1 = np.linspace(box.q1[0], min(box.q1[1], 4.0), 5)
    q2 = q1 if box.equal else np.linspace(box.q2[0], min(box.q2[1], 4.0), 5)
    if box.equal:
        return [(k, q, q) for k in ks for q in q1]
    return [(k, a, b) for k in ks for a in q1 for b in q2]


def _in_box(box, m):
    k, q1, q2 = m
    inside = lambda v, r: r[0] <= v <= r[1]  # noqa: E731
    ok = 0 < k and inside(k, box.kappa) and inside(q1, box.q1) and inside(q2, box.q2)
    return ok and (q1 == q2 or not box.equal)


def test_whole_model_space_closed_form():
    c1, s1, c2, s2, _ = _per_class(4)
    r = mb.ss_over_models(c1, s1, c2, s2, mb.model_box())
    D = c1 * s2 - s1 * c2  # the sign only: these random points are far from D = 0
    expected = np.where(
        (D < 0) | ((c1 <= 0) & (s2 <= 0)),
        U,
        np.where((c1 > 0) & (s2 > 0) & (s1 * c2 >= 0), S, DEP),
    )
    np.testing.assert_array_equal(r["ss_over_models"], expected)
    assert r.stats["undecided_after"] == 0


def test_table2_classes_over_the_whole_model_space():
    c1, s1, c2, s2, cc = _per_class(3)
    code = mb.ss_over_models(c1, s1, c2, s2, mb.model_box())["ss_over_models"]
    for c, v in zip(cc, code):
        if c in (12, 42):
            assert v == S, c
        elif c in CURVED:
            assert v == DEP, c
        else:
            assert v == U, c


def test_curved_classes_split_in_a_bounded_box():
    # kappa in [0.01, 100], q in [0, 1]^2: classes 14 and 23 hold both "depends" and "unstable for
    # every model" (a curved boundary between them); 12 and 42 stay stable for every model
    rng = np.random.default_rng(3)
    b1, b2 = rng.uniform(0, 2 * np.pi, (2, 3000))
    c1, s1 = direction(b1)
    c2, s2 = direction(b2)
    cc = np.asarray(class_code(c1, s1, c2, s2))
    pick = np.concatenate([np.flatnonzero(cc == c)[:50] for c in (14, 23, 12, 42)])
    box = mb.parse_model_box("kappa=0.01:100,q1=0:1,q2=0:1")
    code = mb.ss_over_models(c1[pick], s1[pick], c2[pick], s2[pick], box)["ss_over_models"]
    for c in (14, 23):
        assert set(code[cc[pick] == c].tolist()) == {U, DEP}
    assert set(code[np.isin(cc[pick], (12, 42))].tolist()) == {S}


@pytest.mark.parametrize(
    "text",
    [
        "kappa=0.01:100,q1=0:1,q2=0:1",
        "q=0:inf",
        "kappa=0.2:5,q=0.1:2",
        "kappa=0.1:10,q1=0.5:2,q2=0:0.1",
        "kappa=0.1:10,q1=0:0,q2=0:0",
        "kappa=2,q1=0.5,q2=0:inf",
        "kappa=0:3,q1=0:2,q2=1:1",
    ],
)
def test_dense_sample_never_contradicts_and_witnesses_hold(text):
    box = mb.parse_model_box(text)
    c1, s1, c2, s2, _ = _per_class(1)
    r = mb.ss_over_models(c1, s1, c2, s2, box)
    assert r.stats["undecided_after"] == 0
    models = _sample(box)
    for i, code in enumerate(r["ss_over_models"]):
        g = (c1[i], s1[i], c2[i], s2[i])
        if code in (S, U):
            assert all(_good(g, m) == (code == S) for m in models), (i, code)
            assert all(math.isnan(r[n][i]) for n in mb.WITNESS_NAMES)
        else:
            assert code == DEP
            w = [float(r[n][i]) for n in mb.WITNESS_NAMES]
            assert _in_box(box, w[:3]) and _in_box(box, w[3:])
            assert _good(g, w[:3]) and not _good(g, w[3:])


def test_single_model_box_is_the_exact_verdict():
    c1, s1, c2, s2, _ = _per_class(1)
    for kappa, q in ((0.5, 0.0), (0.5, 0.3), (2.0, 1.0)):
        box = mb.model_box(kappa=kappa, q=q)
        code = mb.ss_over_models(c1, s1, c2, s2, box)["ss_over_models"]
        for i, v in enumerate(code):
            good = _good((c1[i], s1[i], c2[i], s2[i]), (kappa, q, q))
            assert v == (S if good else U)


def test_degenerate_det_zero():
    # beta2 = beta1 = pi/4: D = 0 exactly, a3 >= 0 and kappa c1 + s2 > 0: neutral for every model
    c, s = direction(np.pi / 4)
    code = mb.ss_over_models(c, s, c, s, mb.model_box())["ss_over_models"]
    assert int(code) == S
    # beta2 = beta1 = 3pi/4: D = 0, c1 < 0 < s2 = -c1: a3 = c1 (q1 - q2) changes sign -> depends
    c, s = direction(3 * np.pi / 4)
    r = mb.ss_over_models(c, s, c, s, mb.model_box())
    assert int(r["ss_over_models"]) == DEP
    w = [float(r[n]) for n in mb.WITNESS_NAMES]
    assert _good((c, s, c, s), w[:3]) and not _good((c, s, c, s), w[3:])


def test_settlement_counts():
    c1, s1, c2, s2, _ = _per_class(2)
    # a geometry of class 46 whose "no stable model" proof needs more than the first budget
    hard = np.array([1.5317666284305962, 1.59801498331714]) * np.pi
    (hc1, hc2), (hs1, hs2) = direction(hard)
    c1, s1, c2, s2 = (np.append(a, b) for a, b in ((c1, hc1), (s1, hs1), (c2, hc2), (s2, hs2)))
    box = mb.parse_model_box("kappa=0.01:100,q1=0:1,q2=0:1")
    before = mb.ss_over_models(c1, s1, c2, s2, box, settle=False)
    after = mb.ss_over_models(c1, s1, c2, s2, box)
    n_und = int(np.sum(before["ss_over_models"] == UND))
    assert before.stats["undecided_before"] == n_und == after.stats["undecided_before"] > 0
    assert before["ss_over_models"][-1] == UND and after["ss_over_models"][-1] == U
    assert after.stats["undecided_after"] == 0
    same = before["ss_over_models"] != UND
    np.testing.assert_array_equal(before["ss_over_models"][same], after["ss_over_models"][same])


@pytest.mark.parametrize(
    "text, name",
    [
        ("kappa=2:1", "kappa"),
        ("kappa=0:0", "kappa"),
        ("q1=-1:1", "q1"),
        ("q2=nan:1", "q2"),
        ("kappa=0.1:10,q=1:0.5", "q"),
        ("kappa=1:2,zeta=0:1", "model_box"),
        ("q=0:1,q1=0:1", "q"),
        ("q1=1:inf:2", "q1"),
        ("q1=abc", "q1"),
        ("q1=inf:inf", "q1"),
    ],
)
def test_bad_boxes(text, name):
    with pytest.raises(ValueError, match=f"^model_box: ({name}: )?") as e:
        mb.parse_model_box(text)
    assert "\n" not in str(e.value) and name in str(e.value)


@pytest.mark.parametrize("text", ["kappa=0:inf", "kappa=0.01:100,q1=0:1,q2=0:1", "q=0.1:2"])
def test_sign_rules_agree_with_the_bernstein_proofs(text):
    # the codes proven by signs alone (D, c1, s2, s1 c2) proven again by the subdivision
    box = mb.parse_model_box(text)
    c1, s1, c2, s2, _ = _per_class(1)
    geo = np.stack([c1, s1, c2, s2], axis=1)
    signs = mb._by_signs(geo, mb.det_signs(geo))
    decided = np.flatnonzero((signs != UND) & (mb.det_signs(geo) == 1))
    assert len(decided) >= 4
    for i in decided:
        code, _, _ = mb._decide(tuple(geo[i].tolist()), box, None, None, mb.SETTLE_BUDGET)
        assert code == signs[i]


def test_equal_damping_undamped_point_found_by_the_proof():
    # class 13, q1 = q2 in [0, inf): c1, s2 > 0 > s1 c2; the sampled models miss the unstable ones
    # (undamped, kappa near s2 / c1), the subdivision of disc = X^2 + 4 kappa s1 c2 finds one
    b = (np.array([0, 24]) + 0.5) * 2 * np.pi / 61
    (c1, c2), (s1, s2) = direction(b)
    r = mb.ss_over_models(c1, s1, c2, s2, mb.parse_model_box("q=0:inf"))
    assert int(r["ss_over_models"]) == DEP
    w = [float(r[n]) for n in mb.WITNESS_NAMES]
    g = (c1, s1, c2, s2)
    assert _good(g, w[:3]) and not _good(g, w[3:])


def test_near_tie_points_witnessed_without_settlement():
    """``b1 = b2`` next to ``pi`` on the 361-point offset grid (``D = 0``: neutral or unstable by
    the signs of ``a3``, ``a2``): its unstable models lie far out in the model space; the last
    witness search over many scales finds one, so no proof is needed (was undecided before the
    settlement); both witnesses on their side by the exact tier."""
    b = (180 + 0.5) * 2 * np.pi / 361
    c, s = direction(b)
    r = mb.ss_over_models(c, s, c, s, mb.model_box(), settle=False)
    assert r.stats["undecided_before"] == 0 and int(r["ss_over_models"]) == DEP
    w = [float(r[n]) for n in mb.WITNESS_NAMES]
    assert _good((c, s, c, s), w[:3]) and not _good((c, s, c, s), w[3:])
