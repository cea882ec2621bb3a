"""Fast certified kernels against the exact reference on the seeded hard-case suites (SPEC §4).

Zero disagreements on every point the fast path calls decided; undecided counts are reported.
The fast path checked in CI is the production driver (:func:`atlas.core.points.spectral_points`
without exact settlement: first pass, tier 2, root enclosures), at the lengths every caller runs
it; the monolithic ``spectral.verdicts_jit`` (the bench's ``verdicts_jit`` method) is the ``slow``
case: ``python -m pytest -m slow tests/core/test_hardcases.py``.  Where the batched-eig baseline
misclassifies, that is recorded (not hidden).
"""

import jax.numpy as jnp
import numpy as np
import pytest

from atlas.core import baseline, exact, hardcases, points, spectral
from atlas.core.invariants import KEYS

NAMES = ("stable_SS", "consistent_II", "stable_II")


#: every suite padded to this many points (with the driver's regular point ``points.PAD``), so
#: that the jitted kernels compile once per dtype, not once per suite (~4 s each)
PADDED = 256


def _padded_args(P):
    n = P["c1"].size
    assert n <= PADDED
    return [
        jnp.asarray(np.concatenate([P[k], np.full(PADDED - n, pad, P[k].dtype)]))
        for k, pad in zip(KEYS, points.PAD)
    ]


def _fast(path, P, dtype):
    """The verdicts of the fast path ``path`` (undecided: 3) at the suite's points."""
    if path == "driver":
        got = points.spectral_points(*(P[k] for k in KEYS), names=NAMES, dtype=dtype, resolve=False)
        return {k: np.asarray(got[k]) for k in NAMES}
    n = P["c1"].size
    return {k: np.asarray(v)[:n] for k, v in spectral.verdicts_jit(*_padded_args(P)).items()}


@pytest.mark.parametrize("path", ["driver", pytest.param("verdicts_jit", marks=pytest.mark.slow)])
@pytest.mark.parametrize("dtype", ["float64", "float32"])
@pytest.mark.parametrize("name", list(hardcases.SUITES))
def test_fast_path_never_disagrees_with_exact(name, dtype, path):
    P = hardcases.suite(name, dtype)
    n = P["c1"].size
    fast = _fast(path, P, dtype)
    ref = exact.resolve({k: P[k] for k in KEYS}, names=NAMES)
    eig = {k: np.asarray(v)[:n] for k, v in baseline.eig_verdicts_jit(*_padded_args(P)).items()}
    report = []
    for k in NAMES:
        f, r = fast[k], ref[k]
        assert f.shape == r.shape == (n,)
        assert not (r == 3).any(), "reference left a point undecided"
        decided = f != 3
        bad = np.flatnonzero(decided & (f != r))
        assert bad.size == 0, f"{k}: {bad.size} disagreements, e.g. " + str(
            {kk: float(P[kk][bad[0]]) for kk in ("beta1", "beta2", "kappa", "q1", "q2")}
        )
        miss = int((eig[k] != r).sum())
        report.append(f"{k}: undecided {int((~decided).sum())}/{f.size}, eig misclassified {miss}")
    print(f"[{name} {dtype} {path}] " + "; ".join(report))


def test_eig_baseline_misclassifies_hard_cases():
    """Recorded, not hidden: the tolerance-based eig baseline gets the Hurwitz boundary wrong."""
    P = hardcases.suite("near_hurwitz", "float64")
    ref = exact.resolve({k: P[k] for k in KEYS}, names=("stable_SS",))["stable_SS"]
    eig = np.asarray(baseline.eig_verdicts_jit(*_padded_args(P))["stable_SS"])[: ref.size]
    miss = int((eig != ref).sum())
    print(f"eig misclassified {miss} of {ref.size} near-Hurwitz points")
    assert miss > 0


def _roots_on_the_axis(b1, b2, kap, q) -> int:
    """Independent reference: the roots of ``det(l^2 I + l Q + K) B``'s quartic (the 40-digit
    ``coefficients``) by ``mpmath.polyroots``, counted where off the real axis by < 1e-25."""
    import mpmath

    from atlas.core import expressions as ex

    with mpmath.workdps(40):
        c1, s1, c2, s2 = mpmath.cos(b1), mpmath.sin(b1), mpmath.cos(b2), mpmath.sin(b2)
        det = c1 * s2 - s1 * c2
        co = ex.coefficients(c1, s1, c2, s2, kap, 1, q, q, det, sub=lambda x, y: x - y)
        roots = mpmath.polyroots([1, *co], maxsteps=200, extraprec=80)
        return sum(1 for z in roots if abs(mpmath.im(z)) < mpmath.mpf(10) ** -25)


def test_the_double_root_scan_counts_the_real_roots():
    """The real-root count that places the ``double_roots`` suite (a Sturm count) equals the
    count of mpmath's roots on every point of the suite: on both sides of each switch, down to
    1e-15 from it, both counts of real roots met."""
    s = hardcases.suite("double_roots")
    rows = list(zip(*(s[k].tolist() for k in ("beta1", "beta2", "kappa", "q1"))))
    got = [hardcases._n_real_roots(*r) for r in rows]
    assert got == [_roots_on_the_axis(*r) for r in rows]
    assert len(set(got)) >= 2
