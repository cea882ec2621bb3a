"""``atlas.bench.timing``: repeats, memory, the machine."""

import time

from atlas.bench import timing


def test_timeit_warms_up_then_takes_the_minimum():
    calls = []
    costs = iter([0.0, 0.02, 0.001, 0.01])  # warm-up, then 3 repeats

    def fn():
        calls.append(1)
        time.sleep(next(costs))

    best = timing.timeit(fn, budget=0.0, min_repeats=3)
    assert len(calls) == 4
    assert 0.001 <= best < 0.01


def test_timeit_repeats_are_not_cut_by_the_compilation():
    """A slow first call (compilation) does not set the number of repeats: the first repeat does."""
    calls = []
    costs = iter([0.3] + [0.001] * 20)

    def fn():
        calls.append(1)
        time.sleep(next(costs))

    timing.timeit(fn, budget=0.1, max_repeats=10, min_repeats=2)
    assert len(calls) == 1 + 10


def test_timeit_repeats_within_budget():
    calls = []
    t = timing.timeit(lambda: calls.append(1), budget=1e9, max_repeats=5)
    assert len(calls) == 1 + 5 and t >= 0


def test_peak_rss_is_at_least_rss():
    assert timing.vm("VmHWM") >= timing.vm("VmRSS") > 0


def test_machine():
    m = timing.machine()
    assert m["nproc"] >= 1 and len(m["load"].split()) == 3
    assert set(m) == {
        "nproc", "cpu", "ram", "load", "python", "jax", "numpy", "platform", "jax_backend"
    }  # fmt: skip
