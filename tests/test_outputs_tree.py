"""``outputs/`` is exactly what ``atlas paper`` and ``atlas bench`` write."""

from pathlib import Path

import pytest

from atlas import paper
from atlas.bench import runner
from atlas.paper.runlog import LOG

OUTPUTS = Path(__file__).resolve().parents[1] / "outputs"


def test_outputs_holds_exactly_what_paper_and_bench_write():
    committed = {p.name for p in OUTPUTS.iterdir() if p.is_file() and p.name != LOG}
    declared = set(paper.FILES) | set(runner.files("full"))
    assert committed == declared, (
        f"not written by atlas paper/bench: {sorted(committed - declared)}; "
        f"missing: {sorted(declared - committed)}"
    )


def test_readme_of_outputs_links_every_paper_file():
    readme = (OUTPUTS / "README.md").read_text()
    for name in paper.FILES:
        if name != "README.md":
            assert f"]({name})" in readme, name


def test_quick_and_tiny_runs_write_elsewhere():
    assert runner.files("tiny") and "distributed.md" not in runner.files("tiny")
    assert set(paper.files(quick=True)) < set(paper.FILES)


@pytest.mark.e2e
def test_paper_run_writes_exactly_its_declared_files(paper_run):
    """The session's CI-sized ``atlas paper`` run (``paper_run``, conftest.py) writes exactly
    ``paper.files(quick=True)``, and its untracked run log: the list ``outputs/`` is compared
    with above."""
    written = sorted(f.name for f in paper_run.out.iterdir())
    assert written == sorted([*paper.files(quick=True), LOG])


def test_the_run_log_is_never_committed():
    """The run log (dates, seconds, host) is git-ignored in ``outputs/``."""
    ignored = (OUTPUTS.parent / ".gitignore").read_text().split()
    assert f"outputs/{LOG}" in ignored
