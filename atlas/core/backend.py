"""The certified kernels trust a JAX backend only if it has not failed ``atlas selftest``.

Certificates are proven for IEEE arithmetic as the kernels are written; a backend whose compiler
rewrites it (fusion, FMA contraction, approximate division on an accelerator) can break them.
``atlas selftest`` (:mod:`atlas.core.selftest`) compares the kernels with the exact tier on the
hard-case suites and records the result per backend (:func:`key`: platform, device kind, JAX,
jaxlib and package versions) in ``selftest.json`` beside the persistent compilation cache
(:func:`atlas.core.config.compile_cache_dir`).  :func:`require_trusted`, called by the certified
driver :func:`atlas.core.points.spectral_points`, raises :class:`BackendFailed` on a backend whose
last self-check failed.  A backend never checked is trusted (CI checks the CPU); with the cache
switched off (``ATLAS_JAX_CACHE=0``) nothing is recorded or consulted.

The certificates hold for XLA's CPU arithmetic as measured (docs/SPEC.md, "Certification"):
fused multiply-adds, flush-to-zero and denormals-are-zero, division by a constant as a
multiplication by its rounded reciprocal.  They do not hold under the flags of
:data:`UNSAFE_XLA_FLAGS` (fast math reassociates sums: ``(a + b) - a`` becomes ``b``), so
:func:`require_trusted` refuses to certify where ``$XLA_FLAGS`` switches one on.
"""

from __future__ import annotations

import contextlib
import functools
import json
import os
from pathlib import Path

import jax
import jaxlib

from atlas.core import config

__all__ = [
    "BackendFailed",
    "key",
    "record",
    "recorded",
    "require_trusted",
    "checking",
    "unsafe_xla_flags",
]

#: XLA flags that let the compiler rewrite the kernels' arithmetic beyond what the error bounds
#: cover: fast math (reassociation, no NaN or infinity checks) and NaN-dropping min/max
UNSAFE_XLA_FLAGS = ("xla_cpu_enable_fast_math", "xla_cpu_enable_fast_min_max")

#: file name of the per-backend results, in the compilation cache directory
RECORD_NAME = "selftest.json"
_STATE = {"checking": False}


class BackendFailed(RuntimeError):
    """The JAX backend in use failed ``atlas selftest``: no verdict is called certified on it."""


@functools.cache
def key() -> str:
    """The backend as the self-check saw it: platform, device kind and the software versions."""
    dev = jax.devices()[0]
    return (
        f"{dev.platform}:{dev.device_kind} jax {jax.__version__} jaxlib {jaxlib.__version__} "
        f"painleve-atlas {config.__version__}"
    )


def _path() -> Path | None:
    """The record file, or ``None`` with the cache off (found once per cache setting: the
    certified driver asks on every call)."""
    return _path_for(os.environ.get(config.CACHE_ENV), os.environ.get("HOME"))


@functools.lru_cache(maxsize=8)
def _path_for(cache_env: str | None, home: str | None) -> Path | None:
    where = config.compile_cache_dir()
    return None if where is None else Path(where) / RECORD_NAME


@functools.lru_cache(maxsize=4)
def _read(path: str, mtime_ns: int) -> dict:
    try:
        return json.loads(Path(path).read_text())
    except (OSError, ValueError):
        return {}


def _records(path: Path) -> dict:
    """Every backend's record in ``path`` (read again only when the file changed)."""
    try:
        mtime = path.stat().st_mtime_ns
    except OSError:
        return {}
    return _read(str(path), mtime)


def recorded() -> dict | None:
    """The recorded self-check of this backend (``passed``, ``disagreements``, ``points``, ...)."""
    path = _path()
    if path is None:
        return None
    return _records(path).get(key())


def record(result: dict) -> Path | None:
    """Store ``result`` as this backend's self-check (atomically); returns the file, if any."""
    path = _path()
    if path is None:
        return None
    records = dict(_records(path))
    records[key()] = result
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    tmp.write_text(json.dumps(records, indent=1, sort_keys=True))
    os.replace(tmp, path)
    return path


def unsafe_xla_flags(flags: str | None = None) -> tuple[str, ...]:
    """The flags of :data:`UNSAFE_XLA_FLAGS` switched on in ``flags`` (default ``$XLA_FLAGS``;
    ``--name``, ``--name=true`` or any value but ``false`` / ``0``)."""
    return _unsafe(os.environ.get("XLA_FLAGS", "") if flags is None else flags)


@functools.lru_cache(maxsize=8)
def _unsafe(flags: str) -> tuple[str, ...]:
    on = []
    for token in flags.split():
        name, eq, value = token.lstrip("-").partition("=")
        if name in UNSAFE_XLA_FLAGS and (not eq or value.strip().lower() not in ("false", "0")):
            on.append(name)
    return tuple(on)


@contextlib.contextmanager
def checking():
    """While the self-check runs, the kernels run whatever the record says."""
    before, _STATE["checking"] = _STATE["checking"], True
    try:
        yield
    finally:
        _STATE["checking"] = before


def require_trusted() -> None:
    """Raise :class:`BackendFailed` if this backend's last self-check found disagreements, or
    ``$XLA_FLAGS`` switches on a rewrite the certificates do not cover (:func:`unsafe_xla_flags`)."""
    unsafe = unsafe_xla_flags()
    if unsafe:
        raise BackendFailed(
            f"XLA_FLAGS: {', '.join(unsafe)} lets XLA reassociate or drop NaNs, which the certified "
            "kernels' error bounds do not cover; they refuse to run (unset it, or set it to false)"
        )
    if _STATE["checking"]:
        return
    rec = recorded()
    if rec is not None and not rec.get("passed", False):
        raise BackendFailed(
            f"backend: {key()} failed atlas selftest ({rec.get('disagreements')} disagreements "
            f"with the exact tier, {rec.get('when')}); the certified kernels refuse to run on it "
            "(run atlas selftest again after a fix, or use the CPU: JAX_PLATFORMS=cpu)"
        )
