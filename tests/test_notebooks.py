"""The notebooks execute headless, and the widget's map is the atlas's map.

* ``notebooks/explore.ipynb`` and ``notebooks/paper.ipynb`` run top to bottom in a fresh kernel
  (nbclient, kernel ``python3`` of the current interpreter) with a temporary working directory, so
  every file they write lands there.  Their ``QUICK = True`` first cell keeps them short.
* The widget's redraw callback (moving the controls of :func:`atlas.explore.make_widget`) computes
  exactly the arrays :func:`atlas.tiling.generate` stores for the same parameters.
"""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
NOTEBOOKS = ROOT / "notebooks"


def _need(module: str):
    """Import a [test]-extra dependency; skip locally if missing, but fail in CI (``CI`` set)."""
    if os.environ.get("CI"):
        return __import__(module)
    return pytest.importorskip(module)


NOTEBOOK_NAMES = ("explore", "paper")

# Each notebook runs in its own process (nbclient -> a fresh ``python3`` kernel of this interpreter,
# found through ipykernel's kernel spec in sys.prefix).  Both start as soon as the module's first
# test runs, so they overlap with each other and with the in-process tests below (most of their time
# is single-threaded XLA compilation).
_RUNNER = """
import json, sys, time
import nbclient, nbformat
src, cwd = sys.argv[1], sys.argv[2]
nb = nbformat.read(src, as_version=4)
client = nbclient.NotebookClient(nb, timeout=600, kernel_name="python3",
                                 resources={"metadata": {"path": cwd}})
t = time.perf_counter()
try:
    client.execute()
except nbclient.exceptions.CellExecutionError as e:
    sys.stderr.write(str(e)[-6000:])
    sys.exit(1)
print(json.dumps({"seconds": time.perf_counter() - t}))
"""


@pytest.fixture(scope="module", autouse=True)
def notebook_runs(request, tmp_path_factory):
    """Start the selected notebook executions in the background; yields name -> (process, dir)."""
    wanted = [
        n
        for n in NOTEBOOK_NAMES
        if any(item.name == f"test_{n}_notebook_executes" for item in request.session.items)
    ]
    runs = {}
    if wanted:
        for m in ("nbformat", "nbclient", "ipykernel", "ipywidgets"):
            _need(m)
        path = os.pathsep.join(p for p in (str(ROOT), os.environ.get("PYTHONPATH", "")) if p)
        env = dict(os.environ, PYTHONPATH=path, MPLBACKEND="Agg")
        for name in wanted:
            cwd = tmp_path_factory.mktemp(f"nb_{name}")
            out = open(cwd / "_runner.out", "w")  # closed after the module
            err = open(cwd / "_runner.err", "w")
            proc = subprocess.Popen(
                [sys.executable, "-c", _RUNNER, str(NOTEBOOKS / f"{name}.ipynb"), str(cwd)],
                cwd=cwd,
                env=env,
                stdout=out,
                stderr=err,
            )
            runs[name] = (proc, cwd, out, err)
    yield runs
    for proc, _, out, err in runs.values():
        if proc.poll() is None:
            proc.kill()
            proc.wait()
        out.close()
        err.close()


def _wait(runs, name: str, timeout: float = 900) -> tuple[float, Path]:
    proc, cwd, _, _ = runs[name]
    proc.wait(timeout=timeout)
    err = (cwd / "_runner.err").read_text()
    assert proc.returncode == 0, f"{name}.ipynb failed:\n{err}"
    seconds = json.loads((cwd / "_runner.out").read_text().strip().splitlines()[-1])["seconds"]
    return seconds, cwd


def test_notebooks_committed_without_outputs():
    nbformat = _need("nbformat")
    for name in NOTEBOOK_NAMES:
        nb = nbformat.read(NOTEBOOKS / f"{name}.ipynb", as_version=4)
        nbformat.validate(nb)
        for cell in nb.cells:
            if cell.cell_type == "code":
                assert cell.outputs == [] and cell.execution_count is None, name
        first = next(c for c in nb.cells if c.cell_type == "code")
        assert "QUICK = True" in first.source, name


def test_explore_imports_without_ipywidgets():
    code = "import sys, atlas.explore; assert 'ipywidgets' not in sys.modules"
    env = dict(
        os.environ, PYTHONPATH=os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])
    )
    subprocess.run([sys.executable, "-c", code], check=True, env=env, cwd=ROOT)


# --- the widget's callback against the batch path ---------------------------------------------

N = 65
ALPHA = 0.35 * math.pi


@pytest.mark.parametrize(
    "kappa, q1, q2",
    [(0.5, 0.0, 0.0), (2.0, 0.3, 0.3), (0.5, 1.0, 0.01)],
    ids=["fig1", "damped", "q1-neq-q2"],
)
def test_widget_map_equals_generate(kappa, q1, q2):
    _need("ipywidgets")
    from atlas import explore
    from atlas.tiling import generate
    from atlas.scene import Scene

    box = explore.make_widget(n=N, layer="class_code", alpha=ALPHA)
    c, ex = box.controls, box.explorer
    c["kappa"].value = kappa
    if q1 == q2:
        c["q"].value = q1
    else:
        c["separate"].value = True
        c["q1"].value, c["q2"].value = q1, q2
    c["alpha"].value = ALPHA / math.pi
    assert (ex.params["kappa"], ex.params["q1"], ex.params["q2"]) == (kappa, q1, q2)

    beta = explore.beta_grid(N)
    model = dict(q=q1) if q1 == q2 else dict(q1=q1, q2=q2)
    layers = [k for k in explore.LAYERS if k != "margin_SS"]
    ref = generate(
        Scene(
            beta1=beta, beta2=beta, alpha=ex.params["alpha"], kappa=kappa, outputs=layers, **model
        )
    )
    for layer in layers:
        c["layer"].value = layer  # the redraw callback
        got = ex.ds[layer]
        want = ref[layer]
        assert got.dims == want.dims, layer
        assert got.dtype == want.dtype, layer
        np.testing.assert_array_equal(got["beta1" if "beta1" in got.dims else "beta2"].values, beta)
        if layer == "spectral_abscissa":  # float, not certified: different root finders agree
            np.testing.assert_allclose(got.values, want.values, rtol=1e-9, atol=1e-12)
        else:
            np.testing.assert_array_equal(got.values, want.values, err_msg=layer)
    assert ex.ds.attrs["n_undecided"] == 0


def test_inspector_agrees_with_exact_and_map():
    from atlas import explore

    ds = explore.compute_map(
        0.5, 2**0.5, n=33, layers=("class_code", "stable_SS", "consistent_II", "stable_II")
    )
    for i, j in ((3, 20), (10, 5), (25, 30)):
        b1, b2 = float(ds.beta1[i]), float(ds.beta2[j])
        info = explore.inspect_point(b1, b2, ALPHA, kappa=0.5, q1=2**0.5)
        assert (
            info["class_code"] == int(ds["class_code"][i, j]) == info["exact_codes"]["class_code"]
        )
        assert info["spectral"] == info["spectral_exact"]
        for k in ("stable_SS", "consistent_II", "stable_II"):
            assert info["spectral"][k] == int(ds[k][i, j])
            assert info["spectral_fast"][k] in (info["spectral"][k], 3)
        assert len(info["eigenvalues"]) == 4
        np.testing.assert_allclose(
            np.sort_complex(info["eigenvalues"]),
            np.sort_complex(info["eigenvalues_exact"]),
            atol=1e-9,
        )
        assert "class" in explore.format_inspection(info)


def test_compute_map_rejects_bad_input():
    from atlas import explore

    for kw, msg in (
        (dict(kappa=-1.0), "kappa"),
        (dict(q1=float("nan")), "q1"),
        (dict(layers=("nope",)), "layers"),
        (dict(layers=("subclass_code",)), "alpha"),
    ):
        with pytest.raises(ValueError, match=msg):
            explore.compute_map(**{"n": 9, **kw})


# --- the notebooks (started in the background by ``notebook_runs``) ----------------------------


def test_explore_notebook_executes(notebook_runs):
    seconds, cwd = _wait(notebook_runs, "explore")
    assert (cwd / "tiny_atlas.nc").is_file()
    print(f"explore.ipynb: {seconds:.1f} s")


def test_paper_notebook_executes(notebook_runs):
    seconds, cwd = _wait(notebook_runs, "paper")
    for f in (
        "table2.png",
        "fig1_classes.png",
        "fig1_stability.png",
        "fig1_variants.png",
        "fig2.png",
    ):
        assert (cwd / "paper_outputs" / f).is_file(), f
    print(f"paper.ipynb: {seconds:.1f} s")
