"""Exact settlement of a point kernel's undecided codes from its exact reference of one point.

A kernel whose codes floating point may leave undecided declares its exact reference
(:attr:`atlas.core.kernels.PointKernel.exact`): ``reference(*inputs) -> {result: code}`` on the
float inputs of one point (direction components, model invariants [1]), decided exactly (e.g.
:func:`atlas.core.exact.point_codes`, rational arithmetic).  :func:`by_points` turns it into the
kernel's ``settle``; a new output brings its own reference and edits no shared one.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

__all__ = ["by_points"]


def by_points(reference: Callable) -> Callable:
    """The ``settle(codes, masks, *inputs)`` of a kernel whose exact reference of one point is
    ``reference``: replaces, in place, ``codes[k]`` where ``masks[k]`` holds by the reference's
    ``k``; a point on which the reference raises stays undecided and is recorded (a long atlas run
    is never aborted by one point).  Returns ``resolved_points`` and ``exact_failures``."""

    def settle(codes: dict, masks: dict, *inputs) -> dict:
        stats = {"resolved_points": 0, "exact_failures": []}
        masks = {k: np.asarray(m).reshape(-1) for k, m in masks.items() if k in codes}
        if not masks:
            return stats
        shape = np.shape(codes[next(iter(masks))])
        idx = np.flatnonzero(np.logical_or.reduce(list(masks.values())))
        pts = [np.broadcast_to(np.asarray(a), shape).reshape(-1)[idx] for a in inputs]
        for j, i in enumerate(idx):
            args = tuple(float(p[j]) for p in pts)
            try:
                ref = reference(*args)
            except Exception:
                stats["exact_failures"].append(args)
                continue
            for k, m in masks.items():
                if m[i]:
                    codes[k].reshape(-1)[i] = ref[k]
            stats["resolved_points"] += 1
        return stats

    settle.reference = reference
    return settle
