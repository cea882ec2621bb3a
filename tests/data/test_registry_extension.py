"""A new output is its kernel plus one registry entry: it then appears in ``atlas generate``, in the
atlas Dataset, in the mechanism verdicts, in the Fig. 1 map, as an explorer layer and in the point
inspector.

The dummy output ``aligned_b1b2`` is ``True`` iff ``b1 . b2 > 0``; its reference is the closed form
``cos(beta1 - beta2) > 0`` evaluated in numpy on cells away from the ties (not the kernel).
"""

import jax.numpy as jnp
import numpy as np
import pytest
import xarray as xr

from atlas import cli
from atlas.core import kernels, rigid_body
from atlas.core.verdicts import Codes
from atlas.data import outputs
from atlas.data.engine import generate
from atlas.data.scene import Scene
from atlas.explore import colors, inspector, maps, state
from atlas.paper.figures import stability_map

NAME = "aligned_b1b2"


def _aligned(c1, s1, c2, s2):
    return {NAME: (c1 * c2 + s1 * s2 > 0).astype(jnp.int8)}


def _declare():
    kern = kernels.PointKernel(
        "aligned", ("beta1", "beta2"), (NAME,), _aligned, true_code={NAME: 1}
    )
    out = outputs.Output(
        NAME,
        ("beta1", "beta2"),
        "bool",
        {"long_name": "b1 and b2 point into the same half-plane"},
        kernel="aligned",
        codes=Codes("Aligned", ((0, "opposed"), (1, "aligned"))),
        default=True,
    )
    return kern, out


@pytest.fixture
def dummy():
    kern, out = _declare()
    kernels.register(kern)
    try:
        yield outputs.register(out)
    finally:
        outputs.OUTPUTS.pop(NAME, None)
        kernels.unregister("aligned")


def _reference(beta1, beta2):
    return np.cos(np.subtract.outer(beta1, beta2)) > 0


def test_a_new_output_reaches_every_builder(dummy, tmp_path):
    grid = maps.beta_grid(7)  # odd: no centre on beta2 = beta1 +- pi/2 or on the axes
    want = _reference(grid, grid)
    path = tmp_path / "a.nc"
    rc = cli.main(
        ["generate", "--beta1", ",".join(str(float(b)) for b in grid), "--beta2", ",".join(str(float(b)) for b in grid),
         "--outputs", f"class_code,{NAME}", "--out", str(path), "--no-progress"]
    )  # fmt: skip
    assert rc == 0
    with xr.open_dataset(path) as ds:
        np.testing.assert_array_equal(ds[NAME].values, want)
        assert ds[NAME].attrs["long_name"] == dummy.attrs["long_name"]
        assert ds[NAME].attrs["flag_meanings"] == "opposed aligned"

    atlas = generate(Scene(beta1=grid, beta2=grid, alpha=0.3, kappa="0.5,2"))
    assert NAME in atlas and atlas[NAME].dims == ("beta1", "beta2")
    np.testing.assert_array_equal(atlas[NAME].values, want)

    assert NAME in rigid_body.verdict_names() and NAME in outputs.verdict_outputs()
    at = rigid_body.verdicts_at(grid[:, None], grid[None, :], 0.3, 0.5, 0.0, 0.0, names=(NAME,))
    np.testing.assert_array_equal(at[NAME], want)

    np.testing.assert_array_equal(stability_map(7, margins=False)[NAME].values, want)

    assert NAME in maps.layers() and (NAME,) in maps.layer_groups()
    ex = state.Explorer(n=7, layer=NAME, overlays=())
    np.testing.assert_array_equal(ex.update()[NAME].values, want)
    assert ex.image().shape == (7, 7, 4)
    assert [label for _, label in colors.legend_entries(NAME)] == ["false", "true"]

    info = inspector.inspect_point(grid[1], grid[4])
    assert info["others"] == {NAME: want[1, 4]}
    assert f"{NAME}: {'true' if want[1, 4] else 'false'}" in inspector.format_inspection(info)


def test_outputs_without_a_kernel_are_refused_as_layers():
    for name in ("margin_II_stable", "model_dependent_SS"):
        with pytest.raises(ValueError, match=f"layer: {name} is not a map layer"):
            state.Explorer(n=5, layer=name, overlays=()).update()
        with pytest.raises(ValueError, match="layers: .* no point kernel"):
            maps.compute_map(n=5, layers=(name,))


def _bad(**changes):
    kern, out = _declare()
    fields = {**out.__dict__, **changes}
    return outputs.Output(**fields)


@pytest.mark.parametrize(
    "changes, match",
    [
        (dict(kernel="nope"), "kernel: .* unknown kernel 'nope'"),
        (dict(kernel="b1b2"), "kernel: .* is not a result of kernel 'b1b2'"),
        (dict(kernel=None), "kernel: .* exactly one of"),
        (dict(depends=("beta1", "beta2", "alpha")), "depends: .* parameters of kernel"),
        (dict(depends=("gamma",)), "depends: "),
        (dict(storage="int8"), "storage: .* boolean iff"),
        (dict(storage="complex"), "storage: "),
        (dict(attrs={"units": "1"}), "attrs: .* long_name"),
        (dict(codes=None), "codes: .* needs its codes"),
        (dict(codes=Codes("A", ((0, "no"), (2, "yes")))), "codes: .* boolean, its codes are 0 and 1"),
        (dict(default=True, in_atlas=False, kernel="aligned"), "default: .* atlas output"),
        (dict(name="two words"), "name: "),
    ],
)
def test_an_incomplete_output_fails_at_declaration(changes, match):
    kernels.register(_declare()[0])
    try:
        with pytest.raises(ValueError, match=match):
            outputs.register(_bad(**changes))
        assert NAME not in outputs.OUTPUTS
    finally:
        kernels.unregister("aligned")


def test_a_registered_name_cannot_be_declared_twice():
    with pytest.raises(ValueError, match="name: output 'class_code' is already registered"):
        outputs.register(outputs.OUTPUTS["class_code"])
