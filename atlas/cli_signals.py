"""Stop signals of the ``atlas`` command line (:func:`atlas.cli.main` installs and removes them).

SIGINT and SIGTERM are recorded in atlas.core.interrupts and raised as KeyboardInterrupt, so every
writer removes its temporary files as on Ctrl-C; the run exits 128 + the signal number (130 for
SIGINT, 143 for SIGTERM).  The KeyboardInterrupt can be lost (raised inside a gc callback it is
only reported), so: the writers check the record before every commit and between tiles
(no output is committed after a signal), a swallowed KeyboardInterrupt is raised again at once
(sys.unraisablehook) and, as a last resort, an alarm raises it again every SIGNAL_REPEAT seconds
until main() has caught it.  main() cancels the alarm on every way out.  A run that received a
signal never exits 0, even when its outputs were complete before the signal came.  The console
script ends with os._exit after flushing (no interpreter teardown under XLA threads, where a late
signal could still kill the process); from then on a signal ends the process at once with 128 +
its number.
"""

from __future__ import annotations

import os
import signal
import sys
import threading

from atlas.core import interrupts

__all__ = ["install", "restore", "hard_exit", "signal_code", "state", "arm"]

#: seconds after which a stop signal that did not end the run is raised again
SIGNAL_REPEAT = 5.0
#: seconds after which a KeyboardInterrupt swallowed by a gc callback is raised again
SIGNAL_RETRY = 0.02
_STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM)
_ALARM = getattr(signal, "SIGALRM", None)
state = {"exit_now": False}


def arm(seconds: float) -> None:
    if _ALARM is not None:
        signal.setitimer(signal.ITIMER_REAL, seconds)


def importing(frame) -> bool:
    """Whether ``frame`` runs inside an import: a KeyboardInterrupt raised there can surface as
    an extension module's ``ImportError`` with a printed traceback (numpy's does), so the
    signal is raised once the import has finished."""
    while frame is not None:
        if frame.f_code.co_filename.startswith("<frozen importlib"):
            return True
        frame = frame.f_back
    return False


def on_signal(signum, frame):
    """SIGINT / SIGTERM: record it; the first one raises KeyboardInterrupt (later ones are
    delivered by the alarm while the first is unwinding, so cleanup is not cut short); inside an
    import, the alarm raises it as soon as the import has finished."""
    first = interrupts.requested() is None
    interrupts.request(signum)
    if state["exit_now"]:
        hard_exit(128 + interrupts.requested())
    if first and importing(frame):
        arm(SIGNAL_RETRY)
    elif first:
        arm(SIGNAL_REPEAT)
        raise KeyboardInterrupt


def on_alarm(signum, frame):
    """The alarm: raise the recorded stop signal again (the last one was swallowed, or came
    during an import)."""
    code = interrupts.requested()
    if code is None:
        return
    if state["exit_now"]:
        hard_exit(128 + code)
    if importing(frame):
        arm(SIGNAL_RETRY)
        return
    arm(SIGNAL_REPEAT)
    raise KeyboardInterrupt


def unraisable(info):
    """``sys.unraisablehook``: a KeyboardInterrupt swallowed in a gc callback is raised again at
    once (by the alarm) and not reported; anything else is reported as by default."""
    if isinstance(info.exc_value, KeyboardInterrupt):
        if interrupts.requested() is not None and not state["exit_now"]:
            arm(SIGNAL_RETRY)
        return
    sys.__unraisablehook__(info)


def install():
    """Install the handlers (main thread only); returns what to restore, or ``None``."""
    if threading.current_thread() is not threading.main_thread():
        return None
    interrupts.clear()
    state["exit_now"] = False
    saved = {s: signal.signal(s, on_signal) for s in _STOP_SIGNALS}
    if _ALARM is not None:
        saved[_ALARM] = signal.signal(_ALARM, on_alarm)
    saved["unraisablehook"] = sys.unraisablehook
    sys.unraisablehook = unraisable
    return saved


def restore(saved) -> None:
    """Cancel the alarm and put back the handlers of before :func:`main`."""
    if saved is None:
        return
    arm(0)
    interrupts.clear()  # the library, called again in this process, runs normally
    sys.unraisablehook = saved.pop("unraisablehook")
    for s, h in saved.items():
        signal.signal(s, h)


def hard_exit(code: int):  # pragma: no cover - ends the process
    """End the process with ``code`` (no interpreter teardown).  The main thread first blocks the
    stop signals; one already delivered (its handler pending in Python, or the signal pending in
    the kernel) turns ``code`` into 128 + its number.  A signal that comes after the block cannot
    change the exit code any more: it came after the run had ended."""
    arm(0)
    if hasattr(signal, "pthread_sigmask"):
        signal.pthread_sigmask(signal.SIG_BLOCK, _STOP_SIGNALS)
        late = signal.sigpending() & set(_STOP_SIGNALS)
        if late and code == 0:
            code = 128 + min(late)
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except Exception:
            pass
    os._exit(code)


def signal_code(rc: int) -> int:
    """The exit code of a run: ``128 + signal`` if a stop signal arrived at any time."""
    signum = interrupts.requested()
    if signum is None:
        return rc
    if rc not in (128 + signal.SIGINT, 128 + signum):  # the outputs were complete before it came
        print("atlas: interrupted (after the run had finished)", file=sys.stderr)
    return 128 + signum
