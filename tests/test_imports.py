"""Imports cost what is used: ``import atlas`` and ``atlas --help`` load no heavy library (measured
in a fresh interpreter with ``-X importtime``), and the lazy names still resolve."""

import os
import subprocess
import sys

import pytest

#: libraries ``import atlas`` must not load (JAX: ~1 s; the others come with xarray and the figures)
HEAVY = ("jax", "matplotlib", "scipy", "xarray", "pandas", "flint", "mpmath", "netCDF4")


def _imported(*args: str) -> set[str]:
    """Top-level names of the modules a fresh interpreter imports running ``python -X importtime
    ARGS`` (the importtime lines on stderr: ``import time: self | cumulative | name``)."""
    p = subprocess.run(
        [sys.executable, "-X", "importtime", *args], capture_output=True, text=True, timeout=120
    )
    assert p.returncode == 0, p.stderr[-2000:]
    names = set()
    for line in p.stderr.splitlines():
        if line.startswith("import time:") and "|" in line:
            names.add(line.rsplit("|", 1)[1].strip().split(".")[0])
    assert "atlas" in names or "-m" in args  # the parsing saw the package itself
    return names


def test_import_atlas_loads_no_heavy_library():
    names = _imported("-c", "import atlas")
    assert "atlas" in names
    assert not names & set(HEAVY), sorted(names & set(HEAVY))


def test_help_loads_no_heavy_library():
    names = _imported("-m", "atlas.cli", "--help")
    assert not names & set(HEAVY), sorted(names & set(HEAVY))


def test_generate_to_netcdf_loads_no_xarray():
    """``atlas generate`` streams tiles into netCDF4 directly: its modules (the writer, the size
    estimate, the option parser, the command itself) load neither xarray nor pandas (~0.5-1.3 s of
    a warm run); only ``--scheduler``/``--store`` runs load the tile store and its xarray."""
    code = (
        "import atlas.data.io, atlas.data.limits, atlas.data.generate_cli, atlas.cli as c;"
        " c.build_parser('generate')"
    )
    names = _imported("-c", code)
    assert not names & {"xarray", "pandas", "matplotlib"}, sorted(names & {"xarray", "pandas"})


def test_the_importtime_check_can_fail():
    """The same parsing sees a heavy library where it is imported (so the tests above can fail):
    mpmath, a tenth of JAX's import."""
    assert {"mpmath", "atlas"} <= _imported("-c", "import atlas, mpmath")


@pytest.mark.parametrize(
    "name, module",
    [
        ("generate", "atlas.data.engine"),
        ("Scene", "atlas.data.scene"),
        ("table2", "atlas.paper.tables"),
        ("Mechanism", "atlas.core.rigid_body"),
        ("simulate", "atlas.dynamics.simulator"),
    ],
)
def test_lazy_names_resolve(name, module):
    import atlas

    assert getattr(atlas, name).__module__ == module
    assert name in dir(atlas) and name in atlas.__all__


@pytest.mark.parametrize(
    "code", ["import atlas, jax.numpy as jnp", "import jax.numpy as jnp, atlas"]
)
def test_float64_is_on_whether_jax_comes_first_or_later(code):
    """``import atlas`` turns float64 on before JAX is imported and after (a fresh interpreter:
    this test process has it on already)."""
    env = {k: v for k, v in os.environ.items() if k != "JAX_ENABLE_X64"}
    check = f"{code}; assert jnp.asarray(1.0).dtype == jnp.float64"
    subprocess.run([sys.executable, "-c", check], check=True, env=env, timeout=120)
