"""``atlas.paper.steps``: the steps of ``atlas paper`` and what its second process starts from."""

import os
import subprocess
import sys

from atlas.paper import runlog, side_process
from atlas.paper.steps import Shared, Steps


def _spin(n: int) -> int:
    """Some CPU work (``n`` additions)."""
    return sum(range(n))


def test_a_step_is_announced_timed_and_logged(tmp_path):
    said = []
    step = Steps(said.append)
    with runlog.RunLog(tmp_path) as log:
        assert step("one", lambda: _spin(10**6)) == _spin(10**6)
    assert said == ["one ...", f"one done in {step.timings['one']:.1f} s"]
    assert f"step one seconds: {step.timings['one']:.3f}" in log.lines
    cpu = [line for line in log.lines if line.startswith("step one cpu seconds: ")]
    assert len(cpu) == 1  # the process's CPU seconds of the step, beside its wall seconds


def test_the_driver_starts_its_second_process_before_importing_jax():
    """``atlas paper`` spawns its second process before it imports its steps' modules, so both
    import at once: the driver, the steps and the second process's module import no JAX, xarray
    or matplotlib (counted in a fresh interpreter)."""
    code = (
        "import sys; import atlas.paper.run, atlas.paper.steps, atlas.paper.side_process; "
        "print(sorted(m for m in ('jax', 'xarray', 'matplotlib') if m in sys.modules))"
    )
    got = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert got.stdout.strip() == "[]"


def _claim_many(step, out, quick, ci, shared):
    return [shared.claim() for _ in range(200)]


def test_each_shared_step_is_claimed_once_by_the_two_processes(tmp_path):
    """Both processes claim from one :class:`Shared` at once: every index is given exactly once."""
    with Shared() as shared:
        side = side_process.start(_claim_many, tmp_path, True, False, False, shared)
        try:
            here = [shared.claim() for _ in range(200)]
            there = side_process.join(side, Steps(lambda m: None))
        finally:
            side_process.stop(side)
    assert sorted(here + there) == list(range(400))
    assert not os.path.exists(shared.path)
