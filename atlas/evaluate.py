"""Spectral verdicts on flat point sets: fixed-size jitted chunks, compaction, exact settlement.

The one driver every caller (atlases, figures, audit, benchmarks, notebooks) uses to turn points
``(c1, s1, c2, s2, kappa, q1, q2)`` into verdicts.  It computes only what is asked for:

* ``stable_SS`` alone never finds roots (certified Hurwitz signs, ~10 flops a point);
* undamped points (``q1 = q2 = 0``) get II verdicts in closed form;
* damped points need roots only where the cone test :func:`atlas.spectral.ii_possible` passes
  (elsewhere II is certainly inconsistent), unless ``spectral_abscissa`` is wanted;
* the points the fast path leaves ``UNDECIDED`` are settled by :mod:`atlas.exact` (``resolve``).

Chunks have a fixed length (padding with a harmless point), so each kernel compiles once per dtype.
"""

from __future__ import annotations

import functools

import jax
import jax.numpy as jnp
import numpy as np

from . import spectral
from .verdicts import Verdict

__all__ = ["spectral_points", "SPECTRAL_NAMES", "CHUNK", "last_counts"]

SPECTRAL_NAMES = ("stable_SS", "consistent_II", "stable_II", "spectral_abscissa")
CHUNK = 1 << 16
_KEYS = ("c1", "s1", "c2", "s2", "kappa", "q1", "q2")
_PAD = (1.0, 0.0, 0.0, 1.0, 1.0, 0.0, 0.0)  # B = I, kappa = 1, undamped: a regular point
_LAST: dict = {}


@functools.cache
def _kernel(kind: str, names: tuple[str, ...]):
    if kind == "eig":
        fn = lambda *a: spectral.eig_verdicts(*a)
    elif kind == "ss":
        fn = lambda *a: {"stable_SS": spectral.ss_verdict(*a)}
    elif kind == "undamped":
        fn = lambda *a: spectral.verdicts(*a, damped=False)
    elif kind == "roots":
        ii_names = tuple(k for k in names if k != "stable_SS")
        keys = ("consistent_II", "stable_II", "spectral_abscissa")

        def two_stage(*a):
            res = dict(zip(keys, spectral.ii_verdicts_two_stage(*a)))
            return {k: res[k] for k in ii_names}

        return two_stage
    elif kind == "cone":
        fn = lambda c1, s1, c2, s2, *_: {"ii_possible": spectral.ii_possible(c1, s1, c2, s2)}
    else:  # pragma: no cover
        raise ValueError(kind)
    return jax.jit(lambda *a: {n: v for n, v in fn(*a).items() if n in names})


def _run_chunked(kind, names, cols, dtype, chunk):
    n = cols[0].size
    # small batches: the next power of two (>= 1024) instead of a full chunk of padding
    chunk = min(chunk, max(1024, 1 << max(0, n - 1).bit_length()))
    out = {}
    for start in range(0, n, chunk):
        stop = min(start + chunk, n)
        args = []
        for a, pad in zip(cols, _PAD):
            c = np.full(chunk, pad, dtype)
            c[: stop - start] = a[start:stop]
            args.append(jnp.asarray(c))
        res = _kernel(kind, names)(*args)
        for k, v in res.items():
            v = np.asarray(v)
            if k not in out:
                out[k] = np.empty(n, v.dtype)
            out[k][start:stop] = v[: stop - start]
    return out


def _jit_broadcast(kind: str, names: tuple[str, ...]):
    return _kernel(kind, names)


def spectral_points(
    c1,
    s1,
    c2,
    s2,
    kappa,
    q1,
    q2,
    *,
    names=SPECTRAL_NAMES,
    method: str = "certified",
    dtype="float64",
    resolve: bool = True,
    max_resolve: int | None = None,
    chunk: int = CHUNK,
) -> dict:
    """Verdicts for broadcastable arrays of points; returns numpy arrays of the broadcast shape.

    Parameters
    ----------
    c1, s1, c2, s2 : array_like
        Direction components of ``b1``, ``b2`` [1] (:func:`atlas.mechanics.direction`).
    kappa, q1, q2 : array_like
        ``kappa = k1|b1|/(k2|b2|)`` and the damping ``q_hat`` (SPEC §1) [1].
    names : tuple of str
        Any of ``stable_SS``, ``consistent_II``, ``stable_II``, ``spectral_abscissa``.
    method : {"certified", "eig"}
        Certified kernels (default) or the uncertified batched-``eig`` baseline.
    resolve : bool
        Settle ``UNDECIDED`` points exactly (at most ``max_resolve`` of them; the rest stay 3).

    Broadcast structure is kept for the cheap parts (SS, closed-form undamped II, the cone test
    on the beta plane); only the damped points that need roots are gathered into flat chunks.
    The counts of undecided points before and after settlement are in :func:`last_counts`.
    """
    names = tuple(names)
    bad = set(names) - set(SPECTRAL_NAMES)
    if bad:
        raise ValueError(f"names: unknown output(s) {sorted(bad)}")
    if method not in ("certified", "eig"):
        raise ValueError(f"method: must be 'certified' or 'eig', not {method!r}")
    dtype = np.dtype(dtype)
    inputs = [np.asarray(a, dtype) for a in (c1, s1, c2, s2, kappa, q1, q2)]
    shape = np.broadcast_shapes(*(a.shape for a in inputs))
    n = int(np.prod(shape))
    dev = [jnp.asarray(a) for a in inputs]
    if method == "eig":
        res = _jit_broadcast("eig", names)(*dev)
        _LAST.clear()
        _LAST.update(points=n, roots_points=n, undecided_before=0, undecided_after=0)
        return {k: np.broadcast_to(np.asarray(res[k]), shape).copy() for k in names}

    out = {}
    want_ii = tuple(k for k in names if k != "stable_SS")
    if "stable_SS" in names:
        out["stable_SS"] = np.broadcast_to(
            np.asarray(_jit_broadcast("ss", ("stable_SS",))(*dev)["stable_SS"]), shape
        ).copy()
    roots_points = 0
    if want_ii:
        undamped = np.broadcast_to((inputs[5] == 0) & (inputs[6] == 0), shape)
        if undamped.any():
            res = _jit_broadcast("undamped", want_ii)(*dev)
            for k in want_ii:
                out[k] = np.broadcast_to(np.asarray(res[k]), shape).copy()
        else:
            for k in want_ii:
                out[k] = np.empty(shape, np.float64 if k == "spectral_abscissa" else np.int8)
        if not undamped.all():
            if "spectral_abscissa" in names:
                need = ~undamped
            else:
                cone = np.asarray(_jit_broadcast("cone", ("ii_possible",))(*dev)["ii_possible"])
                need = np.broadcast_to(cone, shape) & ~undamped
                no = ~undamped & ~need
                for k in want_ii:
                    out[k][no] = 0 if k == "consistent_II" else int(Verdict.UNSTABLE)
            idx = np.flatnonzero(need)
            roots_points = idx.size
            if idx.size:
                cols = [np.broadcast_to(a, shape).flat[idx] for a in inputs]
                res = _run_chunked("roots", want_ii, cols, dtype, chunk)
                for k in want_ii:
                    out[k].flat[idx] = res[k]
    counts = {"points": n, "roots_points": int(roots_points)}
    flags = [k for k in names if k != "spectral_abscissa"]
    und = np.zeros(shape, bool)
    for k in flags:
        und |= out[k] == 3
    counts["undecided_before"] = int(und.sum())
    if resolve and und.any():
        from . import exact

        # points undecided only in stable_SS need only the rational Hurwitz test (microseconds);
        # the others get the full root-based reference (milliseconds)
        und_ii = np.zeros(shape, bool)
        for k in flags:
            if k != "stable_SS":
                und_ii |= out[k] == 3
        budget = max_resolve
        for sel_mask, sel_names in ((und & ~und_ii, ("stable_SS",)), (und_ii, tuple(flags))):
            idx = np.flatnonzero(sel_mask)
            if budget is not None:
                idx, budget = idx[:budget], max(0, budget - idx.size)
            if not idx.size:
                continue
            pts = {
                key: np.broadcast_to(a, shape).flat[idx].astype(np.float64)
                for key, a in zip(_KEYS, inputs)
            }
            ref = exact.resolve(pts, names=sel_names)
            for k in sel_names:
                sel = out[k].flat[idx] == 3
                out[k].flat[idx[sel]] = ref[k][sel]
    after = np.zeros(shape, bool)
    for k in flags:
        after |= out[k] == 3
    counts["undecided_after"] = int(after.sum())
    _LAST.clear()
    _LAST.update(counts)
    return out


def last_counts() -> dict:
    """Counts of the last :func:`spectral_points` call: ``points``, ``roots_points`` (points that
    needed root finding), ``undecided_before`` and ``undecided_after`` exact settlement."""
    return dict(_LAST)
