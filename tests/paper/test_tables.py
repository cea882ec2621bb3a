"""Table 2 regenerated from the kernels equals the paper's, cell by cell."""

import numpy as np
import pytest

from atlas.core import contact_modes, exact
from atlas.paper import tables as t2

# The paper's Table 2, transcribed: class: (dual, FF, SS, SF, FS, IF, FI, II, CC)
PAPER = {
    11: ("same", "5", "2", "1 2 6", "2 3 4", "-", "-", "-", "?"),
    12: ("same", "5", "2", "1 6", "3 4", "-", "-", "-", "?"),
    13: (41, "5", "2 3", "1 6", "4", "-", "-", "-", "?"),
    14: (31, "4 5", "2 3 4", "1 6", "4", "-", "-", "(x)", ""),
    15: (32, "4 5", "1 5 6", "1 6", "4", "-", "-", "x", ""),
    16: (21, "4", "1 6", "1 5 6", "4 5", "-", "x", "-", ""),
    22: (45, "5", "3", "4 5", "3 4", "x", "-", "-", ""),
    23: (46, "5", "3", "3 4 5", "4", "x", "-", "-", ""),
    24: (36, "4 5", "3 4", "3 4 5", "4", "x", "-", "(x)", ""),
    25: ("same", "4", "3 4 5", "3 4", "4 5", "x", "x", "x", ""),
    26: ("same", "4", "1 2 6", "3 4", "4 5", "x", "x", "-", ""),
    33: (44, "4 5", "3 4", "5", "3", "-", "-", "x", ""),
    34: ("same", "3 4 5", "4", "5", "3", "-", "-", "x", ""),
    35: ("same", "3 4 5", "4", "4 5", "3 4", "-", "-", "x", ""),
    42: ("same", "4", "1 2 6", "5", "3", "-", "-", "-", "?"),
    43: ("same", "4", "3 4 5", "5", "3", "-", "-", "x", "?"),
}


@pytest.fixture(scope="module")
def rows():
    """Table 2 at the quick run's sample (``atlas paper --quick``): its class kernel's program is
    the audit's dense-alpha one (8 points a class, 720 alphas)."""
    return {r.cls: r for r in t2.table2(n=96, per_class=8)}


def test_all_24_classes(rows):
    assert sorted(rows) == sorted(10 * i + j for i in range(1, 5) for j in range(1, 7))


@pytest.mark.parametrize("cls", sorted(PAPER))
def test_printed_rows(rows, cls):
    r = rows[cls]
    dual, ff, ss, sf, fs, if_, fi, ii, cc = PAPER[cls]
    assert r.dual == (cls if dual == "same" else dual)
    for mode, want in zip(("FF", "SS", "SF", "FS"), (ff, ss, sf, fs)):
        assert " ".join(map(str, r.subclasses[mode])) == want, mode
    assert (r.IF, r.FI, r.II, r.CC) == (if_, fi, ii, cc)


def test_class_25_ii_consistent_but_unstable(rows):
    """Table 2 caption: dark background in class 25 (II consistent but unstable)."""
    assert rows[25].II == "x" and rows[25].II_stability == "unstable"


def test_dual_rows_agree_with_duality(rows):
    """The 8 unprinted rows follow from their printed duals: IF <-> FI, SF <-> FS (as counts),
    II and CC markers equal, FF/SS subclass counts equal."""
    for cls, r in rows.items():
        d = rows[r.dual]
        assert d.dual == cls
        assert (r.IF, r.FI) == (d.FI, d.IF)
        assert r.II == d.II and r.CC == d.CC
        assert len(r.subclasses["FF"]) == len(d.subclasses["FF"])
        assert len(r.subclasses["SS"]) == len(d.subclasses["SS"])
        assert len(r.subclasses["SF"]) == len(d.subclasses["FS"])
        assert r.stability["SF"] == d.stability["FS"]


def test_sf_fs_stability_words(rows):
    # SF stable iff b11 > 0: quadrants 1 and 4 of beta1
    for cls, r in rows.items():
        if r.subclasses["SF"]:
            assert r.stability["SF"] == ("stable" if cls // 10 in (1, 4) else "unstable")


def test_markdown_and_csv(rows):
    md = t2.to_markdown(list(rows.values()))
    assert md.split("\n\n")[0].count("\n") == 25 and "| 25 (same) |" in md
    csv = t2.to_csv(list(rows.values()))
    assert csv.splitlines()[0].startswith("class,dual,FF_subclasses")


# ---- duality: a class and its dual get the same words (SF <-> FS, IF <-> FI) -------------------

DUAL_MODE = {"FF": "FF", "SS": "SS", "SF": "FS", "FS": "SF"}


def test_words_equal_dual_words_for_every_mode(rows):
    for cls, r in rows.items():
        d = rows[r.dual]
        for m, md in DUAL_MODE.items():
            assert r.stability[m] == d.stability[md], (cls, m)
        assert r.II_stability == d.II_stability, cls
        assert (r.II, r.IF, r.FI) == (d.II, d.FI, d.IF), cls


def test_kappa_q_sample_closed_under_dual_map():
    """(kappa, q1, q2) -> (1/kappa, q2/sqrt(kappa), q1/sqrt(kappa)) maps the sample onto itself."""
    sample = {tuple(round(x, 9) for x in t) for t in t2.KAPPA_Q_SAMPLE}
    for k, q1, q2 in t2.KAPPA_Q_SAMPLE:
        dual = (1 / k, q2 / k**0.5, q1 / k**0.5)
        assert any(
            all(abs(a - b) <= 1e-9 * max(1.0, abs(b)) for a, b in zip(dual, t)) for t in sample
        ), (k, q1, q2)
    kappas = {t[0] for t in t2.KAPPA_Q_SAMPLE}
    assert min(kappas) <= 1e-5 and max(kappas) >= 1e5


def test_class_samples_closed_under_dual_map():
    smp = t2.class_samples(96, 12)
    for cls, pts in smp.items():
        b1, b2 = contact_modes.dual_angles(pts[:, 0], pts[:, 1])
        c1, s1 = contact_modes.direction(b1)
        c2, s2 = contact_modes.direction(b2)
        duals = {exact.point_codes(*v)["class_code"] for v in zip(c1, s1, c2, s2)}
        assert len(duals) == 1
        target = smp[duals.pop()]
        got = {(round(a, 9), round(b, 9)) for a, b in zip(b1, b2)}
        assert got == {(round(a, 9), round(b, 9)) for a, b in target}, cls


def test_dual_map_preserves_exact_verdicts():
    """The dual system (angles and (kappa, q1, q2) mapped) has the same exact verdicts."""
    rng = np.random.default_rng(3)
    pts = [(1.38541667 * np.pi, 0.40625 * np.pi, 0.1, 1.0, 0.01)]  # class 32, II unstable
    for _ in range(6):
        b1, b2 = rng.uniform(0, 2 * np.pi, 2)
        pts.append((b1, b2, 10 ** rng.uniform(-3, 3), *(10 ** rng.uniform(-2, 1, 2))))
    for b1, b2, k, q1, q2 in pts:
        d1, d2 = contact_modes.dual_angles(b1, b2)
        a = exact.point_spectral(*_dirs(b1, b2), k, q1, q2)
        b = exact.point_spectral(*_dirs(d1, d2), *t2.dual_kq(k, q1, q2))
        for key in ("stable_SS", "consistent_II", "stable_II"):
            assert a[key] == b[key], (key, b1, b2)


def test_ii_class_15_and_32_model_dependent(rows):
    """Exact reference: II in class 32 at (kappa, q) = (0.1, 1, 0.01) is consistent and unstable, and
    so is its dual point in class 15; at Q = 0 both are stable. Table 2 must shade both light."""
    b1, b2 = 1.38541667 * np.pi, 0.40625 * np.pi
    d1, d2 = contact_modes.dual_angles(b1, b2)
    for (x1, x2), kq, cls in (
        ((b1, b2), (0.1, 1.0, 0.01), 32),
        ((d1, d2), t2.dual_kq(0.1, 1.0, 0.01), 15),
    ):
        c = _dirs(x1, x2)
        assert exact.point_codes(*c)["class_code"] == cls
        r = exact.point_spectral(*c, *kq)
        assert (r["consistent_II"], r["stable_II"]) == (1, 0)
        r0 = exact.point_spectral(*c, kq[0], 0.0, 0.0)
        assert (r0["consistent_II"], r0["stable_II"]) == (1, 1)
    assert rows[15].II_stability == rows[32].II_stability == "model-dependent"


def _dirs(b1, b2):
    c1, s1 = contact_modes.direction(b1)
    c2, s2 = contact_modes.direction(b2)
    return float(c1), float(s1), float(c2), float(s2)


def test_markdown_has_key(rows):
    md = t2.to_markdown(list(rows.values()))
    assert "**bold** = unstable" in md and "_italics_ = model-dependent" in md


@pytest.mark.parametrize(
    "kw, name", [(dict(n="xml"), "n"), (dict(per_class=2.5), "per_class"), (dict(n_alpha=0), "n_alpha"),
                 (dict(dtype="float16"), "dtype")],
)  # fmt: skip
def test_bad_arguments_one_line_naming_the_parameter(kw, name):
    with pytest.raises(ValueError, match=f"^{name}: ") as e:
        t2.table2(**kw)
    assert "\n" not in str(e.value)


# The words over every contact model at the class samples, against the paper and an independent
# closed form: SS (README, worked by hand: unstable for every model iff D < 0 or c1, s2 <= 0;
# stable for every model iff D >= 0, c1, s2 > 0, s1 c2 >= 0) and App. C, Q2 (II consistency).
SS_STABLE, SS_CURVED = {12, 42}, {13, 14, 23, 31, 41, 46}
II_ALWAYS, II_SOME = {15, 25, 32, 33, 34, 35, 43, 44}, {14, 24, 31, 36}


def test_words_over_every_model():
    samples = t2.class_samples(64, 4)
    for cls in contact_modes.ALL_CLASSES:
        w = t2.over_models_words(samples[cls])
        ss = "stable" if cls in SS_STABLE else "model-dependent" if cls in SS_CURVED else "unstable"
        assert w["SS"] == ss, cls
        assert w["II"] == ("x" if cls in II_ALWAYS else "(x)" if cls in II_SOME else "-"), cls
        if w["II"] == "-":
            assert w["II_stability"] == "-", cls
    # certified by witnesses: a complex pair overtakes the II root for some models (the audit's
    # class-32 point and its dual); class 25 never stable (Table 2's dark cell)
    assert t2.over_models_words(samples[25])["II_stability"] == "unstable"
    wide = t2.class_samples(96, 24)
    for cls in (15, 32):
        assert t2.over_models_words(wide[cls])["II_stability"] == "model-dependent", cls


def test_ii_stability_proved_where_the_paper_has_it_plain():
    """Paper, Table 2: II consistent and stable (plain x) in 34 and 35; over every model this is
    proved (Perron-Frobenius), not taken from the model sample."""
    samples = t2.class_samples(64, 4)
    for cls in (34, 35):
        assert t2.over_models_words(samples[cls])["II_stability"] == "stable", cls


def test_rows_say_where_the_words_come_from(rows):
    """A word the verdicts over every model leave open keeps the sample's and says so; the
    Markdown prints the notes."""
    notes = {c: r.notes for c, r in rows.items()}
    assert all("from the model sample" in n for ns in notes.values() for n in ns if "open" in n)
    assert not any(n.startswith("SS") for ns in notes.values() for n in ns)  # SS all decided
    text = t2.to_markdown(list(rows.values()))
    assert ("Notes" in text) == any(notes.values())
