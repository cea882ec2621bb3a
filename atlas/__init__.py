"""painleve-atlas: atlases of contact-mode consistency and stability for two sliding contacts."""

import jax as _jax

_jax.config.update("jax_enable_x64", True)  # float64 kernels are first-class (SPEC §4)

from importlib.metadata import PackageNotFoundError as _PNF  # noqa: E402
from importlib.metadata import version as _version  # noqa: E402

try:
    __version__ = _version("painleve-atlas")
except _PNF:  # pragma: no cover - running from a source tree without installation
    __version__ = "0+unknown"
