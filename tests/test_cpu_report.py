"""``--cpu-durations`` (tests/cpu_report.py): a test's CPU seconds include the processes it waited
for, and reach the listing from pytest-xdist workers; ``--jax-report`` counts the programs each
test compiles."""

import json
import os
import re
import subprocess
import sys
import textwrap
from pathlib import Path

#: a test whose child process burns at least 0.5 CPU seconds, and one that does nothing
_TESTS = """
import subprocess, sys

BURN = "import time\\nt = time.process_time()\\nwhile time.process_time() - t < 0.5:\\n    pass"

def test_busy_child():
    subprocess.run([sys.executable, "-c", BURN], check=True)

def test_idle():
    pass
"""


def _pytest(tmp_path, name: str, source: str, *options: str) -> str:
    """The output of pytest (plugins ``cpu_report`` and ``options`` only) on ``source``, written
    to ``tmp_path / name``; the run must pass."""
    (tmp_path / name).write_text(textwrap.dedent(source))
    here = str(Path(__file__).resolve().parent)
    path = os.pathsep.join([here, os.environ.get("PYTHONPATH", "")])
    env = dict(os.environ, PYTHONPATH=path, PYTEST_DISABLE_PLUGIN_AUTOLOAD="1")
    cmd = [sys.executable, "-m", "pytest", "-q", "-p", "cpu_report", "-p", "no:cacheprovider"]
    p = subprocess.run(
        [*cmd, *options, name], cwd=tmp_path, env=env, capture_output=True, text=True, timeout=300
    )
    assert p.returncode == 0, p.stdout[-3000:] + p.stderr[-3000:]
    return p.stdout


def test_cpu_durations_count_the_waited_children_under_xdist(tmp_path):
    out = _pytest(
        tmp_path, "test_x.py", _TESTS, "-p", "xdist.plugin", "-n", "2", "--cpu-durations=5"
    )
    rows = dict(
        (name, float(s)) for s, name in re.findall(r"^\s*([\d.]+)s\s+test_x\.py::(\w+)$", out, re.M)
    )
    assert set(rows) == {"test_busy_child", "test_idle"}, out
    assert rows["test_busy_child"] >= 0.5 > rows["test_idle"], rows
    assert "most CPU seconds (user + sys), 5 tests" in out


#: a test that compiles one new program, and one that compiles none
_JAX_TESTS = """
import jax
import jax.numpy as jnp
import numpy as np

def test_compiles():
    jax.jit(lambda x: jnp.sin(x) * 3.0)(np.arange(7.0)).block_until_ready()

def test_idle():
    pass
"""


def test_jax_report_counts_the_programs_each_test_compiles(tmp_path):
    report = tmp_path / "cpu.json"
    options = ("--cpu-durations=5", "--jax-report", f"--cpu-json={report}")
    out = _pytest(tmp_path, "test_j.py", _JAX_TESTS, *options)
    rows = re.findall(r"^\s*[\d.]+s\s+test_j\.py::(\w+)\s+\(.*programs (\d+),", out, re.M)
    assert rows == [("test_compiles", "1")], out
    assert re.search(r"^\s*[\d.]+s\s+test_j\.py\s+\(.*programs 1,", out, re.M), out
    tests = json.loads(report.read_text())
    assert set(tests) == {"test_j.py::test_compiles", "test_j.py::test_idle"}
    assert tests["test_j.py::test_compiles"]["programs"] == 1
    assert "programs" not in tests["test_j.py::test_idle"]
