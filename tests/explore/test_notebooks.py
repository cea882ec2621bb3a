"""The notebooks execute headless, and the widget's map is the atlas's map.

* ``notebooks/explore.ipynb`` and ``notebooks/paper.ipynb`` run top to bottom in a fresh kernel
  (nbclient, kernel ``python3`` of the current interpreter) with a temporary working directory, so
  every file they write lands there.  Their ``QUICK = True`` first cell keeps them short.
* The widget's redraw callback (moving the controls of :func:`atlas.explore.make_widget`) computes
  exactly the arrays :func:`atlas.data.engine.generate` stores for the same parameters.
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

ROOT = Path(__file__).resolve().parents[2]
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
    from atlas.data.engine import generate
    from atlas.data.scene import Scene
    from atlas.explore import explorer as explore

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
    from atlas.explore import explorer as explore

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


def _click(box, beta1, beta2, button=1):
    """Deliver a synthetic left click at data point ``(beta1, beta2)`` through the canvas's
    ``button_press_event`` callbacks (what ipympl does for a click in the browser)."""
    from matplotlib.backend_bases import MouseEvent

    fig = box.figure
    ax = fig.axes[0]
    x, y = ax.transData.transform((beta1, beta2))
    event = MouseEvent("button_press_event", fig.canvas, x, y, button=button)
    fig.canvas.callbacks.process("button_press_event", event)
    return event


def test_click_on_map_inspects_that_point():
    _need("ipywidgets")
    from atlas.core import exact
    from atlas.explore import explorer as explore

    kappa, q = 0.5, 2**0.5
    box = explore.make_widget(n=N, layer="stable_II", kappa=kappa, q1=q, alpha=ALPHA)
    ex, c = box.explorer, box.controls
    assert ex.point is None
    # a click outside the axes (in the figure margin) does nothing
    _click(box, -0.5, 1.0)
    assert ex.point is None and ex.last_inspection is None

    seen = set()
    for b1, b2 in ((0.15 * math.pi, 1.07 * math.pi), (0.6, 4.0), (5.5, 2.2), (3.0, 0.4)):
        event = _click(box, b1, b2)
        assert event.inaxes is box.figure.axes[0]
        info = ex.last_inspection
        assert info is not None
        np.testing.assert_allclose(ex.point, (b1, b2), atol=1e-9)
        assert (info["beta1"], info["beta2"]) == ex.point
        np.testing.assert_allclose(
            (c["beta1"].value, c["beta2"].value), (b1 / math.pi, b2 / math.pi), atol=1e-6
        )
        assert explore.format_inspection(info) in box.inspector.value
        # truth: the exact reference at the clicked point, directions from numpy
        d = [np.cos(ex.point[0]), np.sin(ex.point[0]), np.cos(ex.point[1]), np.sin(ex.point[1])]
        ref = exact.point_spectral(*d, kappa, q, q)
        codes = exact.point_codes(*d, np.cos(ALPHA), np.sin(ALPHA))
        for k in ("stable_SS", "consistent_II", "stable_II"):
            assert info["spectral"][k] == int(ref[k]), (b1, b2, k)
        assert info["class_code"] == codes["class_code"]
        assert info["subclass_code"] == codes["subclass_code"]
        np.testing.assert_allclose(
            np.sort_complex(info["eigenvalues"]),
            np.sort_complex(np.asarray(ref["roots"], complex)),
            atol=1e-9,
        )
        seen.add(codes["class_code"])
        # the marker sits on the clicked point
        np.testing.assert_allclose(np.ravel(box.figure.axes[0].lines[-1].get_data()), ex.point)
    assert len(seen) >= 3  # the clicks landed in different classes


def test_redraw_capped_then_settle_undecided():
    """An even grid puts cells on det B = 0 (undecided for the fast path): a redraw settles at most
    ``max_resolve`` of them and draws the rest in the undecided colour; the "settle undecided"
    button settles all, giving the atlas's map."""
    _need("ipywidgets")
    from matplotlib.colors import to_rgba

    from atlas.core.verdicts import Verdict
    from atlas.data.engine import generate
    from atlas.data.scene import Scene
    from atlas.explore import explorer as explore

    n, cap, kappa, q = 64, 5, 0.5, 0.3
    box = explore.make_widget(n=n, layer="stable_SS", kappa=kappa, q1=q, max_resolve=cap)
    ex = box.explorer
    fast = ex.ds.attrs["n_undecided_fast"]
    assert fast > cap
    assert ex.ds.attrs["n_undecided"] == fast - cap
    undecided = ex.ds["stable_SS"].values == int(Verdict.UNDECIDED)
    assert undecided.sum() == fast - cap
    img = ex.image()
    red = np.all(np.isclose(img, to_rgba(Verdict.UNDECIDED.color)), axis=-1)
    np.testing.assert_array_equal(red, undecided.T)  # image is (beta2, beta1)
    labels = [t.get_text() for t in box.figure.axes[0].get_legend().get_texts()]
    assert Verdict.UNDECIDED.label in labels
    assert "settle undecided" in ex.status()

    box.callbacks["settle"]()
    assert ex.ds.attrs["n_undecided"] == 0
    assert ex.ds.attrs["n_undecided_fast"] == fast
    beta = explore.beta_grid(n)
    ref = generate(Scene(beta1=beta, beta2=beta, kappa=kappa, q=q, outputs=["stable_SS"]))
    np.testing.assert_array_equal(ex.ds["stable_SS"].values, ref["stable_SS"].values)
    labels = [t.get_text() for t in box.figure.axes[0].get_legend().get_texts()]
    assert Verdict.UNDECIDED.label not in labels
    # the next slider move is capped again
    box.controls["kappa"].value = 0.6
    assert ex.ds.attrs["n_undecided"] == max(0, ex.ds.attrs["n_undecided_fast"] - cap)


def test_overlays_and_measure_redraw():
    _need("ipywidgets")
    from atlas.explore import explorer as explore

    box = explore.make_widget(n=N, layer="consistent_II", kappa=0.5, q1=0.3)
    c, ax = box.controls, box.figure.axes[0]
    c["overlays"].value = ("SS boundary",)
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert "SS boundary" in labels
    assert not any(a.get_visible() for a in ax.lines[:-1])  # class boundaries hidden
    # the dashed contour is the zero set of the smooth margin (values at its vertices ~ 0)
    m = explore.compute_map(0.5, 0.3, n=N, layers=("margin_SS",))["margin_SS"]
    from scipy.interpolate import RegularGridInterpolator

    f = RegularGridInterpolator((m.beta1.values, m.beta2.values), m.values)
    paths = [p for p in ax.collections[-1].get_paths() if len(p.vertices)]
    assert paths
    v = np.concatenate([p.vertices for p in paths])
    inside = np.all((v > m.beta1.values[0]) & (v < m.beta1.values[-1]), axis=1)
    assert np.abs(f(v[inside])).max() < 1e-9 + 0.05 * np.abs(m.values).max()
    c["overlays"].value = ("class boundaries",)
    assert all(a.get_visible() for a in ax.lines[:-1])
    assert "SS boundary" not in [t.get_text() for t in ax.get_legend().get_texts()]
    with pytest.raises(ValueError, match="overlays"):
        box.explorer.update(overlays=("nope",))

    rows = explore.measure_redraw(
        n=16, cases=((0.3, 0.3),), layers=("stable_SS",), repeats=2, max_resolve=3
    )
    (r,) = rows
    assert r["n"] == 16 and r["layer"] == "stable_SS" and (r["q1"], r["q2"]) == (0.3, 0.3)
    assert r["total_ms"] >= r["compute_ms"] > 0
    want = explore.compute_map(r["kappa"], 0.3, n=16, layers=("stable_SS",), resolve=False)
    assert r["n_undecided_fast"] == want.attrs["n_undecided_fast"] > 3
    assert r["n_undecided"] == r["n_undecided_fast"] - 3
    assert "stable_SS" in explore.format_redraw(rows)


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
