"""painleve-atlas: atlases of contact-mode consistency and stability for two sliding contacts.

The package is layered; imports go one way (checked by import-linter in CI, see ``pyproject.toml``):
``atlas.core`` (mathematics) <- ``atlas.data`` (scenes, engine, I/O) <- ``atlas.dynamics`` (time)
<- ``atlas.paper`` / ``atlas.explore`` / ``atlas.bench`` <- ``atlas.cli``.
"""

from atlas.core import interrupts as _interrupts

_interrupts.exit_during_imports()  # the command line: a signal before main() just ends it

from atlas.core.config import __version__, enable_x64  # noqa: E402

enable_x64()  # float64 kernels are first-class (SPEC §4)

from atlas import _compat  # noqa: E402
from atlas.core.mechanism import Mechanism as Mechanism  # noqa: E402
from atlas.data.boundaries import boundaries as boundaries  # noqa: E402
from atlas.data.engine import generate as generate  # noqa: E402
from atlas.data.mechanisms import mechanism_atlas as mechanism_atlas  # noqa: E402
from atlas.data.scene import Scene as Scene  # noqa: E402
from atlas.dynamics.simulator import simulate as simulate  # noqa: E402
from atlas.paper.tables import table2 as table2  # noqa: E402

_compat.install()


def __getattr__(name):  # old flat modules as attributes: ``from atlas import tiling``
    return _compat.moved_attribute(name)


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
