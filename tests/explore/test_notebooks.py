"""The notebooks execute headless.

* ``notebooks/explore.ipynb`` and ``notebooks/paper.ipynb`` run top to bottom in a fresh kernel
  (nbclient, kernel ``python3`` of the current interpreter) with a temporary working directory, so
  every file they write lands there.  Their ``QUICK = True`` first cell keeps them short; the
  runner turns its ``CI = False`` into ``CI = True`` (the smallest sizes that run every cell)
  and shares the run's compilation cache with the kernel.  They are
  started in the background by ``notebook_runs`` (conftest.py) and waited for by the last tests.
"""

from __future__ import annotations

from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
NOTEBOOKS = ROOT / "notebooks"
NOTEBOOK_NAMES = ("explore", "paper")


def test_notebooks_committed_without_outputs(need):
    nbformat = need("nbformat")
    for name in NOTEBOOK_NAMES:
        nb = nbformat.read(NOTEBOOKS / f"{name}.ipynb", as_version=4)
        nbformat.validate(nb)
        for cell in nb.cells:
            if cell.cell_type == "code":
                assert cell.outputs == [] and cell.execution_count is None, name
        first = next(c for c in nb.cells if c.cell_type == "code")
        assert "QUICK = True" in first.source and "CI = False" in first.source, name


# --- the notebooks (started in the background by ``notebook_runs``) ----------------------------


@pytest.mark.e2e
@pytest.mark.slow  # in CI the browser test runs this notebook at this size (test_notebook_browser)
def test_explore_notebook_executes(notebook_runs):
    seconds, cwd = notebook_runs.wait("explore")
    assert (cwd / "tiny_atlas.nc").is_file()
    print(f"explore.ipynb: {seconds:.1f} s")


@pytest.mark.e2e
def test_paper_notebook_executes(notebook_runs):
    seconds, cwd = notebook_runs.wait("paper")
    for f in (
        "table2.png",
        "fig1_classes.png",
        "fig1_stability.png",
        "fig1_variants.png",
        "fig2.png",
    ):
        assert (cwd / "paper_outputs" / f).is_file(), f
    print(f"paper.ipynb: {seconds:.1f} s")
