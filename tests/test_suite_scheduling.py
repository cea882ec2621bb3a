"""How the suite's tests are dealt to pytest-xdist workers (tests/conftest.py): whole modules when
a run selects no e2e test, one by one (xdist's own choice) otherwise."""

import conftest
import pytest
from xdist.scheduler import LoadFileScheduling


class _Config:
    """The options the scheduler hook and xdist's schedulers read."""

    def __init__(self, markexpr, dist="load"):
        self.options = dict(markexpr=markexpr, dist=dist, tx=["popen", "popen"])

    def getoption(self, name):
        return self.options[name]

    getvalue = getoption


@pytest.mark.parametrize("markexpr", ["not slow and not e2e", "not e2e", "slow and not e2e"])
def test_a_run_without_e2e_tests_deals_whole_modules(markexpr):
    got = conftest.pytest_xdist_make_scheduler(_Config(markexpr), log=None)
    assert isinstance(got, LoadFileScheduling)


@pytest.mark.parametrize("markexpr", ["e2e and not slow", "not slow", "", "e2e or slow"])
def test_a_run_with_e2e_tests_keeps_xdists_choice(markexpr):
    assert conftest.pytest_xdist_make_scheduler(_Config(markexpr), log=None) is None


def test_an_explicit_dist_mode_is_kept():
    assert conftest.pytest_xdist_make_scheduler(_Config("not e2e", "worksteal"), log=None) is None
