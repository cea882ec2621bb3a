"""Table 2 regenerated from the kernels equals the paper's, cell by cell."""

import pytest

from atlas import tables as t2

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
    return {r.cls: r for r in t2.table2(n=64, per_class=12, n_alpha=480)}


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
    assert md.count("\n") == 26 and "| 25 (same) |" in md
    csv = t2.to_csv(list(rows.values()))
    assert csv.splitlines()[0].startswith("class,dual,FF_subclasses")
