import importlib
import os
from pathlib import Path
from pkgutil import iter_modules

import pytest
from shared_run import shared_run

os.environ.setdefault("MPLBACKEND", "Agg")

import jax  # noqa: E402

import atlas  # noqa: E402,F401  (turns on float64 in JAX)
from atlas.core import signs  # noqa: E402
from atlas.core.config import CACHE_ENV, use_compile_cache  # noqa: E402
from atlas.core.warm import KERNEL_ENV  # noqa: E402

jax.config.update("jax_enable_x64", True)

pytest_plugins = ["cpu_report"]  # --cpu-durations=N: the tests that used the most CPU seconds

# One persistent compilation cache for the whole run, shared by both xdist workers, the CLI
# subprocesses and the notebook kernels (which inherit the variable).  Every compilation is kept
# (no minimum time): a program one worker compiled is loaded by the other when it comes to it;
# a cold unit step (CI's) took 442 s CPU against 500 s with the 0.2 s minimum.
# Under .pytest_cache (git-ignored); ATLAS_JAX_CACHE=0 switches it off.
os.environ.setdefault(CACHE_ENV, str(Path(__file__).resolve().parents[1] / ".pytest_cache" / "jax"))
use_compile_cache(min_compile_seconds=0.0)

# In-process `cli.main` calls compile the plain jitted kernels the library tests compile (one
# compilation per kernel and shape in a worker), not their exported programs (a second trace,
# export and compilation of each): the exported path has its own tests (tests/core/test_warm.py,
# tests/test_cli.py, which switches it back on, and the subprocess runs).
os.environ.setdefault(KERNEL_ENV, "0")


def pytest_collection_modifyitems(items):
    """The tests that clear every jit cache (:func:`bounded_det_b`) run last, so that the kernels
    the other tests compiled stay compiled for the rest of the run (a cleared kernel is traced,
    lowered and loaded again by the next test that calls it)."""
    items.sort(key=lambda item: "bounded_det_b" in getattr(item, "fixturenames", ()))


@pytest.fixture(scope="session")
def paper_run(tmp_path_factory):
    """One ``atlas paper`` run at the CI size per test session (``atlas.paper.run(ci=True)``): its
    directory, step timings and audit claims, shared by the run, audit and outputs-tree tests
    (and by the xdist workers: :func:`shared_run`)."""
    from types import SimpleNamespace

    def compute(out):
        from atlas import paper
        from atlas.paper import audit

        seen = {}
        run_audit = audit.run_audit

        def keep_claims(*args, **kwargs):
            seen["claims"] = run_audit(*args, **kwargs)
            return seen["claims"]

        with pytest.MonkeyPatch.context() as mp:
            mp.setattr(audit, "run_audit", keep_claims)
            timings = paper.run(out=out, ci=True, progress=lambda m: None, jobs=1)
        return {"timings": timings, "claims": seen["claims"]}

    out, got = shared_run(tmp_path_factory, "paper_run", compute)
    return SimpleNamespace(out=out, **got)


def det2_sign_users() -> list:
    """Every module of :mod:`atlas.core` that calls :func:`atlas.core.signs.det2_sign` by its own
    name (found, not listed: a new user is patched too)."""
    import atlas.core

    mods = [
        importlib.import_module(f"atlas.core.{m.name}") for m in iter_modules(atlas.core.__path__)
    ]
    return [m for m in mods if m is not signs and getattr(m, "det2_sign", None) is signs.det2_sign]


#: whether this process's jit caches hold kernels traced with the float-bounded ``sign det B``
_BOUNDED_TRACES = {"held": False}


@pytest.fixture
def bounded_det_b():
    """The fast kernels with ``sign det B`` certified by its float error bound only (as before the
    exact integer sign): cells on ``beta2 = beta1 + pi`` of an even grid (``det B`` of the rounded
    directions ~ 1e-17) are then undecided, which exercises the settlement paths.  Every jit cache
    is cleared before the first such test (the kernels retrace with it) and before the first test
    after them that does not use it (:func:`pytest_runtest_setup`); the tests using it run one
    after another (:func:`pytest_collection_modifyitems`) and share their traces."""
    with pytest.MonkeyPatch.context() as mp:
        for mod in det2_sign_users():
            mp.setattr(mod, "det2_sign", signs.det2_sign_bounded)
        if not _BOUNDED_TRACES["held"]:
            jax.clear_caches()
            _BOUNDED_TRACES["held"] = True
        yield


@pytest.hookimpl(tryfirst=True)
def pytest_runtest_setup(item):
    """A test without :func:`bounded_det_b` after one with it starts from cleared jit caches (the
    kernels retrace with the exact ``sign det B``)."""
    if _BOUNDED_TRACES["held"] and "bounded_det_b" not in getattr(item, "fixturenames", ()):
        jax.clear_caches()
        _BOUNDED_TRACES["held"] = False
