"""``--cpu-durations=N``: the N tests that used the most CPU seconds (user + sys), a test's setup,
call and teardown together, with the processes it started and waited for (subprocesses, notebook
kernels, the browser's server), as ``--durations`` lists wall seconds.  Measured in the process
that runs the test (each xdist worker) and listed by the one that reports; a process a test
starts but another test waits for counts for the one that waits.  The listing ends with the CPU
seconds of each test module.

``--jax-report``: with ``--cpu-durations``, the seconds (wall, in the test's process) JAX spent
tracing, lowering and compiling in each test and module, the number of programs compiled by XLA
and the persistent compilation cache's hits and misses (``jax.monitoring`` events).
``--cpu-json=PATH``: every test's figures, as JSON (to compare two runs test by test)."""

from __future__ import annotations

import json
import resource
from collections import Counter
from pathlib import Path, PurePosixPath

import pytest

_START = pytest.StashKey[float]()


def pytest_addoption(parser):
    parser.addoption(
        "--cpu-durations",
        type=int,
        default=None,
        metavar="N",
        help="list the N tests that used the most CPU seconds (user + sys, with waited children)",
    )
    parser.addoption(
        "--cpu-json",
        default=None,
        metavar="PATH",
        help="with --cpu-durations: write every test's CPU seconds (and JAX counts) to PATH as JSON",
    )
    parser.addoption(
        "--jax-report",
        action="store_true",
        help="with --cpu-durations: JAX trace, lowering and compile seconds and programs compiled",
    )


#: jax.monitoring duration events (seconds) and plain events (counts), by their short names
JAX_DURATIONS = {
    "/jax/core/compile/jaxpr_trace_duration": "trace_s",
    "/jax/core/compile/jaxpr_to_mlir_module_duration": "lower_s",
    "/jax/core/compile/backend_compile_duration": "compile_s",
    "/jax/compilation_cache/cache_retrieval_time_sec": "cache_load_s",
}
JAX_EVENTS = {
    "/jax/compilation_cache/cache_hits": "cache_hits",
    "/jax/compilation_cache/cache_misses": "cache_misses",
}
_JAX = Counter()  # this process's running totals


def _on_duration(event, seconds, **kwargs):
    name = JAX_DURATIONS.get(event)
    if name:
        _JAX[name] += seconds
        if name == "compile_s":
            _JAX["programs"] += 1


def _on_event(event, **kwargs):
    name = JAX_EVENTS.get(event)
    if name:
        _JAX[name] += 1


def _cpu() -> float:
    own, kids = (
        resource.getrusage(resource.RUSAGE_SELF),
        resource.getrusage(resource.RUSAGE_CHILDREN),
    )
    return own.ru_utime + own.ru_stime + kids.ru_utime + kids.ru_stime


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item, call):
    """Each phase's report carries the CPU seconds spent since the previous phase ended."""
    now = _cpu()
    before = item.stash.get(_START, None)
    outcome = yield
    if before is not None:
        report = outcome.get_result()  # a new list: the item's own is shared by its reports
        jax = Counter(_JAX)
        jax.subtract(item.stash.get(_JAX_START, Counter()))
        props = [("cpu_s", now - before)] + ([("jax", dict(+jax))] if +jax else [])
        report.user_properties = [*report.user_properties, *props]
    item.stash[_START] = _cpu()
    item.stash[_JAX_START] = Counter(_JAX)


@pytest.hookimpl(tryfirst=True)
def pytest_runtest_setup(item):
    item.stash[_START] = _cpu()
    item.stash[_JAX_START] = Counter(_JAX)


_JAX_START = pytest.StashKey[Counter]()


def _module(nodeid: str) -> str:
    return str(PurePosixPath(nodeid.split("::")[0]))


class _Totals:
    def __init__(self):
        self.by_test: dict[str, float] = {}
        self.jax_by_test: dict[str, Counter] = {}

    @pytest.hookimpl
    def pytest_runtest_logreport(self, report):
        for key, value in report.user_properties:
            if key == "cpu_s":
                self.by_test[report.nodeid] = self.by_test.get(report.nodeid, 0.0) + value
            elif key == "jax":
                self.jax_by_test.setdefault(report.nodeid, Counter()).update(value)

    def _write_modules(self, tr, n):
        cpu, jax = Counter(), {}
        for nodeid, seconds in self.by_test.items():
            cpu[_module(nodeid)] += seconds
            jax.setdefault(_module(nodeid), Counter()).update(self.jax_by_test.get(nodeid, {}))
        tr.write_sep("=", f"most CPU seconds (user + sys), {n} test modules")
        for mod, seconds in cpu.most_common(n):
            tr.write_line(f"{seconds:8.2f}s  {mod}{_jax_line(jax[mod])}")

    def _write_jax(self, tr, n):
        total = Counter()
        for counts in self.jax_by_test.values():
            total.update(counts)
        tr.write_sep("=", f"most JAX trace + lower + compile seconds, {n} tests")
        ranked = sorted(self.jax_by_test.items(), key=lambda kv: -_jax_seconds(kv[1]))
        for nodeid, counts in ranked[:n]:
            tr.write_line(f"{_jax_seconds(counts):8.2f}s  {nodeid}{_jax_line(counts)}")
        tr.write_line(f"{_jax_seconds(total):8.2f}s  in all tests{_jax_line(total)}")

    def pytest_terminal_summary(self, terminalreporter, config):
        n = config.getoption("cpu_durations")
        top = sorted(self.by_test.items(), key=lambda kv: -kv[1])[:n]
        terminalreporter.write_sep("=", f"most CPU seconds (user + sys), {n} tests")
        for nodeid, seconds in top:
            terminalreporter.write_line(f"{seconds:8.2f}s  {nodeid}")
        terminalreporter.write_line(
            f"{sum(self.by_test.values()):8.2f}s  in all {len(self.by_test)} tests"
        )
        self._write_modules(terminalreporter, n)
        if self.jax_by_test:
            self._write_jax(terminalreporter, n)
        if config.getoption("cpu_json"):
            tests = {
                k: {"cpu_s": v, **self.jax_by_test.get(k, {})} for k, v in self.by_test.items()
            }
            Path(config.getoption("cpu_json")).write_text(
                json.dumps(tests, indent=1, sort_keys=True)
            )


def _jax_seconds(counts) -> float:
    return counts.get("trace_s", 0.0) + counts.get("lower_s", 0.0) + counts.get("compile_s", 0.0)


def _jax_line(counts) -> str:
    if not counts:
        return ""
    parts = [f"{k} {counts.get(k, 0):.1f}" for k in ("trace_s", "lower_s", "compile_s")]
    parts += [f"{k} {counts.get(k, 0)}" for k in ("programs", "cache_hits", "cache_misses")]
    return "  (" + ", ".join(parts) + ")"


def pytest_configure(config):
    if config.getoption("cpu_durations"):
        config.pluginmanager.register(_Totals(), "cpu_report_totals")
    if config.getoption("jax_report"):
        import jax.monitoring

        jax.monitoring.register_event_duration_secs_listener(_on_duration)
        jax.monitoring.register_event_listener(_on_event)
