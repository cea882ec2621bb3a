"""``atlas.data.tiles``: the tiles of a scene (beta1 slabs, (beta1, beta2) blocks)."""

import pytest

from atlas.data.scene import Scene
from atlas.data.tiles import owns, ranges, region, tile_plan, unique

SCENE = dict(beta1="0:2pi:8", beta2="0:2pi:8", kappa="0.5,2", q1="0,1", q2="0,0.5")


def scene(**kw):
    return Scene(**{**SCENE, **kw})


def test_tile_plan():
    assert tile_plan(scene(), 3) == [(0, 3), (3, 6), (6, 8)]
    assert tile_plan(scene(), 100) == [(0, 8)]
    assert tile_plan(scene(beta1=0.3)) == [(0, 1)]
    assert tile_plan(scene()) == [(0, 8)]  # default: ~2**18 points per tile
    with pytest.raises(ValueError, match="^slab:"):
        tile_plan(scene(), 0)
    # 2-D (beta1, beta2) blocks, given explicitly
    assert tile_plan(scene(), 4, 3) == [
        (0, 4, 0, 3),
        (0, 4, 3, 6),
        (0, 4, 6, 8),
        (4, 8, 0, 3),
        (4, 8, 3, 6),
        (4, 8, 6, 8),
    ]
    with pytest.raises(ValueError, match="^block2:"):
        tile_plan(scene(), 2, 0)
    with pytest.raises(ValueError, match="^block2:"):
        tile_plan(scene(beta2=0.2), 2, 2)
    # ... and by default when one beta1 value holds 1024 * 512 = 2**19 points > 2**18 per tile
    big = scene(beta1="0:2pi:4", beta2="0:2pi:1024", kappa="log:0.1:10:32", q1="0:1:4", q2="0:1:4")
    assert tile_plan(big) == [(a, a + 1, c, c + 512) for a in range(4) for c in (0, 512)]
    assert tile_plan(big, slab=2) == [(0, 2), (2, 4)]  # an explicit slab alone: beta1 slabs


def test_regions_and_owners_of_a_2d_block():
    """A (beta1, beta2) block covers its ranges of every variable; a variable without beta1
    (stable_FS) is owned by the blocks of the first slab only."""
    split = ranges(True, (4, 8, 3, 6))
    assert split == {"beta1": (4, 8), "beta2": (3, 6)}
    assert region(("beta1", "beta2", "kappa"), split) == {
        "beta1": slice(4, 8),
        "beta2": slice(3, 6),
    }
    assert region(("beta2",), split) == {"beta2": slice(3, 6)}
    assert unique(("beta1", "beta2"), split) and not unique(("beta2",), split)
    assert owns(("beta1", "beta2"), split) and not owns(("beta2",), split)
    assert owns(("beta2",), ranges(True, (0, 4, 3, 6)))
