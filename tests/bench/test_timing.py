"""``atlas.bench.timing``: repeats, memory, the machine."""

from types import SimpleNamespace

from atlas.bench import timing


def _costed_calls(monkeypatch, costs):
    """A function whose calls cost ``costs`` seconds in turn on a clock it advances itself
    (``timing``'s ``perf_counter`` is that clock): repeats and minima are counted, not timed, so
    a busy machine cannot change them.  Returns the function and its list of calls."""
    now = [0.0]
    monkeypatch.setattr(timing, "time", SimpleNamespace(perf_counter=lambda: now[0]))
    costs, calls = iter(costs), []

    def fn():
        calls.append(1)
        now[0] += next(costs)

    return fn, calls


def test_timeit_warms_up_then_takes_the_minimum(monkeypatch):
    # warm-up, then 3 repeats (dyadic costs: the clock's sums and differences are exact)
    fn, calls = _costed_calls(monkeypatch, [0.0, 0.5, 0.125, 0.25])
    best = timing.timeit(fn, budget=0.0, min_repeats=3)
    assert len(calls) == 4
    assert best == 0.125


def test_timeit_repeats_are_not_cut_by_the_compilation(monkeypatch):
    """A slow first call (compilation) does not set the number of repeats: the first repeat does."""
    fn, calls = _costed_calls(monkeypatch, [0.3] + [0.001] * 20)
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
