"""Fixtures of the boundary tests: slices traced once per process and shared between modules."""

import functools

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
