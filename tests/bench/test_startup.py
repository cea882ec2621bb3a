"""``atlas.bench.startup``: its pure parts (parsing, spread, met/missed) and the section run with
made-up processes: one temporary cache, never the user's, each figure against its target."""

import json
import math
import os
from pathlib import Path

import pytest

from atlas.bench import startup
from atlas.bench.config import CONFIG
from atlas.bench.report import startup_section
from atlas.bench.startup import Timed, parse_selftest, spread, verdict

#: the last lines ``atlas selftest`` printed on this machine
PASSED = (
    "  class_boundaries   float32     72 points,    72 decided by the fast tiers, 0 disagreements "
    "with the exact tier\n"
    "PASSED: 0 disagreements in 1752 decided of 1752 points; fast tiers float64 3,971 ns/point, "
    "float32 2,937 ns/point (compiled, small batches); 10.2 s\n"
    "recorded in /tmp/cache/selftest.json\n"
)


def test_parse_selftest():
    assert parse_selftest(PASSED) == dict(
        passed=True, disagreements=0, decided=1752, points=1752, seconds=10.2
    )
    failed = "FAILED: 3 disagreements in 1700 decided of 1752 points; fast tiers x; 7.5 s"
    assert parse_selftest(failed) == dict(
        passed=False, disagreements=3, decided=1700, points=1752, seconds=7.5
    )
    assert parse_selftest("atlas: error: suites: unknown ['x']") is None


def test_spread_median_min_max():
    assert spread([3.0, 1.0, 2.0, 10.0]) == dict(median_s=2.5, min_s=1.0, max_s=10.0)
    assert spread([4.0, math.nan, None, 1.0, 2.0]) == dict(median_s=2.0, min_s=1.0, max_s=4.0)
    assert all(math.isnan(v) for v in spread([]).values())


@pytest.mark.parametrize(
    "value, target, word",
    [
        (0.4, 0.5, "met"),
        (0.5, 0.5, "met"),
        (0.51, 0.5, "missed"),
        (0, 0, "met"),
        (2, 0, "missed"),
        (None, 0.5, "failed"),
        (math.nan, 2.0, "failed"),
        (3.0, None, ""),
    ],
)
def test_verdict(value, target, word):
    assert verdict(value, target) == word


class FakeProcesses:
    """Made-up processes: wall times by figure, the outputs each command prints; every call
    writes into the cache and the working directory it was given, as a real run would."""

    def __init__(self, selftest=PASSED, selftest_rc=0):
        self.calls = []
        self.selftest, self.selftest_rc, self.selftest_err = selftest, selftest_rc, ""
        self.plain_jit_cold = True

    def __call__(self, cmd, env, cwd):
        cache = Path(env["ATLAS_JAX_CACHE"])
        self.calls.append(
            dict(cmd=cmd, env=dict(env), cwd=cwd, cache_before=sorted(os.listdir(cache)))
        )
        (cache / f"entry{len(self.calls)}").write_text("x")
        Path(cwd, "written").write_text("x")
        text = " ".join(cmd)
        if "atlas.bench.startup_programs" in cmd:  # a cold command's programs (its recording)
            prog = dict(
                name=cmd[4], shapes="f64[16]", compiles=1, trace_s=1, lower_s=1, compile_s=4
            )
            Path(cmd[3]).write_text(json.dumps(dict(rc=0, wall_s=7.0, programs=[prog])))
            return Timed(8.0, 0)
        if cmd[-1] == "import atlas":
            return Timed(0.3, 0)
        if cmd[-1] == "--help":
            return Timed(0.7, 0)
        if "0:2pi:10000000" in text:
            return Timed(0.9, 2, "", "atlas: error: size: 1e+14 points ...")
        if "0:2pi:16" in text:
            if not self.calls[-1]["cache_before"]:
                wall = 20.0
            else:
                wall = {"0": 5.0}.get(env.get("ATLAS_KERNEL_CACHE"), 2.5)
                if env.get("ATLAS_KERNEL_CACHE") == "0" and self.plain_jit_cold:
                    wall, self.plain_jit_cold = 30.0, False  # its first run compiles
                wall = {"0": 4.0}.get(env.get("ATLAS_KERNEL_EXECUTABLES"), wall)
            return Timed(wall, 0, "", _summary(512, wall - 1.0))
        if "0:2pi:512" in text:
            first = not any("0:2pi:512" in " ".join(c["cmd"]) for c in self.calls[:-1])
            return Timed(40.0 if first else 5.0, 0, "", _summary(8388608, 4.0))
        if cmd[-1] == "selftest":
            return Timed(9.0, self.selftest_rc, self.selftest, self.selftest_err)
        if cmd[-1] == startup.EXPLORER:
            js = '{"first_map": 3.5, "click": 8.0, "second_click": 0.1, "n": 513}'
            return Timed(15.0, 0, "BENCH_JSON " + js)
        raise AssertionError(cmd)


def _summary(points, seconds):
    return (
        f"atlas generate: /x/atlas.nc: {points} points in {seconds:.2f} s "
        f"({points / seconds:.3g} points/s), 0.10 MB; undecided 3 before, 0 after exact resolution"
    )


@pytest.fixture
def user_cache(tmp_path, monkeypatch):
    """A user's cache with an entry, and warm-start switches set in the user's environment."""
    cache = tmp_path / "user-cache"
    cache.mkdir()
    (cache / "mine").write_text("keep")
    monkeypatch.setenv("ATLAS_JAX_CACHE", str(cache))
    monkeypatch.setenv("ATLAS_KERNEL_CACHE", "0")
    monkeypatch.setenv("ATLAS_KERNEL_EXECUTABLES", "0")
    monkeypatch.setattr(startup, "_have", lambda module: True)
    return cache


def _by_figure(rows):
    return {r["figure"]: r for r in rows}


def test_full_section_in_a_temporary_cache(user_cache, tmp_path):
    procs = FakeProcesses()
    rows = _by_figure(startup.measure(CONFIG["full"]["startup"], run=procs))
    # the user's cache is neither read nor written; one temporary cache, gone afterwards
    assert (
        sorted(os.listdir(user_cache)) == ["mine"] and (user_cache / "mine").read_text() == "keep"
    )
    caches = {c["env"]["ATLAS_JAX_CACHE"] for c in procs.calls}
    (cache,) = caches
    assert Path(cache) != user_cache and not Path(cache).exists()
    assert all(not Path(c["cwd"]).exists() and Path(cache).parent in Path(c["cwd"]).parents
               for c in procs.calls)  # fmt: skip
    # the cold run starts from an empty cache; the user's switches are not inherited
    gen = [c for c in procs.calls if "0:2pi:16" in " ".join(c["cmd"]) and "-m" not in c["cmd"]]
    assert gen[0]["cache_before"] == [] and all(c["cache_before"] for c in gen[1:])
    switched = [(c["env"].get("ATLAS_KERNEL_CACHE"), c["env"].get("ATLAS_KERNEL_EXECUTABLES"))
                for c in gen[1:]]  # fmt: skip
    assert switched == [(None, None), (None, "0"), ("0", None)] * 4  # a round untimed
    # the figures and their targets, from the made-up times
    assert rows["import atlas"]["met"] == "met" and rows["import atlas"]["runs"] == 5
    refused = rows["1e14-point scene refused"]  # reported, no target: exit 2 is its success
    assert (refused["median_s"], refused["met"], refused["runs"]) == (0.9, "", 5)
    assert rows["atlas --help"]["met"] == "missed"  # 0.7 s > 0.5 s
    warm = rows["generate 512 points, warm"]
    assert (warm["median_s"], warm["target"], warm["met"]) == (2.5, 2.0, "missed")
    assert rows["generate 512 points, cold"]["value"] == pytest.approx(8.0)  # 20 / 2.5
    assert rows["generate 512 points, exported programs only"]["value"] == pytest.approx(1.6)
    assert rows["generate 512 points, compilation cache only"]["value"] == pytest.approx(2.0)
    large = rows["8.4M-point atlas, warm"]
    assert (large["value"], large["in_run_s"], large["met"]) == (1.25, 4.0, "met")  # 5 s / 4 s
    assert rows["8.4M-point atlas, first run in the cache"]["value"] == pytest.approx(8.0)
    assert (rows["atlas selftest"]["value"], rows["atlas selftest"]["met"]) == (0, "met")
    assert rows["explorer: first click"]["median_s"] == 8.0
    assert rows["explorer: first map"]["note"] == "513 x 513 map"
    first = rows["explorer, first session in the cache: first click"]
    assert (first["runs"], first["median_s"]) == (1, 8.0)
    explorer = [c for c in procs.calls if "make_widget" in " ".join(c["cmd"])]
    assert len(explorer) == 1 + CONFIG["full"]["startup"]["explorer_runs"]
    # each cold command's programs, in an emptied cache
    cold = [c for c in procs.calls if "atlas.bench.startup_programs" in c["cmd"]]
    assert [c["cmd"][4] for c in cold] == [k for _, k, _ in startup.PROGRAMS]
    assert all(c["cache_before"] == [] for c in cold)
    paper = rows["cold, programs compiled: atlas paper --quick"]
    assert (paper["value"], paper["median_s"]) == (1, 8.0)
    md = "\n".join(startup_section(list(rows.values())))
    assert "| cli | f64[16] | 1 | 1.00 | 1.00 | 4.00 |" in md
    assert "**Targets**: met in 3 of 5 figures." in md
    assert "| atlas --help | 5 | 0.7 | 0.7 | 0.7 | - | median s | 0.7 | 0.5 | missed |" in md


#: the section with ``import atlas``, ``atlas --help`` and ``atlas selftest`` only
SELFTEST_ONLY = dict(CONFIG["full"]["startup"], generate_runs=0, large_runs=0, explorer_runs=0)


@pytest.mark.parametrize(
    "text, rc, note",
    [("no verdict line", 0, "no verdict line"), ("", 2, "exit 2: atlas: error: x")],
)
def test_selftest_without_its_verdict_line_failed(user_cache, text, rc, note):
    procs = FakeProcesses(text, rc)
    procs.selftest_err = "atlas: error: x"
    rows = _by_figure(startup.measure(SELFTEST_ONLY, run=procs))
    assert rows["atlas selftest"]["met"] == "failed" and rows["atlas selftest"]["note"] == note


def test_selftest_disagreements_miss_the_target(user_cache):
    text = PASSED.replace("PASSED: 0", "FAILED: 2")  # atlas selftest then exits 1
    rows = _by_figure(startup.measure(SELFTEST_ONLY, run=FakeProcesses(text, 1)))
    assert (rows["atlas selftest"]["value"], rows["atlas selftest"]["met"]) == (2, "missed")


@pytest.mark.parametrize("mode", ["quick", "tiny"])
def test_quick_and_tiny_runs_start_two_processes(user_cache, mode):
    procs = FakeProcesses()
    rows = startup.measure(CONFIG[mode]["startup"], run=procs)
    assert [r["figure"] for r in rows] == ["import atlas", "atlas --help"]
    assert len(procs.calls) == 2


def test_a_refusal_that_does_not_refuse_is_a_failure(user_cache):
    """``atlas generate`` of the 1e14-point scene must exit 2; exit 0 is reported as a failure."""
    procs = FakeProcesses()
    real = procs.__call__

    def accepting(cmd, env, cwd):
        got = real(cmd, env, cwd)
        return Timed(got.wall, 0) if got.returncode == 2 else got

    rows = _by_figure(startup.measure(CONFIG["full"]["startup"], run=accepting))
    assert rows["1e14-point scene refused"]["note"] == "exit 2; exit 0: not refused"
