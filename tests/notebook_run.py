"""The notebooks as the tests run them: a copy at the smallest sizes that shares the run's
compilation cache (``$ATLAS_JAX_CACHE``, tests/conftest.py)."""

from __future__ import annotations

from pathlib import Path


def prepare_notebook(src: Path, dst: Path, n: int | None = None) -> Path:
    """Write ``src`` to ``dst`` with its ``CI = False`` set to ``CI = True`` (the smallest sizes
    that run every cell) or, with ``n``, the map's ``N = n``; a first cell turns the compilation
    cache on."""
    import nbformat

    nb = nbformat.read(src, as_version=4)
    first = next(c for c in nb.cells if c.cell_type == "code")
    first.source = first.source.replace("CI = False", "CI = True")
    if n is not None:
        first.source += f"\nN = {int(n)}"
    nb.cells.insert(
        0,
        nbformat.v4.new_code_cell(
            "from atlas.core.config import use_compile_cache\n"
            "use_compile_cache(min_compile_seconds=0.0)"
        ),
    )
    nbformat.write(nb, dst)
    return dst
