"""Process configuration, one copy: the package version, the persistent JAX compilation
cache, and the provenance strings (``source``, ``history``) every written file carries."""

import datetime
import os
import sys
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path

import jax
import numpy as np

try:
    __version__ = version("painleve-atlas")
except PackageNotFoundError:  # pragma: no cover - a source tree without installation
    __version__ = "0+unknown"

#: environment variable naming the persistent compilation cache directory (``0`` or empty: off)
CACHE_ENV = "ATLAS_JAX_CACHE"
#: compilations shorter than this are not worth a cache entry (seconds)
CACHE_MIN_COMPILE_SECONDS = 0.1


def compile_cache_dir() -> str | None:
    """The persistent JAX compilation cache directory (``$ATLAS_JAX_CACHE``, default
    ``~/.cache/painleve-atlas/jax``), created; ``None`` when switched off or not writable."""
    where = os.environ.get(CACHE_ENV, str(Path.home() / ".cache" / "painleve-atlas" / "jax"))
    if where in ("", "0"):
        return None
    try:
        Path(where).mkdir(parents=True, exist_ok=True)
    except OSError:
        return None
    return where


def use_compile_cache(
    where: str | None = None, min_compile_seconds: float = CACHE_MIN_COMPILE_SECONDS
) -> None:
    """Turn the persistent compilation cache on for this process (no-op if already on or off);
    compilations shorter than ``min_compile_seconds`` are not stored."""
    if jax.config.jax_compilation_cache_dir:
        return
    where = where or compile_cache_dir()
    if where is None:
        return
    try:
        jax.config.update("jax_compilation_cache_dir", where)
        jax.config.update("jax_persistent_cache_min_compile_time_secs", min_compile_seconds)
    except AttributeError:  # pragma: no cover - an old JAX: just compile
        pass


def source() -> str:
    """CF ``source``: the software that made a file."""
    try:
        xarray = version("xarray")  # by metadata: this layer does not import xarray
    except PackageNotFoundError:  # pragma: no cover
        xarray = "absent"
    return f"painleve-atlas {__version__} (JAX {jax.__version__}, numpy {np.__version__}, xarray {xarray})"


def history(call: str | None = None) -> str:
    """CF ``history`` entry: UTC time stamp and the call (default: this process's command line)."""
    now = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")
    return f"{now}: {call or ' '.join(sys.argv) or 'python'}"
