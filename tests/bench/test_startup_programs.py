"""``atlas.bench.startup_programs``: the programs a block compiles, named and shaped (a kept kernel
under its own name), and the Start-up rows and tables built from a command's recording."""

import json
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np

from atlas.bench import startup_programs as sp
from atlas.bench.startup import Timed
from atlas.core import warm


def _twice(x, y):
    return 2 * x + y


def test_a_plain_jit_is_one_program_with_its_shapes():
    f = jax.jit(lambda a, b: jnp.sin(a) * b)
    with sp.recorded() as rec:
        f(np.ones(5), np.ones(5)).block_until_ready()
        f(np.ones(5), np.ones(5)).block_until_ready()  # cached: no second program
    (prog,) = rec.programs
    assert prog.compiles == 1 and "lambda" in prog.name
    assert prog.shapes == "f64[5] f64[5]"
    assert prog.trace_s > 0 and prog.lower_s > 0 and prog.compile_s > 0


def test_a_kept_kernel_is_one_program_under_its_own_name(tmp_path):
    """Exported (trace, lower), then compiled for its executable: one program per shape, named
    for the kernel."""
    kern = warm.Kernel(_twice)
    with warm.kernel_cache(str(tmp_path)), sp.recorded() as rec:
        np.asarray(kern(np.arange(7.0), np.ones(7)))
        np.asarray(kern(np.arange(9.0), np.ones(9)))  # another shape: another program
    names = [p.name for p in rec.programs if p.compiles]
    assert names == [f"{__name__}._twice"] * 2, names
    assert [p.shapes for p in rec.programs] == ["f64[7] f64[7]", "f64[9] f64[9]"]
    s = sp.summary(rec.programs)
    assert s["programs"] == 2 and s["compile_s"] > 0


class _Session:
    """A made-up start-up session: each command 'writes' the recording it was given."""

    def __init__(self, tmp: Path, recordings):
        self.work, self.recordings, self.cmds, self.emptied = tmp, list(recordings), [], 0

    def empty_cache(self):
        self.emptied += 1

    def times(self, cmd, n):
        self.cmds.append(cmd)
        got = self.recordings.pop(0)
        if got is None:
            return [Timed(3.0, 1, "", "boom")]
        Path(cmd[3]).write_text(json.dumps(got))
        return [Timed(5.0, 0)]


def test_rows_and_tables_of_the_cold_commands(tmp_path):
    progs = [
        dict(name="k.a", shapes="f64[16]", compiles=1, trace_s=0.5, lower_s=0.25, compile_s=2.0),
        dict(name="k.b", shapes="f64[4096]", compiles=2, trace_s=1.0, lower_s=0.5, compile_s=8.0),
        dict(name="traced", shapes="", compiles=0, trace_s=0.125, lower_s=0.0, compile_s=0.0),
    ]
    s = _Session(tmp_path, [dict(rc=0, wall_s=4.0, programs=progs), None])
    cmds = (("gen", "cli", ["generate", "--out", "{work}/a.nc"]), ("map", "explorer-map", ["9"]))
    rows = sp.measure(s, cmds)
    assert s.emptied == 2  # each command in an empty cache
    assert s.cmds[0][-3:] == ["generate", "--out", f"{tmp_path}/a.nc"]
    ok, failed = rows
    assert ok["value"] == 2 and ok["median_s"] == 5.0  # the traced-only function is no program
    assert ok["in_run_s"] == 4.0  # the work's own seconds beside the process's
    assert failed["in_run_s"] == ""
    assert ok["note"] == ("tracing 1.6 s, lowering 0.8 s, XLA compilation 10.0 s (3 compilations)")
    assert failed["value"] == "" and failed["note"] == "exit 1: boom"
    text = "\n".join(sp.program_tables(rows))
    assert text.index("| k.b | f64[4096] | 2 | 1.00 | 0.50 | 8.00 |") < text.index("| k.a |")
    assert "`gen`: 2 programs compiled (3 compilations)" in text
