"""The work a block of code does, counted instead of timed (the machine running the suite may be
busy): calls of the functions of the modules that compute, the JAX programs traced or compiled,
and the peak memory Python and numpy allocate (tracemalloc)."""

from __future__ import annotations

import contextlib
import dataclasses
import sys
import tracemalloc
from collections import Counter

import jax

#: the modules whose functions compute verdicts, outcomes or curves (or start workers for them)
WORK_MODULES = tuple(
    f"/atlas/{m}.py"
    for m in (
        "core/points",
        "core/spectral",
        "core/rootfree",
        "core/hurwitz",
        "core/enclosures",
        "core/undamped",
        "core/baseline",
        "core/exact",
        "data/marching",
        "data/boundary_paths",
        "data/cluster",
        "data/tile_store",
        "dynamics/fast_engine",
        "dynamics/jax_engine",
        "dynamics/simulator",
        "dynamics/lane_pool",
    )
)
#: JAX's events of a program traced to a jaxpr and compiled by XLA
JAX_EVENTS = (
    "/jax/core/compile/jaxpr_trace_duration",
    "/jax/core/compile/backend_compile_duration",
)


@dataclasses.dataclass
class Work:
    """What :func:`counted` saw: ``calls`` per work module (``{path: calls}``), ``jax`` events
    (``{event: count}``) and ``peak_bytes`` allocated at once."""

    calls: Counter = dataclasses.field(default_factory=Counter)
    jax: Counter = dataclasses.field(default_factory=Counter)
    peak_bytes: int = 0


def _importing(frame) -> bool:
    """Whether ``frame`` runs inside an import (a module body and what it calls)."""
    while frame is not None:
        if frame.f_code.co_filename.startswith("<frozen importlib"):
            return True
        frame = frame.f_back
    return False


@contextlib.contextmanager
def counted():
    """``with counted() as work:`` counts the work of the block (:class:`Work`); imports are not
    work."""
    work = Work()

    def profile(frame, event, arg):
        if event == "call" and frame.f_code.co_filename.endswith(WORK_MODULES):
            if not _importing(frame.f_back):
                work.calls[frame.f_code.co_filename.split("/atlas/")[-1]] += 1

    def listen(event, seconds, **kw):
        if event in JAX_EVENTS:
            work.jax[event.rsplit("/", 1)[-1]] += 1

    jax.monitoring.register_event_duration_secs_listener(listen)
    tracing = tracemalloc.is_tracing()
    if not tracing:
        tracemalloc.start()
    tracemalloc.reset_peak()
    sys.setprofile(profile)
    try:
        yield work
    finally:
        sys.setprofile(None)
        work.peak_bytes = tracemalloc.get_traced_memory()[1]
        if not tracing:
            tracemalloc.stop()
        jax.monitoring.unregister_event_duration_listener(listen)
