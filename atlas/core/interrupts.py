"""Whether this process was asked to stop (SIGINT / SIGTERM), for writers that must not commit after.

The ``atlas`` command line records every SIGINT and SIGTERM here (:func:`request`) before it
raises ``KeyboardInterrupt``.  That exception can be lost: raised while Python runs a gc callback
or a ``__del__`` it is only reported ("Exception ignored in ..."), and the run goes on.  So every
writer calls :func:`check` before it makes an output visible (the rename of a temporary file, the
completion mark of a store) and between tiles: after a signal no output is ever committed, and a
long run stops at its next tile.  Outside the command line nothing calls :func:`request`, and
:func:`check` never raises.  Standard library only: cheap to load before anything else.  :func:`exit_during_imports` covers
the seconds the command line spends importing the package, before its own handlers exist.
"""

from __future__ import annotations

import os
import signal
import sys
import threading

__all__ = ["request", "requested", "check", "clear", "exit_during_imports"]

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


def _command_line() -> bool:
    """True in the ``atlas`` console script and ``python -m atlas.cli``."""
    if os.path.basename(sys.argv[0] if sys.argv else "") == "atlas":
        return True
    argv = list(getattr(sys, "orig_argv", []))
    return "-m" in argv[:-1] and argv[argv.index("-m") + 1] == "atlas.cli"


def _exit_now(signum, frame):  # pragma: no cover - ends the process
    os._exit(128 + signum)


def exit_during_imports():
    """In the command line only (main thread): until ``atlas.cli.main`` installs its own handlers,
    SIGINT and SIGTERM end the process at once with ``128 + signal`` -- nothing is written yet,
    and a ``KeyboardInterrupt`` raised inside an import would print a traceback, or be swallowed
    by a gc callback and let the run go on.  Returns the handlers replaced (``None``: none)."""
    if not _command_line() or not _main_thread():
        return None
    return {s: signal.signal(s, _exit_now) for s in (signal.SIGINT, signal.SIGTERM)}


def _main_thread() -> bool:
    return threading.current_thread() is threading.main_thread()
