"""``atlas.paper.side_process``: a group of ``atlas paper``'s steps in a second process."""

import os
import signal
import time

import pytest

from atlas import paper
from atlas.data import io
from atlas.paper import runlog, side_process
from atlas.paper.steps import Steps


def _steps_ok(step, out, quick, ci):
    from atlas.core import warm

    runlog.record("side line", 1.5)
    return step("a step", lambda: (str(out), quick, ci, os.getpid(), warm.active_cache()))


def _steps_fail(step, out, quick, ci):
    step("a step", lambda: 1 / 0)


def _steps_die(step, out, quick, ci):
    os._exit(3)


def _steps_wait(step, out, quick, ci):
    io.atomic_write_text(os.path.join(out, "done.md"), "done\n")
    while True:  # until interrupted
        time.sleep(0.05)


def _join(steps, tmp_path, step):
    side = side_process.start(steps, tmp_path, True, False, False)
    try:
        return side_process.join(side, step)
    finally:
        side_process.stop(side)


def test_the_result_timings_log_lines_messages_and_kept_kernels_come_back(tmp_path):
    said = []
    step = Steps(said.append)
    from atlas.core import warm

    kept = str(tmp_path / "kernels")
    with warm.kernel_cache(kept, run="a run"), runlog.RunLog(tmp_path) as log:
        out, quick, ci, pid, cache = _join(_steps_ok, tmp_path, step)
    assert (out, quick, ci) == (str(tmp_path), True, False)
    assert pid != os.getpid()
    # the calling run's kept kernels serve the second process too, under a name of its own
    assert cache == (kept, "a run (second process)")
    assert said == ["a step ...", f"a step done in {step.timings['a step']:.1f} s"]
    assert "side line: 1.500" in log.lines
    assert any(line.startswith("step a step seconds: ") for line in log.lines)


def test_an_error_of_the_second_process_is_raised_with_its_traceback(tmp_path):
    with pytest.raises(ZeroDivisionError) as got:
        _join(_steps_fail, tmp_path, Steps(lambda m: None))
    assert "_steps_fail" in str(got.value.__cause__)


def test_a_second_process_that_dies_is_an_error(tmp_path):
    with pytest.raises(RuntimeError, match=r"exit code 3\) before its steps were done"):
        _join(_steps_die, tmp_path, Steps(lambda m: None))


@pytest.mark.parametrize("jobs", [0, -1, 1.5, "2", True])
def test_bad_jobs_are_refused_before_any_work(tmp_path, jobs):
    out = tmp_path / "out"
    with pytest.raises(ValueError, match=r"^jobs: must be an integer >= 1, got "):
        paper.run(out=out, jobs=jobs, progress=lambda m: None)
    assert not out.exists()


@pytest.mark.parametrize("ignored", [False, True])
def test_stopped_early_it_names_the_files_it_completed(tmp_path, monkeypatch, ignored):
    """The calling run failed (or was interrupted) first: the second process is interrupted and
    its complete files join the run's list (the interrupt message names them); so too where the
    run was started with SIGINT ignored (a shell's background job), which the second process
    inherits."""
    monkeypatch.setattr(io, "COMMITTED", [])
    before = signal.signal(
        signal.SIGINT, signal.SIG_IGN if ignored else signal.getsignal(signal.SIGINT)
    )
    try:
        side = side_process.start(_steps_wait, tmp_path, True, False, False)
    finally:
        signal.signal(signal.SIGINT, before)
    while not (tmp_path / "done.md").exists() and side[0].is_alive():
        time.sleep(0.05)
    side_process.stop(side)
    assert not side[0].is_alive()
    assert io.COMMITTED == [str(tmp_path / "done.md")]
