"""Fixtures of the boundary tests: slices traced once per process and shared between modules."""

import copy
import functools
import inspect

import numpy as np
import pytest

from atlas.data import boundaries as bd

#: the 32 x 32 grid [rad] (cell 0.2 rad) of the boundary tests' slices
GRID_32 = np.arange(32) * 2 * np.pi / 32


@pytest.fixture(scope="session")
def slice_32():
    """``slice_32(model, fields=("SS", "II"), chord=bd.CHORD)``: slice ``model = (kappa, q1,
    q2)`` on :data:`GRID_32`, unchecked (``check=0``), at the default ``tol``, traced once per
    process and arguments (the fields are traced independently: a one-field run gives that
    field's curves, points and attrs).  The result is shared: tests only read it."""

    @functools.cache
    def traced(model, fields, chord):
        return bd.slice_boundaries(GRID_32, GRID_32, *model, fields=fields, check=0, chord=chord)

    def one(model, fields=("SS", "II"), chord=bd.CHORD):
        return traced(tuple(model), tuple(fields), float(chord))

    return one


@pytest.fixture
def traced_once(monkeypatch):
    """For the test, :func:`bd.slice_boundaries` traces each distinct call once: a call with the
    same arguments (defaults filled in, arrays by value) gets a copy of the first one's result,
    any other call its own run.  For tests that two routes to a slice (the command line and the
    API, a scene and its atlas) give the same curves: they trace it once when they pass the
    same arguments, and are compared as before when they do not."""
    real = bd.slice_boundaries
    sig, seen = inspect.signature(real), {}

    def once(*args, **kwargs):
        bound = sig.bind(*args, **kwargs)
        bound.apply_defaults()
        key = tuple(
            (k, (v.dtype.str, v.shape, v.tobytes()) if isinstance(v, np.ndarray) else repr(v))
            for k, v in bound.arguments.items()
        )
        if key not in seen:
            seen[key] = real(*args, **kwargs)
        return copy.deepcopy(seen[key])

    monkeypatch.setattr(bd, "slice_boundaries", once)
    return seen
