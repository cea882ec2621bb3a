"""Kernels kept as exported programs: the same results as ``jax.jit``, loaded (not traced again)
by a later process, and never reused across a change of the kernels' code."""

import functools
import re
import subprocess
import sys
from pathlib import Path

import jax
import numpy as np
import pytest

from atlas.core import enclosures, hardcases, points, rootfree, signs, warm
from atlas.core.invariants import KEYS


def _suite():
    P = hardcases.suite("near_hurwitz", "float64")
    return [P[k] for k in KEYS]


def test_exported_kernel_equals_jit_and_is_loaded_not_traced(tmp_path, monkeypatch):
    args = _suite()
    want = np.asarray(enclosures.abscissa(*args))
    with warm.kernel_cache(str(tmp_path)):
        got = np.asarray(enclosures.abscissa(*args))
    files = sorted(p.name for p in tmp_path.iterdir())
    assert len(files) == 1 and files[0].startswith("atlas.core.enclosures.abscissa-")
    # a fresh Kernel (as in a new process) reads the file: exporting again would fail the test
    fresh = warm.Kernel(enclosures.abscissa.fn)
    monkeypatch.setattr(jax.export, "export", lambda *a, **k: pytest.fail("exported again"))
    with warm.kernel_cache(str(tmp_path)):
        again = np.asarray(fresh(*args))
    np.testing.assert_array_equal(got, want)
    np.testing.assert_array_equal(again, want)
    assert sorted(p.name for p in tmp_path.iterdir()) == files


def test_exported_first_pass_is_one_loop_fusion(tmp_path):
    """Soundness of the first pass (rootfree module docstring: each sign code computed once per
    point) holds for the exported program too: its compiled form has one per-point fusion."""
    x = np.ones(64)
    kern = warm.Kernel(functools.partial(rootfree.codes, damped=None))
    call = kern._load(Path(tmp_path), ("key",), (x,) * 7, {})
    text = call.lower(*(x,) * 7).compile().as_text()
    entry = text[text.index("ENTRY") :]
    fusions = re.findall(r"^\s*(?:ROOT )?%\S+ = (\S+) fusion\(", entry, re.M)
    assert len([f for f in fusions if not f.endswith("[]")]) == 1, fusions


@pytest.mark.e2e
def test_driver_under_the_kernel_cache_is_unchanged(tmp_path):
    args = _suite()
    want = points.spectral_points(*args, resolve=False)
    with warm.kernel_cache(str(tmp_path)):
        got = points.spectral_points(*args, resolve=False)
    for k in want:
        np.testing.assert_array_equal(got[k], want[k], err_msg=k)


def test_a_patched_kernel_function_gets_another_digest(monkeypatch):
    with warm.kernel_cache("unused"):
        before = warm._digest("atlas.core.rootfree")
    monkeypatch.setattr(rootfree, "det2_sign", signs.det2_sign_bounded)
    with warm.kernel_cache("unused"):
        assert warm._digest("atlas.core.rootfree") != before


DIGEST = (
    "import atlas.core.points, atlas.data.engine\n"
    "from atlas.core import warm\n"
    "with warm.kernel_cache('unused'):\n"
    "    print(warm._digest('atlas.data.engine'))\n"
)


def test_digest_is_the_same_in_every_process():
    got = {
        subprocess.run(
            [sys.executable, "-c", DIGEST], capture_output=True, text=True, check=True
        ).stdout
        for _ in range(2)
    }
    assert len(got) == 1, got
