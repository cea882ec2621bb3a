"""The agreement table of the bridge's verdicts against MuJoCo rollouts (tests/mujoco_agreement.py;
slow: ~30-50 s).  It is a measurement: the table is printed (``-s``) and recorded in
docs/mujoco.md; the test checks its size and the region where the theory leaves one answer that
no soft model can fake, the jams of the ladder's foot (only impacts without collision consistent),
and that the verdict at separation is taken only where MuJoCo separates a contact."""

from __future__ import annotations

import pytest

pytest.importorskip("mujoco", reason="the mujoco extra is not installed")

import mujoco_agreement as agreement  # noqa: E402


@pytest.mark.slow
def test_agreement_table():
    rows = agreement.measure()
    print(agreement.table(rows))
    decided = [r for r in rows if r[1] != "several"]
    assert len(decided) >= 60
    jams = [r for r in rows if r[0] == "ladder" and r[1] == "jam"]
    assert jams and all(r[2] == r[3] == "jam" for r in jams)
    lifts = sum(o in ("SF", "FS", "FF") for r in rows for o in r[2:4])
    assert lifts and sum(w is not None for r in rows for w in r[6:8]) == lifts
    for r in rows:
        for outcome, at_separation, when in zip(r[2:4], r[4:6], r[6:8]):
            if outcome in ("SF", "FS", "FF"):
                assert 0.0 <= when < agreement.HORIZON
            else:
                assert at_separation == r[1] and when is None
