"""painleve-atlas: atlases of contact-mode consistency and stability for two sliding contacts.

The package is layered; imports go one way (checked by import-linter in CI, see ``pyproject.toml``):
``atlas.core`` (mathematics) <- ``atlas.data`` (scenes, engine, I/O) <- ``atlas.dynamics`` (time)
<- ``atlas.paper`` / ``atlas.explore`` / ``atlas.bench`` <- ``atlas.cli``.

``import atlas`` is cheap: the public names below and the layers are attached lazily (PEP 562,
the scientific-Python ``lazy_loader`` convention), so JAX, xarray, scipy and matplotlib load when
a name that needs them is first used.  float64 is switched on for JAX here all the same (SPEC §4):
directly if JAX is loaded, else through ``JAX_ENABLE_X64``, which JAX reads when it is imported.
"""

import os
import sys

from atlas.core import interrupts as _interrupts

_interrupts.exit_during_imports()  # the command line: a signal before main() just ends it

import lazy_loader  # noqa: E402


def _enable_x64() -> None:
    """float64 kernels are first-class (SPEC §4); float32 is chosen per call."""
    jax = sys.modules.get("jax")
    if jax is not None and hasattr(jax, "config"):
        jax.config.update("jax_enable_x64", True)
    else:
        os.environ["JAX_ENABLE_X64"] = "1"


_enable_x64()

__getattr__, __dir__, _ = lazy_loader.attach(
    __name__,
    submodules=["core", "data", "dynamics", "paper", "explore", "bench", "cli"],
    submod_attrs={
        "core.config": ["__version__"],
        "core.rigid_body": ["Mechanism"],
        "data.boundaries": ["boundaries"],
        "data.engine": ["generate"],
        "data.body_atlas": ["mechanism_atlas"],
        "data.scene": ["Scene"],
        "dynamics.simulator": ["simulate"],
        "paper.tables": ["table2"],
    },
)

__all__ = [
    "Mechanism",
    "Scene",
    "boundaries",
    "generate",
    "mechanism_atlas",
    "simulate",
    "table2",
    "__version__",
]
