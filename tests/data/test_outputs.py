"""The output registry: every Dataset the package builds takes names, types and attributes from it.

Reference values are the data contract (SPEC §2) and the verdict enumerations, not the registry
itself: a stored ``stable_SF`` is ``True`` iff the verdict is *stable* (neutral stored as False), a
stored Table 1 flag is ``True`` iff consistent, undecided verdict flags are 3 and undecided codes -1.
"""

import itertools
import re
from pathlib import Path

import numpy as np
import pytest

from atlas.core import kernels, verdicts
from atlas.core.verdicts import Consistency, Verdict
from atlas.data import outputs
from atlas.data.engine import generate
from atlas.data.scene import Scene
from atlas.explore.maps import beta_grid, compute_map, layers
from atlas.paper.figures import stability_map

N = 15  # odd: no cell centre on beta2 = beta1 + pi
GRID = beta_grid(N)  # the offset grid of stability_map
ALPHA, KAPPA, Q1, Q2 = 0.7, 0.5, 0.3, 0.1
#: attributes a builder adds to the registry's: run diagnostics and the margin's recipe
EXTRA = {"undecided_fast", "undecided", "comment"}


def _same(a: dict, b: dict) -> bool:
    if a.keys() != b.keys():
        return False
    return all(
        np.array_equal(a[k], b[k]) if isinstance(a[k], np.ndarray) else a[k] == b[k] for k in a
    )


@pytest.fixture(scope="module")
def atlas_full():
    """Every atlas output (alpha and the model varied, so model dependence is defined)."""
    s = Scene(beta1="0:2pi:6", beta2="0:2pi:5", alpha="0.3,1.1", kappa="0.5,2", q="0,0.3")
    return generate(s, tile_points=1024)


@pytest.fixture(scope="module")
def atlas_slice():
    """The atlas on the figure's grid at one model: comparable with the map and the figure."""
    s = Scene(beta1=GRID, beta2=GRID, alpha=ALPHA, kappa=KAPPA, q1=Q1, q2=Q2)
    return generate(s, tile_points=1024)


@pytest.fixture(scope="module")
def explorer_map():
    return compute_map(KAPPA, Q1, Q2, beta=GRID, layers=layers(), alpha=ALPHA)


@pytest.fixture(scope="module")
def figure_map():
    return stability_map(N, KAPPA, Q1, Q2)


def _spec_table() -> list[tuple[str, str]]:
    """``(variable, type)`` rows of the output table of docs/SPEC.md §2, brace patterns expanded
    (``ss_witness_{stable,unstable}_{kappa,q1,q2}``), in the table's order."""
    text = (Path(__file__).resolve().parents[2] / "docs" / "SPEC.md").read_text()
    section = text.split("## 2. Data contract")[1].split("## 3.")[0]
    rows = []
    for line in section.splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) != 3 or cells[0] in ("variable", "---"):
            continue
        for name in re.findall(r"`([^`]+)`", cells[0]):
            parts = [p.split(",") for p in re.split(r"[{}]", name)[1::2]]
            stems = re.split(r"\{[^}]*\}", name)
            for combo in itertools.product(*parts):
                expanded = stems[0] + "".join(
                    c + st for c, st in zip(combo, stems[1:], strict=True)
                )
                rows.append((expanded, cells[2]))
    return rows


def test_spec_table_lists_the_registry():
    """SPEC §2's table names each output of the registry once (display margins aside), each with
    its stored type."""
    rows = _spec_table()
    documented = [n for n in outputs.OUTPUTS if not n.startswith("margin_")]
    assert sorted(n for n, _ in rows) == sorted(documented)
    for name, kind in rows:
        storage = outputs.OUTPUTS[name].storage
        assert kind.split(",")[0].split(":")[0].split()[0].startswith(storage), (name, kind)
    assert set(outputs.atlas_outputs()) <= {n for n, _ in rows}


def test_every_output_appears_with_its_attributes(atlas_full):
    s = Scene(beta1="0:2pi:6", beta2="0:2pi:5", alpha="0.3,1.1", kappa="0.5,2", q="0,0.3")
    assert set(atlas_full.data_vars) == set(outputs.default_outputs())
    for name in outputs.default_outputs():
        v = atlas_full[name]
        reg = outputs.variable_attrs(name)
        assert _same({k: v.attrs[k] for k in reg}, reg), name
        assert set(v.attrs) - set(reg) <= EXTRA, name
        assert v.dims == s.output_dims(name)
        assert v.dtype == outputs.storage_dtype(name, "float64")
    for name, c in atlas_full.coords.items():
        assert dict(c.attrs) == outputs.coord_attrs(name)


def test_flag_attributes_are_cf_consistent():
    for name, o in outputs.OUTPUTS.items():
        a = outputs.variable_attrs(name)
        assert a["long_name"]
        if "flag_values" in a:
            assert len(a["flag_meanings"].split()) == len(a["flag_values"]), name
        if o.undecided is not None and o.storage != "bool":
            # undecided values are stored, so the flags must name them
            i = list(a["flag_values"]).index(o.undecided)
            assert a["flag_meanings"].split()[i] == "undecided", name
        if o.storage == "float":
            assert a["units"] == "1"


def test_undecided_encodings():
    assert verdicts.UNDECIDED_FLAG == int(Verdict.UNDECIDED) == int(Consistency.UNDECIDED) == 3
    assert verdicts.UNDECIDED_CODE == -1
    assert outputs.OUTPUTS["class_code"].undecided == -1
    assert outputs.OUTPUTS["stable_SS"].undecided == 3
    codes = np.array([-1, 0, 11, 46])
    assert outputs.undecided("class_code", codes).tolist() == [True, False, False, False]
    assert not outputs.undecided("stable_SF", np.array([0, 1, 2])).any()


def test_storage_follows_the_contract():
    # SPEC §2: stable_SF bool, True iff stable (neutral b11 = 0 stored as not stable)
    v = np.array([0, 1, 2], np.int8)
    assert outputs.to_storage("stable_SF", v, "float64").tolist() == [False, True, False]
    # Table 1 flags: True iff consistent; an undecided flag (left by resolve=False) is False
    c = np.array([0, 1, 3], np.int8)
    assert outputs.to_storage("consistent_SS", c, "float64").tolist() == [False, True, False]
    assert outputs.to_storage("stable_SS", v, "float64").dtype == np.int8
    assert outputs.to_storage("subclass_code", np.array([466]), "float64").dtype == np.int16
    assert outputs.to_storage("spectral_abscissa", np.zeros(2), "float32").dtype == np.float32


def test_outputs_of_a_kernel_share_its_parameters():
    for name, k in kernels.KERNELS.items():
        for n in outputs.in_kernel(name, atlas_only=False):
            assert outputs.OUTPUTS[n].depends == k.params, n
    for o in outputs.OUTPUTS.values():
        for n in o.needs:
            assert outputs.OUTPUTS[n].kernel == "spectral"


def test_builders_agree_on_shared_variables_and_coords(atlas_slice, explorer_map, figure_map):
    built = {"atlas": atlas_slice, "explorer": explorer_map, "figure": figure_map}
    for a, da in built.items():
        for b, db in built.items():
            if a >= b:
                continue
            shared = set(da.data_vars) & set(db.data_vars)
            assert shared, (a, b)
            for k in shared:
                ka = {x: y for x, y in da[k].attrs.items() if x not in EXTRA}
                kb = {x: y for x, y in db[k].attrs.items() if x not in EXTRA}
                assert _same(ka, kb), (a, b, k)
                assert da[k].dtype == db[k].dtype, (a, b, k)
                assert da[k].dims == db[k].dims, (a, b, k)
            for k in set(da.coords) & set(db.coords):
                assert dict(da[k].attrs) == dict(db[k].attrs), (a, b, k)
    assert {"stable_SF", "class_code", "stable_II"} <= set(figure_map.data_vars)


def test_map_and_figure_equal_the_atlas_slice(atlas_slice, explorer_map, figure_map):
    """The same grid and model give the same stored values, whoever builds the Dataset."""
    for ds in (explorer_map, figure_map):
        for k in set(ds.data_vars) & set(atlas_slice.data_vars):
            np.testing.assert_array_equal(ds[k].values, atlas_slice[k].values, err_msg=k)


def test_display_margins_are_not_atlas_outputs(figure_map, explorer_map):
    for m in ("margin_SS", "margin_II_consistent", "margin_II_stable"):
        assert m not in outputs.atlas_outputs()
        assert m in figure_map
    assert (
        explorer_map["margin_SS"].attrs["long_name"] == figure_map["margin_SS"].attrs["long_name"]
    )


def test_lists_that_name_outputs_agree_with_the_registry():
    """The lists kept outside the registry that name its outputs: the spectral verdicts (the
    results the spectral kernel may leave undecided, in its order) wherever they are spelled out,
    and the layers and lines the explorer and inspector choose, all registered."""
    from atlas.bench import config as bench_config
    from atlas.core import brackets, exact, points, selftest
    from atlas.explore import inspector, maps

    flags = tuple(outputs.kernel_of("stable_SS").undecided)
    assert flags == ("stable_SS", "consistent_II", "stable_II")  # SPEC §2's three verdicts of M
    copies = {
        "points.SPECTRAL_NAMES[:3]": points.SPECTRAL_NAMES[:3],
        "selftest.NAMES": selftest.NAMES,
        "exact._SPECTRAL": exact._SPECTRAL,
        "bench.config.FLAGS": bench_config.FLAGS,
        "brackets.FIELDS": sum(brackets.FIELDS.values(), ()),
        "inspector._FLAGS": inspector._FLAGS,
    }
    assert {k: v for k, v in copies.items() if tuple(v) != flags} == {}
    chosen = {*maps.DEFAULT_LAYERS, *inspector._SHOWN}
    assert chosen <= set(outputs.OUTPUTS), chosen - set(outputs.OUTPUTS)
