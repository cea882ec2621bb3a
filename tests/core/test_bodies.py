"""The body registry (atlas.core.bodies): a body is one declaration, checked when it is made."""

import pytest

from atlas.core import bodies
from atlas.core.bodies import Axis, Body, Param
from atlas.core.rigid_body import Mechanism


def _block(*, width=0.4, height=0.2, m=2.0, mu=0.5):
    a, c = width / 2, height / 2
    return dict(
        m=m, I=m * (width**2 + height**2) / 12, r1=(-a, -c), r2=(a, -c), n1=(0.0, 1.0),
        n2=(0.0, 1.0), mu1=mu, mu2=mu, s1=1,
    )  # fmt: skip


PARAMS = {
    "width": Param("m", "width of the block", 0.0, open_low=True),
    "height": Param("m", "height of the block", 0.0, open_low=True),
    "m": Param("kg", "mass", 0.0, open_low=True),
    "mu": Param("1", "friction coefficient at both corners", 0.0),
}
AXES = {"mu": Axis("0:1:3", "1", "friction coefficient (both corners)", ("mu",))}


def block(**changes) -> Body:
    """A block sliding on its two bottom corners, in one declaration."""
    fields = dict(
        name="block_test", geometry=_block, params=PARAMS, axes=AXES,
        description="a block sliding on its two bottom corners",
    )  # fmt: skip
    return Body(**{**fields, **changes})


@pytest.mark.parametrize(
    "changes, match",
    [
        (dict(params={**PARAMS, "height": Param("", "height")}), "params: .*'height' needs units"),
        (dict(params={k: v for k, v in PARAMS.items() if k != "m"}), "params: .*'m' needs units"),
        (dict(params={**PARAMS, "depth": PARAMS["width"]}), "params: .*'depth', not a geometry"),
        (dict(name="ladder"), "name: body 'ladder' is already registered"),
        (dict(axes={"mu": Axis("0:1:3", "m", "x", ("mu",))}), "axes: .*'mu' in 'm' sets other"),
        (dict(axes={"mu": Axis("0:1:3", "1", "x", ("nu",))}), "axes: .* unknown parameters"),
        (dict(axes={"k1": Axis("0:1:3", "1", "x", ("mu",))}), "axes: .*'k1' is not a free name"),
        (dict(geometry=lambda *, width=0.4: {}), "params: .*declares 'height', not a geometry"),
        (dict(params={**PARAMS, "mu": Param("1", "friction", 1.0)}), "geometry: .* defaults: mu"),
        (dict(description=" "), "description: "),
    ],
)
def test_a_bad_body_fails_when_declared_in_one_line(changes, match):
    with pytest.raises(ValueError, match=match) as e:
        bodies.register(block(**changes))
    assert "\n" not in str(e.value)
    assert "block_test" not in bodies.BODIES


def test_a_body_declared_once_is_a_mechanism_constructor():
    bodies.register(block())
    try:
        b = Mechanism.block_test(mu=0.3, height=0.3, c1=5.0)
        assert (b.name, b.mu1, b.mu2, b.c1) == ("block_test", 0.3, 0.3, 5.0)
        assert b.r1 == (-0.2, -0.15) and b.I == pytest.approx(2.0 * (0.16 + 0.09) / 12)
        with pytest.raises(ValueError, match=r"^mu: must be >= 0, got -1"):
            Mechanism.block_test(mu=-1.0)
        assert "block_test" in dir(Mechanism)
    finally:
        bodies.unregister("block_test")
    with pytest.raises(AttributeError):
        Mechanism.block_test  # noqa: B018
