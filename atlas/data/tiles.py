"""The tiles of a scene: ``beta1`` slabs, or ``(beta1, beta2)`` blocks, as index ranges.

A scene is split along ``beta1`` into *slabs* of ``slab`` consecutive values, and, when one
``beta1`` value alone holds more points than a tile should (or ``block2`` is given), along ``beta2``
too, into 2-D ``(beta1, beta2)`` blocks (:func:`tile_plan`).  A tile is ``(start, stop)`` or
``(start, stop, start2, stop2)``; each is an ordinary :func:`atlas.generate` run on the sub-scene
holding its block (:func:`sub_scene`).  Generation is pointwise-deterministic and the
``model_dependent_*`` reductions run over the model dimensions at fixed ``(beta1, beta2)``, so
assembled tiles equal the single-process atlas bit for bit.

A variable lacking a split dimension (``stable_FS`` and ``consistent_FI`` have no ``beta1``,
``stable_SF`` no ``beta2``) is computed by every tile that covers its region; the first of them
along the missing dimension *owns* it (:func:`owns`).
"""

from __future__ import annotations

import collections.abc
import dataclasses
import operator

import numpy as np

from atlas.core import checks
from atlas.data.scene import Scene

__all__ = [
    "DEFAULT_SLAB_POINTS",
    "TilePlan",
    "tile_plan",
    "sub_scene",
    "ranges",
    "region",
    "unique",
    "owns",
]

#: default points per tile (largest output): a few kernel tiles, so per-tile overhead is amortized
DEFAULT_SLAB_POINTS = 1 << 18


def tile_plan(scene: Scene, slab: int | None = None, block2: int | None = None) -> TilePlan:
    """The tiles of a scene: ``[(start, stop), ...]`` (``beta1`` slabs; one tile if ``beta1`` is
    fixed), or ``[(start, stop, start2, stop2), ...]`` when ``beta2`` is split too (2-D blocks),
    as a lazy :class:`TilePlan` (no tile is materialised: a 1e14-point scene costs nothing).

    ``slab=None`` picks about :data:`DEFAULT_SLAB_POINTS` points per tile; if then one ``beta1``
    value alone holds more than that and ``block2`` is not given, ``beta2`` is split into blocks of
    about that many points as well.  ``block2`` = ``beta2`` values per tile.
    """
    n1 = scene.axes["beta1"].size if "beta1" in scene.dims else 1
    n2 = scene.axes["beta2"].size if "beta2" in scene.dims else 1
    per = max(1, scene.points() // n1)
    if slab is None:
        slab = max(1, min(n1, round(DEFAULT_SLAB_POINTS / per)))
        if block2 is None and per > DEFAULT_SLAB_POINTS and n2 > 1:
            block2 = max(1, round(DEFAULT_SLAB_POINTS / max(1, per // n2)))
            block2 = None if block2 >= n2 else block2
    s = checks.positive_int("slab", slab)
    if block2 is None:
        return TilePlan(n1, n2, s, None)
    b = checks.positive_int("block2", block2)
    if "beta2" not in scene.dims:
        raise ValueError("block2: the scene has a single beta2 value")
    return TilePlan(n1, n2, s, b)


@dataclasses.dataclass(frozen=True)
class TilePlan(collections.abc.Sequence):
    """The tiles of :func:`tile_plan`, computed on demand: ``n1`` x ``n2`` (beta1, beta2) values in
    slabs of ``slab`` beta1 values, split into blocks of ``block2`` beta2 values (``None``: not
    split).  A sequence of tuples; equal to the list of its tiles."""

    n1: int
    n2: int
    slab: int
    block2: int | None

    @property
    def _per1(self) -> int:
        return 1 if self.block2 is None else -(-self.n2 // self.block2)

    def __len__(self) -> int:
        return -(-self.n1 // self.slab) * self._per1

    def __getitem__(self, i):
        if isinstance(i, slice):
            return [self[j] for j in range(*i.indices(len(self)))]
        n = len(self)
        i = operator.index(i)
        if i < 0:
            i += n
        if not 0 <= i < n:
            raise IndexError(i)
        a, c = divmod(i, self._per1)
        a *= self.slab
        tile = (a, min(a + self.slab, self.n1))
        if self.block2 is None:
            return tile
        c *= self.block2
        return (*tile, c, min(c + self.block2, self.n2))

    def __eq__(self, other):
        if isinstance(other, collections.abc.Sequence) and not isinstance(other, str):
            return len(self) == len(other) and all(a == tuple(b) for a, b in zip(self, other))
        return NotImplemented

    __hash__ = None

    def describe(self) -> dict:
        """The plan's parameters (stored in the store's plan instead of every tile)."""
        return {"n1": self.n1, "n2": self.n2, "slab": self.slab, "block2": self.block2}

    @classmethod
    def of(cls, stored) -> TilePlan | list:
        """The tiles of a stored plan (:meth:`describe`, or a list of tiles)."""
        return cls(**stored) if isinstance(stored, dict) else [tuple(t) for t in stored]


def sub_scene(scene: Scene, tile) -> Scene:
    """The scene of one tile: ``beta1`` (and for 2-D blocks ``beta2``) cut to its ranges."""
    kw = {}
    if "beta1" in scene.dims:
        kw["beta1"] = np.array(scene.axes["beta1"].values[tile[0] : tile[1]])
    if len(tile) == 4:
        kw["beta2"] = np.array(scene.axes["beta2"].values[tile[2] : tile[3]])
    return scene.replace(**kw) if kw else scene


def ranges(has_beta1: bool, tile) -> dict:
    """``{dim: (start, stop)}``: the dimensions a tile is a range of."""
    out = {"beta1": (tile[0], tile[1])} if has_beta1 else {}
    if len(tile) == 4:
        out["beta2"] = (tile[2], tile[3])
    return out


def region(dims, split: dict) -> dict:
    """A variable's region in a tile of :func:`ranges` ``split`` (``{}``: the whole variable)."""
    return {d: slice(*split[d]) for d in split if d in dims}


def unique(dims, split: dict) -> bool:
    """The variable's region in this tile belongs to no other tile (it has every split dim)."""
    return all(d in dims for d in split)


def owns(dims, split: dict) -> bool:
    """The tile writes the variable's region: it is the first tile along the dims it lacks."""
    return all(d in dims or split[d][0] == 0 for d in split)
