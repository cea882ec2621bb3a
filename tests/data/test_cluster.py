"""``atlas.data.cluster``: where tiles run (in process, LocalCluster workers pinned to cores)."""

import contextlib
import os

import pytest

from atlas.data.cluster import InProcess, executor


def test_in_process_executor_runs_every_call_in_order():
    ex = executor(None)
    assert isinstance(ex, InProcess) and ex.workers == 1
    assert list(ex.map(lambda a, b: a + b, [("x", (1, 2)), ("y", (3, 4))])) == [("x", 3), ("y", 7)]
    ex.close()


@pytest.mark.parametrize("bad", ["local:0", "local:x", "nowhere", 3])
def test_a_bad_scheduler_is_refused_naming_it(bad):
    with pytest.raises(ValueError, match="^scheduler:"):
        executor(bad)


def _thread_affinities():
    import os

    return sorted(
        {tuple(sorted(os.sched_getaffinity(int(t)))) for t in os.listdir("/proc/self/task")}
    )


@pytest.mark.e2e
@pytest.mark.skipif(not hasattr(os, "sched_setaffinity"), reason="Linux affinity only")
def test_local_cluster_pins_each_worker_to_one_core():
    """Every thread of a LocalCluster worker (XLA's task pool included) runs on one core, and the
    worker has the single-thread XLA environment; the scheduler's HTTP server is on a free loopback
    port, not on dask's 8787 (held here: two clusters at once would warn, an error in the suite)."""
    import socket

    import jax.numpy as jnp  # noqa: F401  (XLA's pools exist in this process too)

    pytest.importorskip("distributed")
    from atlas.data.cluster import WORKER_ENV, local_cluster

    with socket.socket() as held:
        held.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        with contextlib.suppress(OSError):  # already held by someone else: as good
            held.bind(("127.0.0.1", 8787))
            held.listen()
        cluster, client = local_cluster(1)
    try:
        http = cluster.scheduler.http_server
        assert (http.address, http.port != 8787) == ("127.0.0.1", True), (http.address, http.port)

        def probe():
            import os

            import jax.numpy as jnp

            jnp.ones(1 << 16).sum().block_until_ready()  # start XLA's threads
            return _thread_affinities(), os.environ.get("XLA_FLAGS")

        (res,) = client.run(probe).values()
    finally:
        client.close()
        cluster.close()
    affinities, flags = res
    assert len(affinities) == 1 and len(affinities[0]) == 1, affinities
    assert flags == WORKER_ENV["XLA_FLAGS"]
