"""What a store directory may be, who writes it, and how it is replaced (both kinds of store:
the zarr store of :mod:`atlas.data.tile_store` and the outcome store of
:mod:`atlas.dynamics.outcome_tiles`).

* :func:`check_place`: ``''``, ``.``, the working directory, a directory above it, the home
  directory and ``/`` are never a store (one-line ``ValueError`` naming ``store``);
* :func:`check_replaceable`: an existing path is replaced only if the project wrote it (the
  store kind's own test of its marker and plan); a non-empty directory without it, or a file, is
  refused;
* :func:`install`: a new store, laid out in a temporary directory beside ``store``, takes its
  place by renames (the old one is moved aside first and removed only after the new one is in
  place; never deleted before);
* :func:`held`: a writer holds ``store`` by a lock file beside it, ``.NAME.lock``, holding its
  pid and host; a second writer is refused with one line (a lock left by a process of this host
  that no longer runs is taken over);
* :func:`recover`: the old store an :func:`install` left aside, ``.NAME.old.PID``, when its
  process was killed between the renames, is renamed back if ``store`` is missing (it is the only
  copy), or removed if the store in place is one the project wrote; one line says which.
"""

from __future__ import annotations

import contextlib
import json
import os
import re
import shutil
import socket
import sys

__all__ = [
    "check_place",
    "check_replaceable",
    "install",
    "held",
    "lock_path",
    "recover",
    "settle",
    "write_failure",
]


def check_place(store: str, option: str = "store") -> str:
    """``store`` as an absolute path, or ``ValueError`` naming ``option`` for a path that must
    never be a store: empty, the working directory or a directory above it, home, ``/``."""
    text = os.fspath(store)
    if not str(text).strip():
        raise ValueError(f"{option}: empty path")
    path = os.path.realpath(text)
    cwd = os.path.realpath(os.getcwd())
    home = os.path.realpath(os.path.expanduser("~"))
    above = path == os.sep or cwd == path or cwd.startswith(path.rstrip(os.sep) + os.sep)
    if above or path == home:
        what = "the home directory" if path == home else "the working directory or above it"
        raise ValueError(f"{option}: {text!r} is {what}, not a store (name a new directory)")
    return os.path.abspath(text)


def check_replaceable(store: str, ours, kind: str, option: str = "store") -> bool:
    """True if ``store`` exists and ``ours(store)`` recognises it as a ``kind`` the project
    wrote (so that it may be replaced), false if it does not exist or is an empty directory;
    ``ValueError`` naming ``option`` for anything else."""
    if not os.path.lexists(store):
        return False
    if not os.path.isdir(store) or os.path.islink(store):
        raise ValueError(f"{option}: {store} is not a directory, refusing to replace it")
    if not os.listdir(store):
        return True
    if not ours(store):
        raise ValueError(
            f"{option}: {store} is not {kind} (no marker), refusing to replace it; "
            "name a new directory"
        )
    return True


def install(tmp: str, store: str) -> None:
    """Put the directory ``tmp`` (beside ``store``) in place of ``store``: the old store is
    renamed aside, ``tmp`` renamed onto ``store``, then the old one removed (restored if the
    second rename fails)."""
    if not os.path.lexists(store):
        os.replace(tmp, store)
        return
    head, name = os.path.split(store)
    old = os.path.join(head, f".{name}.old.{os.getpid()}")
    os.replace(store, old)
    try:
        os.replace(tmp, store)
    except BaseException:
        os.replace(old, store)
        raise
    shutil.rmtree(old, ignore_errors=True)


def _leftovers(store: str) -> list[tuple[str, int]]:
    """``(path, pid)`` of each ``.NAME.old.PID`` beside ``store`` whose process no longer runs,
    newest first."""
    head, name = os.path.split(os.path.abspath(store))
    pattern = re.compile(rf"\.{re.escape(name)}\.old\.(\d+)")
    try:
        names = os.listdir(head)
    except OSError:
        return []
    found = []
    for entry in names:
        match = pattern.fullmatch(entry)
        path = os.path.join(head, entry)
        if match and os.path.isdir(path) and not os.path.islink(path):
            pid = int(match.group(1))
            if pid != os.getpid() and not _alive(pid):
                found.append((path, pid, os.lstat(path).st_mtime))
    return [(p, pid) for p, pid, _ in sorted(found, key=lambda f: -f[2])]


def recover(store: str, ours, option: str = "store") -> list[str]:
    """Finish the replacements of ``store`` that a killed process left half done (see the
    module docstring; ``ours(path)`` recognises a store the project wrote): a leftover is
    restored when ``store`` is missing, removed when ``ours(store)``, else kept. Call it holding
    ``store`` (:func:`held`). Returns the lines said (each also printed to stderr)."""
    said = []
    for old, pid in _leftovers(store):
        gone = f"left by process {pid}, which was stopped while replacing {store}"
        if not os.path.lexists(store):
            os.replace(old, store)
            line = f"{option}: restored {store} from {old} ({gone})"
        elif ours(store):
            shutil.rmtree(old)
            line = f"{option}: removed the old copy {old} ({gone}; the new store is in place)"
        else:
            line = f"{option}: kept {old} ({gone}; {store} is not a store this project wrote)"
        print(line, file=sys.stderr)
        said.append(line)
    return said


def settle(store: str, ours, option: str = "store") -> None:
    """:func:`recover` holding ``store``, if a killed replacement left anything beside it (for a
    check of the store's existence made before the writer holds it)."""
    if _leftovers(store):
        with held(store, option, ours):
            pass


def lock_path(store: str) -> str:
    """The lock file of ``store``: ``.NAME.lock`` beside it."""
    head, name = os.path.split(os.path.abspath(store))
    return os.path.join(head, f".{name}.lock")


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def _holder(path: str) -> dict | None:
    """The ``{"pid", "host"}`` of a lock file, ``None`` if unreadable."""
    try:
        with open(path, encoding="utf-8") as fh:
            rec = json.load(fh)
        return {"pid": int(rec["pid"]), "host": str(rec["host"])}
    except (OSError, ValueError, KeyError, TypeError):
        return None


def _take(path: str, me: dict, option: str, store: str) -> None:
    for _ in range(2):
        try:
            fd = os.open(path, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644)
        except FileExistsError:
            other = _holder(path)
            stale = other is not None and other["host"] == me["host"] and not _alive(other["pid"])
            if not stale:
                who = (
                    "an unreadable lock"
                    if other is None
                    else (f"process {other['pid']} on {other['host']}")
                )
                raise BlockingIOError(
                    f"{option}: {store} is being written by {who} (lock {path}); wait for it, "
                    "or remove the lock if no such run is going on"
                ) from None
            os.unlink(path)  # left by a run of this host that no longer exists
            continue
        with os.fdopen(fd, "w", encoding="utf-8") as fh:
            json.dump(me, fh)
        return
    raise BlockingIOError(f"{option}: {store}: could not take the lock {path}")


@contextlib.contextmanager
def held(store: str, option: str = "store", ours=None):
    """Hold ``store`` for writing while the block runs (see the module docstring); with
    ``ours`` (the store kind's test), first :func:`recover` what a killed replacement left."""
    path = lock_path(store)
    if not os.path.isdir(os.path.dirname(path)):
        raise FileNotFoundError(f"{option}: directory {os.path.dirname(path)} does not exist")
    me = {"pid": os.getpid(), "host": socket.gethostname()}
    _take(path, me, option, store)
    try:
        if ours is not None:
            recover(store, ours, option)
        yield path
    finally:
        if _holder(path) == me:
            with contextlib.suppress(FileNotFoundError):
                os.unlink(path)


def write_failure(store: str, exc: BaseException) -> OSError | None:
    """The one-line ``OSError`` of a failed write into ``store`` (a full disk, a read-only
    location): it names ``store``, the cause and, when the store exists, that the same command
    with ``--resume`` continues it; ``None`` when ``exc`` is not a failed write."""
    from atlas.data.io import write_error  # noqa: PLC0415 - netCDF4: only on a failure

    err = exc if ": cannot write " in str(exc) else write_error(store, exc, "store")
    if err is None:
        return None
    if os.path.isdir(store):
        return OSError(
            f"{err}; finished tiles are kept in {store}: make room and continue with the same "
            "command and --resume"
        )
    return err
