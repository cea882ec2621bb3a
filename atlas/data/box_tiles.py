"""Verdicts over a model box in a tiled store (:mod:`atlas.data.distributed`).

``ss_over_models``, ``ii_consistent_over_models``, ``ii_stable_over_models`` and their witnesses
(:mod:`atlas.data.over_models`) span ``beta1, beta2`` only: exactly the axes the tiles split
(:mod:`atlas.data.tiles`).  Each point's code and witnesses depend on that point and the box alone,
so every tile computes them on its own block (:func:`add_to_tile`) and owns their region; the
assembled store equals ``atlas.generate(scene, model_box=box)`` value for value.  The box is part
of the store's plan (a resume with another box, or none, is refused); each tile records its counts
(:func:`tile_counts`) and the finished store carries their sums (:func:`total_counts`): the same
global attributes as in memory, ``*_seconds`` being the sum over the tiles.
"""

from __future__ import annotations

import dataclasses

from atlas.data import over_models as om
from atlas.data.engine import Schema, block_shape
from atlas.data.outputs import storage_dtype, variable_attrs

__all__ = ["BOX_OUTPUTS", "BOX_COUNTS", "with_box", "add_to_tile", "tile_counts", "total_counts"]

#: the variables a model box adds, in the order of ``atlas.generate(scene, model_box=...)``
BOX_OUTPUTS = (*om.OVER_MODELS_OUTPUTS, *om.II_OVER_MODELS_OUTPUTS)
#: the counts of :mod:`atlas.data.over_models` (global attributes; SS then II)
BOX_COUNTS = tuple(
    f"{prefix}_{count}"
    for prefix in ("over_models", "ii_over_models")
    for count in ("undecided_before_settlement", "undecided", "seconds")
)


def with_box(sch: Schema, tile_points: int) -> Schema:
    """``sch`` with the :data:`BOX_OUTPUTS` over its ``beta1, beta2`` (those that vary): codes
    int8, witnesses float64 [1] whatever the working dtype, chunks as :func:`atlas.data.io.write_netcdf`
    gives them."""
    dims = tuple(d for d in ("beta1", "beta2") if d in sch.shape)
    shape = tuple(sch.shape[d] for d in dims)
    chunks = block_shape(shape, tile_points) if dims else None
    extra = {n: (dims, storage_dtype(n, "float64"), variable_attrs(n), chunks) for n in BOX_OUTPUTS}
    return dataclasses.replace(sch, variables={**sch.variables, **extra})


def add_to_tile(ds, box):
    """The atlas of one tile with the :data:`BOX_OUTPUTS` over its block
    (:func:`atlas.data.over_models.add_all_over_models`)."""
    return om.add_all_over_models(ds, box)


def tile_counts(ds) -> dict:
    """The :data:`BOX_COUNTS` of one tile's atlas (``{}`` without a box)."""
    return {k: ds.attrs[k] for k in BOX_COUNTS if k in ds.attrs}


def total_counts(box_text: str | None, counts) -> dict:
    """The global attributes of a finished store over the box ``box_text`` (``{}`` without):
    ``model_box`` and the sums of the tiles' ``counts`` (seconds rounded to ms)."""
    if box_text is None:
        return {}
    out = {"model_box": box_text}
    for k in BOX_COUNTS:
        total = sum(c[k] for c in counts)
        out[k] = round(float(total), 3) if k.endswith("_seconds") else int(total)
    return out
