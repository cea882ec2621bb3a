"""Lanes on several processes (atlas.dynamics.lane_pool): the fast engine's result is the same
bit for bit for any number of processes; bad ``workers``: one line naming it."""

import dataclasses
import math
import time

import numpy as np
import pytest

from atlas import dynamics as S
from atlas.dynamics import fast_engine as F
from atlas.dynamics.lane_pool import MIN_GAIN, LanePool, check_workers, chunks, helped, usable_cores

PI = math.pi


def _reference(x1, x2, alpha, k, q, g0):
    return S.simulate_outcome(x1, x2, alpha, k=k, q=q, g0=g0, max_events=2000)


def test_any_number_of_processes_gives_the_same_result_bit_for_bit():
    """7 x 7 map (49 lanes: the chunks differ in size) plus a degenerate direction served in
    closed form (``beta2 = pi``: one chunk with quartic segments, the others without) and a lane
    that falls back to the exact simulator (``beta1 = pi``, ``beta2 = 0``, ``kappa = 0.1``: a
    divergence within rounding); 1 process against 2 and 3."""
    alpha, kappa, q = 0.35 * PI, 0.5, 0.3
    b1, b2 = S.outcome_grid(7)
    g0 = S.perturbed_initial_states(b1, b2, alpha, kappa)[:, :, 0].reshape(-1, 4)
    B1, B2 = (x.ravel() for x in np.meshgrid(b1, b2, indexing="ij"))
    b = np.linspace(0, 2 * PI, 32, endpoint=False)
    B1, B2 = np.append(B1, [b[4], PI]), np.append(B2, [b[16], 0.0])
    near = [-6.643684176097953e16, -7286426781335026.0, -689019560184056.4, 177319680430470.12]
    g0 = np.vstack([g0, S.perturbed_initial_states(b, b, alpha, kappa)[4, 16, 0], near])
    n = B1.size
    al, k, qq = np.full(n, alpha), np.tile([kappa, 1.0], (n, 1)), np.full((n, 2), q)
    al[-1], k[-1], qq[-1] = 0.3 * PI, (0.1, 1.0), (0.05, 0.05)
    args = (B1, B2, al, k, qq, g0)
    one = F.run_batch(*args, reference=_reference)
    fb = F.DECIDED_BY.index("fallback")
    assert one.decided_by[-2] != fb and one.decided_by[-1] == fb and one.within_rounding[-1]
    with LanePool(3, min_lanes=1) as pool:
        for workers in (2, 3):
            pool.workers = workers
            res = F.run_batch(*args, reference=_reference, pool=pool)
            for field in dataclasses.fields(F.FastResult):
                a, b = getattr(one, field.name), getattr(res, field.name)
                assert a.dtype == b.dtype and np.array_equal(a, b, equal_nan=True), field.name


def _idle_double(x):
    """A chunk that takes wall time but no CPU (a process given no core)."""
    time.sleep(0.2)
    return x * 2


def test_processes_that_only_take_turns_are_given_up():
    """A batch whose processes together got less CPU than ``MIN_GAIN`` cores over its wall time
    (here none: the chunks sleep) runs the later batches in this process alone; the result is
    complete either way."""
    with LanePool(2, min_lanes=1) as pool:
        parts = pool.map(_idle_double, (np.arange(10),), {})
        assert pool.workers == 1 and pool._executor is None
        got = np.empty(10, dtype=int)
        for idx, res in parts:
            got[idx] = res
        assert np.array_equal(got, 2 * np.arange(10)) and len(parts) == 2
        assert len(pool.map(_idle_double, (np.arange(10),), {})) == 1


@pytest.mark.parametrize(("cpu", "wall", "expected"), [
    ([1.0, 1.0], 1.0, True), ([MIN_GAIN / 2] * 2, 1.0, True), ([0.5, 0.5], 1.0, False),
    ([0.9, 0.0, 0.0], 1.0, False), ([0.4, 0.4, 0.4], 0.5, True),
])  # fmt: skip
def test_processes_help_when_they_get_more_than_one_core(cpu, wall, expected):
    """CPU seconds of the chunks against the batch's wall time: more than one core's worth
    (``MIN_GAIN``) of CPU in that time, else one process would have done as well."""
    assert helped(cpu, wall) is expected


def test_small_batches_stay_in_this_process():
    pool = LanePool(2, min_lanes=10)
    calls = pool.map(lambda x: x * 2, (np.arange(19),), {})
    assert len(calls) == 1 and pool._executor is None


@pytest.mark.parametrize("bad", [0, -1, 1.5, "2", True])
def test_bad_workers_one_line(bad):
    with pytest.raises(ValueError, match="^workers: ") as e:
        check_workers(bad)
    assert "\n" not in str(e.value)


def test_default_is_the_usable_cores():
    assert check_workers(None) == usable_cores() >= 1
    assert check_workers(np.int64(2)) == 2


@pytest.mark.parametrize(
    ("n", "w", "extra"), [(49, 2, 0), (49, 3, 5), (10, 2, 100), (65536, 2, 2048)]
)
def test_chunks_cover_every_lane_once(n, w, extra):
    idx = chunks(n, w, extra)
    assert len(idx) == w
    assert np.array_equal(np.sort(np.concatenate(idx)), np.arange(n))
    assert idx[0].size == min(n - (w - 1) * math.ceil(n / (2 * w)), math.ceil(n / w) + extra)
    assert min(c.size for c in idx) > 0
    sizes = [c.size for c in idx[1:]]
    assert max(sizes) - min(sizes) <= 1
    if idx[0].size < n:  # the first chunk spread over the whole batch, not a block
        assert (
            idx[0][0] == 0 and idx[0][-1] == n - 1 and np.diff(idx[0]).max() <= 2 * n / idx[0].size
        )


@pytest.mark.parametrize(("n", "w"), [(1, 3), (4, 6), (0, 1)])
def test_chunks_refuse_fewer_lanes_than_chunks(n, w):
    with pytest.raises(ValueError, match="need n >= w"):
        chunks(n, w)


@pytest.mark.parametrize(("cores", "load", "expected"), [
    (2, 1.0, 2), (2, 0.2, 2), (2, 1.4, 2), (2, 1.6, 1), (2, 2.6, 1), (2, 7.0, 1), (8, 3.0, 6), (1, 0.0, 1),
])  # fmt: skip
def test_usable_cores_leave_out_the_load_of_other_processes(monkeypatch, cores, load, expected):
    """The cores idle for more processes of this one (this process counted in the load): on 2
    cores shared with 6 running processes one process, never fewer."""
    import os

    monkeypatch.setattr(os, "sched_getaffinity", lambda _: set(range(cores)), raising=False)
    monkeypatch.setattr(os, "getloadavg", lambda: (load, load, load))
    assert usable_cores() == expected
