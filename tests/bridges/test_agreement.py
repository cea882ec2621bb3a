"""The agreement table of the bridge's verdicts against MuJoCo rollouts (tests/mujoco_agreement.py;
slow: ~30-50 s).  It is a measurement: the table is printed (``-s``) and recorded in
docs/mujoco.md; the test checks its size and the region where the theory leaves one answer that
no soft model can fake, the jams of the ladder's foot (only impacts without collision consistent)."""

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
