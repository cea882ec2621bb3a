"""Whether this process was asked to stop (SIGINT / SIGTERM), for writers that must not commit after.

The ``atlas`` command line records every SIGINT and SIGTERM here (:func:`request`) before it
raises ``KeyboardInterrupt``.  That exception can be lost: raised while Python runs a gc callback
or a ``__del__`` it is only reported ("Exception ignored in ..."), and the run goes on.  So every
writer calls :func:`check` before it makes an output visible (the rename of a temporary file, the
completion mark of a store) and between tiles: after a signal no output is ever committed, and a
long run stops at its next tile.  Outside the command line nothing calls :func:`request`, and
:func:`check` never raises.  No imports: cheap to load before anything else.
"""

from __future__ import annotations

__all__ = ["request", "requested", "check", "clear"]

_signum: int | None = None


def request(signum: int) -> None:
    """Record that signal ``signum`` asked the process to stop (the first one is kept)."""
    global _signum
    if _signum is None:
        _signum = int(signum)


def requested() -> int | None:
    """The first stop signal received, or ``None``."""
    return _signum


def check() -> None:
    """Raise ``KeyboardInterrupt`` if a stop signal was received (call before any commit)."""
    if _signum is not None:
        raise KeyboardInterrupt


def clear() -> None:
    """Forget a received signal (for a new run in the same process)."""
    global _signum
    _signum = None
