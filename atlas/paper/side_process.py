"""A group of ``atlas paper``'s steps run in a second process beside the others.

:func:`start` spawns it (a fresh interpreter: JAX does not survive ``fork``), :func:`join`
waits for its result and folds its step timings, run-log lines and (when the run is not printing
live) its messages into the calling run, :func:`stop` ends it if the calling run failed first (an interrupt, which it answers with
the files it completed, as an interrupted ``atlas paper`` names them).
The files the group writes are written atomically by its steps, as in one process.  This module
imports no JAX until it is used (the calling run starts its second process first).
"""

from __future__ import annotations

import contextlib
import multiprocessing
import os
import signal
import sys
import traceback

__all__ = ["start", "join", "stop"]


class _RemoteTraceback(Exception):
    """The second process's traceback, as the cause of the error it raised."""

    def __str__(self) -> str:
        return self.args[0]


def start(steps, out, quick: bool, ci: bool, live: bool, *args):
    """Run ``steps(step, out, quick, ci, *args)`` in a spawned process; ``live``: it prints its
    own progress (else :func:`join` hands its messages to the calling run's ``say``)."""
    ctx = multiprocessing.get_context("spawn")
    receive, send = ctx.Pipe(duplex=False)
    warm = sys.modules.get("atlas.core.warm")  # kept kernels only if the caller has JAX already
    kept = warm.active_cache() if warm is not None else (None, None)
    proc = ctx.Process(
        target=_main,
        args=(send, steps, out, quick, ci, live, args, kept),
        name="atlas-paper-steps",
    )
    proc.start()
    send.close()
    return proc, receive


def join(side, step):
    """The result of the steps of ``side`` (:func:`start`); their timings go into ``step``, their
    run-log lines into the active :class:`atlas.paper.runlog.RunLog`; their error is raised here."""
    from atlas.data import io
    from atlas.paper import runlog

    proc, receive = side
    try:
        kind, committed, *got = receive.recv()
    except EOFError:
        proc.join()
        raise RuntimeError(
            f"atlas paper: its second process ended (exit code {proc.exitcode}) before its "
            "steps were done"
        ) from None
    io.COMMITTED.extend(committed)  # complete files of the run, for an interrupt's message
    if kind == "error":
        error, text = got
        error.__cause__ = _RemoteTraceback(text)
        raise error
    result, timings, lines, said = got
    for msg in said:
        step.say(msg)
    step.timings.update(timings)
    runlog.extend(lines)
    return result


def stop(side, grace: float = 10.0) -> None:
    """End the process of ``side`` (nothing for ``None``) and wait for it: an interrupt first, so
    that it names the files it completed (added to :data:`atlas.data.io.COMMITTED`), then, after
    ``grace`` seconds [s], a ``SIGTERM``."""
    if side is None:
        return
    from atlas.data import io

    proc, receive = side
    if proc.is_alive() and proc.pid is not None:
        try:
            os.kill(proc.pid, signal.SIGINT)
            if receive.poll(grace):
                io.COMMITTED.extend(receive.recv()[1])
        except (OSError, EOFError):  # it ended meanwhile
            pass
        if proc.is_alive():
            proc.terminate()
    proc.join()
    receive.close()


def _main(send, steps, out, quick, ci, live, args, kept) -> None:
    """The second process: the steps under a collecting run log and, when the calling run keeps
    its kernels (``kept``: :func:`atlas.core.warm.active_cache`), under a kernel cache of its
    own name in the same place; sends the result or the error."""
    from atlas.data import io
    from atlas.paper.steps import Steps, say_stderr

    # :func:`stop` ends this process by an interrupt: it must raise here even where the calling
    # run was started with SIGINT ignored (a background job of a shell, ``nohup``), which a new
    # interpreter inherits and then leaves ignored
    signal.signal(signal.SIGINT, signal.default_int_handler)
    said: list[str] = []
    try:
        from atlas.core import warm
        from atlas.core.config import use_compile_cache
        from atlas.paper import runlog

        step = Steps(say_stderr if live else said.append)
        use_compile_cache()
        where, name = kept
        block = warm.kernel_cache(where, run=f"{name} (second process)" if name else None)
        with block if where else contextlib.nullcontext(), runlog.RunLog(None) as log:
            result = steps(step, out, quick, ci, *args)
        send.send(("done", io.COMMITTED, result, step.timings, log.lines, said))
    except BaseException as e:  # noqa: BLE001 - every error goes to the calling run
        text = traceback.format_exc()
        try:
            send.send(("error", io.COMMITTED, e, text))
        except Exception:  # the error itself does not pickle
            send.send(("error", io.COMMITTED, RuntimeError(f"{type(e).__name__}: {e}"), text))
    finally:
        send.close()
