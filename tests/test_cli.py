"""The ``atlas`` CLI: one-line errors with exit code 2, existing files untouched, a tiny scene end to
end, ``--help`` on every subcommand.  Through ``cli.main`` in this process (the code path of the
console script, without an interpreter start-up each), except one subprocess smoke test and the
signal test (``e2e``)."""

import contextlib
import functools
import io
import os
import re
import subprocess
import sys

import numpy as np
import pytest
import xarray as xr
from work_count import counted

from atlas import cli
from atlas.core.warm import KERNEL_ENV

TINY = ["--beta1", "0:2pi:8", "--beta2", "0:2pi:8"]


@pytest.fixture
def exported_kernels(monkeypatch):
    """The kernels run as exported programs kept on disk, as in a user's run (conftest.py
    switches that off for the other in-process CLI calls)."""
    monkeypatch.delenv(KERNEL_ENV, raising=False)


@pytest.fixture(scope="module", autouse=True)
def table2_once():
    """Table 2 computed once for this module's ``atlas table`` runs (~0.5 s each), on the quick
    run's sample (8 points a class, as tests/paper/test_tables.py, which checks the rows): they
    check where the table goes and in which format (all 24 classes), not its sample size."""
    from atlas.paper import tables

    table2 = tables.table2
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(tables, "table2", functools.cache(lambda: table2(n=96, per_class=8)))
        yield


def _env():
    env = dict(os.environ)  # ATLAS_JAX_CACHE: the run's shared compilation cache (conftest.py)
    env.pop("ATLAS_PROGRESS", None)
    env.pop(KERNEL_ENV, None)  # a user's run: exported kernels
    return env


def _spawn(args, env):
    return subprocess.Popen(
        [sys.executable, "-m", "atlas.cli", *args],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
    )


# bad inputs without --overwrite: (arguments, parameter)
BAD = [
    (["--kappa", "nan"], "kappa"),
    (["--q", "inf"], "q"),
    (["--physical", "k1=-100,k2=200"], "k1"),
    (["--physical", "k1=100,k2=200,b2=-1"], "b2"),
    (["--beta2", "0:1:0"], "beta2"),
    (["--beta1", "1:0:5"], "beta1"),
    (["--outputs", "class_code,no_such_var"], "outputs"),
    (["--out", "/nonexistent-dir/a.nc"], "out"),
    (["--out", "{existing}"], "out"),  # exists, no --overwrite
]
# more bad inputs, with --overwrite
BAD_OVERWRITE = [
    (["--kappa", "-1"], "kappa"),
    (["--kappa", "log:1:0.1:3"], "kappa"),
    (["--alpha", "0:2pi:x"], "alpha"),
    (["--q1", "0.1"], "q2"),
    (["--q", "0.1", "--q1", "0.1", "--q2", "0.2"], "q"),
    (["--physical", "k1=1"], "k2"),
    (["--physical", "k1=1,k2=1,z=3"], "physical"),
    (["--physical", "k1=1,k2=1", "--kappa", "2"], "physical"),
    (["--dtype", "float16"], "dtype"),
    (["--method", "magic"], "method"),
    (["--tile-points", "0"], "tile-points"),
    (["--scene", "fig9"], "scene"),
    (["--outputs", "subclass_code"], "outputs"),  # needs alpha
    (["--out", "{dir}"], "out"),  # a directory
]


def _check_one_line(err, name, extra):
    lines = err.strip().splitlines()
    assert len(lines) == 1, (extra, err)
    assert "Traceback" not in err
    assert name in lines[0], (extra, lines[0])


@pytest.mark.parametrize("extra, name", BAD)
def test_bad_inputs_exit_2_one_line(extra, name, tmp_path, capsys):
    existing = tmp_path / "existing.nc"
    existing.write_bytes(b"keep me")
    extra = [a.format(existing=existing) for a in extra]
    args = ["generate", *TINY, "--outputs", "class_code", "--out", str(existing), *extra]
    assert cli.main(args) == 2
    _check_one_line(capsys.readouterr().err, name, extra)
    assert existing.read_bytes() == b"keep me"
    assert sorted(os.listdir(tmp_path)) == ["existing.nc"]


@pytest.mark.parametrize("extra, name", BAD_OVERWRITE)
def test_bad_inputs_with_overwrite(extra, name, tmp_path, capsys):
    existing = tmp_path / "existing.nc"
    existing.write_bytes(b"keep me")
    extra = [a.format(dir=tmp_path) for a in extra]
    args = ["generate", *TINY, "--outputs", "class_code", "--out", str(existing), "--overwrite"]
    assert cli.main(args + extra) == 2
    _check_one_line(capsys.readouterr().err, name, extra)
    assert existing.read_bytes() == b"keep me"
    assert sorted(os.listdir(tmp_path)) == ["existing.nc"]


@pytest.mark.usefixtures("exported_kernels")
def test_generate_end_to_end(tmp_path, capsys):
    out = tmp_path / "tiny.nc"
    args = ["generate", *TINY, "--kappa", "0.5,2", "--q", "0,0.5", "--alpha", "0:2pi:4"]
    args += ["--outputs", "class_code,subclass_code,stable_SS,model_dependent_SS,stable_SF"]
    args += ["--out", str(out), "--tile-points", "256"]
    rc, err = cli.main(args), capsys.readouterr().err
    assert rc == 0, err
    summary = err.strip().splitlines()[-1]
    for word in ("points", " s ", "points/s", "undecided"):
        assert word in summary
    with xr.open_dataset(out) as ds:
        assert ds.stable_SS.dims == ("beta1", "beta2", "kappa", "q")
        assert ds.stable_SS.dtype == np.int8 and ds.class_code.dtype == np.int8
        assert ds.attrs["Conventions"] == "CF-1.10"
        assert "atlas generate" in ds.attrs["history"]
        assert ds.attrs["undecided_after_resolve"] == 0
    # an existing output is replaced only with --overwrite
    before = out.read_bytes()
    rc, err = cli.main(args), capsys.readouterr().err
    assert rc == 2 and "out:" in err and out.read_bytes() == before
    args2 = [a for a in args if a not in ("--kappa", "0.5,2", "--q", "0,0.5")]
    args2 = [a if a != "model_dependent_SS" else "cc_possible" for a in args2]
    args2 = [a.replace(",model_dependent_SS", "") for a in args2]
    rc = cli.main([*args2, "--overwrite", "--physical", "k1=100,k2=200,q1=20,q2=20"])
    assert rc == 0, capsys.readouterr().err
    with xr.open_dataset(out) as ds:
        assert float(ds.kappa) == pytest.approx(0.5) and float(ds.q) == pytest.approx(2**0.5)


@pytest.mark.e2e
def test_subprocess_smoke(tmp_path):
    """The console entry point in a fresh interpreter; ATLAS_PROGRESS=1 forces the bar (as on a
    terminal): the run completes and shows it."""
    env = _env()
    env["ATLAS_PROGRESS"] = "1"
    out = tmp_path / "p.nc"
    p = _spawn(["generate", *TINY, "--outputs", "class_code,stable_SS", "--out", str(out)], env)
    _, err = p.communicate(timeout=300)
    assert p.returncode == 0, err
    assert "atlas custom" in err and "pt" in err  # the tqdm bar, then the summary line
    assert out.exists()


@pytest.mark.parametrize("sub", list(cli.HELP))
def test_help(sub, capsys):
    assert cli.main([sub, "--help"]) == 0
    assert "usage: atlas " + sub in capsys.readouterr().out


def test_top_level_help_lists_every_subcommand(capsys):
    assert cli.main(["--help"]) == 0
    out = " ".join(capsys.readouterr().out.split())
    for sub, line in cli.HELP.items():
        assert f"{sub} {line}" in out, sub


def test_simulate_and_table_run(tmp_path, capsys):
    """The dispatched subcommands resolve to real functions (no placeholder path)."""
    csv = tmp_path / "d.csv"
    rc = cli.main(["simulate", "--case", "fig2b", "--t-end", "5", "--out", str(csv)])
    out, err = capsys.readouterr()
    assert rc == 0, err
    assert out.startswith("b: ") and csv.read_text().startswith("t,kind,contact")
    rc = cli.main(["table", "--format", "csv"])
    out, err = capsys.readouterr()
    assert rc == 0, err
    assert len(out.strip().splitlines()) == 25  # header + 24 classes


@pytest.mark.parametrize(
    "argv",
    [
        ["paper"],
        ["paper", "--quick", "--jobs", "1", "--out", "d"],
        ["bench"],
        ["bench", "--quick", "--out", "d"],
        ["table", "--format", "csv"],
        ["simulate", "--case", "fig2b", "--t-end", "1"],
        ["simulate", "--map", "--n", "4", "--store", "s", "--engine", "jax"],
        ["boundaries", "--kappa", "2"],
        ["boundaries", "--model-box", "kappa=0.5:2"],
        ["mechanism", "ladder"],
        ["selftest"],
        ["mujoco", "m.xml", "--json"],
    ],
)
def test_every_option_reaches_a_parameter_of_the_real_function(argv):
    """The options a command line parses bind to the signature of the function the command
    really runs (not a stand-in): a renamed or removed parameter, or a new option without one,
    fails here, before any user meets the ``TypeError``."""
    import inspect

    args = cli.build_parser(argv[0]).parse_args(argv)
    fn, opts = cli.dispatch_call(args, argv)
    params = inspect.signature(fn).parameters
    inspect.signature(fn).bind(**opts)
    if not any(p.kind is p.VAR_KEYWORD for p in params.values()):
        assert set(opts) <= set(params), (fn.__module__, set(opts) - set(params))


def test_simulate_a_custom_trajectory_equals_its_fig2_case(tmp_path, capsys):
    """``--beta1 --beta2 --alpha --k1 --k2 --q1 --q2`` (the custom trajectory starts at rest,
    ``g0 = 0``, as the Fig. 2d case) writes the same events, byte for byte, as ``--case fig2d``;
    the events are those of :func:`atlas.dynamics.simulate` on the caption's parameters."""
    from atlas.dynamics import simulate
    from atlas.dynamics.outcome import fig2_cases

    custom = ["--beta1", "0.15pi", "--beta2", "1.07pi", "--alpha", "0.2pi", "--k1", "100"]
    custom += ["--k2", "200", "--q1", "20", "--q2", "20", "--t-end", "3"]
    a, b = tmp_path / "custom.csv", tmp_path / "case.csv"
    assert cli.main(["simulate", *custom, "--out", str(a)]) == 0
    assert cli.main(["simulate", "--case", "fig2d", "--t-end", "3", "--out", str(b)]) == 0
    out = capsys.readouterr().out
    assert "custom: " in out and "d: " in out
    assert a.read_bytes() == b.read_bytes()
    res = simulate(**dict(fig2_cases()["d"], t_end=3.0), max_events=100_000)
    rows = a.read_text().splitlines()[1:]
    assert len(rows) == res.n_events and res.n_events > 0
    assert [float(r.split(",")[0]) for r in rows] == [float(t) for t in res.t_events]


@pytest.mark.parametrize(
    "args, ending, magic",
    [
        (["--case", "fig2b", "--t-end", "1"], ".png", b"\x89PNG"),
        (["--case", "fig2b", "--t-end", "1"], ".pdf", b"%PDF"),
        (["--case", "fig2b", "--t-end", "1"], ".svg", b"<?xml"),
        (["--map", "--n", "3", "--t-end", "2", "--workers", "1"], ".pdf", b"%PDF"),
    ],
)
def test_simulate_figure_outputs_are_reproducible(args, ending, magic, tmp_path, capsys):
    """``atlas simulate --out`` as a figure (one trajectory: ``.png``, ``.pdf``, ``.svg``; a map:
    ``.pdf``, the same drawing code as ``.png``): the file is of that format, and a second run
    writes the same bytes (fixed metadata, no date)."""
    got = []
    for k in range(2):
        out = tmp_path / f"f{k}{ending}"
        assert cli.main(["simulate", *args, "--out", str(out)]) == 0, capsys.readouterr().err
        got.append(out.read_bytes())
    assert got[0].startswith(magic) and got[0] == got[1]


@pytest.mark.parametrize(
    "name, fmt, first",
    [("t.csv", [], "class,"), ("t.md", [], "| class"), ("t.txt", [], "| class"),
     ("t.txt", ["--format", "csv"], "class,"), ("t.csv", ["--format", "csv"], "class,")],
)  # fmt: skip
def test_table_out_ending_names_the_format(name, fmt, first, tmp_path, capsys):
    """``atlas table --out t.csv`` writes CSV and ``t.md`` Markdown (both wrote Markdown
    before); ``--format`` picks where the ending does not (``.txt``)."""
    out = tmp_path / name
    assert cli.main(["table", "--out", str(out), *fmt]) == 0, capsys.readouterr().err
    assert out.read_text().startswith(first)


def test_table_format_against_the_ending_is_refused(tmp_path, capsys):
    out = tmp_path / "t.md"
    assert cli.main(["table", "--format", "csv", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("atlas: error: format: --format csv but --out")
    assert not out.exists()


def test_dispatch_passes_options(monkeypatch):
    import types

    seen = {}
    fake = types.ModuleType("atlas._fake_table")
    fake.run_cli = lambda **kw: seen.update(kw) or 0
    monkeypatch.setitem(sys.modules, "atlas._fake_table", fake)
    monkeypatch.setitem(cli._DISPATCH, "table", ("atlas._fake_table", "run_cli"))
    assert cli.main(["table", "--format", "csv"]) == 0
    assert seen == {"format": "csv", "out": None, "overwrite": False}
    assert cli.main(["table"]) == 0 and seen["format"] is None  # the ending or Markdown decides


def test_no_subcommand_is_usage_error(capsys):
    assert cli.main([]) == 2
    assert len(capsys.readouterr().err.strip().splitlines()) == 1


@pytest.mark.e2e
def test_sigterm_leaves_no_partial_file(tmp_path):
    import signal
    import time

    out = tmp_path / "big.nc"
    # ~1e9 points: minutes of work at 1e7 points/s, so the signal arrives mid-run
    args = ["generate", "--beta1", "0:2pi:4096", "--beta2", "0:2pi:4096", "--kappa", "log:1:4:8"]
    args += ["--q", "log:0.1:0.4:8", "--outputs", "stable_SS", "--out", str(out)]
    p = _spawn(args, _env())
    deadline = time.time() + 60
    while time.time() < deadline and not any(f.endswith(".tmp") for f in os.listdir(tmp_path)):
        time.sleep(0.1)  # wait until the temporary file is being written
    p.send_signal(signal.SIGTERM)
    _, err = p.communicate(timeout=60)
    assert p.returncode == 128 + signal.SIGTERM, err
    assert "interrupted" in err and "Traceback" not in err
    assert os.listdir(tmp_path) == []


# --- atlas generate --scheduler/--store/--resume (atlas.data.distributed through the CLI) ---------------

SCENE5 = ["--beta1", "0:2pi:8", "--beta2", "0:2pi:8", "--kappa", "0.5,2"]
SCENE5 += ["--q1", "0,1", "--q2", "0,0.5", "--tile-points", "128", "--no-progress"]
# a beta1-free variable (stable_FS: shared by all tiles) and a reduction over the model dimensions
SCENE5 += ["--outputs", "class_code,stable_SS,model_dependent_SS,stable_SF,stable_FS"]


def _main(args) -> tuple[int, str]:
    """``cli.main(args)`` in this process: its exit code and what it wrote on stderr."""
    err = io.StringIO()
    with contextlib.redirect_stderr(err):
        rc = cli.main(args)
    return rc, err.getvalue()


def _same_netcdf(a, b):
    """Same variables, coordinates, dtypes, raw bytes, attributes (global ones but ``history``)."""
    with xr.open_dataset(a) as x, xr.open_dataset(b) as y:
        x, y = x.load(), y.load()
    assert set(x.variables) == set(y.variables)
    for k in y.variables:
        assert x[k].dims == y[k].dims and x[k].dtype == y[k].dtype, k
        assert x[k].values.tobytes() == y[k].values.tobytes(), k
        assert x[k].attrs.keys() == y[k].attrs.keys(), k
        for name, v in y[k].attrs.items():
            np.testing.assert_array_equal(x[k].attrs[name], v)
    drop = lambda attrs: {k: v for k, v in attrs.items() if k != "history"}  # noqa: E731
    assert drop(x.attrs) == drop(y.attrs)


@pytest.fixture(scope="module")
def distributed_run(tmp_path_factory):
    """The in-process ``atlas generate`` file and ``--scheduler inprocess --slab 2`` (4 tiles)."""
    pytest.importorskip("zarr")
    d = tmp_path_factory.mktemp("dist")
    rc, err = _main(["generate", *SCENE5, "--out", str(d / "ref.nc")])
    assert rc == 0, err
    args = ["generate", *SCENE5, "--scheduler", "inprocess", "--slab", "2"]
    rc, err = _main([*args, "--out", str(d / "a.nc")])
    assert rc == 0, err
    return d, err


def test_generate_scheduler_inprocess_then_resume(distributed_run):
    d, err = distributed_run
    summary = err.strip().splitlines()[-1]
    assert str(d / "a.zarr") in summary and "4 tiles: 4 computed, 0 verified" in summary
    assert "in-process" in summary and "points/s" in summary
    _same_netcdf(d / "a.nc", d / "ref.nc")
    # lose one tile's record, damage another's bytes: --resume recomputes exactly those two
    import shutil

    import zarr

    shutil.rmtree(d / "a.zarr" / "_tiles" / "t000001")
    g = zarr.open_group(str(d / "a.zarr"), mode="r+")
    g["class_code"][6:8] = 0
    args = ["generate", *SCENE5, "--scheduler", "inprocess", "--slab", "2"]
    args += ["--store", str(d / "a.zarr"), "--out", str(d / "b.nc"), "--resume"]
    rc, err = _main(args)
    assert rc == 0, err
    summary = err.strip().splitlines()[-1]
    assert "4 tiles: 2 computed, 2 verified, 1 missing and 1 corrupt before" in summary, summary
    _same_netcdf(d / "b.nc", d / "ref.nc")
    with xr.open_dataset(d / "b.nc") as ds:
        assert "resumed, 2 of 4 tiles recomputed" in ds.attrs["history"]


def test_generate_resume_after_a_killed_replacement(distributed_run, tmp_path):
    """A run killed between the renames of ``--overwrite`` leaves the store only as
    ``.NAME.old.PID`` (its process gone): ``--resume`` renames it back, says so in one line,
    and verifies every tile (it was "store ... does not exist")."""
    import shutil

    d, _ = distributed_run
    gone = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True, check=True)  # fmt: skip
    shutil.copytree(d / "a.zarr", tmp_path / f".c.zarr.old.{int(gone.stdout)}")
    args = ["generate", *SCENE5, "--scheduler", "inprocess", "--slab", "2"]
    rc, err = _main([*args, "--store", str(tmp_path / "c.zarr"), "--out", str(tmp_path / "c.nc"),
                     "--resume"])  # fmt: skip
    assert rc == 0, err
    lines = err.strip().splitlines()
    assert lines[0].startswith(f"store: restored {tmp_path / 'c.zarr'} from "), err
    assert "4 tiles: 0 computed, 4 verified" in lines[-1], err
    assert sorted(os.listdir(tmp_path)) == ["c.nc", "c.zarr"]
    _same_netcdf(tmp_path / "c.nc", d / "ref.nc")


def test_generate_distributed_bad_inputs(distributed_run, tmp_path, capsys):
    """One line ``atlas: error: PARAMETER: ...``, exit code 2, existing files untouched."""
    d, _ = distributed_run
    store = d / "a.zarr"
    before = sorted(str(p) for p in store.rglob("*"))
    bad = [
        (["--scheduler", "nowhere"], "scheduler:"),
        (["--resume", "--store", str(tmp_path / "none.zarr")], "resume:"),
        (["--store", str(store), "--resume", "--kappa", "0.5,3"], "store:"),  # another scene
    ]
    base = ["generate", *SCENE5, "--scheduler", "inprocess", "--slab", "2"]
    more = [
        (["--scheduler", "local:0"], "scheduler:"),
        (["--scheduler", "tcp://"], "scheduler:"),
        (["--resume", "--overwrite", "--store", str(store)], "resume:"),
        (["--store", str(store)], "store:"),  # exists: neither --resume nor --overwrite
        (["--store", str(store), "--resume", "--slab", "4"], "store:"),  # another tiling
        (["--store", str(store), "--resume", "--method", "eig"], "store:"),  # other options
        (["--store", str(tmp_path / "no" / "x.zarr")], "store:"),
        (["--store", str(tmp_path / "x.zarr"), "--out", str(d / "ref.nc")], "out:"),
        (["--store", str(tmp_path / "x.zarr"), "--slab", "0"], "slab"),
        (["--store", str(tmp_path / "x.zarr"), "--block2", "0"], "block2"),
        (["--store", str(tmp_path / "x.zarr"), "--block2", "2", "--beta2", "1"], "block2:"),
    ]
    got = []
    for extra, _ in bad + more:
        rc = cli.main([*base, *extra])
        got.append((rc, capsys.readouterr().err))
    for (extra, name), (rc, err) in zip(bad + more, got, strict=True):
        assert rc == 2, (extra, err)
        lines = err.strip().splitlines()
        assert len(lines) == 1 and "Traceback" not in err, (extra, err)
        assert "error: " in lines[0] and name in lines[0], (extra, lines[0])
    assert sorted(str(p) for p in store.rglob("*")) == before
    assert os.listdir(tmp_path) == []


def test_swallowed_interrupt_is_not_reported_but_other_errors_are(capsys):
    """A KeyboardInterrupt lost in a gc callback is re-delivered, not printed; others print."""
    import sys
    import types

    from atlas import cli_signals

    def info(exc):
        return types.SimpleNamespace(
            exc_type=type(exc), exc_value=exc, exc_traceback=None, err_msg=None, object=None
        )

    cli_signals.unraisable(info(KeyboardInterrupt()))
    assert capsys.readouterr().err == ""
    forwarded = []
    default = sys.__unraisablehook__
    try:
        sys.__unraisablehook__ = forwarded.append
        cli_signals.unraisable(info(RuntimeError("boom")))
    finally:
        sys.__unraisablehook__ = default
    assert [str(i.exc_value) for i in forwarded] == ["boom"]


# --- signals: SIGINT / SIGTERM always end the run, and nothing is committed after one ----------

TINY_RUN = ["generate", *TINY, "--outputs", "class_code,stable_SS", "--no-progress"]


def _handles_sigterm(pid) -> bool:
    """True once the process catches SIGTERM (from the first line of the package's import)."""
    import signal

    try:
        with open(f"/proc/{pid}/status") as fh:
            mask = next(line for line in fh if line.startswith("SigCgt:")).split()[1]
    except (OSError, StopIteration):
        return False
    return bool(int(mask, 16) >> (signal.SIGTERM - 1) & 1)


def _exited(pid) -> bool:
    """True once the process is past its last word on the exit code: gone, a zombie, or its
    main thread blocking the stop signals (``cli_signals.hard_exit``, which never unblocks)."""
    import signal

    try:
        with open(f"/proc/{pid}/status") as fh:
            rows = dict(line.split(":", 1) for line in fh if ":" in line)
    except OSError:
        return True
    if rows.get("State", "").split()[:1] in (["Z"], ["X"]):
        return True
    blocked = int(rows.get("SigBlk", "0").strip() or "0", 16)
    return bool(blocked >> (signal.SIGTERM - 1) & 1)


def _stage(p, out) -> str:
    """How far a run is: ``"start"`` (the interpreter), ``"main"`` (the package imports and
    ``main()``: stop signals caught) or ``"write"`` (its temporary output file exists)."""
    if any(n.endswith(".tmp") for n in os.listdir(out.parent)):
        return "write"
    return "main" if _handles_sigterm(p.pid) else "start"


@pytest.mark.skipif(not os.path.isdir("/proc/self"), reason="needs Linux /proc")
@pytest.mark.parametrize("writes", [2, pytest.param(5, marks=pytest.mark.slow)])
def test_sigterm_at_random_points_never_exits_0_nor_dies_late(writes, tmp_path):
    """SIGTERM at random points of whole runs, from the imports to just before exit: a run never
    ends with exit 0 after the signal (ignored) nor by another signal (a late alarm), prints no
    traceback and leaves no temporary file; with exit 143 (130 for SIGINT) the file is absent or
    complete.  During the package imports a signal ends the run at once (130 / 143, no
    traceback); before them, in the interpreter's start, SIGTERM kills by its default action
    (-15).  Each delay counts from a stage of the run (``_stage``), in units of a warm-up run's
    time from that stage to its exit; ``writes`` trials aim at the end (tile writes, commit,
    exit): 2 in CI, 5 with ``-m slow``.  A first run, in this process (the caches are the
    subprocesses'; one interpreter start fewer), fills the compilation and kernel caches with
    the exported kernels a user's run keeps (timed on a cold cache, the trials would finish
    before their signals)."""
    import random
    import signal
    import time

    env = _env()
    with pytest.MonkeyPatch.context() as mp:
        mp.delenv(KERNEL_ENV, raising=False)  # a user's run: exported kernels
        assert cli.main([*TINY_RUN, "--out", str(tmp_path / "cold.nc")]) == 0
    warm = tmp_path / "warm" / "a.nc"
    warm.parent.mkdir()
    p = _spawn([*TINY_RUN, "--out", str(warm)], env)
    seen = {}
    while p.poll() is None:
        seen.setdefault(_stage(p, warm), time.perf_counter())
        time.sleep(0.002)
    end = time.perf_counter()
    _, err = p.communicate()
    assert p.returncode == 0, err
    left = {k: end - t for k, t in seen.items()}
    rng = random.Random(28)
    plan = [("start", rng.uniform(0, 0.5), signal.SIGTERM), ("main", 0.0, signal.SIGINT)]
    plan += [("main", rng.uniform(0, 1), signal.SIGTERM)]
    plan += [("write", rng.uniform(0, 1.3), signal.SIGTERM) for _ in range(writes)]
    outcomes = []
    for batch in range(0, len(plan), 4):
        trials = []
        for k, (stage, f, sig) in enumerate(plan[batch : batch + 4], start=batch):
            out = tmp_path / f"t{k}" / "a.nc"
            out.parent.mkdir()
            proc = _spawn([*TINY_RUN, "--out", str(out)], env)
            at = time.perf_counter() + f if stage == "start" else None
            delay = f * left.get(stage, 0)
            trials.append(dict(out=out, stage=stage, delay=delay, p=proc, at=at, sig=sig))
        pending = list(trials)
        while pending:
            for t in list(pending):
                now = time.perf_counter()
                if t["p"].poll() is not None:
                    t["sent"] = None  # finished before its signal was due
                    pending.remove(t)
                elif t["at"] is None and _stage(t["p"], t["out"]) == t["stage"]:
                    t["at"] = now + t["delay"]
                elif t["at"] is not None and now >= t["at"]:
                    t["sent"] = _stage(t["p"], t["out"])
                    t["p"].send_signal(t["sig"])
                    t["late"] = _exited(t["p"].pid)  # read after the signal: it may have come late
                    pending.remove(t)
            time.sleep(0.002)
        for t in trials:
            _, err = t["p"].communicate(timeout=120)
            rc, files = t["p"].returncode, os.listdir(t["out"].parent)
            outcomes.append((t["stage"], t["sent"], rc, files))
            assert "Traceback" not in err, err
            assert not any(n.endswith(".tmp") for n in files), (files, err)
            if t["sent"] is None or (rc == 0 and t["late"]):  # finished before the signal
                assert rc == 0 and files == ["a.nc"], err
            elif rc == -signal.SIGTERM:  # before the package's first line: nothing written
                assert t["sent"] == "start" and files == [], err
            else:
                assert rc == 128 + t["sig"], (rc, err)
                if files:
                    with xr.open_dataset(t["out"]) as ds:  # complete before the signal came
                        assert ds.attrs["undecided_after_resolve"] == 0
    print("trials (aimed at, stage when sent, exit code, files):", outcomes)
    assert sum(sent in ("main", "write") for _, sent, *_ in outcomes) >= min(4, writes + 1)


def test_a_swallowed_signal_commits_nothing(tmp_path, monkeypatch, capsys):
    """A SIGTERM whose KeyboardInterrupt was lost (as in a gc callback: recorded, not raised)
    still ends the run with 143 before the file is committed, and main() leaves no alarm and
    its signal handlers restored."""
    import signal

    from atlas.core import interrupts
    from atlas.data import io as aio

    begin = aio.NetCDFSink.begin

    def begin_then_swallowed_signal(self, sch):
        begin(self, sch)
        interrupts.request(signal.SIGTERM)

    monkeypatch.setattr(aio.NetCDFSink, "begin", begin_then_swallowed_signal)
    before = signal.getsignal(signal.SIGTERM)
    out = tmp_path / "a.nc"
    assert cli.main([*TINY_RUN, "--out", str(out)]) == 128 + signal.SIGTERM
    assert os.listdir(tmp_path) == []
    assert "interrupted" in capsys.readouterr().err
    assert signal.getitimer(signal.ITIMER_REAL) == (0.0, 0.0)
    assert signal.getsignal(signal.SIGTERM) is before
    # the next run in the same process starts without the old signal
    monkeypatch.setattr(aio.NetCDFSink, "begin", begin)
    assert cli.main([*TINY_RUN, "--out", str(out)]) == 0 and out.exists()


def test_signal_after_the_commit_is_not_exit_0(tmp_path, monkeypatch, capsys):
    """A signal that comes after the output was committed: the file is complete, the exit code
    still says the run was interrupted (never 0 after a signal)."""
    import signal

    from atlas.core import interrupts
    from atlas.data import generate_cli

    generate_to_file = generate_cli.generate_to_file

    def then_signal(*a, **kw):
        stats = generate_to_file(*a, **kw)
        interrupts.request(signal.SIGTERM)
        return stats

    monkeypatch.setattr(generate_cli, "generate_to_file", then_signal)
    out = tmp_path / "a.nc"
    assert cli.main([*TINY_RUN, "--out", str(out)]) == 143
    assert "after the run had finished" in capsys.readouterr().err
    with xr.open_dataset(out) as ds:
        assert ds.class_code.shape == (8, 8)


# --- sizes: refused before any work -------------------------------------------------------------

HUGE_AXES = ["--beta1", "0:2pi:10000000", "--beta2", "0:2pi:10000000"]


@pytest.mark.parametrize(
    "args, limit",
    [
        (["generate", *HUGE_AXES], "free"),  # 1e14 points of every output: the disk
        (["generate", *HUGE_AXES, "--kappa", "0.5,2"], "memory"),
        (["generate", *HUGE_AXES, "--scheduler", "inprocess"], "free"),
        (["generate", *HUGE_AXES, "--scheduler", "local:2"], "free"),
        (["boundaries", *HUGE_AXES, "--kappa", "2", "--q", "0.1"], "memory"),
        (["mechanism", "ladder", "--theta", "0.1:1:10000000", "--mu", "0:1:10000000"], "memory"),
        (["simulate", "--map", "--n", "10000000"], "memory"),
    ],
)
def test_a_1e14_point_scene_is_refused_at_once(args, limit, tmp_path, capsys):
    """One line naming the numbers and the way out, exit 2, nothing written, before any work:
    no function of the modules that compute (or start workers) is called, no JAX program is
    traced or compiled, and at most 1 GiB is allocated (the two 1e7-value axes and their
    copies; the scene is 1e14 points)."""
    out = tmp_path / "a.nc"
    with counted() as work:
        assert cli.main([*args, "--out", str(out)]) == 2
    err = capsys.readouterr().err
    _check_one_line(err, "size:", args)
    assert "e+14 points" in err and limit in err and "coarser" in err
    assert os.listdir(tmp_path) == []
    assert not work.calls and not work.jax, (work.calls, work.jax)
    assert work.peak_bytes < 1 << 30, work.peak_bytes


def test_the_work_counter_sees_a_tiny_run(tmp_path):
    """The counter of the refusal test above sees work: a tiny run calls the point driver."""
    with counted() as work:
        assert cli.main([*TINY_RUN, "--out", str(tmp_path / "a.nc")]) == 0
    assert work.calls["core/points.py"] > 0 and work.peak_bytes > 0, work


def test_no_size_check_runs_what_the_estimate_refuses(tmp_path, monkeypatch, capsys):
    """With no memory to spare a tiny run is refused (``size:``, exit 2, nothing written); with
    ``--no-size-check`` it runs and writes the same atlas as with room to spare."""
    import atlas.data.limits as limits

    roomy = tmp_path / "roomy.nc"
    assert cli.main([*TINY_RUN, "--out", str(roomy)]) == 0
    monkeypatch.setattr(limits, "available_memory", lambda: 2048)  # > an axis, < the run
    out = tmp_path / "a.nc"
    assert cli.main([*TINY_RUN, "--out", str(out)]) == 2
    assert "size: " in capsys.readouterr().err and not out.exists()
    assert cli.main([*TINY_RUN, "--out", str(out), "--no-size-check"]) == 0
    with xr.open_dataset(roomy) as a, xr.open_dataset(out) as b:
        xr.testing.assert_identical(a.drop_attrs(), b.drop_attrs())


def test_dry_run_prints_the_estimate_and_writes_nothing(tmp_path, capsys):
    out = tmp_path / "a.nc"
    assert cli.main([*TINY_RUN, "--out", str(out), "--dry-run"]) == 0
    line = capsys.readouterr().out.strip()
    assert line.startswith("atlas generate: 64 points; output ~128 B uncompressed; peak memory")
    assert os.listdir(tmp_path) == []


# --- faults: a full disk is one line naming the path, and nothing partial is left ---------------


@pytest.fixture
def full_disk(monkeypatch):
    """A full file system for the outputs whose names end with one of ``full_disk.suffixes``:
    their temporary files are links to ``/dev/full`` (every write fails with ENOSPC); netCDF
    files (HDF5 refuses to open the link) fail as HDF5 does on a full disk, with netCDF4's
    ``RuntimeError: NetCDF: HDF error`` after part of the file was written, and the file
    system reports no free space."""
    from atlas.data import io as aio

    if not os.path.exists("/dev/full"):
        pytest.skip("needs /dev/full")
    init = aio.AtomicFile.__init__
    state = type("FullDisk", (), {"suffixes": ("",)})()

    def on_full_disk(self, path, *a, **kw):
        init(self, path, *a, **kw)
        if str(path).endswith(state.suffixes) and not str(path).endswith(".nc"):
            os.symlink("/dev/full", self.tmp)

    def hdf_error(path):
        if str(path).endswith(state.suffixes):
            raise RuntimeError("NetCDF: HDF error")

    to_netcdf, write = xr.Dataset.to_netcdf, aio.NetCDFSink.write

    def to_netcdf_full(self, path, *a, **kw):
        with open(path, "wb") as fh:
            fh.write(b"\x89HDF\r\n\x1a\n")
        hdf_error(path)
        return to_netcdf(self, path, *a, **kw)

    class Unwritable:  # a tile whose write into the netCDF variable fails
        def __array__(self, *a, **kw):
            hdf_error(self_path[0])

    def write_full(self, name, index, block):
        self_path[:] = [self.path]
        full = str(self.path).endswith(state.suffixes)
        return write(self, name, index, Unwritable() if full else block)

    self_path = [None]

    monkeypatch.setattr(aio.AtomicFile, "__init__", on_full_disk)
    monkeypatch.setattr(xr.Dataset, "to_netcdf", to_netcdf_full)
    monkeypatch.setattr(aio.NetCDFSink, "write", write_full)
    monkeypatch.setattr(aio, "_FULL", float("inf"))  # below any free space: "full"
    return state


WRITERS = {
    "generate": ["generate", *TINY, "--outputs", "class_code", "--out", "{d}/a.nc"],
    "mechanism": [
        "mechanism",
        "ladder",
        "--theta",
        "0.1:1:3",
        "--mu",
        "0:1:3",
        "--out",
        "{d}/m.nc",
    ],
    "table": ["table", "--format", "csv", "--out", "{d}/t.csv"],
    "simulate": ["simulate", "--case", "fig2b", "--t-end", "1", "--out", "{d}/s.csv"],
    "boundaries": ["boundaries", *TINY, "--kappa", "2", "--q", "0.1", "--out", "{d}/b.nc"]
    + ["--csv", "{d}/b.csv", "--geojson", "{d}/b.json"]
    + ["--fields", "SS", "--chord", "1e-2", "--check", "0"],  # any curves will do: the fewest
}


@pytest.mark.parametrize("writer", sorted(WRITERS))
def test_a_full_disk_is_one_line_and_leaves_nothing(writer, full_disk, tmp_path, capsys):
    if writer == "boundaries":  # the netCDF file and the CSV fit, the GeoJSON does not
        full_disk.suffixes = (".json",)
    args = [a.format(d=tmp_path) for a in WRITERS[writer]]
    assert cli.main(args) == 2
    err = capsys.readouterr().err
    _check_one_line(err, "out: cannot write " + str(tmp_path), args)
    assert "no space left on device" in err
    assert os.listdir(tmp_path) == []


def test_a_full_disk_under_the_store_says_how_to_resume(tmp_path, monkeypatch, capsys):
    """ENOSPC while a tile is written into the zarr store: one line naming the store, the cause
    and ``--resume``; the store is kept (its finished tiles are verified on resume)."""
    import errno

    pytest.importorskip("zarr")
    to_zarr = xr.Dataset.to_zarr

    def full(self, store, *a, region=None, **kw):
        if region is not None and region["beta1"].start >= 4:
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), f"{store}/class_code/4.0")
        return to_zarr(self, store, *a, region=region, **kw)

    monkeypatch.setattr(xr.Dataset, "to_zarr", full)
    args = ["generate", *TINY, "--outputs", "class_code", "--scheduler", "inprocess"]
    args += ["--slab", "4", "--out", str(tmp_path / "a.nc"), "--no-progress"]
    assert cli.main(args) == 2
    err = capsys.readouterr().err
    _check_one_line(err, f"store: cannot write {tmp_path / 'a.zarr'}", args)
    assert "no space left on device" in err and "--resume" in err
    assert os.listdir(tmp_path) == ["a.zarr"]
    monkeypatch.setattr(xr.Dataset, "to_zarr", to_zarr)
    assert cli.main([*args, "--resume"]) == 0
    assert "1 computed, 1 verified" in capsys.readouterr().err


# --- one option parser and the output rules of every writer ---------------------------------------


@pytest.mark.parametrize(
    "args, name",
    [
        (["generate", "--beta1", "0:2PI:8", "--beta2", "0:2pi:8"], "beta1"),  # case-sensitive
        (["generate", *TINY, "--out", ""], "out: empty path"),
        (["generate", *TINY, "--out", "{d}/a.txt"], "out: expected a file name ending in .nc"),
        (["generate", *TINY, "--store", "{d}/s.db", "--out", "{d}/a.nc"], "store:"),
        (["mechanism", "ladder", "--out", "{d}/m.csv"], "out:"),
        (["boundaries", *TINY, "--kappa", "2", "--csv", "{d}/b.txt"], "csv:"),
        (["boundaries", *TINY, "--kappa", "2", "--geojson", ""], "geojson: empty path"),
        (["simulate", "--case", "fig2b", "--out", "{d}/fig.nc"], "out:"),  # before simulating
        (["simulate", "--map", "--out", "{d}/map.csv"], "out:"),
        (["table", "--out", "{d}/t.nc"], "out:"),
        (["table", "--out", "{d}/missing/t.md"], "out: directory"),  # never created silently
        (["simulate", "--case", "fig2b", "--out", "/proc/s.csv"], "out: directory /proc is not"),
        (["paper", "--out", "/proc/paper"], "out: directory /proc is not"),
        (["paper", "--out", "{d}/no/such/dir"], "out: directory"),
        (["bench", "--out", "{d}/existing.md"], "out: "),  # a file, not a directory
        (["generate", *TINY, "--dtype", "float16"], "dtype"),
        (["generate", "--no-such-option"], "unrecognized"),
        (["nonsense"], "invalid choice"),
        (["simulate", "--map", "--n", "4", "--seed", "99999999999999999999999"], "seed: "),
        (["simulate", "--map", "--n", "4", "--seed", "4294967296"], "seed: "),
        (["simulate", "--map", "--n", "4", "--t-end", "1e300"], "t_end: must be <= 10000"),
        (["simulate", "--case", "fig2b", "--t-end", "1e300"], "t-end: must be > 0 and <= 10000"),
    ],
)
def test_usage_errors_one_prefix_nothing_written(args, name, tmp_path, capsys):
    """One line ``atlas: error: ...`` naming the parameter for every subcommand (argparse's
    errors included), exit 2, before any work, and no file or directory made."""
    (tmp_path / "existing.md").write_text("keep me")
    args = [a.format(d=tmp_path) for a in args]
    assert cli.main(args) == 2
    err = capsys.readouterr().err
    _check_one_line(err, name, args)
    assert err.startswith("atlas: error: "), err
    assert sorted(os.listdir(tmp_path)) == ["existing.md"]
    assert (tmp_path / "existing.md").read_text() == "keep me"


def _dry_run_seconds(args, capsys) -> float:
    """The time ``--dry-run`` predicts for ``args`` [s]."""
    assert cli.main([*args, "--dry-run"]) == 0
    out = capsys.readouterr().out
    value, unit = re.search(r"~(\S+) (s|min|h|days|years) on one core", out).groups()
    return float(value) * {"s": 1, "min": 60, "h": 3600, "days": 86400, "years": 31536000}[unit]


@pytest.mark.parametrize(
    "extra, name",
    [(["--dry-run"], "dry-run"), (["--no-size-check"], "no-size-check"), (["--n", "8"], "n"),
     (["--n-perturb", "4"], "n-perturb"), (["--no-theory"], "no-theory")],
)  # fmt: skip
def test_simulate_map_options_without_map_are_refused(extra, name, tmp_path, capsys):
    """An option of the outcome map given to one trajectory is one line naming it, exit 2, and
    nothing simulated or written (``--dry-run`` simulated and wrote before)."""
    out = tmp_path / "s.csv"
    with counted() as work:
        rc = cli.main(["simulate", "--case", "fig2b", "--t-end", "1", "--out", str(out), *extra])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1 and err[0].startswith(f"atlas: error: {name}: only with --map")
    assert not out.exists() and not work.calls["dynamics/simulator.py"], work


@pytest.mark.e2e
def test_simulate_map_with_the_jax_engine_equals_the_exact_simulator(tmp_path, capsys):
    """``atlas simulate --map --engine jax`` (no other CI test runs that engine: its own tests
    are slow) gives the exact simulator's (``--engine numpy``) outcome in every cell."""

    got = {}
    for engine in ("jax", "numpy"):
        out = tmp_path / f"{engine}.nc"
        args = ["simulate", "--map", "--n", "3", "--no-theory", "--workers", "1"]
        assert cli.main([*args, "--engine", engine, "--out", str(out)]) == 0
        with xr.open_dataset(out) as ds:
            got[engine] = (ds["outcome"].values.copy(), ds.attrs["engine"])
    assert got["jax"][1] == "jax" and got["numpy"][1] == "numpy"
    np.testing.assert_array_equal(got["jax"][0], got["numpy"][0])


def test_simulate_dry_run_time_grows_with_t_end(capsys):
    """``simulate --map --dry-run``'s time is proportional to ``--t-end`` over the default
    horizon 150 (it predicted the same time for every ``--t-end``)."""
    args = ["simulate", "--map", "--n", "8", "--no-theory"]
    base = _dry_run_seconds(args, capsys)
    long = _dry_run_seconds([*args, "--t-end", "1e4"], capsys)
    assert base == _dry_run_seconds([*args, "--t-end", "150"], capsys)
    assert 60 < long / base < 73  # 1e4 / 150 = 66.7, both printed to 2 significant digits


@pytest.mark.parametrize("where", [[], ["--store", "box.zarr"]])
def test_generate_dry_run_counts_the_model_box(where, capsys):
    """``--model-box`` adds its verdicts' bytes (3 int8 codes, 18 float64 witness parameters per
    (beta1, beta2) point, SPEC §2) and their time (the II verdicts: milliseconds per point) to the
    estimate, in memory and with a store."""
    args = ["generate", "--beta1", "0:2pi:64", "--beta2", "0:2pi:64", "--kappa", "1", *where]
    box = ["--model-box", "kappa=0.5:2,q=0.1:1"]
    plain = _dry_run_seconds(args, capsys)
    assert _dry_run_seconds([*args, *box], capsys) > plain + 64 * 64 * 1e-3
    kib = []
    for extra in ([], box):
        assert cli.main([*args, *extra, "--dry-run"]) == 0
        kib.append(float(re.search(r"output ~(\S+) KiB", capsys.readouterr().out).group(1)))
    assert kib[1] - kib[0] == pytest.approx(64 * 64 * 147 / 1024, abs=0.11)  # 588.0 KiB


def test_negative_range_start_needs_no_equals_sign(capsys):
    args = ["generate", "--beta1", "-0.5pi:0.5pi:8", "--beta2", "-pi:pi:4", "--kappa", "2"]
    assert cli.main([*args, "--q", "-0", "--dry-run"]) == 0
    assert capsys.readouterr().out.startswith("atlas generate: 32 points")


def test_table_and_simulate_replace_only_with_overwrite(tmp_path, capsys):
    out = tmp_path / "t.csv"
    out.write_text("keep me")
    assert cli.main(["table", "--format", "csv", "--out", str(out)]) == 2
    assert "--overwrite" in capsys.readouterr().err and out.read_text() == "keep me"
    assert cli.main(["table", "--format", "csv", "--out", str(out), "--overwrite"]) == 0
    assert out.read_text().startswith("class")
    sim = tmp_path / "s.csv"
    sim.write_text("keep me")
    args = ["simulate", "--case", "fig2b", "--t-end", "1", "--out", str(sim)]
    assert cli.main(args) == 2 and sim.read_text() == "keep me"
    assert cli.main([*args, "--overwrite"]) == 0 and sim.read_text().startswith("t,kind")


def test_an_interrupted_run_names_the_files_it_completed(tmp_path, monkeypatch, capsys):
    """``atlas paper`` keeps the files finished before a Ctrl-C: the message says which."""
    import types

    from atlas.data.io import atomic_write_text

    def run(out, quick, jobs):
        atomic_write_text(os.path.join(out, "table2.md"), "done\n")
        with open(os.path.join(out, "partial.tmp"), "w"):
            pass
        os.unlink(os.path.join(out, "partial.tmp"))
        raise KeyboardInterrupt

    fake = types.ModuleType("atlas._fake_paper")
    fake.run = run
    monkeypatch.setitem(sys.modules, "atlas._fake_paper", fake)
    monkeypatch.setitem(cli._DISPATCH, "paper", ("atlas._fake_paper", "run"))
    assert cli.main(["paper", "--out", str(tmp_path)]) == 130
    err = capsys.readouterr().err
    assert "no partial output file left; complete before it: " in err
    assert str(tmp_path / "table2.md") in err


@pytest.mark.parametrize("place", [".", "", "~"])
def test_overwrite_never_deletes_the_working_directory(place, tmp_path, monkeypatch, capsys):
    """``simulate --map --store . --overwrite`` (or ``''``, the home directory) in a directory
    holding a file and a sub-directory: one line naming ``store``, exit 2, everything kept."""
    work = tmp_path / "d"
    (work / "sub").mkdir(parents=True)
    (work / "keep.txt").write_text("x")
    monkeypatch.chdir(work)
    monkeypatch.setenv("HOME", str(work))
    args = ["simulate", "--map", "--n", "4", "--no-theory", "--overwrite", "--workers", "1"]
    assert cli.main([*args, "--store", os.path.expanduser(place)]) == 2
    _check_one_line(capsys.readouterr().err, "atlas: error: store: ", place)
    assert sorted(os.listdir(work)) == ["keep.txt", "sub"]
    assert (work / "keep.txt").read_text() == "x"


def test_simulate_map_resume_of_no_store_is_refused(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    args = ["simulate", "--map", "--n", "4", "--no-theory", "--store", "st", "--resume"]
    assert cli.main(args) == 2
    _check_one_line(capsys.readouterr().err, "resume: store", args)
    assert os.listdir(tmp_path) == []


@pytest.mark.parametrize("fault", ["full", "read-only"])
def test_a_failed_write_into_the_outcome_store_names_it(fault, tmp_path, monkeypatch, capsys):
    """ENOSPC while a tile is written, or a read-only place (the temporary layout refused): one
    line naming the store (not a temporary path) and the cause; a store holding tiles says that
    ``--resume`` continues, and it does."""
    import errno

    from atlas.dynamics import outcome_tiles

    store = tmp_path / "st"
    args = ["simulate", "--map", "--n", "4", "--no-theory", "--slab", "2", "--workers", "1"]
    args += ["--t-end", "2", "--store", str(store)]  # a short horizon: the store is checked
    if fault == "full":
        write = outcome_tiles._write

        def full(path, data):
            if os.path.basename(path).startswith("t000001"):
                raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), f"{path}.123.tmp")
            write(path, data)

        monkeypatch.setattr(outcome_tiles, "_write", full)
    else:

        def read_only(*a, dir=None, **kw):
            raise PermissionError(errno.EACCES, os.strerror(errno.EACCES), f"{dir}/.st.x.tmp")

        monkeypatch.setattr(outcome_tiles.tempfile, "mkdtemp", read_only)
    assert cli.main(args) == 2
    err = capsys.readouterr().err
    _check_one_line(err, f"atlas: error: store: cannot write {store}: ", args)
    assert ".tmp" not in err
    if fault == "read-only":
        assert "Permission denied" in err and os.listdir(tmp_path) == []
        return
    assert "no space left on device" in err and "--resume" in err
    monkeypatch.undo()
    assert cli.main([*args, "--resume"]) == 0
    assert "1 computed, 1 verified" in capsys.readouterr().err
