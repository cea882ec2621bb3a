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


#: a LocalCluster started from a script that imports JAX at its top, as a script of the Python API
#: may: its spawned worker imports the script (and JAX) before it gets the workers' environment
_SCRIPT = """
import json

import jax  # noqa: F401


def probe():
    import os

    import jax
    import jax.numpy as jnp

    jnp.ones(1 << 16).sum().block_until_ready()  # start XLA's threads
    tasks = os.listdir("/proc/self/task")
    affinities = sorted({tuple(sorted(os.sched_getaffinity(int(t)))) for t in tasks})
    return affinities, os.environ.get("XLA_FLAGS"), jax.config.jax_compilation_cache_dir


if __name__ == "__main__":
    from atlas.data.cluster import local_cluster

    cluster, client = local_cluster(1)
    try:
        http = cluster.scheduler.http_server
        (res,) = client.run(probe).values()
        print(json.dumps({"http": [http.address, http.port], "worker": res}))
    finally:
        client.close()
        cluster.close()
"""


@pytest.mark.e2e
@pytest.mark.skipif(not hasattr(os, "sched_setaffinity"), reason="Linux affinity only")
def test_local_cluster_pins_each_worker_to_one_core(tmp_path):
    """Every thread of a LocalCluster worker (XLA's task pool included) runs on one core, and the
    worker has the single-thread XLA environment and the persistent compilation cache (started from
    a script that imports JAX first: the cache variables reach a spawned worker too late for it);
    the scheduler's HTTP server is on a free loopback port, not on dask's 8787 (held here: two
    clusters at once would warn, an error in the suite)."""
    import json
    import socket
    import subprocess
    import sys

    pytest.importorskip("distributed")
    from atlas.data.cluster import WORKER_ENV

    script, cache = tmp_path / "cluster_probe.py", tmp_path / "jax"
    script.write_text(_SCRIPT)
    env = dict(os.environ, ATLAS_JAX_CACHE=str(cache))
    with socket.socket() as held:
        held.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        with contextlib.suppress(OSError):  # already held by someone else: as good
            held.bind(("127.0.0.1", 8787))
            held.listen()
        run = subprocess.run(
            [sys.executable, str(script)], env=env, capture_output=True, text=True, timeout=300
        )
    assert run.returncode == 0, run.stderr
    got = json.loads(run.stdout.strip().splitlines()[-1])
    address, port = got["http"]
    assert (address, port != 8787) == ("127.0.0.1", True), got["http"]
    affinities, flags, cache_dir = got["worker"]
    assert len(affinities) == 1 and len(affinities[0]) == 1, affinities
    assert flags == WORKER_ENV["XLA_FLAGS"]
    assert cache_dir == str(cache)
