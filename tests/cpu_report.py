"""``--cpu-durations=N``: the N tests that used the most CPU seconds (user + sys), a test's setup,
call and teardown together, with the processes it started and waited for (subprocesses, notebook
kernels, the browser's server), as ``--durations`` lists wall seconds.  Measured in the process
that runs the test (each xdist worker) and listed by the one that reports; a process a test
starts but another test waits for counts for the one that waits."""

from __future__ import annotations

import resource

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
        report.user_properties = [*report.user_properties, ("cpu_s", now - before)]
    item.stash[_START] = _cpu()


@pytest.hookimpl(tryfirst=True)
def pytest_runtest_setup(item):
    item.stash[_START] = _cpu()


class _Totals:
    def __init__(self):
        self.by_test: dict[str, float] = {}

    @pytest.hookimpl
    def pytest_runtest_logreport(self, report):
        for key, value in report.user_properties:
            if key == "cpu_s":
                self.by_test[report.nodeid] = self.by_test.get(report.nodeid, 0.0) + value

    def pytest_terminal_summary(self, terminalreporter, config):
        n = config.getoption("cpu_durations")
        top = sorted(self.by_test.items(), key=lambda kv: -kv[1])[:n]
        terminalreporter.write_sep("=", f"most CPU seconds (user + sys), {n} tests")
        for nodeid, seconds in top:
            terminalreporter.write_line(f"{seconds:8.2f}s  {nodeid}")
        terminalreporter.write_line(
            f"{sum(self.by_test.values()):8.2f}s  in all {len(self.by_test)} tests"
        )


def pytest_configure(config):
    if config.getoption("cpu_durations"):
        config.pluginmanager.register(_Totals(), "cpu_report_totals")
