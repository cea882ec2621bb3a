"""Layer 4, measurement: ``atlas bench`` (speed against error, scaling, hard cases, simulation).

Modules: :mod:`~atlas.bench.config` (what a run measures: ``full``, ``quick``, ``tiny``),
:mod:`~atlas.bench.timing` (clocks, memory, subprocess workers), :mod:`~atlas.bench.grids` (one
beta grid, every method, checked exactly), :mod:`~atlas.bench.boundaries` (contours, Hausdorff
distance), :mod:`~atlas.bench.suites` and :mod:`~atlas.bench.simulation` (the measured sections),
:mod:`~atlas.bench.startup` (start-up figures, whole processes),
:mod:`~atlas.bench.report` and :mod:`~atlas.bench.plots` (``bench.md`` and its figures),
:mod:`~atlas.bench.runner` (:func:`run`, the entry point of ``atlas bench``),
:mod:`~atlas.bench.partial` (``--only``: some sections re-measured, the others read back), and
:mod:`~atlas.bench.distributed` (throughput of distributed generation, ``distributed.md``).
The names below load on first use (``lazy_loader``).
"""

import lazy_loader

__getattr__, __dir__, __all__ = lazy_loader.attach(
    __name__, submod_attrs={"config": ["CONFIG"], "runner": ["run"]}
)
