"""Lanes of a batch on several processes: the trajectories of :mod:`atlas.dynamics.fast_engine`
split into one strided chunk per process (lanes ``c, c + w, c + 2w, ...``), the calling process
one of them.

A lane's result depends on its own parameters only (every operation of the engine is lane by
lane), so any split gives the same arrays, bit for bit.  One chunk per process keeps the batches
large: the engine's cost per step is mostly fixed (NumPy calls), so smaller batches cost more per
trajectory.  The other processes are started with ``spawn`` once per :class:`LanePool` and reused
by every batch; they import NumPy and the engine only (no JAX, no xarray), so starting one takes
about half a second on a quiet machine, which counts in the wall time of the batch that
starts it.
"""

from __future__ import annotations

import concurrent.futures
import multiprocessing
import os

import numpy as np

__all__ = ["usable_cores", "check_workers", "LanePool", "MIN_LANES"]


def usable_cores() -> int:
    """Cores this process may run on (``os.sched_getaffinity``; ``os.cpu_count`` elsewhere)."""
    if hasattr(os, "sched_getaffinity"):
        return max(1, len(os.sched_getaffinity(0)))
    return max(1, os.cpu_count() or 1)


def check_workers(workers) -> int:
    """``workers`` as an ``int >= 1`` (``None``: :func:`usable_cores`), or a one-line
    ``ValueError`` naming it."""
    if workers is None:
        return usable_cores()
    ok = not isinstance(workers, (bool, np.bool_, str, bytes, float))
    try:
        ok = ok and int(workers) == workers and int(workers) >= 1
    except (TypeError, ValueError, OverflowError):
        ok = False
    if not ok:
        raise ValueError(f"workers: must be an integer >= 1, got {workers!r}")
    return int(workers)


#: fewest lanes per process: a smaller batch runs on fewer processes (starting one costs about as
#: much as a few thousand trajectories)
MIN_LANES = 4096


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
        idx = [np.arange(c, n, w) for c in range(w)]
        if w == 1:
            return [(idx[0], fn(*arrays, **kwargs))]
        if self._executor is None:
            self._executor = concurrent.futures.ProcessPoolExecutor(
                max_workers=self.workers - 1, mp_context=multiprocessing.get_context("spawn")
            )
        futures = [self._executor.submit(fn, *(a[i] for a in arrays), **kwargs) for i in idx[1:]]
        try:
            first = fn(*(a[idx[0]] for a in arrays), **kwargs)
            rest = [f.result() for f in futures]
        except BaseException:
            for f in futures:
                f.cancel()
            self.close()
            raise
        return list(zip(idx, [first, *rest], strict=True))
