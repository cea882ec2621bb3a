"""Where a cold run's seconds go: the distinct programs a command compiles, with their shapes and
their tracing, lowering and XLA compilation seconds.

:func:`recorded` listens to JAX's compilation events (:mod:`jax.monitoring`: a function traced to
a jaxpr, a jaxpr lowered to StableHLO, a module compiled by XLA, each with its name and seconds)
and to JAX's own log line naming the shapes of each module it lowers.  An event raised while a
kept kernel (:class:`atlas.core.warm.Kernel`) exports or compiles its program is attributed to
that kernel (:func:`atlas.core.warm.current_kernel`), so a kept kernel is one program under its
own name; any other program (a plain ``jax.jit``, an eager operation) keeps JAX's name for it.

``python -m atlas.bench.startup_programs OUT.json KIND [ARGS...]`` runs one command in this
process and writes its programs to ``OUT.json``: ``cli ARGS`` (``atlas ARGS``), ``explorer-map N``
(the explorer's first ``N x N`` map, headless), ``explorer-overlay N`` (the first certified
boundary overlay of the explorer's default slice, asked for as soon as the first map is drawn and
the widget's background warm-up started), ``explorer-overlay-warm N`` (the same, asked for once
the warm-up has ended: a user who looked at the map first).  :func:`measure` runs the commands of the
Start-up section in fresh processes with an empty cache and returns its rows.
"""

from __future__ import annotations

import contextlib
import importlib
import json
import logging
import math
import re
import sys
import threading
import time
from dataclasses import asdict, dataclass, field

import jax

from atlas.core import warm

__all__ = [
    "Program",
    "main",
    "measure",
    "program_lines",
    "program_tables",
    "recorded",
    "summary",
]

#: JAX's events: jaxpr tracing, lowering to StableHLO, XLA compilation -> our column
EVENTS = {
    "/jax/core/compile/jaxpr_trace_duration": "trace_s",
    "/jax/core/compile/jaxpr_to_mlir_module_duration": "lower_s",
    "/jax/core/compile/backend_compile_duration": "compile_s",
}
#: JAX's log line (logger ``jax._src.interpreters.pxla``, DEBUG) naming a lowered module's shapes
_SHAPES = re.compile(r"^Compiling (\S+) with global shapes and types (.*?)\. Argument mapping")
_AVAL = re.compile(r"([a-z]+\d*)\[([\d,]*)\]")


@dataclass
class Program:
    """One distinct program: its name, the shapes of its arguments (``float64[4096] ...``), how
    many times XLA compiled it, and the seconds spent tracing, lowering and compiling it."""

    name: str
    shapes: str = ""
    compiles: int = 0
    trace_s: float = 0.0
    lower_s: float = 0.0
    compile_s: float = 0.0

    @property
    def seconds(self) -> float:
        return self.trace_s + self.lower_s + self.compile_s


@dataclass
class Recording:
    """What :func:`recorded` saw: the programs in the order they were first compiled (or traced)
    and the wall seconds of the block."""

    programs: list = field(default_factory=list)
    wall_s: float = math.nan


def _short_shapes(text: str) -> str:
    """``[ShapedArray(float64[4096]), ...]`` -> ``f64[4096] ...`` (the argument shapes)."""
    got = []
    for dtype, dims in _AVAL.findall(text):
        kind = {"float": "f", "int": "i", "uint": "u", "bool": "b", "complex": "c"}
        short = next((v + dtype[len(k) :] for k, v in kind.items() if dtype.startswith(k)), dtype)
        got.append(f"{short}[{dims}]")
    return " ".join(got)


class _Listener(logging.Handler):
    """The event listener and the log handler of one :func:`recorded` block."""

    def __init__(self):
        super().__init__(logging.DEBUG)
        self.guard = threading.Lock()
        self.open: dict[str, Program] = {}  # per thread: the program being compiled
        self.programs: list[Program] = []
        self.shapes: dict[str, str] = {}

    def program(self, fun_name: str) -> Program:
        """The program an event of this thread belongs to: the current kept kernel's, else a
        new one per (JAX name, its last lowered shapes) when XLA compiles it."""
        kernel = warm.current_kernel()
        key = kernel or threading.get_ident()
        prog = self.open.get(key)
        if prog is None or (kernel is None and prog.compiles):
            prog = Program(kernel[0] if kernel else fun_name)
            self.open[key] = prog
            self.programs.append(prog)
        return prog

    def event(self, event, seconds, **kw):
        column = EVENTS.get(event)
        if column is None:
            return
        with self.guard:
            prog = self.program(kw.get("fun_name", "?"))
            setattr(prog, column, getattr(prog, column) + seconds)
            if column == "compile_s":
                prog.compiles += 1
                prog.shapes = prog.shapes or self.shapes.get(kw.get("fun_name", ""), "")
                if warm.current_kernel() is None:
                    self.open.pop(threading.get_ident(), None)

    def emit(self, record):
        m = _SHAPES.match(record.getMessage())
        if m:
            with self.guard:
                self.shapes[m[1]] = _short_shapes(m[2])
                kernel = warm.current_kernel()
                if kernel is not None and kernel in self.open:
                    self.open[kernel].shapes = self.open[kernel].shapes or self.shapes[m[1]]


@contextlib.contextmanager
def recorded():
    """``with recorded() as rec:`` the programs JAX traces, lowers and compiles in the block
    (:class:`Recording`; programs traced but never compiled are kept with ``compiles == 0``)."""
    rec, listener = Recording(), _Listener()
    log = logging.getLogger("jax._src.interpreters.pxla")
    level = log.level
    log.setLevel(logging.DEBUG)
    log.addHandler(listener)
    jax.monitoring.register_event_duration_secs_listener(listener.event)
    t0 = time.perf_counter()
    try:
        yield rec
    finally:
        rec.wall_s = time.perf_counter() - t0
        jax.monitoring.unregister_event_duration_listener(listener.event)
        log.removeHandler(listener)
        log.setLevel(level)
        rec.programs = [p for p in listener.programs if p.compiles or p.seconds > 0]


def summary(programs) -> dict:
    """``programs`` (compiled ones), and the seconds of all: tracing, lowering, compiling."""
    compiled = [p for p in programs if p.compiles]
    return dict(
        programs=len(compiled),
        compiles=sum(p.compiles for p in compiled),
        trace_s=sum(p.trace_s for p in programs),
        lower_s=sum(p.lower_s for p in programs),
        compile_s=sum(p.compile_s for p in programs),
    )


def program_lines(command: str, programs, top: int = 12) -> list[str]:
    """Markdown: the ``top`` programs of ``command`` by seconds (name, shapes, seconds)."""
    s = summary(programs)
    lines = [
        f"`{command}`: {s['programs']} programs compiled ({s['compiles']} compilations); "
        f"tracing {s['trace_s']:.1f} s, lowering {s['lower_s']:.1f} s, "
        f"XLA compilation {s['compile_s']:.1f} s. The slowest:\n",
        "| program | argument shapes | compiles | trace s | lower s | compile s |",
        "|---|---|---:|---:|---:|---:|",
    ]
    for p in sorted(programs, key=lambda p: -p.seconds)[:top]:
        shapes = p.shapes if len(p.shapes) <= 60 else p.shapes[:57] + "..."
        lines.append(
            f"| {p.name} | {shapes or '-'} | {p.compiles} | {p.trace_s:.2f} | "
            f"{p.lower_s:.2f} | {p.compile_s:.2f} |"
        )
    return [*lines, ""]


#: the explorer of a notebook's first session, headless (a script: the bench layer does not
#: import the explorer): its first map (``first_map()``), the first map and the background
#: warm-up the widget starts then (``map_and_warm_up()``; ``map_then_warm_up()`` waits for it)
#: and its certified boundary overlay (``overlay()``: waits for the worker thread)
_EXPLORER = """
import time
from atlas.explore.state import Explorer
ex = Explorer(n={n})

def first_map():
    ex.update()
    return 0

def map_and_warm_up():
    ex.update()
    ex.warm_up()

def map_then_warm_up():
    ex.update()
    ex.warm_up().result()

def overlay():
    ex.update(overlays=("class boundaries", "certified boundaries"))
    while ex.boundaries() is None:
        time.sleep(0.05)
    return 0
"""


def _command(kind: str, args: list[str]):
    """``(set-up, the measured work)`` of one command (module docstring); the work returns an
    exit code."""
    if kind == "cli":  # the entry point, as ``atlas ARGS`` runs it (bench sits below the CLI)
        cli = importlib.import_module("atlas.cli")
        return (lambda: None), (lambda: cli.main(args))
    setups = {
        "explorer-map": None,
        "explorer-overlay": "map_and_warm_up",
        "explorer-overlay-warm": "map_then_warm_up",
    }
    if kind in setups:
        names: dict = {}
        exec(_EXPLORER.format(n=int(args[0]) if args else 513), names)  # noqa: S102 - ours
        if kind == "explorer-map":
            return (lambda: None), names["first_map"]
        return names[setups[kind]], names["overlay"]
    raise SystemExit(f"startup_programs: unknown kind {kind!r} ({', '.join(['cli', *setups])})")


def main(argv=None) -> int:
    """``python -m atlas.bench.startup_programs OUT.json KIND [ARGS...]``."""
    argv = list(sys.argv[1:] if argv is None else argv)
    if len(argv) < 2:
        raise SystemExit("usage: python -m atlas.bench.startup_programs OUT.json KIND [ARGS...]")
    out, kind, args = argv[0], argv[1], argv[2:]
    setup, work = _command(kind, args)
    setup()
    with recorded() as rec:
        rc = work()
    data = dict(rc=rc, wall_s=rec.wall_s, programs=[asdict(p) for p in rec.programs])
    with open(out, "w") as f:
        json.dump(data, f, indent=1)
    return rc


def measure(session, commands) -> list[dict]:
    """One row per ``(label, kind, arguments)`` of ``commands`` (``{work}`` in an argument: the
    session's directory), each run once in a fresh process with an emptied
    cache (``session``: :class:`atlas.bench.startup._Session`): the process's wall [s] (start-up
    and imports included), the measured work's own wall in the run [s] (``in_run_s``: the
    command, or the explorer's overlay from the moment it is asked for, as :func:`main` times
    it), the programs compiled and the seconds spent tracing, lowering and compiling them
    (``programs``: the list, JSON)."""
    rows = []
    for label, kind, args in commands:
        session.empty_cache()
        out = session.work / "programs.json"
        args = [a.format(work=session.work) for a in args]
        cmd = [sys.executable, "-m", "atlas.bench.startup_programs", str(out), kind, *args]
        t = session.times(cmd, 1)[0]
        got = json.loads(out.read_text()) if out.exists() and not t.failure() else None
        out.unlink(missing_ok=True)
        progs = [Program(**p) for p in got["programs"]] if got else []
        s = summary(progs)
        note = (
            f"tracing {s['trace_s']:.1f} s, lowering {s['lower_s']:.1f} s, XLA compilation "
            f"{s['compile_s']:.1f} s ({s['compiles']} compilations)"
        )
        rows.append(dict(
            figure=f"cold, programs compiled: {label}", command=" ".join(args), runs=1,
            median_s=t.wall, min_s=t.wall, max_s=t.wall, in_run_s=got["wall_s"] if got else "",
            compared="programs",
            value=s["programs"] if got else "", target="", met="",
            note=note if got else t.failure() or "no programs recorded",
            programs=json.dumps([asdict(p) for p in progs]),
        ))  # fmt: skip
    return rows


def program_tables(rows, top: int = 12) -> list[str]:
    """Markdown: for each row of :func:`measure`, its slowest programs (:func:`program_lines`)."""
    lines = []
    for r in rows:
        if r.get("programs"):
            progs = [Program(**p) for p in json.loads(r["programs"])]
            label = r["figure"].split(": ", 1)[-1]
            lines += program_lines(label, progs, top)
    return ["### Where a cold run's seconds go\n", *lines] if lines else []


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
