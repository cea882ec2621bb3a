"""painleve-atlas: atlases of contact-mode consistency and stability for two sliding contacts."""

import jax as _jax

_jax.config.update("jax_enable_x64", True)  # float64 kernels are first-class (SPEC §4)

from importlib.metadata import PackageNotFoundError as _PNF  # noqa: E402
from importlib.metadata import version as _version  # noqa: E402

try:
    __version__ = _version("painleve-atlas")
except _PNF:  # pragma: no cover - running from a source tree without installation
    __version__ = "0+unknown"

from .dynamics import simulate as simulate  # noqa: E402
from .scene import Scene as Scene  # noqa: E402
from .tables import table2 as table2  # noqa: E402
from .tiling import generate as generate  # noqa: E402

__all__ = ["Scene", "generate", "simulate", "table2", "__version__"]
