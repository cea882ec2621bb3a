"""Clocks, memory and subprocesses of ``atlas bench``: the minimum of repeats after a warm-up,
peak RSS, the machine, and the subprocess workers of the scaling and end-to-end sections.

A subprocess per measured size keeps each peak RSS (``VmHWM``) to itself; the worker prints one
``BENCH_JSON {...}`` line that :func:`run_worker` reads back.
"""

from __future__ import annotations

import json
import math
import os
import platform
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import jax
import numpy as np

from atlas.bench.config import FLAGS
from atlas.core.config import use_compile_cache
from atlas.core.contact_modes import direction
from atlas.core.points import spectral_points
from atlas.data.io import generate_to_file
from atlas.data.scene import Scene

__all__ = [
    "log",
    "timeit",
    "vm",
    "machine",
    "run_worker",
    "run_cli",
    "bench_json",
    "scale_worker",
    "generate_worker",
    "worker_main",
]


def log(msg):
    """One progress line on stderr, with the wall-clock time."""
    print(f"[bench {time.strftime('%H:%M:%S')}] {msg}", file=sys.stderr, flush=True)


def timeit(fn, *, budget=2.0, max_repeats=7, min_repeats=2):
    """Call ``fn`` once (compilation / warm-up), then the minimum of repeats [s]; as many repeats
    as fit in ``budget`` seconds, within ``[min_repeats, max_repeats]``, sized by the first
    repeat (not by the warm-up call, whose compilation would cut the repeats to the minimum)."""
    fn()
    best = math.inf
    done, reps = 0, min_repeats
    while done < reps:
        t0 = time.perf_counter()
        fn()
        t = time.perf_counter() - t0
        best = min(best, t)
        if done == 0:
            reps = int(max(min_repeats, min(max_repeats, budget / max(t, 1e-6))))
        done += 1
    return best


def vm(field: str) -> float:
    """``field`` of ``/proc/self/status`` (``VmRSS``, ``VmHWM`` = peak RSS) [MB]; the peak RSS of
    ``getrusage`` where there is no ``/proc``."""
    try:
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith(field + ":"):
                return int(line.split()[1]) / 1024
    except OSError:
        pass
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def _proc_field(path: str, key: str) -> str:
    """The value after ``key`` in the first line of ``path`` starting with it ("" if none)."""
    try:
        for line in Path(path).read_text().splitlines():
            if line.startswith(key):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return ""


def machine() -> dict:
    """CPUs available to this process, CPU model, RAM, load average and software versions."""
    ram = _proc_field("/proc/meminfo", "MemTotal")
    try:
        avail = len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover
        avail = os.cpu_count()
    return dict(
        nproc=avail,
        cpu=_proc_field("/proc/cpuinfo", "model name") or platform.processor(),
        ram=f"{int(ram.split()[0]) / 2**20:.1f} GiB" if ram else "",
        load=" ".join(f"{x:.2f}" for x in os.getloadavg()),
        python=platform.python_version(),
        jax=jax.__version__,
        numpy=np.__version__,
        platform=platform.platform(),
        jax_backend=jax.default_backend(),
    )


# --------------------------------------------------------------------------- subprocess workers


def scale_worker(n_target: int, q: float, dtype: str) -> dict:
    """Stream an atlas of ~``n_target`` points through :func:`atlas.core.points.spectral_points` in
    fixed tiles (256 beta1 rows x 1024 beta2 values, kappa = 0.5), writing the verdicts to a
    scratch file; returns seconds (after a warm-up tile), peak RSS [MB] and undecided count."""
    cols, rows_per_tile = 1024, 256
    rows = -(-n_target // cols)
    rows = -(-rows // rows_per_tile) * rows_per_tile
    c1, s1 = direction(np.linspace(0, 2 * np.pi, rows, endpoint=False), dtype)
    c2, s2 = direction(np.linspace(0, 2 * np.pi, cols, endpoint=False), dtype)
    k, qq = np.asarray(0.5, dtype), np.asarray(q, dtype)

    def tile(r0):
        sl = slice(r0, r0 + rows_per_tile)
        return spectral_points(
            c1[sl, None],
            s1[sl, None],
            c2[None],
            s2[None],
            k,
            qq,
            qq,
            names=FLAGS,
            dtype=dtype,
            resolve=False,
        )

    tile(0)  # compile
    rss_warm = vm("VmRSS")
    und = 0
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "atlas.bin"
        t0 = time.perf_counter()
        with open(path, "wb") as fh:
            for r0 in range(0, rows, rows_per_tile):
                res = tile(r0)
                und += res.stats["undecided_before"]
                for name in FLAGS:
                    fh.write(res[name].tobytes())
        seconds = time.perf_counter() - t0
        size = path.stat().st_size
    return dict(
        points=rows * cols,
        seconds=seconds,
        ns_per_point=seconds / (rows * cols) * 1e9,
        peak_rss_mb=vm("VmHWM"),
        rss_after_warmup_mb=rss_warm,
        undecided=und,
        bytes_written=size,
    )


def generate_worker(n_target: int) -> dict:
    """End to end: :func:`atlas.data.io.generate_to_file` of a Fig. 1 scene with ~``n_target``
    points (``resolve=False``)."""
    m = int(round(math.sqrt(n_target)))
    sc = Scene(beta1=f"0:2pi:{m}", beta2=f"0:2pi:{m}", kappa=0.5, q=0.0, outputs=",".join(FLAGS))
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        st = generate_to_file(sc, Path(tmp) / "g.nc", resolve=False)
        seconds = time.perf_counter() - t0
    return dict(
        points=int(st["points"]),
        seconds=seconds,
        ns_per_point=seconds / st["points"] * 1e9,
        peak_rss_mb=vm("VmHWM"),
        rss_after_warmup_mb=math.nan,
        undecided=int(st["undecided_fast"]),
        bytes_written=int(st["bytes"]),
    )


def worker_main():  # pragma: no cover - runs in a subprocess
    """Subprocess entry: ``KIND N Q DTYPE`` on the command line, one ``BENCH_JSON`` line out."""
    kind, n, q, dtype = sys.argv[1], int(sys.argv[2]), float(sys.argv[3]), sys.argv[4]
    if kind == "tiles":  # its first (compiling) tile is not timed: load it from the cache
        use_compile_cache()
    out = scale_worker(n, q, dtype) if kind == "tiles" else generate_worker(n)
    print("BENCH_JSON " + json.dumps(out))


def run_worker(kind: str, n: int, q: float, dtype: str) -> dict:
    """:func:`scale_worker` (``kind="tiles"``) or :func:`generate_worker` in a fresh interpreter;
    its result plus ``wall_seconds`` (start-up included)."""
    code = "from atlas.bench import timing; timing.worker_main()"
    cmd = [sys.executable, "-c", code, kind, str(n), repr(q), dtype]
    env = dict(os.environ, PYTHONWARNINGS="ignore")
    t0 = time.perf_counter()
    p = subprocess.run(cmd, capture_output=True, text=True, env=env, check=False)
    wall = time.perf_counter() - t0
    d = bench_json(p.stdout)
    if d is None:
        raise RuntimeError(f"bench worker failed: {p.stderr.strip().splitlines()[-1:]}")
    d["wall_seconds"] = wall
    return d


def bench_json(stdout: str) -> dict | None:
    """The value of a subprocess's first ``BENCH_JSON {...}`` line (None without one)."""
    for line in stdout.splitlines():
        if line.startswith("BENCH_JSON "):
            return json.loads(line[len("BENCH_JSON ") :])
    return None


#: ``atlas <args>`` in a subprocess that prints its own peak RSS at exit
_CLI_PEAK = (
    "import sys; from atlas import cli; from atlas.bench.timing import vm; "
    "rc = cli.main(sys.argv[1:]); print('BENCH_PEAK_MB', vm('VmHWM')); sys.exit(rc)"
)


def run_cli(args: list[str]) -> tuple[subprocess.CompletedProcess, float, float | None]:
    """``atlas ARGS`` in a fresh interpreter (no progress bar): the finished process, its wall
    time [s] and its peak RSS [MB] (None if it did not get to print it)."""
    cmd = [sys.executable, "-c", _CLI_PEAK, *args]
    env = dict(os.environ, PYTHONWARNINGS="ignore", ATLAS_PROGRESS="0")
    t0 = time.perf_counter()
    p = subprocess.run(cmd, capture_output=True, text=True, env=env, check=False)
    wall = time.perf_counter() - t0
    peak = [ln for ln in p.stdout.splitlines() if ln.startswith("BENCH_PEAK_MB")]
    return p, wall, float(peak[-1].split()[1]) if peak else None
