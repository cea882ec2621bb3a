"""Where tiles run: in this process, on a dask LocalCluster, or on an existing dask cluster.

:func:`executor` turns a ``scheduler`` argument into an object with ``map(fn, calls)`` (yields
``(key, fn(*args))`` as the calls finish), ``close()``, ``workers`` and ``description``:

``scheduler=None``
    in this process, call after call (:class:`InProcess`, no dask);
``"local"`` / ``"local:N"``
    a :class:`distributed.LocalCluster` of N worker *processes* (default: the number of cores),
    one thread each, one JAX runtime per worker with XLA's intra-op threading off
    (:data:`WORKER_ENV`) and each worker pinned to its own core (:func:`pin_to_cpus`: XLA's task
    pool ignores the flags), so N workers use N cores; the workers share the CLI's persistent JAX
    compilation cache (:func:`worker_env`);
``"tcp://host:8786"`` or a :class:`distributed.Client`
    an existing cluster.  The workers need ``painleve-atlas`` (the same version and JAX version as
    the client) and, for stores, the path on a shared file system.  Start the workers with one
    thread each and the same environment, e.g.::

        dask scheduler                                    # on host, port 8786
        XLA_FLAGS="--xla_cpu_multi_thread_eigen=false" \\
            dask worker tcp://host:8786 --nworkers 16 --nthreads 1   # on each machine
"""

from __future__ import annotations

import contextlib
import os

from atlas.core.config import CACHE_MIN_COMPILE_SECONDS, compile_cache_dir, use_compile_cache

__all__ = [
    "WORKER_ENV",
    "worker_env",
    "pin_to_cpus",
    "local_cluster",
    "check_scheduler",
    "executor",
    "InProcess",
    "DaskExecutor",
]

#: environment of LocalCluster workers: one JAX process per worker, no intra-op thread pools
WORKER_ENV = {
    "XLA_FLAGS": "--xla_cpu_multi_thread_eigen=false",
    "OMP_NUM_THREADS": "1",
    "MKL_NUM_THREADS": "1",
    "OPENBLAS_NUM_THREADS": "1",
}


def pin_to_cpus(cpus) -> list[int]:
    """Restrict every thread of this process to ``cpus`` (Linux); returns the threads pinned.

    XLA splits large fusions into parallel tasks on its own thread pool whatever ``XLA_FLAGS`` say
    (measured: one worker used 1.5-1.8 cores with ``--xla_cpu_multi_thread_eigen=false``), so a
    LocalCluster of N workers on N cores oversubscribed them (2 workers gave 1.12x one worker).
    Affinity is per thread on Linux: every existing thread is set, and threads created later
    inherit it.  A no-op (empty list) where ``os.sched_setaffinity`` does not exist.
    """
    if not hasattr(os, "sched_setaffinity"):  # pragma: no cover - macOS, Windows
        return []
    done = []
    for tid in os.listdir("/proc/self/task"):
        with contextlib.suppress(OSError):
            os.sched_setaffinity(int(tid), set(cpus))
            done.append(int(tid))
    return done


def local_cluster(n_workers: int):
    """``(cluster, client)``: a LocalCluster of ``n_workers`` single-thread worker processes with
    :func:`worker_env`, worker ``i`` pinned to core ``i mod ncores`` (:func:`pin_to_cpus`), so N
    workers use N cores, each with the persistent compilation cache on; the scheduler's HTTP
    server on a free loopback port (no dashboard)."""
    from distributed import Client, LocalCluster

    env = worker_env()
    cluster = LocalCluster(
        n_workers=n_workers,
        threads_per_worker=1,
        processes=True,
        env=env,
        dashboard_address=None,
        # no dashboard, but the scheduler still serves HTTP (health, metrics): on a free loopback
        # port, not on 8787, where a second cluster (or a user's own) would make it warn and move
        scheduler_kwargs={"dashboard_address": "127.0.0.1:0"},
        silence_logs=40,
    )
    client = Client(cluster)
    client.wait_for_workers(n_workers)
    where = env.get("JAX_COMPILATION_CACHE_DIR")
    if where is not None:
        # a worker is spawned: it imports the parent's main script first (a script of the Python
        # API may import JAX at its top) and gets :func:`worker_env` only after that, too late for
        # JAX to read its cache variables; so the cache is switched on in each worker here
        client.run(use_compile_cache, where, CACHE_MIN_COMPILE_SECONDS)
    cores = sorted(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else []
    if cores and n_workers <= len(cores):
        for i, addr in enumerate(sorted(client.scheduler_info()["workers"])):
            client.run(pin_to_cpus, [cores[i]], workers=[addr])
    return cluster, client


def worker_env() -> dict:
    """Environment for worker processes: :data:`WORKER_ENV` plus the persistent JAX compilation
    cache of the CLI (``$ATLAS_JAX_CACHE``, default ``~/.cache/painleve-atlas/jax``; ``0`` = off),
    so each worker loads the compiled kernels instead of compiling them again."""
    env = dict(WORKER_ENV)
    where = compile_cache_dir()
    if where is not None:
        env["JAX_COMPILATION_CACHE_DIR"] = where
        env.setdefault("JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS", str(CACHE_MIN_COMPILE_SECONDS))
    return env


class InProcess:
    """Runs the calls here, one after the other (the reference code path)."""

    workers = 1
    description = "in-process"

    def map(self, fn, calls):
        for key, args in calls:
            yield key, fn(*args)

    def close(self):
        pass


class DaskExecutor:
    """Runs the calls as dask tasks on a LocalCluster it starts, or on an existing cluster."""

    def __init__(self, scheduler):
        from distributed import Client

        self.cluster = None
        if isinstance(scheduler, Client):
            self.client, self.own = scheduler, False
        elif isinstance(scheduler, str) and scheduler.split(":")[0] == "local":
            n = scheduler.partition(":")[2]
            n = int(n) if n else (os.cpu_count() or 1)
            self.cluster, self.client = local_cluster(n)
            self.own = True
        elif isinstance(scheduler, str) and "://" in scheduler:
            try:
                self.client, self.own = Client(scheduler), True
            except (OSError, TimeoutError) as e:  # unreachable or not a dask scheduler
                raise OSError(f"scheduler: cannot connect to {scheduler}: {e}") from None
        else:  # pragma: no cover - rejected by check_scheduler
            raise ValueError(f"scheduler: unsupported {scheduler!r}")
        self.workers = max(1, len(self.client.scheduler_info().get("workers", {})))
        self.description = str(scheduler if isinstance(scheduler, str) else "client")

    def map(self, fn, calls):
        from distributed import as_completed

        futures = {}
        for key, args in calls:
            futures[self.client.submit(fn, *args, pure=False)] = key
        try:
            for fut in as_completed(futures):
                yield futures[fut], fut.result()
        finally:
            self.client.cancel(list(futures))

    def close(self):
        if self.own:
            self.client.close()
        if self.cluster is not None:
            self.cluster.close()


def check_scheduler(scheduler):
    """``ValueError`` naming ``scheduler`` unless it is None, local[:N], an address or a Client."""
    if scheduler is None or (isinstance(scheduler, str) and "://" in scheduler):
        return
    if isinstance(scheduler, str) and scheduler.split(":")[0] == "local":
        n = scheduler.partition(":")[2]
        if n == "" or (n.isdigit() and int(n) >= 1):
            return
        raise ValueError(f"scheduler: expected local:N with N >= 1, got {scheduler!r}")
    if type(scheduler).__name__ == "Client":
        return
    raise ValueError(
        f"scheduler: expected None, 'local', 'local:N', an address (tcp://host:8786) or a "
        f"distributed.Client, got {scheduler!r}"
    )


def executor(scheduler) -> InProcess | DaskExecutor:
    """The executor of a checked ``scheduler`` (see the module docstring)."""
    check_scheduler(scheduler)
    if scheduler is None:
        return InProcess()
    return DaskExecutor(scheduler)
