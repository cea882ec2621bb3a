"""What varies from one ``atlas paper`` run to the next, kept out of the files it writes.

The files ``atlas paper`` writes are a pure function of the code and its inputs: two runs, on
one machine or two, give the same bytes, so a regenerated file that changed is a result that
changed.  Dates, seconds, the host and the command line (absolute paths) go instead to one log,
``run.log`` in the output directory (git-ignored in ``outputs/``): :class:`RunLog` collects them
while a run is active, :func:`record` adds a line, :func:`fixed` moves the run-dependent
attributes of a Dataset (the time stamp of ``history``, ``seconds``, ``trajectories_per_second``,
``*_seconds`` inside JSON attributes) into it.  Figures get fixed metadata in
:func:`atlas.data.io.savefig`.
"""

from __future__ import annotations

import datetime
import json
import os
import platform
import re
import sys
from pathlib import Path

from atlas.data.io import atomic_write_text

__all__ = ["LOG", "VOLATILE", "RunLog", "extend", "fixed", "record"]

#: the run log's file name in the output directory (never a tracked file)
LOG = "run.log"
#: Dataset attributes that differ between runs of the same code: they go to the log
VOLATILE = ("seconds", "trajectories_per_second")
#: the UTC time stamp :func:`atlas.core.config.history` puts before the call
_STAMP = re.compile(r"^\d{4}-\d\d-\d\dT\d\d:\d\d:\d\dZ: ")
_ACTIVE: list[RunLog] = []


class RunLog:
    """``with RunLog(out) as log:`` collects :func:`record` lines of the block and writes them,
    after the run's date, host and command line, to ``out/run.log`` when the block ends (also
    when it fails: what was recorded until then).  ``RunLog(None)`` only collects the lines (a
    second process of the run: :mod:`atlas.paper.side_process`)."""

    def __init__(self, out):
        self.path = None if out is None else Path(out) / LOG
        self.lines: list[str] = []
        if out is None:
            return
        now = datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds")
        self.lines = [
            f"date: {now}",
            f"host: {platform.node()} ({platform.machine()}, {os.cpu_count()} CPUs)",
            f"command: {' '.join(sys.argv) or 'python'}",
            f"directory: {Path(out).resolve()}",
        ]

    def add(self, what: str, value) -> None:
        """One line ``what: value`` (floats with 3 decimals)."""
        self.lines.append(
            f"{what}: {value:.3f}" if isinstance(value, float) else f"{what}: {value}"
        )

    def __enter__(self) -> RunLog:
        _ACTIVE.append(self)
        return self

    def __exit__(self, *exc) -> None:
        _ACTIVE.remove(self)
        if self.path is not None:
            atomic_write_text(self.path, "\n".join(self.lines) + "\n")


def record(what: str, value) -> None:
    """Add ``what: value`` to the active :class:`RunLog` (nothing without one)."""
    if _ACTIVE:
        _ACTIVE[-1].add(what, value)


def extend(lines) -> None:
    """Add finished ``what: value`` lines (another process's :class:`RunLog`) to the active one."""
    if _ACTIVE:
        _ACTIVE[-1].lines.extend(lines)


def fixed(ds, name: str):
    """A copy of ``ds`` without its run-dependent attributes (module docstring), which are
    recorded as ``name attribute: value``; ``history`` keeps its call without the time stamp."""
    ds = ds.copy()
    for key, value in list(ds.attrs.items()):
        if key == "history" and isinstance(value, str) and _STAMP.match(value):
            record(f"{name} history", value)
            ds.attrs[key] = _STAMP.sub("", value)
        elif _volatile(key):
            record(f"{name} {key}", ds.attrs.pop(key))
        elif isinstance(value, str) and value[:1] in "[{":
            ds.attrs[key] = _fixed_json(value, f"{name} {key}")
    return ds


def _volatile(key: str) -> bool:
    return key in VOLATILE or key.endswith("_seconds")


def _fixed_json(text: str, name: str) -> str:
    """``text`` (a JSON attribute) without the volatile keys of its objects (recorded)."""
    try:
        value = json.loads(text)
    except ValueError:
        return text

    def strip(v, where):
        if isinstance(v, dict):
            for k in [k for k in v if _volatile(k)]:
                record(f"{where}.{k}", v.pop(k))
            return {k: strip(x, f"{where}.{k}") for k, x in v.items()}
        if isinstance(v, list):
            return [strip(x, f"{where}[{i}]") for i, x in enumerate(v)]
        return v

    stripped = strip(value, name)
    return text if stripped == json.loads(text) else json.dumps(stripped)
