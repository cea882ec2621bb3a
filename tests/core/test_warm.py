"""Kernels kept as exported programs: the same results as ``jax.jit``, loaded (not traced again)
by a later process, and never reused across a change of the kernels' code."""

import functools
import os
import re
import subprocess
import sys
import threading
from pathlib import Path

import jax
import numpy as np
import pytest

from atlas.core import enclosures, hardcases, model_box, points, rootfree, signs, warm
from atlas.core.invariants import KEYS, PAD


def _suite():
    """A hard-case suite padded to the driver's length of the spectral abscissa
    (:data:`points.FLAT_BATCH`): the jitted program is the one every atlas runs."""
    P = hardcases.suite("near_hurwitz", "float64")
    n = P["c1"].size
    return [np.concatenate([P[k], np.full(points.FLAT_BATCH - n, p)]) for k, p in zip(KEYS, PAD)]


def test_exported_kernel_equals_jit_and_is_loaded_not_traced(tmp_path, monkeypatch):
    monkeypatch.setenv(warm.EXECUTABLE_ENV, "0")  # the exported programs alone
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


def _scaled(x, k):
    return x * k


def test_numpy_scalar_arguments_keep_the_program_like_zero_d_arrays(tmp_path, monkeypatch):
    """A kernel given NumPy scalars (a map's model parameters, ``np.float64(0.5)``) keeps its
    program as with 0-d arrays (before, it traced in every process): one file, loaded by a
    fresh Kernel without exporting again; the results and dtypes are ``jax.jit``'s."""
    monkeypatch.setenv(warm.EXECUTABLE_ENV, "0")  # the exported programs alone
    kernel = warm.Kernel(_scaled)
    cases = [(np.arange(4.0), np.float64(0.5)), (np.arange(4, dtype=np.float32), np.float32(3))]
    want = [np.asarray(jax.jit(_scaled)(*a)) for a in cases]
    with warm.kernel_cache(str(tmp_path)):
        got = [np.asarray(kernel(*a)) for a in cases]
    files = sorted(p.name for p in tmp_path.iterdir())
    assert len(files) == 2 and all(".jaxexport" in f for f in files)
    fresh = warm.Kernel(_scaled)
    monkeypatch.setattr(jax.export, "export", lambda *a, **k: pytest.fail("exported again"))
    with warm.kernel_cache(str(tmp_path)):
        again = [np.asarray(fresh(*a)) for a in cases]
    for w, g, a in zip(want, got, again):
        assert g.dtype == w.dtype == a.dtype
        np.testing.assert_array_equal(g, w)
        np.testing.assert_array_equal(a, w)
    assert sorted(p.name for p in tmp_path.iterdir()) == files


def test_threads_asking_at_once_load_a_kernel_once(tmp_path, monkeypatch):
    """A first use and a background warm-up asking for the same program at the same time: one
    of them exports and compiles it, the other waits and shares it (both compiled it before,
    which doubled the first overlay's compilation)."""
    kernel = warm.Kernel(lambda x: x * 2.0)
    started, loads = threading.Event(), []
    real = warm.Kernel._load

    def slow_load(self, *a):
        loads.append(threading.current_thread().name)
        started.set()
        threading.Event().wait(0.2)  # the other thread asks meanwhile
        return real(self, *a)

    monkeypatch.setattr(warm.Kernel, "_load", slow_load)
    x = np.arange(4.0)
    out = {}
    with warm.kernel_cache(str(tmp_path)), _compiled_here():
        other = threading.Thread(target=lambda: out.setdefault("other", kernel(x)), name="other")
        other.start()
        started.wait()
        out["main"] = kernel(x)
        other.join()
    assert loads == ["other"]
    np.testing.assert_array_equal(np.asarray(out["main"]), 2 * x)
    np.testing.assert_array_equal(np.asarray(out["other"]), 2 * x)


def test_exported_first_pass_is_one_loop_fusion(tmp_path):
    """Soundness of the first pass (rootfree module docstring: each sign code computed once per
    point) holds for the exported program too: its compiled form has one per-point fusion."""
    x = np.ones(64)
    kern = warm.Kernel(functools.partial(rootfree.codes, damped=None))
    exp = kern._export(
        Path(tmp_path) / "codes.jaxexport", [jax.ShapeDtypeStruct(x.shape, x.dtype)] * 7, {}
    )
    text = jax.jit(exp.call).lower(*(x,) * 7).compile().as_text()
    entry = text[text.index("ENTRY") :]
    fusions = re.findall(r"^\s*(?:ROOT )?%\S+ = (\S+) fusion\(", entry, re.M)
    assert len([f for f in fusions if not f.endswith("[]")]) == 1, fusions


@pytest.mark.e2e
def test_driver_under_the_kernel_cache_is_unchanged(tmp_path, monkeypatch):
    monkeypatch.setenv(warm.EXECUTABLE_ENV, "0")  # the programs (executables: a fresh compile each)
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


def _with_a_helper(c1, s1, c2, s2):
    """A kernel of this module whose helper lives in :mod:`atlas.core.model_box` (outside the
    twelve modules every digest once covered by a hand-kept list)."""
    return model_box.det_signs(c1 * s2 - s1 * c2)


def test_a_kernel_whose_helper_changes_gets_another_digest(monkeypatch):
    kern = warm.Kernel(_with_a_helper)
    with warm.kernel_cache("unused"):
        before = warm._digest(kern.module)
    monkeypatch.setattr(model_box, "det_signs", lambda geo: geo)
    with warm.kernel_cache("unused"):
        assert warm._digest(kern.module) != before


#: the kernels' digests as each entry point sees them, in one fresh process: after importing the
#: warm-cache module alone, then the command line, then the explorer
DIGEST = (
    "import importlib\n"
    "from atlas.core import warm\n"
    "for entry in ('atlas.core.warm', 'atlas.cli', 'atlas.explore.state'):\n"
    "    importlib.import_module(entry)\n"
    "    with warm.kernel_cache('unused'):\n"
    "        print(*(warm._digest(f'atlas.core.{m}') for m in ('kernels', 'rootfree', 'points')))\n"
)


def test_digest_is_the_same_whatever_the_entry_point_imported():
    """A fresh process importing the warm-cache module alone, then the command line (which
    imports lazily: every command's modules), then the explorer (everything): the kernels' digests
    agree at each step (else every entry point exports and compiles its own copy of each
    program).  One process serves the three: each digest is computed again in its own
    :func:`warm.kernel_cache` block, after more modules were imported."""
    env = {**os.environ, "JAX_ENABLE_X64": "1"}
    out = subprocess.run(
        [sys.executable, "-c", DIGEST],
        capture_output=True, text=True, env=env, timeout=300, check=True,
    ).stdout.strip().splitlines()[-3:]  # fmt: skip
    assert len(out) == 3 and len(set(out)) == 1, out


def _dominance_args(n=256, seed=0):
    """Inputs of ``rootfree._tier2_dominance`` (a small certified program: quick to compile), of
    the types and length the driver gives it (:data:`points.LATER_BATCH`): its jitted program is
    the driver's."""
    rng = np.random.default_rng(seed)
    geometry = [rng.uniform(-1, 1, n) for _ in range(4)]
    model = [rng.uniform(0.1, 10, n), rng.uniform(0, 1, n), rng.uniform(0, 1, n)]
    verdicts = [rng.choice(np.array([0, 1, 3], np.int8), n) for _ in range(2)]
    dominance = rng.integers(0, 2, n).astype(bool)
    shifts = [rng.integers(-1, 2, n).astype(np.int32), rng.uniform(-2, 0, n), rng.uniform(-1, 0, n)]
    return geometry + model + verdicts + [dominance] + shifts


STORED = """
import os, sys, jax, numpy as np
from atlas.core import config, rootfree, warm
from tests.core.test_warm import _dominance_args
config.use_compile_cache(sys.argv[1] + "/xla", min_compile_seconds=0)
if sys.argv[2] == "load":  # the stored executable serves: no program is read or exported
    jax.export.deserialize = jax.export.export = None
with warm.kernel_cache(sys.argv[1] + "/kernels"):
    out = rootfree._tier2_dominance(*_dominance_args())
print(warm._result_digest(out))
"""


def _in_fresh_process(where, mode, **env):
    root = Path(__file__).resolve().parents[2]
    p = subprocess.run(
        [sys.executable, "-c", STORED, str(where), mode],
        capture_output=True,
        text=True,
        cwd=root,
        timeout=300,
        env={**os.environ, **env},
    )
    assert p.returncode == 0, p.stderr[-2000:]
    return p.stdout.strip()


@pytest.mark.e2e
def test_stored_executable_gives_the_jit_results_in_a_fresh_process(tmp_path):
    """A first process leaves the program in the compilation cache (whose executables serialize
    incompletely: module docstring), a second stores the executable, a third runs it alone;
    each gives the bits of plain ``jax.jit`` (this process)."""
    want = warm._result_digest(rootfree._tier2_dominance.jitted(*_dominance_args()))
    assert _in_fresh_process(tmp_path, "fill", **{warm.EXECUTABLE_ENV: "0"}) == want
    assert not list(tmp_path.glob("kernels/*.xlaexec"))
    assert _in_fresh_process(tmp_path, "store") == want
    assert len(list(tmp_path.glob("kernels/*.xlaexec"))) == 1
    assert _in_fresh_process(tmp_path, "load") == want


@pytest.fixture(scope="module")
def stored_dominance(tmp_path_factory):
    """A kernel directory holding ``_tier2_dominance``'s program and executable."""
    where = tmp_path_factory.mktemp("stored")
    with warm.kernel_cache(str(where)), _compiled_here():
        warm.Kernel(rootfree._tier2_dominance.fn)(*_dominance_args())
    return where


def _compiled_here():
    """The persistent compilation cache off: an executable stored in the block was compiled in
    this process, so it serializes completely at once (one the cache served would be compiled
    afresh, which clears every jit cache of the test process: warm module docstring)."""
    return warm._no_compilation_cache()


def test_a_damaged_executable_is_never_used(stored_dominance, tmp_path):
    """A stored executable that does not load, whose canary result differs from the one
    recorded, or that is another program's, is refused; the exported program then gives the
    right result (and a good executable is stored again)."""
    import pickle
    import shutil

    from jax.experimental import serialize_executable

    for f in stored_dominance.iterdir():
        shutil.copy(f, tmp_path)
    args = _dominance_args()
    want = warm._result_digest(rootfree._tier2_dominance.jitted(*args))
    (xpath,) = tmp_path.glob("*.xlaexec")
    assert warm._load_executable(xpath) is not None
    good = pickle.loads(xpath.read_bytes())
    other = jax.jit(lambda *a: rootfree._tier2_dominance.fn(*a)[::-1])  # same argument shapes
    damaged = {
        "garbage": b"not an executable",
        "digest": pickle.dumps({**good, "digest": "0" * 64}),
        "blob": pickle.dumps(
            {**good, "executable": serialize_executable.serialize(other.lower(*args).compile())}
        ),
    }
    for damage, data in damaged.items():
        xpath.write_bytes(data)
        assert warm._load_executable(xpath) is None, damage
    with warm.kernel_cache(str(tmp_path)), _compiled_here():
        got = warm.Kernel(rootfree._tier2_dominance.fn)(*args)
    assert warm._result_digest(got) == want
    assert warm._load_executable(xpath) is not None  # stored again, valid


def test_an_executable_that_fails_on_its_first_call_falls_back():
    """A loaded executable that raises when its results are read hands the call (and every
    later one) to the exported program."""

    def broken(*args):
        raise RuntimeError("NOT_FOUND: Function maximum_log_fusion not found")

    args = _dominance_args()
    guarded = warm._Guarded(broken, lambda: rootfree._tier2_dominance.jitted)
    want = warm._result_digest(rootfree._tier2_dominance.jitted(*args))
    assert warm._result_digest(guarded(*args)) == want
    assert guarded.compiled is None
    assert warm._result_digest(guarded(*args)) == want


def test_the_executables_of_the_last_run_load_in_the_background(
    stored_dominance, tmp_path, monkeypatch
):
    """A run named like an earlier one loads the executables that run used in background threads
    from its start, and uses them (same results)."""
    import shutil

    for f in stored_dominance.iterdir():
        shutil.copy(f, tmp_path)
    args = _dominance_args()
    want = warm._result_digest(rootfree._tier2_dominance.jitted(*args))
    with warm.kernel_cache(str(tmp_path), run="a run"):
        warm.Kernel(rootfree._tier2_dominance.fn)(*args)
    (manifest,) = tmp_path.glob("run-*.txt")
    assert manifest.read_text() == next(tmp_path.glob("*.xlaexec")).name
    threads = []
    load = warm._load_executable
    monkeypatch.setattr(
        warm,
        "_load_executable",
        lambda p: threads.append(threading.current_thread().name) or load(p),
    )
    with warm.kernel_cache(str(tmp_path), run="a run"):
        got = warm.Kernel(rootfree._tier2_dominance.fn)(*args)
    assert warm._result_digest(got) == want
    assert len(threads) == 1 and threads[0].startswith("warm"), threads


def test_other_compiler_flags_get_other_executables(stored_dominance, tmp_path, monkeypatch):
    """An executable compiled under other ``$XLA_FLAGS`` is never served: its file differs."""
    import shutil

    for f in stored_dominance.iterdir():
        shutil.copy(f, tmp_path)
    monkeypatch.setenv("XLA_FLAGS", "--xla_cpu_enable_fast_math=true")
    with warm.kernel_cache(str(tmp_path)), _compiled_here():
        warm.Kernel(rootfree._tier2_dominance.fn)(*_dominance_args())
    assert len(list(tmp_path.glob("*.xlaexec"))) == 2


def test_an_executable_given_other_arguments_falls_back():
    """Arguments an executable was not compiled for (here the driver's bulk length for its
    batch length) go to the exported program, which gives its results for them."""
    args = _dominance_args()
    compiled = jax.jit(rootfree._tier2_dominance.fn).lower(*args).compile()
    guarded = warm._Guarded(compiled, lambda: rootfree._tier2_dominance.jitted)
    guarded(*args)
    other = _dominance_args(points.LATER_BULK)
    want = warm._result_digest(rootfree._tier2_dominance.jitted(*other))
    assert warm._result_digest(guarded(*other)) == want
    assert guarded.compiled is None


def test_save_used_writes_the_run_list_before_the_block_ends(stored_dominance, tmp_path):
    """A long-lived session (:func:`warm.keep_kernels`) lists the executables it used when it
    calls :func:`warm.save_used`, not only when its block ends (at exit)."""
    import shutil

    for f in stored_dominance.iterdir():
        shutil.copy(f, tmp_path)
    with warm.kernel_cache(str(tmp_path), run="a session"):
        warm.Kernel(rootfree._tier2_dominance.fn)(*_dominance_args())
        assert not list(tmp_path.glob("run-*.txt"))
        warm.save_used()
        (manifest,) = tmp_path.glob("run-*.txt")
        assert manifest.read_text() == next(tmp_path.glob("*.xlaexec")).name


#: the programs a cold 16 x 16 x 2 ``atlas generate`` compiles (every output, damped): the first
#: pass per point (``rootfree.codes``), the spectral abscissa and the axis and geometry kernels
#: (``_b1``, ``_b2``, ``_b1b2``); the few points the first pass leaves open go to the exact tier
#: directly (``points.HOST_POINTS``), no tier-2 or enclosure program
COLD_GENERATE_PROGRAMS = 5
COLD = """
import json, sys, jax
compiles = []
jax.monitoring.register_event_duration_secs_listener(
    lambda event, seconds, **kw: compiles.append(event.endswith("backend_compile_duration")))
from atlas import cli
print(json.dumps({"rc": cli.main(sys.argv[1:]), "compiles": sum(compiles)}))
"""


@pytest.mark.e2e
def test_a_cold_small_generate_compiles_no_more_programs(tmp_path):
    """A 16 x 16 x 2 ``atlas generate`` in an empty cache compiles each kernel program it keeps
    once (no other XLA compilation: no eager operation, no second compilation of a kept
    kernel) and at most :data:`COLD_GENERATE_PROGRAMS` of them: a new program (another shape
    bucket, a kernel split in two) fails here.  Counted, not timed."""
    import json

    cache = tmp_path / "cache"
    args = ["generate", "--beta1", "0:2pi:16", "--beta2", "0:2pi:16", "--kappa", "0.5,2"]
    args += ["--q", "0.1", "--no-progress", "--out", str(tmp_path / "a.nc")]
    env = {**os.environ, "ATLAS_JAX_CACHE": str(cache)}
    env.pop(warm.KERNEL_ENV, None)  # as a user runs it (conftest.py turns it off in-process)
    p = subprocess.run(
        [sys.executable, "-c", COLD, *args], capture_output=True, text=True, env=env, timeout=900
    )
    assert p.returncode == 0, p.stderr[-2000:]
    got = json.loads(p.stdout.strip().splitlines()[-1])
    programs = sorted(f.name.rsplit("-", 1)[0] for f in (cache / "kernels").glob("*.jaxexport"))
    assert got["rc"] == 0 and programs, (got, p.stderr[-2000:])
    assert got["compiles"] == len(programs), (got, programs)
    assert len(programs) <= COLD_GENERATE_PROGRAMS, programs
