"""Start-up: what a user waits for before the first answer, timed as whole processes.

Each figure is the wall time of a fresh subprocess of this environment (from its start to its
exit), over several runs (median, min, max): ``python -c "import atlas"``, ``atlas --help``, a
16 x 16 x 2 damped ``atlas generate`` (512 points, every output) with an empty compilation cache
(cold) and with the cache that run left (warm), and the same warm run with only part of the warm
start (``ATLAS_KERNEL_EXECUTABLES=0``: the exported programs and the compilation cache;
``ATLAS_KERNEL_CACHE=0``: the compilation cache alone); the 8.4-million-point atlas (:data:`LARGE`)
against the seconds of its own summary line; ``atlas selftest`` and its disagreements; the
explorer widget built headless (:data:`EXPLORER`: first map, one click); the refusal of a 1e14-point
scene (:data:`HUGE`, exit 2); where the seconds of a cold run go (:data:`PROGRAMS`: each command in an
empty cache, the programs it compiles with their shapes and their tracing, lowering and compilation
seconds, :mod:`atlas.bench.startup_programs`).

Every run uses one temporary ``ATLAS_JAX_CACHE`` that this module creates and deletes (the user's
cache is neither read nor written) and writes its files into a temporary directory, its working
directory.  Each figure with a target is compared with it (:func:`verdict`); :func:`measure` is
called by :func:`atlas.bench.runner.run`, ``python -m atlas.bench.startup [MODE]`` runs this
section alone and prints it.
"""

from __future__ import annotations

import importlib.util
import json
import math
import os
import re
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

from atlas.bench import startup_programs
from atlas.bench.config import CONFIG, FLAGS, mode_name
from atlas.bench.suites import parse_summary
from atlas.bench.timing import bench_json, log

__all__ = [
    "EXPLORER",
    "HUGE",
    "LARGE",
    "MEDIAN",
    "PROGRAMS",
    "SMALL",
    "TARGETS",
    "Timed",
    "atlas_command",
    "measure",
    "parse_selftest",
    "run_timed",
    "spread",
    "startup_env",
    "verdict",
]

#: the 16 x 16 x 2 damped atlas (512 points, every output)
SMALL = ["--beta1", "0:2pi:16", "--beta2", "0:2pi:16", "--kappa", "0.5,2", "--q", "0.1"]
SMALL += ["--alpha", "0.35pi"]
#: the 8.4-million-point damped atlas (512 x 512 x 8 x 2 x 2), the three flag verdicts
LARGE = ["--beta1", "0:2pi:512", "--beta2", "0:2pi:512", "--kappa", "log:0.1:10:8"]
LARGE += ["--q1", "0.1,1", "--q2", "0.1,1", "--outputs", ",".join(FLAGS)]

#: a 1e14-point scene (every output): refused with one line, exit 2, before any work (the suite
#: proves "before any work" by counting, tests/test_cli.py; its seconds are reported here)
HUGE = ["--beta1", "0:2pi:10000000", "--beta2", "0:2pi:10000000"]

#: the cold commands whose compiled programs the section lists (:mod:`atlas.bench.startup_programs`):
#: label, kind, arguments (``{work}``: the section's directory)
PROGRAMS = (
    ("atlas paper --quick", "cli", ["paper", "--quick", "--out", "{work}/paper"]),
    ("atlas generate 16 x 16 x 2", "cli", ["generate", *SMALL, "--out", "{work}/small.nc",
                                           "--overwrite"]),
    ("explorer: first 513^2 map", "explorer-map", ["513"]),
    ("explorer: first certified boundary overlay", "explorer-overlay", ["513"]),
    ("explorer: first certified boundary overlay after the warm-up", "explorer-overlay-warm",
     ["513"]),
)  # fmt: skip

#: the figure compared with a time target: the median wall time [s]
MEDIAN = "median s"
#: figure -> (what is compared, target): median wall [s], wall / in-run seconds, disagreements
TARGETS = {
    "import atlas": (MEDIAN, 0.5),
    "atlas --help": (MEDIAN, 0.5),
    "generate 512 points, warm": (MEDIAN, 2.0),
    "8.4M-point atlas, warm": ("wall / in run", 2.0),
    "atlas selftest": ("disagreements", 0),
}

#: the explorer as a notebook builds it (``make_widget()``, its default map), headless
#: (matplotlib Agg: the map is drawn to the widget's PNG), then two clicks on the map delivered
#: through the canvas's ``button_press_event`` callbacks as ipympl delivers a browser's click;
#: each must update the inspector.  Times from the script's first statement.
EXPLORER = r"""
import time
t0 = time.perf_counter()
import json, math
import matplotlib
matplotlib.use("Agg")
from matplotlib.backend_bases import MouseEvent
from atlas.explore.widget import make_widget
box = make_widget()
first_map = time.perf_counter() - t0
fig = box.figure

def click(b1, b2):
    x, y = fig.axes[0].transData.transform((b1 * math.pi, b2 * math.pi))
    before = box.inspector.value
    t = time.perf_counter()
    event = MouseEvent("button_press_event", fig.canvas, x, y, button=1)
    fig.canvas.callbacks.process("button_press_event", event)
    dt = time.perf_counter() - t
    if box.inspector.value == before or box.explorer.last_inspection is None:
        raise SystemExit("explorer: the click did not update the inspector")
    return dt

first = click(0.15, 1.07)
second = click(1.15, 0.07)
out = dict(first_map=first_map, click=first, second_click=second, n=box.explorer.params["n"])
print("BENCH_JSON " + json.dumps(out))
"""

#: environment switches of the warm start that a measured run must not inherit
_SWITCHES = ("ATLAS_KERNEL_CACHE", "ATLAS_KERNEL_EXECUTABLES", "JAX_COMPILATION_CACHE_DIR")


@dataclass
class Timed:
    """One finished subprocess: wall time [s], exit code, output."""

    wall: float
    returncode: int
    stdout: str = ""
    stderr: str = ""

    def failure(self) -> str:
        """Empty if the process succeeded, else its exit code and last line of stderr."""
        if self.returncode == 0:
            return ""
        last = (self.stderr.strip().splitlines() or [""])[-1]
        return f"exit {self.returncode}: {last[:200]}"


def run_timed(cmd: list[str], env: dict, cwd: str) -> Timed:
    """``cmd`` in a fresh process: wall time from start to exit."""
    t0 = time.perf_counter()
    p = subprocess.run(cmd, capture_output=True, text=True, env=env, cwd=cwd, check=False)
    return Timed(time.perf_counter() - t0, p.returncode, p.stdout, p.stderr)


def atlas_command() -> list[str]:
    """The ``atlas`` entry point of this environment (beside ``sys.executable``), else
    ``python -m atlas.cli``."""
    exe = Path(sys.executable).with_name("atlas")
    if exe.is_file() and os.access(exe, os.X_OK):
        return [str(exe)]
    return [sys.executable, "-m", "atlas.cli"]


def startup_env(cache: str, **switches: str) -> dict:
    """The environment of a measured run: this one, with ``cache`` as ``ATLAS_JAX_CACHE``, the
    warm-start switches given here only, no progress bar, matplotlib's Agg backend."""
    env = {k: v for k, v in os.environ.items() if k not in _SWITCHES}
    env.update(ATLAS_JAX_CACHE=cache, ATLAS_PROGRESS="0", PYTHONWARNINGS="ignore", MPLBACKEND="Agg")
    env.update(switches)
    return env


def spread(xs) -> dict:
    """``median_s``, ``min_s``, ``max_s`` of the finite values of ``xs`` (NaN if none)."""
    xs = [x for x in xs if x is not None and math.isfinite(x)]
    if not xs:
        return dict(median_s=math.nan, min_s=math.nan, max_s=math.nan)
    return dict(median_s=statistics.median(xs), min_s=min(xs), max_s=max(xs))


def verdict(value, target) -> str:
    """``met`` if ``value <= target``, ``missed`` if above, ``failed`` if there is no value,
    ``""`` without a target."""
    if target is None:
        return ""
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return "failed"
    return "met" if value <= target else "missed"


_SELFTEST = re.compile(
    r"^(PASSED|FAILED): (\d+) disagreements in (\d+) decided of (\d+) points;.*; ([\d.]+) s$"
)


def parse_selftest(text: str) -> dict | None:
    """``passed``, ``disagreements``, ``decided``, ``points`` and ``seconds`` from the verdict
    line of ``atlas selftest`` (``PASSED: D disagreements in N decided of P points; ...; S s``);
    None without one."""
    for line in reversed(text.splitlines()):
        m = _SELFTEST.match(line.strip())
        if m:
            return dict(
                passed=m[1] == "PASSED",
                disagreements=int(m[2]),
                decided=int(m[3]),
                points=int(m[4]),
                seconds=float(m[5]),
            )
    return None


def _row(figure, command, walls, failures=None, compared="", value=None, in_run=None, note=""):
    """One row of the section: the spread of the successful runs' ``walls`` [s] and the figure
    compared with its target (:data:`TARGETS`; ``compared``, ``value`` for a figure without)."""
    failures = failures or [""] * len(walls)
    kind, target = TARGETS.get(figure, (compared, None))
    times = spread([w for w, f in zip(walls, failures) if not f])
    if kind == MEDIAN:
        value = times["median_s"]
    failed = [f for f in failures if f]
    if failed:
        value, note = None, "; ".join(x for x in (note, failed[0]) if x)
    return dict(
        figure=figure,
        command=command,
        runs=len(walls),
        **times,
        in_run_s="" if in_run is None else in_run,
        compared=kind,
        value="" if value is None else value,
        target="" if target is None else target,
        met=verdict(value, target),
        note=note,
    )


def _fails(timed) -> list[str]:
    return [t.failure() for t in timed]


class _Session:
    """The runs of one section: a temporary cache and working directory, one runner."""

    def __init__(self, tmp: Path, run):
        self.cache = tmp / "jax"
        self.work = tmp / "work"
        self.cache.mkdir()
        self.work.mkdir()
        self.run = run
        self.atlas = atlas_command()

    def times(self, cmd, n, **switches) -> list[Timed]:
        """``n`` runs of ``cmd`` in the section's cache and directory."""
        env = startup_env(str(self.cache), **switches)
        return [self.run(cmd, env, str(self.work)) for _ in range(n)]

    def generate(self, args) -> list[str]:
        """``atlas generate ARGS`` into the section's directory."""
        return [*self.atlas, "generate", *args, "--out", str(self.work / "atlas.nc"), "--overwrite"]

    def empty_cache(self) -> None:
        """The section's cache, emptied (the section created it)."""
        shutil.rmtree(self.cache)
        self.cache.mkdir()


def _cheap(s: _Session, runs: int) -> list[dict]:
    """``import atlas`` and ``atlas --help``."""
    rows = []
    for figure, cmd in (
        ("import atlas", [sys.executable, "-c", "import atlas"]),
        ("atlas --help", [*s.atlas, "--help"]),
    ):
        log(f"start-up: {figure} x {runs}")
        t = s.times(cmd, runs)
        text = 'python -c "import atlas"' if figure == "import atlas" else figure
        rows.append(_row(figure, text, [x.wall for x in t], _fails(t)))
    return rows


def _refusal(s: _Session, runs: int) -> list[dict]:
    """``atlas generate`` of :data:`HUGE`: exit 2 (one line) is its success."""
    log(f"start-up: 1e14-point scene refused x {runs}")
    t = s.times(s.generate(HUGE), runs)
    fails = ["" if x.returncode == 2 else x.failure() or "exit 0: not refused" for x in t]
    text = "atlas generate " + " ".join(HUGE)
    return [_row("1e14-point scene refused", text, [x.wall for x in t], fails, note="exit 2")]


#: the 512-point atlas with each layer of the warm start, and the switches that leave it out
_LAYERS = (
    ("generate 512 points, warm", {}),
    ("generate 512 points, exported programs only", {"ATLAS_KERNEL_EXECUTABLES": "0"}),
    ("generate 512 points, compilation cache only", {"ATLAS_KERNEL_CACHE": "0"}),
)


def _generate(s: _Session, cold_runs: int, runs: int) -> list[dict]:
    """The 512-point atlas: cold (each run in an emptied cache; the last one's cache serves the
    rest), then an untimed round and ``runs`` timed rounds of each of :data:`_LAYERS`
    (interleaved: the machine's load changes alike for each); every figure but the warm one as a
    multiple of the warm median.  The untimed round leaves each layer's own programs in the
    cache (``ATLAS_KERNEL_CACHE=0`` runs plain ``jax.jit`` programs, which the cold run's
    exported ones do not serve)."""
    cmd, text = s.generate(SMALL), "atlas generate " + " ".join(SMALL)
    cold = []
    for _ in range(cold_runs):
        s.empty_cache()
        log("start-up: generate 512 points, cold")
        cold += s.times(cmd, 1)
    timed = {name: [] for name, _ in _LAYERS}
    for i in range(runs + 1):  # the first round untimed: each layer's own programs cached
        for name, switches in _LAYERS:
            log(f"start-up: {name}" + ("" if i else " (untimed)"))
            t = s.times(cmd, 1, **switches)
            timed[name] += t if i else []
    rows = [_row("generate 512 points, cold", text, [x.wall for x in cold], _fails(cold))]
    for name, switches in _LAYERS:
        env = "".join(f"{k}={v} " for k, v in switches.items())
        rows.append(_row(name, env + text, [x.wall for x in timed[name]], _fails(timed[name])))
    warm = rows[1]["median_s"]
    for r in rows[:1] + rows[2:]:
        r["compared"], r["value"] = "x warm", r["median_s"] / warm
    return rows


def _in_run(t: Timed) -> float:
    """The seconds of ``atlas generate``'s own summary line (NaN without one)."""
    lines = [ln for ln in t.stderr.splitlines() if ln.startswith("atlas generate:")]
    return parse_summary(lines[-1])["seconds"] if lines else math.nan


def _large(s: _Session, runs: int) -> list[dict]:
    """The 8.4-million-point atlas: a first run (it compiles into the cache), then ``runs`` warm
    runs, each wall time against the seconds of its own summary line."""
    cmd, text = s.generate(LARGE), "atlas generate " + " ".join(LARGE)
    log("start-up: 8.4M-point atlas, first run")
    first = s.times(cmd, 1)
    log(f"start-up: 8.4M-point atlas, warm x {runs}")
    warm = s.times(cmd, runs)
    in_run = [_in_run(t) for t in warm]
    rows = [
        _row("8.4M-point atlas, first run in the cache", text, [t.wall for t in first],
             _fails(first), in_run=_in_run(first[0])),
        _row("8.4M-point atlas, warm", text, [t.wall for t in warm], _fails(warm),
             value=statistics.median(t.wall / r for t, r in zip(warm, in_run)),
             in_run=statistics.median(in_run)),
    ]  # fmt: skip
    rows[0]["compared"], rows[0]["value"] = "x warm", rows[0]["median_s"] / rows[1]["median_s"]
    return rows


def _selftest(s: _Session, runs: int) -> list[dict]:
    """``atlas selftest``: a first run in the cache, then ``runs`` warm runs; the most
    disagreements of any run (a run that prints no verdict line failed; one that found
    disagreements exits 1 with its verdict line)."""
    cmd = [*s.atlas, "selftest"]
    log(f"start-up: atlas selftest x {runs + 1}")
    first, warm = s.times(cmd, 1), s.times(cmd, runs)
    rows = []
    for figure, t in (("atlas selftest, first run in the cache", first), ("atlas selftest", warm)):
        parsed = [parse_selftest(x.stdout) for x in t]
        fails = ["" if p else x.failure() or "no verdict line" for x, p in zip(t, parsed)]
        bad = max((p["disagreements"] for p in parsed if p), default=None)
        rows.append(_row(figure, "atlas selftest", [x.wall for x in t], fails,
                         compared="disagreements", value=bad))  # fmt: skip
    return rows


def _explorer(s: _Session, runs: int) -> list[dict]:
    """:data:`EXPLORER` in fresh processes: a first session in the cache (it compiles and keeps
    the explorer's kernels), then ``runs`` sessions that start warm; the first map, the first
    click, a second click."""
    figures = (
        ("first map", "first_map"),
        ("first click", "click"),
        ("second click", "second_click"),
    )
    sessions = (("explorer, first session in the cache: ", 1), ("explorer: ", runs))
    if not _have("ipywidgets"):
        note = "not measured: ipywidgets not installed (the notebook extra)"
        return [_row(p + f, "", [], note=note) for p, _ in sessions for f, _ in figures]
    text = "python -c EXPLORER (atlas.bench.startup)"
    rows = []
    for prefix, n_runs in sessions:
        log(f"start-up: {prefix}x {n_runs}")
        t = s.times([sys.executable, "-c", EXPLORER], n_runs)
        got = [bench_json(x.stdout) for x in t]
        fails = [x.failure() or ("" if g else "no result line") for x, g in zip(t, got)]
        n = next((g["n"] for g in got if g), "?")
        some = [_row(prefix + figure, text, [g[key] if g else math.nan for g in got], fails)
                for figure, key in figures]  # fmt: skip
        some[0]["note"] = "; ".join(x for x in (f"{n} x {n} map", some[0]["note"]) if x)
        rows += some
    return rows


def _have(module: str) -> bool:
    """``module`` can be imported in this environment (not imported here)."""
    return importlib.util.find_spec(module) is not None


def measure(cfg: dict, run=run_timed) -> list[dict]:
    """The section's rows for ``cfg`` (the ``startup`` entry of a
    :data:`~atlas.bench.config.CONFIG` mode: the runs of each figure, 0 = not measured);
    ``run(cmd, env, cwd) -> Timed`` starts one process (:func:`run_timed`)."""
    with tempfile.TemporaryDirectory(prefix="atlas-bench-startup-") as tmp:
        s = _Session(Path(tmp), run)
        rows = _cheap(s, cfg["runs"])
        if cfg["generate_runs"]:
            rows += _refusal(s, cfg["runs"])
            rows += _generate(s, cfg["cold_runs"], cfg["generate_runs"])
        if cfg["large_runs"]:
            rows += _large(s, cfg["large_runs"])
        if cfg["selftest_runs"]:
            rows += _selftest(s, cfg["selftest_runs"])
        if cfg["explorer_runs"]:
            rows += _explorer(s, cfg["explorer_runs"])
        if cfg["cold_runs"]:
            log("start-up: the programs of each cold command")
            rows += startup_programs.measure(s, PROGRAMS)
    return rows


def main(argv=None) -> int:  # pragma: no cover - a measurement
    """``python -m atlas.bench.startup [full|quick|tiny]``: this section alone, printed."""
    from atlas.bench.report import startup_section  # noqa: PLC0415

    args = argv if argv is not None else sys.argv[1:]
    mode = mode_name(config=args[0] if args else None)
    rows = measure(CONFIG[mode]["startup"])
    print("\n".join(startup_section(rows)))
    print("BENCH_JSON " + json.dumps(rows))
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
