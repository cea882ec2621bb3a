"""Old flat import paths (``atlas.mechanics``, ``atlas.tiling``, ...) for one release.

Version 0.2 moved the modules into layers (``atlas.core``, ``atlas.data``, ``atlas.dynamics``,
``atlas.paper``, ``atlas.explore``, ``atlas.bench``).  ``import atlas.tiling`` still works: this finder
returns the moved module itself (the same object, so monkeypatching either name is the same), after a
``DeprecationWarning`` naming the new path.  Removed in 0.3.
"""

import importlib
import importlib.machinery
import sys
import warnings

MOVED = {
    "atlas.verdicts": "atlas.core.verdicts",
    "atlas.mechanics": "atlas.core.mechanics",
    "atlas.spectral": "atlas.core.spectral",
    "atlas.rootfree": "atlas.core.rootfree",
    "atlas.exact": "atlas.core.exact",
    "atlas.evaluate": "atlas.core.points",
    "atlas.hardcases": "atlas.core.hardcases",
    "atlas.scene": "atlas.data.scene",
    "atlas.tiling": "atlas.data.engine",
    "atlas.io": "atlas.data.io",
    "atlas.distributed": "atlas.data.distributed",
    "atlas.dynamics_jax": "atlas.dynamics.jax_engine",
    "atlas.figures": "atlas.paper.figures",
    "atlas.figures_dynamics": "atlas.paper.figures_dynamics",
    "atlas.tables": "atlas.paper.tables",
    "atlas.audit": "atlas.paper.audit",
}


class _Alias:
    """A meta path finder and loader (the protocol of ``importlib.abc.MetaPathFinder`` and
    ``Loader``, without importing ``importlib.abc``, which costs ``import atlas`` 0.1 s)."""

    def find_spec(self, fullname, path=None, target=None):
        if fullname in MOVED:
            return importlib.machinery.ModuleSpec(fullname, self)
        return None

    def create_module(self, spec):
        warnings.warn(
            f"{spec.name} moved to {MOVED[spec.name]}; the old path goes in painleve-atlas 0.3",
            DeprecationWarning,
            stacklevel=2,
        )
        return importlib.import_module(MOVED[spec.name])

    def exec_module(self, module):
        pass


def install() -> None:
    """Put the alias finder on ``sys.meta_path`` (once)."""
    if not any(isinstance(f, _Alias) for f in sys.meta_path):
        sys.meta_path.insert(0, _Alias())


def moved_attribute(name: str):
    """``atlas.<old name>`` as an attribute (``from atlas import tiling``)."""
    full = f"atlas.{name}"
    if full not in MOVED:
        raise AttributeError(f"module 'atlas' has no attribute {name!r}")
    return importlib.import_module(full)
