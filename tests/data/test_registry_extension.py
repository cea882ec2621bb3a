"""A new output is its kernel plus one registry entry: it then appears in ``atlas generate``, in the
atlas Dataset, in the mechanism verdicts, in the Fig. 1 map, as an explorer layer and in the point
inspector.

The dummy output ``aligned_b1b2`` is ``True`` iff ``b1 . b2 > 0``; its reference is the closed form
``cos(beta1 - beta2) > 0`` evaluated in numpy on cells away from the ties (not the kernel).
"""

import dataclasses
from fractions import Fraction

import jax.numpy as jnp
import numpy as np
import pytest
import xarray as xr

from atlas import cli
from atlas.core import bodies, kernels, rigid_body
from atlas.core.contact_modes import direction
from atlas.core.verdicts import Code, Codes
from atlas.data import outputs
from atlas.data.engine import generate
from atlas.data.scene import Scene
from atlas.explore import colors, inspector, maps, state
from atlas.paper.figures import stability_map
from tests.core import test_bodies

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
        (
            dict(codes=Codes("A", ((0, "no"), (2, "yes")))),
            "codes: .* boolean, its codes are 0 and 1",
        ),
        (dict(default=True, in_atlas=False, kernel="aligned"), "default: .* atlas output"),
        (dict(name="two words"), "name: "),
        (dict(raw=Codes("R", ((0, "no"), (2, "yes")))), "raw: .* disagree with kernel"),
        (dict(raw=Codes("R", ((0, "no"), (1, "yes"))), kernel=None, computed_by="x.y"), "raw: "),
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


# --- a three-valued sign, declared at run time in one declaration --------------------------------

SIGN = "det_B_sign_test"
SIGN_CODES = Codes(
    "DetBSign",
    ((-1, "negative"), (0, "zero"), (1, "positive"), (2, "undecided")),
    undecided=2,
)


def _det_sign(c1, s1, c2, s2):
    """sign det B with a crude float bound: rounding-level determinants are left undecided (2)."""
    det = c1 * s2 - s1 * c2
    bound = 8 * jnp.finfo(det.dtype).eps * (jnp.abs(c1 * s2) + jnp.abs(s1 * c2))
    return {SIGN: jnp.where(det > bound, 1, jnp.where(det < -bound, -1, 2)).astype(jnp.int8)}


def _det_sign_exact(c1, s1, c2, s2):
    d = Fraction(c1) * Fraction(s2) - Fraction(s1) * Fraction(c2)
    return {SIGN: (d > 0) - (d < 0)}


def _sign_output(**changes) -> outputs.Output:
    kern = kernels.PointKernel(
        "det_b_test", ("beta1", "beta2"), (SIGN,), _det_sign, undecided={SIGN: 2},
        exact=_det_sign_exact,
    )  # fmt: skip
    fields = dict(
        name=SIGN,
        depends=("beta1", "beta2"),
        storage="int8",
        attrs={"long_name": "certified sign of det B"},
        kernel=kern,
        codes=SIGN_CODES,
        default=True,
    )
    return outputs.Output(**{**fields, **changes})


@pytest.fixture
def sign():
    out = outputs.register(_sign_output())
    try:
        yield out
    finally:
        outputs.unregister(SIGN)
    assert "det_b_test" not in kernels.KERNELS


def _exact_sign(beta1, beta2):
    """The sign of det B = sin(beta2 - beta1) of the rounded directions: the closed form away from
    the ties, exact rational arithmetic on the same floats on them."""
    c1, s1 = (np.asarray(x) for x in direction(beta1[:, None], np.float64))
    c2, s2 = (np.asarray(x) for x in direction(beta2[None, :], np.float64))
    d = np.sin(np.subtract.outer(beta2, beta1)).T
    out = np.sign(d).astype(np.int8)
    for i, j in zip(*np.nonzero(np.abs(d) < 1e-9)):
        c1i, s1i, c2j, s2j = (Fraction(float(x)) for x in (c1[i, 0], s1[i, 0], c2[0, j], s2[0, j]))
        e = c1i * s2j - s1i * c2j
        out[i, j] = (e > 0) - (e < 0)
    return out


def test_a_sign_output_reaches_generate_mechanism_explorer_and_inspector(sign, tmp_path):
    grid = np.arange(8) * (np.pi / 4)  # ties: beta2 = beta1 and beta2 = beta1 + pi
    want = _exact_sign(grid, grid)
    raw = kernels.run(kernels.KERNELS["det_b_test"], _dirs(grid))[SIGN]
    assert (raw == 2).sum() >= 8 and (want == -1).any()  # the exact reference has work to do
    path = tmp_path / "s.nc"
    values = ",".join(repr(float(b)) for b in grid)
    rc = cli.main(
        ["generate", "--beta1", values, "--beta2", values, "--outputs", SIGN, "--out", str(path),
         "--no-progress"]
    )  # fmt: skip
    assert rc == 0
    with xr.open_dataset(path) as ds:
        np.testing.assert_array_equal(ds[SIGN].values, want)
        assert ds[SIGN].dtype == np.int8
        assert ds[SIGN].attrs["flag_values"].tolist() == [-1, 0, 1, 2]
        assert ds[SIGN].attrs["flag_meanings"] == "negative zero positive undecided"

    assert [lbl for _, lbl in colors.legend_entries(SIGN)] == [
        "negative", "zero", "positive", "undecided"
    ]  # fmt: skip
    assert colors.value_label(SIGN, -1) == "negative"  # not 'undecided'
    ex = state.Explorer(n=7, layer=SIGN, overlays=())
    odd = maps.beta_grid(7)
    np.testing.assert_array_equal(ex.update()[SIGN].values, _exact_sign(odd, odd))
    assert ex.image().shape == (7, 7, 4)
    assert [lbl for _, lbl in colors.legend_entries(SIGN, ex.ds)] == [
        "negative",
        "zero",
        "positive",
    ]
    assert len(set(c for c, _ in colors.legend_entries(SIGN))) == 4

    i, j = 1, 6  # det B = sin(5 pi / 4) < 0
    info = inspector.inspect_point(grid[i], grid[j])
    assert info["others"][SIGN] == want[i, j] == -1
    assert f"{SIGN}: negative" in inspector.format_inspection(info)

    mech = tmp_path / "m.nc"
    rc = cli.main(
        ["mechanism", "ladder", "--theta", "0.1pi:0.4pi:4", "--mu", "0:2:3", "--out", str(mech)]
    )  # fmt: skip
    assert rc == 0
    with xr.open_dataset(mech) as ds:
        det = ds.b11 * ds.b22 - ds.b12 * ds.b21
        np.testing.assert_array_equal(ds[SIGN].values, np.sign(det.values))
        assert ds[SIGN].attrs["flag_meanings"] == "negative zero positive undecided"


def _dirs(grid):
    c1, s1 = direction(grid[:, None], np.float64)
    c2, s2 = direction(grid[None, :], np.float64)
    return {"c1": c1, "s1": s1, "c2": c2, "s2": s2}


@pytest.mark.parametrize(
    "make, match",
    [
        (lambda: Codes("S", ((-1, "negative"), (0, ""), (1, "positive"))), "meaning: .* value 0"),
        (lambda: Codes("S", ((-1, "neg"), (1, "pos")), undecided=2), "undecided: .* no value"),
        (lambda: _sign_output(storage="float", codes=None), "attrs: .* needs units"),
        (lambda: _sign_output(codes=None), "codes: .* needs its codes"),
        (lambda: _sign_output(codes=Codes("S", ((-1, "n"), (0, "z"), (1, "p")))), "undecided: "),
        (lambda: _sign_output(name="class_code"), "name: output 'class_code' is already"),
    ],
)
def test_a_bad_declaration_fails_when_made_in_one_line(make, match):
    with pytest.raises(ValueError, match=match) as e:
        outputs.register(make())
    assert "\n" not in str(e.value)
    assert SIGN not in outputs.OUTPUTS and "det_b_test" not in kernels.KERNELS


# --- a made-up body, declared at run time in one declaration --------------------------------------


@pytest.fixture
def block():
    body = bodies.register(test_bodies.block())
    try:
        yield body
    finally:
        bodies.unregister(body.name)


def test_a_body_and_an_output_reach_atlas_mechanism(block, sign, tmp_path, capsys):
    """``atlas mechanism block_test``: B by the closed form of a block on its two bottom corners
    sliding along +x (``w_j = (-mu, 1)``, ``r_j = (-+a, -c)``), every parameter stored with its
    declared units, the sign output's flags and values."""
    sub = cli.build_parser("mechanism")._subparsers._group_actions[0].choices["mechanism"]
    for name in bodies.BODIES:  # every body a choice, with its axes and fixed parameters
        assert f"{name} ({bodies.BODIES[name].description})" in " ".join(sub.format_help().split())
    path = tmp_path / "b.nc"
    rc = cli.main(
        ["mechanism", "block_test", "--mu", "0:1.2:4", "--fixed", "height=0.3,k1=2e5",
         "--out", str(path)]
    )  # fmt: skip
    assert rc == 0
    mu = np.linspace(0, 1.2, 4)
    a, c, m = 0.2, 0.15, 2.0
    inertia = m * (0.4**2 + 0.3**2) / 12
    b11 = 1 / m + a * (a + c * mu) / inertia  # (r1 x n)(r1 x w1) / I, r1 x n = -a
    b12 = 1 / m - a * (a - c * mu) / inertia  # (r1 x n)(r2 x w2) / I, r2 x w2 = a - c mu
    with xr.open_dataset(path) as ds:
        np.testing.assert_allclose(ds.b11.values, b11, rtol=1e-13)
        np.testing.assert_allclose(ds.b12.values, b12, rtol=1e-13)
        assert ds.mu.attrs == {"units": "1", "long_name": "friction coefficient (both corners)"}
        assert float(ds.height) == 0.3 and ds.height.attrs["units"] == "m"
        assert ds.width.attrs == {"units": "m", "long_name": "width of the block"}
        assert ds.k1.attrs["units"] == "N m-1" and float(ds.k1) == 2e5
        det = ds.b11 * ds.b22 - ds.b12 * ds.b21
        np.testing.assert_array_equal(ds[SIGN].values, np.sign(det.values))
        assert ds[SIGN].attrs["flag_meanings"] == "negative zero positive undecided"
    assert "block_test" in capsys.readouterr().out


def test_a_new_output_joins_the_defaults_only_by_saying_so():
    """Without ``default=True`` a new output is computed when asked for, and the default set (the
    scenes without outputs, the Fig. 1 map, the mechanism files, the inspector) stays as it was."""
    from atlas.paper.figures import map_outputs

    before = (outputs.default_outputs(), map_outputs(), outputs.verdict_outputs())
    outputs.register(_sign_output(default=False))
    try:
        assert (outputs.default_outputs(), map_outputs(), outputs.verdict_outputs()) == before
        assert SIGN not in Scene(beta1="0:2pi:4", beta2="0:2pi:4").output_names
        assert Scene(beta1="0:2pi:4", beta2="0:2pi:4", outputs=SIGN).output_names == (SIGN,)
        assert SIGN in outputs.atlas_outputs() and SIGN in maps.layers()
    finally:
        outputs.unregister(SIGN)


# --- the class codes declared anew: the explorer's key and the inspector follow ------------------


def test_a_class_declaration_reaches_the_explorer_key_and_the_inspector(monkeypatch):
    """``class_code`` declared again with other words, a new colour for class 13 and a made-up
    class 51 without a colour, and ``stable_SF``'s raw codes with another word for neutral: the
    explorer's key and the inspector say what is declared (nothing in ``atlas/explore`` edited).
    At ``beta1 = pi/2`` the direction is the exact axis vector: ``c1 = 0``, ``b11 = 0``, SF
    neutral."""
    cls = outputs.OUTPUTS["class_code"]
    codes = [
        dataclasses.replace(c, label=c.label.replace("class", "Klasse"))
        if c.value != 13
        else dataclasses.replace(c, label="Klasse 13", color="#010203")
        for c in cls.codes.codes
    ]
    made_up = Codes("ClassCode", (*codes, Code(51, "class_51", "Klasse 51")), undecided=-1)
    monkeypatch.setitem(outputs.OUTPUTS, "class_code", dataclasses.replace(cls, codes=made_up))
    sf = outputs.OUTPUTS["stable_SF"]
    raw = Codes(
        "SF", tuple(dataclasses.replace(c, label="marginal") if c.value == 2 else c
                    for c in sf.raw.codes), undecided=sf.raw.undecided,
    )  # fmt: skip
    monkeypatch.setitem(outputs.OUTPUTS, "stable_SF", dataclasses.replace(sf, raw=raw))

    key = colors.legend_entries("class_code")
    assert [lbl for _, lbl in key][:3] == ["undecided", "degenerate", "Klasse 11"]
    assert key[-1][1] == "Klasse 51" and ("#010203", "Klasse 13") in key
    assert len({c for c, _ in key}) == len(key)  # the made-up class has a colour of its own

    # class 13: c1 > 0, s2 > 0, s1 c2 < 0 (beta1 = 0.3, beta2 = 2: cos 2 < 0 < sin 0.3)
    text = inspector.format_inspection(inspector.inspect_point(0.3, 2.0))
    assert text.splitlines()[2].startswith("class_code: Klasse 13 (exact 13)")
    text = inspector.format_inspection(inspector.inspect_point(np.pi / 2, 2.0))
    assert "SF: marginal (b11 = +0)" in text


def test_the_class_colours_are_declared_once():
    """The explorer draws each class in the colour the classification module declares."""
    from atlas.core import contact_modes

    key = dict((lbl, c) for c, lbl in colors.legend_entries("class_code"))
    assert len(contact_modes.CLASS_COLORS) == 24
    for code, color in contact_modes.CLASS_COLORS.items():
        assert key[f"class {code}"] == color
