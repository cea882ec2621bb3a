"""``--cpu-durations`` (tests/cpu_report.py): a test's CPU seconds include the processes it waited
for, and reach the listing from pytest-xdist workers."""

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


def test_cpu_durations_count_the_waited_children_under_xdist(tmp_path):
    (tmp_path / "test_x.py").write_text(textwrap.dedent(_TESTS))
    here = str(Path(__file__).resolve().parent)
    path = os.pathsep.join([here, os.environ.get("PYTHONPATH", "")])
    env = dict(os.environ, PYTHONPATH=path, PYTEST_DISABLE_PLUGIN_AUTOLOAD="1")
    cmd = [sys.executable, "-m", "pytest", "-q", "-p", "xdist.plugin", "-n", "2"]
    cmd += ["-p", "cpu_report", "-p", "no:cacheprovider", "--cpu-durations=5", "test_x.py"]
    p = subprocess.run(cmd, cwd=tmp_path, env=env, capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stdout[-3000:] + p.stderr[-3000:]
    rows = dict(
        (name, float(s))
        for s, name in re.findall(r"^\s*([\d.]+)s\s+test_x\.py::(\w+)$", p.stdout, re.M)
    )
    assert set(rows) == {"test_busy_child", "test_idle"}, p.stdout
    assert rows["test_busy_child"] >= 0.5 > rows["test_idle"], rows
    assert "most CPU seconds (user + sys), 5 tests" in p.stdout


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
    (tmp_path / "test_j.py").write_text(textwrap.dedent(_JAX_TESTS))
    here = str(Path(__file__).resolve().parent)
    path = os.pathsep.join([here, os.environ.get("PYTHONPATH", "")])
    env = dict(os.environ, PYTHONPATH=path, PYTEST_DISABLE_PLUGIN_AUTOLOAD="1")
    cmd = [sys.executable, "-m", "pytest", "-q", "-p", "cpu_report", "-p", "no:cacheprovider"]
    cmd += ["--cpu-durations=5", "--jax-report", "test_j.py"]
    p = subprocess.run(cmd, cwd=tmp_path, env=env, capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stdout[-3000:] + p.stderr[-3000:]
    rows = re.findall(r"^\s*[\d.]+s\s+test_j\.py::(\w+)\s+\(.*programs (\d+),", p.stdout, re.M)
    assert rows == [("test_compiles", "1")], p.stdout
    assert re.search(r"^\s*[\d.]+s\s+test_j\.py\s+\(.*programs 1,", p.stdout, re.M), p.stdout
