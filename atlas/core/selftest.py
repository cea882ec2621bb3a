"""``atlas selftest``: the certified kernels against the exact tier on the hard-case suites, on the
JAX device in use.

Every suite of :mod:`atlas.core.hardcases` (points within ``1e-15`` relative of a stability, class
or root-structure boundary, extreme ratios) goes through :func:`atlas.core.points.spectral_points`
(all fast tiers, no exact settlement), per dtype in one call, and every point the fast tiers decide
is compared with :func:`atlas.core.exact.resolve` (rational arithmetic on the same float inputs).
A certificate that holds on the backend gives zero disagreements; one disagreement means a sign
was called certified wrongly there (e.g. an accelerator's compiler changed the rounding the error
bounds assume).  The result is recorded per backend (:mod:`atlas.core.backend`), and the certified
driver refuses a backend whose last check failed.
"""

from __future__ import annotations

import datetime
import time

import numpy as np

from atlas.core import backend, config, exact, hardcases, points
from atlas.core.invariants import KEYS
from atlas.core.verdicts import UNDECIDED_FLAG

__all__ = ["check", "report", "run_cli", "DTYPES", "NAMES"]

#: the verdicts checked (the spectral abscissa is not a certified verdict)
NAMES = ("stable_SS", "consistent_II", "stable_II")
DTYPES = ("float64", "float32")


def check(suites=None, dtypes=DTYPES) -> dict:
    """Run the suites (default: all) in each dtype; returns ``passed``, ``disagreements``,
    ``points``, ``decided``, the ``rows`` per suite and dtype (with up to 3 ``examples`` of
    disagreeing points), ``ns_per_point`` per dtype (a second, compiled call of the fast tiers)
    and ``seconds`` (the whole check)."""
    t0 = time.perf_counter()
    suites = list(suites or hardcases.SUITES)
    rows, speed = [], {}
    with backend.checking():
        for dtype in dtypes:
            parts = [hardcases.suite(name, dtype) for name in suites]
            cols = [np.concatenate([p[k] for p in parts]) for k in KEYS]
            fast = points.spectral_points(*cols, names=NAMES, dtype=dtype, resolve=False)
            t = time.perf_counter()
            points.spectral_points(*cols, names=NAMES, dtype=dtype, resolve=False)
            speed[dtype] = (time.perf_counter() - t) / cols[0].size * 1e9
            ref = exact.resolve({k: c.astype(np.float64) for k, c in zip(KEYS, cols)}, NAMES)
            start = 0
            for name, part in zip(suites, parts):
                sl = slice(start, start + part["c1"].size)
                start = sl.stop
                rows.append(_compare(name, dtype, part, {k: fast[k][sl] for k in NAMES},
                                     {k: ref[k][sl] for k in NAMES}))  # fmt: skip
    bad = sum(r["disagreements"] for r in rows)
    return {
        "passed": bad == 0,
        "disagreements": bad,
        "points": sum(r["points"] for r in rows),
        "decided": sum(r["decided"] for r in rows),
        "rows": rows,
        "ns_per_point": speed,
        "seconds": time.perf_counter() - t0,
        "backend": backend.key(),
        "when": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
    }


def _compare(name, dtype, part, fast, ref) -> dict:
    """Disagreements of the decided verdicts of one suite (a point counts once)."""
    n = part["c1"].size
    decided = np.zeros(n, bool)
    wrong = np.zeros(n, bool)
    for k in NAMES:
        d = fast[k] != UNDECIDED_FLAG
        decided |= d
        wrong |= d & (ref[k] != UNDECIDED_FLAG) & (fast[k] != ref[k])
    examples = [
        {k: float(part[k][i]) for k in ("beta1", "beta2", "kappa", "q1", "q2")}
        | {f"fast_{k}": int(fast[k][i]) for k in NAMES}
        | {f"exact_{k}": int(ref[k][i]) for k in NAMES}
        for i in np.flatnonzero(wrong)[:3]
    ]
    return dict(suite=name, dtype=dtype, points=n, decided=int(decided.sum()),
                disagreements=int(wrong.sum()), examples=examples)  # fmt: skip


def report(res: dict) -> str:
    """The lines ``atlas selftest`` prints."""
    lines = [f"atlas selftest on {res['backend']}"]
    for r in res["rows"]:
        lines.append(
            f"  {r['suite']:<18} {r['dtype']:<8} {r['points']:5d} points, {r['decided']:5d} "
            f"decided by the fast tiers, {r['disagreements']} disagreements with the exact tier"
        )
        lines += [f"    disagrees: {ex}" for ex in r["examples"]]
    speed = ", ".join(f"{dt} {ns:,.0f} ns/point" for dt, ns in res["ns_per_point"].items())
    verdict = "PASSED" if res["passed"] else "FAILED"
    lines.append(
        f"{verdict}: {res['disagreements']} disagreements in {res['decided']} decided of "
        f"{res['points']} points; fast tiers {speed} (compiled, small batches); "
        f"{res['seconds']:.1f} s"
    )
    return "\n".join(lines)


def run_cli(suites=None, dtypes=",".join(DTYPES)) -> int:
    """``atlas selftest``: run, print, record; exit code 0 if passed, 1 if not."""
    names = [s for s in (suites or "").split(",") if s] or None
    unknown = sorted(set(names or ()) - set(hardcases.SUITES))
    if unknown:
        raise ValueError(f"suites: unknown {unknown}; choose from {', '.join(hardcases.SUITES)}")
    dts = [d for d in dtypes.split(",") if d]
    if not dts or set(dts) - set(DTYPES):
        raise ValueError(f"dtypes: expected float64 and/or float32, got {dtypes!r}")
    config.use_compile_cache()
    res = check(names, dts)
    print(report(res))
    keep = {k: v for k, v in res.items() if k != "rows"}
    where = backend.record(keep)
    print(f"recorded in {where}" if where else "not recorded (compilation cache off)")
    return 0 if res["passed"] else 1
