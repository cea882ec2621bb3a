"""``atlas.paper.run(quick=True)`` end to end."""

import os
import subprocess
import sys

import pytest
import xarray as xr

from atlas import paper
from atlas.paper.runlog import LOG


def test_atomic_write_text(tmp_path):
    p = tmp_path / "a.txt"
    paper.atomic_write_text(p, "one")
    paper.atomic_write_text(p, "two")
    assert p.read_text() == "two"
    assert [f.name for f in tmp_path.iterdir()] == ["a.txt"]


def _check_outputs(tmp_path):
    """The declared files (``outputs/`` is compared with the same list), none empty."""
    for f in paper.files(quick=True):
        assert (tmp_path / f).stat().st_size > 0, f
    ds = xr.open_dataset(tmp_path / "fig1_map.nc")
    assert ds["stable_SS"].dtype == "int8"
    assert "flag_meanings" in ds["stable_SS"].attrs
    assert "NOT verified" not in (tmp_path / "audit.md").read_text()
    assert not list(tmp_path.glob("*.tmp*"))


@pytest.mark.e2e
def test_run_ci(paper_run):
    """`atlas paper` end to end at the CI size (smallest grids, reduced audit): the session's
    shared run (``paper_run``, tests/conftest.py)."""
    _check_outputs(paper_run.out)
    assert "quick = True, ci = True" in (paper_run.out / "audit.md").read_text()
    assert {"table2", "fig1 map (compute)", "audit (compute)"} <= set(paper_run.timings)
    readme = (paper_run.out / "README.md").read_text()
    assert "## Fig. 1 plane over every contact model" in readme
    assert "| depends on the model |" in readme


@pytest.mark.slow
def test_run_quick(tmp_path):
    paper.run(out=tmp_path, quick=True, progress=lambda m: None)
    _check_outputs(tmp_path)
    assert sorted(f.name for f in tmp_path.iterdir()) == sorted([*paper.files(quick=True), LOG])


@pytest.mark.e2e
def test_a_second_run_elsewhere_writes_the_same_bytes(paper_run, tmp_path):
    """The files ``atlas paper`` writes are a pure function of the code and its inputs: a second
    CI-sized run, in another process (another hash seed, time zone, working directory and output
    path, a later time, its independent steps in a second process where the shared run has one),
    gives every file byte for byte; dates and seconds are in the run log."""
    env = dict(os.environ, PYTHONHASHSEED="7", TZ="Asia/Tokyo")
    code = (
        "import sys; from atlas import paper; "
        "paper.run(sys.argv[1], ci=True, progress=print, jobs=2)"
    )
    out = tmp_path / "again"
    subprocess.run([sys.executable, "-c", code, str(out)], env=env, cwd=tmp_path, check=True)
    differ = [
        f
        for f in paper.files(quick=True)
        if (out / f).read_bytes() != (paper_run.out / f).read_bytes()
    ]
    assert differ == []
    log = (out / LOG).read_text()
    assert "date: " in log and "total seconds: " in log and str(out) in log
    assert "processes: 2" in log and "step fig1_boundaries.png seconds: " in log


def test_the_files_drawn_from_the_audit_reuse_its_computations(tmp_path, monkeypatch):
    """``fig1_models.png`` and ``realisability.md`` come from what the audit computed: the
    whole-model-space map and the 2^19-body search run once each in a run (twice before: once
    in the audit, once in a step of their own), and the figure has the standalone drawing's
    bytes."""
    import collections

    from atlas.paper import audit, figure_models, realisability
    from atlas.paper.run import _from_the_audit
    from atlas.paper.steps import Steps

    calls = collections.Counter()

    def counted(name, fn):
        def wrapper(*args, **kwargs):
            calls[name] += 1
            return fn(*args, **kwargs)

        return wrapper

    real_map = figure_models.model_dependence_map
    monkeypatch.setattr(figure_models, "model_dependence_map", counted("map", real_map))
    monkeypatch.setattr(realisability, "search", counted("search", realisability.search))
    ctx = audit.Context(ci=True)
    audit.run_audit(context=ctx, select=["C1w", "S144"])
    _from_the_audit(Steps(lambda m: None), tmp_path, ctx)
    assert calls == {"map": 1, "search": 1}
    assert "subclasses realised" in (tmp_path / "realisability.md").read_text()
    alone = tmp_path / "alone.png"
    n, boxes = figure_models.N_MODELS[2], figure_models.BOXES[:1]
    figure_models.plot_model_dependence(alone, n=n, boxes=boxes)
    assert (tmp_path / "fig1_models.png").read_bytes() == alone.read_bytes()
