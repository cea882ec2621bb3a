"""Shared by the explorer's tests: optional dependencies of the ``test`` extra, and the notebook
executions started in the background (``notebook_runs``)."""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest
from notebook_run import prepare_notebook

ROOT = Path(__file__).resolve().parents[2]
_NOTEBOOK_TEST = re.compile(r"test_(\w+)_notebook_executes$")


def need_module(module: str):
    """Import a [test]-extra dependency; skip locally if missing, but fail in CI (``CI`` set)."""
    if os.environ.get("CI"):
        return __import__(module)
    return pytest.importorskip(module)


#: environment variables of the warm start a probe process must not inherit
_SWITCHES = ("ATLAS_JAX_CACHE", "ATLAS_KERNEL_CACHE", "ATLAS_KERNEL_EXECUTABLES")
_SWITCHES += ("JAX_COMPILATION_CACHE_DIR",)


@pytest.fixture(scope="session")
def probe_env():
    """``probe_env(cache, **switches)``: a fresh process's environment, ``cache`` as
    ``$ATLAS_JAX_CACHE``, only ``switches`` of the warm start set, this source tree first on the
    path, matplotlib's Agg backend."""

    def env(cache, **switches) -> dict:
        base = {k: v for k, v in os.environ.items() if k not in _SWITCHES}
        path = os.pathsep.join(p for p in (str(ROOT), os.environ.get("PYTHONPATH", "")) if p)
        return dict(base, ATLAS_JAX_CACHE=str(cache), PYTHONPATH=path, MPLBACKEND="Agg", **switches)

    return env


@pytest.fixture(scope="session")
def need():
    """:func:`need_module` as a fixture (``need("ipywidgets")``)."""
    return need_module


def pytest_collection_modifyitems(items):
    """The notebook tests (which wait for the background runs) go last, so that the runs overlap
    with the in-process tests."""
    items.sort(key=lambda item: bool(_NOTEBOOK_TEST.match(item.name)))


# Each notebook runs in its own process (nbclient -> a fresh ``python3`` kernel of this interpreter,
# found through ipykernel's kernel spec in sys.prefix), as :func:`prepare_notebook` copies it.  They start with the first test of this
# directory, so they overlap with each other and with the in-process tests (most of their time is
# single-threaded XLA compilation); ``test_<name>_notebook_executes`` waits for ``<name>.ipynb``.
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


class NotebookRuns:
    """Notebook executions in background processes, each in its own temporary directory."""

    def __init__(self, tmp_path_factory):
        self.tmp_path_factory = tmp_path_factory
        self.runs = {}

    def start(self, name: str) -> None:
        """Start ``notebooks/<name>.ipynb`` (once)."""
        if name in self.runs:
            return
        for m in ("nbformat", "nbclient", "ipykernel", "ipywidgets"):
            need_module(m)
        path = os.pathsep.join(p for p in (str(ROOT), os.environ.get("PYTHONPATH", "")) if p)
        env = dict(os.environ, PYTHONPATH=path, MPLBACKEND="Agg")
        cwd = self.tmp_path_factory.mktemp(f"nb_{name}")
        src = prepare_notebook(ROOT / "notebooks" / f"{name}.ipynb", cwd / f"_{name}.ipynb")
        out = open(cwd / "_runner.out", "w")  # closed by close()
        err = open(cwd / "_runner.err", "w")
        proc = subprocess.Popen(
            [sys.executable, "-c", _RUNNER, str(src), str(cwd)],
            cwd=cwd,
            env=env,
            stdout=out,
            stderr=err,
        )
        self.runs[name] = (proc, cwd, out, err)

    def wait(self, name: str, timeout: float = 900) -> tuple[float, Path]:
        """Wait for ``<name>.ipynb`` (starting it if needed); returns (seconds, working dir)."""
        self.start(name)
        proc, cwd, _, _ = self.runs[name]
        proc.wait(timeout=timeout)
        err = (cwd / "_runner.err").read_text()
        assert proc.returncode == 0, f"{name}.ipynb failed:\n{err}"
        last = (cwd / "_runner.out").read_text().strip().splitlines()[-1]
        return json.loads(last)["seconds"], cwd

    def close(self) -> None:
        for proc, _, out, err in self.runs.values():
            if proc.poll() is None:
                proc.kill()
                proc.wait()
            out.close()
            err.close()


@pytest.fixture(scope="session", autouse=True)
def notebook_runs(request, tmp_path_factory):
    """The selected notebooks, started in the background with the first test of this directory
    (under pytest-xdist, by the test that waits for them: a worker does not know its tests)."""
    runs = NotebookRuns(tmp_path_factory)
    if not os.environ.get("PYTEST_XDIST_WORKER"):
        for item in request.session.items:
            m = _NOTEBOOK_TEST.match(item.name)
            if m:
                runs.start(m.group(1))
    yield runs
    runs.close()
