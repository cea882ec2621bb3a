"""Lanes of a batch on several processes: the trajectories of :mod:`atlas.dynamics.fast_engine`
split into one interleaved chunk per process (:func:`chunks`: lanes spread evenly over the
batch), the calling process one of them.

A lane's result depends on its own parameters only (every operation of the engine is lane by
lane), so any split gives the same arrays, bit for bit.  One chunk per process keeps the batches
large: the engine's cost per step is mostly fixed (NumPy calls), so smaller batches cost more per
trajectory.  The other processes are started with ``spawn`` once per :class:`LanePool` and reused
by every batch; they import NumPy and the engine only (no JAX, no xarray), so starting one takes
about half a second on a quiet machine, which counts in the wall time of the batch that
starts them: that batch gives the calling process ``START_LANES`` more lanes than an even split
(half of them at two processes), so that the processes finish together.

The number of processes is chosen by what helps: at most the usable cores (:func:`usable_cores`:
the affinity less the load), and after every batch on several processes the CPU they got
together is measured (:func:`helped`: CPU seconds of the chunks over the batch's wall time,
the start of the processes included); where it is under ``MIN_GAIN`` cores, the processes only took turns (a machine busy with
other work), and the pool runs the later batches in the calling process alone.
"""

from __future__ import annotations

import concurrent.futures
import math
import multiprocessing
import os
import time

import numpy as np

__all__ = [
    "usable_cores",
    "check_workers",
    "chunks",
    "helped",
    "LanePool",
    "MIN_LANES",
    "MIN_GAIN",
    "START_LANES",
]


def usable_cores() -> int:
    """Cores that would run more processes of this one now: those it may run on
    (``os.sched_getaffinity``; ``os.cpu_count`` elsewhere) less the load of the others (the
    1-minute ``os.getloadavg``, this process counted as one of it), rounded; never below one.
    On a machine shared with other work a process per core only takes turns with it: more
    processes than idle cores run slower than one."""
    if hasattr(os, "sched_getaffinity"):
        n = max(1, len(os.sched_getaffinity(0)))
    else:
        n = max(1, os.cpu_count() or 1)
    try:
        load = os.getloadavg()[0]
    except (AttributeError, OSError):  # no load average here: the cores alone
        return n
    idle = n - max(0.0, load - 1.0)
    return int(min(n, max(1, math.floor(idle + 0.5))))


def check_workers(workers, name: str = "workers") -> int:
    """``workers`` as an ``int >= 1`` (``None``: :func:`usable_cores`), or a one-line
    ``ValueError`` naming it (as ``name``)."""
    if workers is None:
        return usable_cores()
    ok = not isinstance(workers, (bool, np.bool_, str, bytes, float))
    try:
        ok = ok and int(workers) == workers and int(workers) >= 1
    except (TypeError, ValueError, OverflowError):
        ok = False
    if not ok:
        raise ValueError(f"{name}: must be an integer >= 1, got {workers!r}")
    return int(workers)


#: fewest lanes per process: a smaller batch runs on fewer processes (starting one costs about as
#: much as a few thousand trajectories)
MIN_LANES = 4096


#: lanes the calling process runs while the others start (~0.3 s of stepping)
START_LANES = 4096


#: cores' worth of CPU the processes of a batch must get together for more than one to help
MIN_GAIN = 1.2


def helped(cpu, wall) -> bool:
    """Whether a batch's processes ran side by side: the CPU seconds of its chunks ``cpu``
    (sequence) sum to at least ``MIN_GAIN`` times the batch's wall time ``wall`` [s]: more CPU
    than one process could have had over that time."""
    return float(sum(cpu)) >= MIN_GAIN * float(wall)


def _timed(fn, *arrays, **kwargs):
    """``(fn(*arrays, **kwargs), CPU seconds)`` of one chunk, in its process."""
    c = time.process_time()
    out = fn(*arrays, **kwargs)
    return out, time.process_time() - c


def chunks(n: int, w: int, extra: int = 0) -> list[np.ndarray]:
    """Lane indices (sorted) of ``w`` chunks of ``n`` lanes: the first ``ceil(n / w) + extra``
    lanes spread evenly over ``0 .. n - 1`` (``extra`` taken from the others, at most half of
    their even share), the others strided over the rest; every lane in exactly one chunk, none
    empty (``n >= w``, as :meth:`LanePool.map` ensures)."""
    if n < w:
        raise ValueError(f"chunks: {n} lanes cannot fill {w} chunks (need n >= w)")
    if w == 1:
        return [np.arange(n)]
    n0 = min(n - (w - 1) * (-(-n // (2 * w))), -(-n // w) + max(0, int(extra)))
    first = np.unique(np.rint(np.linspace(0, n - 1, n0)).astype(np.int64))
    rest = np.setdiff1d(np.arange(n), first, assume_unique=True)
    return [first] + [rest[c :: w - 1] for c in range(w - 1)]


class LanePool:
    """``workers`` processes (the caller and ``workers - 1`` spawned ones, started at the first
    batch that has lanes for them: at least ``min_lanes`` per process); a context manager that
    shuts them down on exit."""

    def __init__(self, workers=1, min_lanes: int = MIN_LANES):
        self.workers = check_workers(workers)
        self.min_lanes = max(1, int(min_lanes))
        self._executor = None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def close(self):
        if self._executor is not None:
            self._executor.shutdown(wait=True, cancel_futures=True)
            self._executor = None

    def map(self, fn, arrays, kwargs) -> list[tuple[np.ndarray, object]]:
        """``fn(*chunk_arrays, **kwargs)`` over the strided chunks of the lanes of ``arrays``
        (each ``(N, ...)``); returns ``[(lane indices, result), ...]``, one per chunk."""
        n = arrays[0].shape[0]
        w = max(1, min(self.workers, n // self.min_lanes))
        if w == 1:
            return [(np.arange(n), fn(*arrays, **kwargs))]
        starting, wall = self._executor is None, time.perf_counter()
        if starting:
            self._executor = concurrent.futures.ProcessPoolExecutor(
                max_workers=self.workers - 1, mp_context=multiprocessing.get_context("spawn")
            )
        idx = chunks(n, w, START_LANES * (w - 1) // w if starting else 0)
        futures = [self._executor.submit(_timed, fn, *(a[i] for a in arrays), **kwargs)
                   for i in idx[1:]]  # fmt: skip
        try:
            parts = [_timed(fn, *(a[idx[0]] for a in arrays), **kwargs)]
            parts += [f.result() for f in futures]
        except BaseException:
            for f in futures:
                f.cancel()
            self.close()
            raise
        if not helped([p[1] for p in parts], time.perf_counter() - wall):
            self.workers = 1  # the processes took turns: the later batches here alone
            self.close()
        return list(zip(idx, [p[0] for p in parts], strict=True))
