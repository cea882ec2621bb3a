"""Spectral verdicts on point sets: one packed kernel, compaction by tiers, exact settlement.

The one driver every caller (atlases, figures, audit, benchmarks, notebooks) uses to turn points
``(c1, s1, c2, s2, kappa, q1, q2)`` into verdicts.  It computes only what is asked for, in tiers,
each on the points the previous one left ``UNDECIDED``:

1. :func:`atlas.core.rootfree.codes` on the broadcast grid (never materialized in the inputs): every
   certified sign once, ``stable_SS`` and the II verdicts in one ``uint8`` a point, no roots
   (closed forms for ``q1 = q2 = 0``, the monotone-curve analysis with damping);
2. :func:`atlas.core.rootfree.tier2` on the points the first pass flagged (sharper error bounds,
   dominance by shifted Routh counts): typically < 0.1 % of the points; damped points whose
   ``det B`` has no certified sign (an input not a normal number) skip it (it cannot decide them);
3. the certified root enclosures of :func:`atlas.core.enclosures.ii_verdicts_two_stage` on what is left;
4. the exact tier :func:`atlas.core.exact.resolve` (rational arithmetic) on the rest.

Compacted points are gathered by index into each input's own (broadcast) shape, never through a
materialized ``broadcast_to``.  ``spectral_abscissa`` (the largest real part, for display) needs the
roots of every damped point and is computed only when asked.  Shape buckets shared by every
caller: small point sets run in flat batches of :data:`FLAT_BATCH` points (the smallest in one of
:data:`FLAT_SMALL`), tiers 2 and 3 in
batches of :data:`LATER_BATCH` points (padding with a harmless point), so each of these kernels
is one program per dtype whichever command, figure or explorer overlay calls it
(:func:`compile_programs` compiles or loads them ahead of use).
"""

from __future__ import annotations

import contextlib
import functools
import math
import threading

import numpy as np

from atlas.core import backend, baseline, enclosures, exact, rootfree, spectral, warm
from atlas.core.invariants import KEYS, PAD, Invariants
from atlas.core.verdicts import UNDECIDED_FLAG

__all__ = [
    "spectral_points",
    "tally",
    "Verdicts",
    "settle_codes",
    "SPECTRAL_NAMES",
    "CHUNK",
    "CHUNK_SIZES",
    "BLOCK",
    "FLAT_BATCH",
    "LATER_BATCH",
    "host_first",
    "LATER_BULK",
    "LATER_BULK_FROM",
    "compile_programs",
    "PAD",
]

SPECTRAL_NAMES = ("stable_SS", "consistent_II", "stable_II", "spectral_abscissa")


class Verdicts(dict):
    """What :func:`spectral_points` returns: the verdict arrays by name, and in ``stats`` the
    call's diagnostics: ``points``, ``tier2_points``, ``roots_points`` (points that needed root
    enclosures), ``exact_points`` (points sent to the exact tier, if any), ``undecided_before``
    and ``undecided_after`` exact settlement (points with any verdict undecided),
    ``undecided_by_name`` (per output, before), ``exact_failures`` (points the exact tier failed
    on, if any)."""

    def __init__(self, arrays: dict, stats: dict):
        super().__init__(arrays)
        self.stats = stats


#: length of the full batches of the spectral abscissa's enclosures (:func:`_abscissa`)
CHUNK = 1 << 16
#: largest number of points the first-pass kernel sees at once (bounds its temporaries)
BLOCK = 1 << 22
#: the one padded length of the flat first pass (small grids and point lists run in batches of
#: it, :func:`_on_flat`): one compilation per dtype for every small input of every caller
FLAT_BATCH = 1 << 12
#: the padded lengths of small point sets (:func:`_flat_columns`)
FLAT_SIZES = (FLAT_BATCH,)
#: the padded length of the smallest point sets: a batch of it runs in about a third of the time
#: of :data:`FLAT_BATCH` (0.42 against 1.38 ms, float64, loaded machine), and a certified
#: boundary slice makes hundreds of calls of at most this many points (a bisection's samples)
FLAT_SMALL = 1 << 9
#: grids of one model and at most this many points are evaluated as flat columns (:func:`_flat`)
FLAT_LIMIT = CHUNK
#: the dtype of tiers 2 and 3 whatever the input dtype: float32 inputs convert exactly, the tiers
#: see few points (their cost is mostly fixed), and float64 bounds decide more of them
LATER_DTYPE = np.float64
#: the one length of later-tier batches (tier 2 and the enclosures: five programs), shared by
#: every caller (atlas, paper, explorer overlay): each length is one trace and compilation (~3.5 s
#: for the five programs, cold) or one load per process, while a batch takes about 0.6 ms
#: (float64, best of 300 calls; 0.15 ms padded to 16 points), so one length: a set of 5,000
#: points runs in 20 batches (~12 ms), a handful in one
LATER_BATCH = 1 << 8
#: the padded lengths of later-tier batches (:func:`_batches`)
CHUNK_SIZES = (LATER_BATCH,)
#: the bulk of a later-tier set of at least :data:`LATER_BULK_FROM` points runs in batches of this
#: length (the rest in :data:`LATER_BATCH`): on a 5-D grid's 30,178 tier-2 points, 256-point
#: batches cost about 20 % more than 4,096-point ones; smaller sets (every small input of the
#: explorer, the paper, the boundaries) never compile it
LATER_BULK = 1 << 12
#: the smallest later-tier set that runs in :data:`LATER_BULK` batches
LATER_BULK_FROM = 1 << 14
#: a first pass that leaves at most this many points open, with exact settlement on (and its
#: budget holding them), sends them to the exact tier directly: it settles a handful of points in
#: milliseconds (11 points of a 16 x 16 x 2 atlas: 2.8 ms), where the five later-tier programs
#: cost seconds to compile (or to load) in each new process
HOST_POINTS = 16
#: the later tiers whose programs have run in this process (:func:`host_first`)
_LATER_RAN: set[str] = set()
#: this thread's :func:`host_first` limit
_HOST = threading.local()
_UND = UNDECIDED_FLAG


@functools.cache
def _kernel(kind: str, names: tuple[str, ...] = (), **static):
    """Jitted kernels by kind (one compilation per kind, names, static flags and dtype)."""
    if kind == "eig":
        fn = baseline.eig_verdicts
    elif kind == "codes":
        return warm.Kernel(functools.partial(rootfree.codes, **static))
    elif kind == "tier2":
        return functools.partial(rootfree.tier2, **static)  # two compiled programs inside
    elif kind == "undamped_abscissa":
        fn = lambda *a: spectral.verdicts(*a, damped=False)  # noqa: E731
    elif kind == "roots":
        keys = ("consistent_II", "stable_II", "spectral_abscissa")

        def two_stage(*a):
            res = dict(zip(keys, enclosures.ii_verdicts_two_stage(*a)))
            return {k: res[k] for k in names}

        return two_stage
    else:  # pragma: no cover
        raise ValueError(kind)
    return warm.Kernel(lambda *a: {n: v for n, v in fn(*a).items() if n in names})


def compile_programs(dtype="float64", before_each=None) -> None:
    """Compile (or load) ahead of use the programs shared by every caller's small inputs and
    later tiers: the flat first pass (:data:`FLAT_BATCH` points of ``dtype``), tier 2 and the
    enclosures (:data:`LATER_BATCH` points, :data:`LATER_DTYPE`), each run once on padding
    points (e.g. in a background thread while a first map is shown; ``before_each()`` is called
    before each program, e.g. to wait while the foreground is busy)."""
    wait = before_each or (lambda: None)
    for size in (FLAT_SMALL, FLAT_BATCH):
        wait()
        _kernel("codes", ss=True, ii=True, damped=None)(
            *(np.full(size, pad, np.dtype(dtype)) for pad in PAD)
        )
    later = [np.full(LATER_BATCH, pad, LATER_DTYPE) for pad in PAD]
    wait()
    _kernel("tier2", ss=True, ii=True)(*later)
    wait()
    _kernel("roots", ("consistent_II", "stable_II"))(*later)
    _LATER_RAN.update(("tier2", "roots"))


def _batches(n: int, chunk: int, sizes=CHUNK_SIZES):
    """``(start, stop, length)`` of the padded batches of ``n`` points.

    Full batches of ``chunk``; the rest runs at the first of ``sizes`` (or ``chunk``)
    that holds it, except that a rest above the largest size below ``chunk`` runs in batches of
    that size where ``chunk`` is more than 4 times longer (a rest of 4,696 points: two batches of
    4,096, not one of 65,536)."""
    small = [m for m in sizes if m < chunk]
    start = 0
    while start < n:
        rest = n - start
        if rest >= chunk or not small or (rest > small[-1] and chunk <= 4 * small[-1]):
            length = chunk
        else:
            length = next((m for m in small if m >= rest), small[-1])
        yield start, min(start + length, n), length
        start += length


def _run_chunked(kernel, cols, dtype, chunk, sizes=CHUNK_SIZES):
    """``kernel`` on 1-D columns in padded batches (:func:`_batches`); returns a dict (or tuple)
    of 1-D numpy arrays."""
    n = cols[0].size
    out = None
    for start, stop, length in _batches(n, chunk, sizes):
        args = []
        for a, pad in zip(cols, PAD):
            c = np.full(length, pad, dtype)
            c[: stop - start] = a[start:stop]
            args.append(c)
        res = kernel(*args)
        if not isinstance(res, dict):
            res = dict(enumerate(res if isinstance(res, (tuple, list)) else (res,)))
        res = {k: np.asarray(v) for k, v in res.items()}
        if out is None:
            out = {k: np.empty(n, v.dtype) for k, v in res.items()}
        for k, v in res.items():
            out[k][start:stop] = v[: stop - start]
    return out or {}


def _run_later(kernel, cols):
    """A later tier's ``kernel`` on 1-D columns (:data:`LATER_DTYPE`): batches of
    :data:`LATER_BATCH` points, the bulk of sets of at least :data:`LATER_BULK_FROM` points in
    batches of :data:`LATER_BULK`."""
    chunk = LATER_BULK if cols[0].size >= LATER_BULK_FROM else LATER_BATCH
    return _run_chunked(kernel, cols, LATER_DTYPE, chunk, CHUNK_SIZES)


def _gather(inputs: Invariants, shape, idx) -> Invariants:
    """1-D columns of the inputs at flat indices ``idx`` of the broadcast ``shape``."""
    if not shape:  # one point given as scalars
        return Invariants(*(np.broadcast_to(a, idx.shape) for a in inputs))
    sub = np.unravel_index(idx, shape)
    cols = []
    for a in inputs:
        a = a.reshape((1,) * (len(shape) - a.ndim) + a.shape)
        ix = tuple(s if a.shape[d] > 1 else 0 for d, s in enumerate(sub))
        cols.append(np.broadcast_to(a[ix], idx.shape))
    return Invariants(*cols)


def _blocks(shape, limit):
    """Index tuples of slabs of ``shape`` with at most ``limit`` points each (split leading axes)."""
    if math.prod(shape) <= limit or not shape:
        yield ()
        return
    inner = math.prod(shape[1:])
    if inner > limit:
        for i in range(shape[0]):
            for rest in _blocks(shape[1:], limit):
                yield (slice(i, i + 1),) + rest
        return
    step = max(1, limit // max(inner, 1))
    for i in range(0, shape[0], step):
        yield (slice(i, min(i + step, shape[0])),)


def _bucket(n: int) -> int:
    """``n`` rounded up to one of a few sizes: powers of two up to 16, then 8 sizes per octave
    (<= 12.5 % padding) below 256 and 32 per octave (<= 3.2 %) from 256 on, where the padded
    work outweighs an extra compilation (a 513 x 513 grid: 528 x 528, 6 % extra, not 26 %)."""
    if n <= 16:
        return 1 << max(0, n - 1).bit_length()
    granule = 1 << max(0, n.bit_length() - (4 if n < 256 else 6))
    return -(-n // granule) * granule


def _flat_columns(inputs, shape):
    """The inputs of a small broadcast ``shape`` as flat columns, their length
    :data:`FLAT_SMALL` or a multiple of :data:`FLAT_BATCH` (padded with the last point)."""
    n = math.prod(shape)
    size = FLAT_SMALL if n <= FLAT_SMALL else -(-n // FLAT_BATCH) * FLAT_BATCH
    cols = []
    for a in inputs:
        if a.size == 1:  # a model parameter shared by every point
            cols.append(np.full(size, a.reshape(-1)[0]))
            continue
        flat = np.broadcast_to(a.reshape((1,) * (len(shape) - a.ndim) + a.shape), shape).ravel()
        col = np.empty(size, a.dtype)
        col[:n], col[n:] = flat, flat[-1]
        cols.append(col)
    return cols


def _on_flat(kernel, inputs, shape):
    """``kernel`` (elementwise, one array out) on a grid of at most ``CHUNK`` points through
    :func:`_flat_columns`, in batches of at most :data:`FLAT_BATCH` points; returns the result in
    ``shape``."""
    cols = _flat_columns(inputs, shape)
    parts = [
        np.asarray(kernel(*(c[i : i + FLAT_BATCH] for c in cols)))
        for i in range(0, cols[0].size, FLAT_BATCH)
    ]
    return np.concatenate(parts)[: math.prod(shape)].reshape(shape)


def _flat(inputs, shape) -> bool:
    """Whether the first pass takes a grid as flat columns: at most :data:`FLAT_LIMIT` points,
    unless above ``FLAT_SIZES[0]`` points the grid spans several models ``(kappa, q1, q2)``, each
    shared by at least 8 points.  Flat columns repeat per point what the grid kernel computes
    once per model (the exact scalings, the majorants of every error bound): 3.5-7x its time
    per point on the tiles ``atlas generate`` hands over (16 x 128 x 8 x 2 x 2, loaded machine),
    which share one compiled grid shape.  Point lists (a model per point) stay flat."""
    n = math.prod(shape)
    models = math.prod(np.broadcast_shapes(*(a.shape for a in inputs[4:])))
    over_models = n > FLAT_SIZES[0] and 1 < models <= n // 8
    return n <= FLAT_LIMIT and not over_models


def _first_pass(inputs, shape, dtype, *, ss, ii, damped):
    """Packed codes of :func:`atlas.core.rootfree.codes` over the broadcast grid, in slabs.

    A small grid (:func:`_flat`) is evaluated as flat columns (:func:`_on_flat`)
    by the general kernel (both verdicts, any damping): two compilations per dtype serve every
    small grid and output choice, and the kernel time (< 15 ms) is far below one compilation
    (~1 s).  Beyond, every axis of a slab is padded (edge values) to a size of
    :func:`_bucket` and the kernel shares the row and column factors of the grid; grids of many
    sizes still share a few compilations (and the persistent compilation cache of the CLI).  The
    grid is evaluated with its longest axis innermost (:func:`_layout`), the codes returned in
    the order of ``shape`` (C-contiguous: the later tiers fill them in place).
    """
    if _flat(inputs, shape):
        kern = _kernel("codes", ss=True, ii=True, damped=None)
        return _on_flat(kern, inputs, shape).astype(np.uint8)
    kern = _kernel("codes", ss=ss, ii=ii, damped=damped)
    nd = len(shape)
    order = _layout(shape)
    full = [a.reshape((1,) * (nd - a.ndim) + a.shape).transpose(order) for a in inputs]
    code = np.empty(tuple(shape[d] for d in order), np.uint8)
    for blk in _blocks(code.shape, BLOCK):
        args = []
        for a in full:
            ix = tuple(s if a.shape[d] > 1 else slice(None) for d, s in enumerate(blk))
            part = a[ix]
            pad = [(0, _bucket(m) - m if m > 1 else 0) for m in part.shape]
            args.append(np.pad(part, pad, mode="edge") if any(p for _, p in pad) else part)
        res = np.asarray(kern(*args))
        sub = code[blk]
        res = np.broadcast_to(res, np.broadcast_shapes(res.shape, (1,) * sub.ndim))
        code[blk] = res[tuple(slice(0, m) for m in sub.shape)]
    if order == tuple(range(nd)):
        return code
    return np.ascontiguousarray(code.transpose(np.argsort(order)))


def _layout(shape) -> tuple[int, ...]:
    """The axis order of the first pass over a grid: shorter axes outside, the longest inside
    (stable).  The compiled loop vectorizes its innermost axis: a grid laid out ``(beta1, beta2,
    kappa, q1, q2)`` would put an axis of two values there (measured 5.5x the time per point
    of the same kernel on ``(q1, q2, kappa, beta1, beta2)``, float64, and 7.7x float32).  Every
    point's arithmetic is the same in either order."""
    return tuple(sorted(range(len(shape)), key=lambda d: shape[d]))


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
    needed=None,
) -> Verdicts:
    """Verdicts for broadcastable arrays of points: numpy arrays of the broadcast shape by name,
    with the call's diagnostics in ``.stats`` (:class:`Verdicts`).

    Parameters
    ----------
    c1, s1, c2, s2 : array_like
        Direction components of ``b1``, ``b2`` [1] (:func:`atlas.core.contact_modes.direction`).
    kappa, q1, q2 : array_like
        ``kappa = k1|b1|/(k2|b2|)`` and the damping ``q_hat`` (SPEC §1) [1].
    names : tuple of str
        Any of ``stable_SS``, ``consistent_II``, ``stable_II``, ``spectral_abscissa``.
    method : {"certified", "eig"}
        Certified kernels (default) or the uncertified batched-``eig`` baseline.
    resolve : bool
        Settle ``UNDECIDED`` points exactly (at most ``max_resolve`` of them; the rest stay 3).
    needed : callable, optional
        ``needed(idx, verdicts, exact) -> bool mask``: which of the flat indices ``idx`` (points
        some verdict of which is still undecided) the caller wants decided next, given the
        verdict arrays so far (flat, by name).  Asked before tiers 2 and 3 (``exact`` False) and,
        with ``exact`` True, in rounds of exact settlement until it wants none of the undecided
        points not yet tried (e.g. one sample a bracket and round: a bisection's search,
        :func:`atlas.core.brackets.bisect`).  The points it never wants stay undecided (counted
        in ``stats["unneeded_points"]``); ``max_resolve`` then bounds each round.
    """
    names = _checked_names(names, method)
    dtype = np.dtype(dtype)
    inputs = Invariants(*(np.asarray(a, dtype) for a in (c1, s1, c2, s2, kappa, q1, q2)))
    shape = np.broadcast_shapes(*(a.shape for a in inputs))
    n = math.prod(shape)
    counts = {"points": n, "tier2_points": 0, "roots_points": 0}
    if method == "eig":
        res = _kernel("eig", names)(*inputs)
        counts.update(roots_points=n, undecided_before=0, undecided_after=0)
        return Verdicts(
            {k: np.broadcast_to(np.asarray(res[k]), shape).copy() for k in names}, counts
        )

    backend.require_trusted()  # a backend that failed atlas selftest certifies nothing
    flags = [k for k in names if k != "spectral_abscissa"]
    undamped_q = (inputs.q1 == 0) & (inputs.q2 == 0)
    host = _host_limit(resolve, max_resolve)
    keep = _needed_filter(needed, flags)
    out, open_idx, later = _fast_tiers(
        inputs, shape, dtype, flags, undamped_q, counts, host_limit=host, keep=keep
    )
    if "spectral_abscissa" in names:
        out["spectral_abscissa"] = _abscissa(inputs, shape, dtype, chunk, undamped_q)
    open_ = {k: out[k].reshape(-1)[open_idx] == _UND for k in flags}
    counts["undecided_by_name"] = {k: int(u.sum()) for k, u in open_.items()}
    und = np.logical_or.reduce(list(open_.values())) if flags else open_idx.astype(bool)
    counts["undecided_before"] = int(und.sum())
    if resolve and und.any():
        _exact_rounds(inputs, shape, out, flags, open_idx[und], max_resolve, counts, keep)
    if later is not None:  # the later tiers were left to the exact tier; where it failed, they try
        still = [out[k].reshape(-1)[open_idx] == _UND for k in flags]
        later(open_idx[np.logical_or.reduce(still)])
    after = [out[k].reshape(-1)[open_idx] == _UND for k in flags]
    after = np.logical_or.reduce(after) if flags else np.zeros(0, bool)
    wanted = keep(open_idx[after], out, exact=False)
    counts["undecided_after"] = int(wanted.sum())
    counts["unneeded_points"] = int(wanted.size - wanted.sum())
    _count_in_tallies(counts)
    return Verdicts(out, counts)


def _count_in_tallies(counts: dict) -> None:
    """Add one certified call and its points per tier to every open :func:`tally`."""
    for total in getattr(_TALLY, "open", ()):
        total["calls"] += 1
        for k in TALLY_KEYS[1:]:
            total[k] += counts.get(k, 0)


#: what :func:`tally` adds up: certified calls, and the points each tier received
TALLY_KEYS = ("calls", "points", "tier2_points", "roots_points", "exact_points")
_TALLY = threading.local()


@contextlib.contextmanager
def tally():
    """Within the block (in this thread), the :data:`TALLY_KEYS` of every certified
    :func:`spectral_points` call added up in the dict it yields: the work of a whole computation
    (a boundary slice) per tier, counted rather than timed."""
    total = dict.fromkeys(TALLY_KEYS, 0)
    before = getattr(_TALLY, "open", ())
    _TALLY.open = (*before, total)
    try:
        yield total
    finally:
        _TALLY.open = before


def _checked_names(names, method) -> tuple[str, ...]:
    """``names`` as a tuple, or a one-line ``ValueError`` for an unknown name or ``method``."""
    names = tuple(names)
    bad = set(names) - set(SPECTRAL_NAMES)
    if bad:
        raise ValueError(f"names: unknown output(s) {sorted(bad)}")
    if method not in ("certified", "eig"):
        raise ValueError(f"method: must be 'certified' or 'eig', not {method!r}")
    return names


def _needed_filter(needed, flags):
    """``keep(idx, verdicts, exact=False)``: the mask of the flat indices ``idx`` that
    ``needed`` (the caller's, :func:`spectral_points`) wants decided next, all of them without
    one (``exact``: for the next round of exact settlement, else for tiers 2 and 3)."""

    def keep(idx, verdicts, exact=False):
        if needed is None or not idx.size:
            return np.ones(idx.size, bool)
        flat = {k: verdicts[k].reshape(-1) for k in flags}
        return np.asarray(needed(idx, flat, exact), bool).reshape(idx.shape)

    return keep


def _exact_rounds(inputs, shape, out, flags, idx, max_resolve, counts, keep):
    """Tier 4 in rounds at the undecided flat indices ``idx``: each round settles the points
    ``keep`` wants (:func:`_needed_filter`) that no round tried yet, until there are none (one
    round, every point, without a ``needed``)."""
    tried = np.zeros(idx.size, bool)
    counts["exact_rounds"] = 0
    while True:
        still = np.logical_or.reduce([out[k].reshape(-1)[idx] == _UND for k in flags])
        todo = np.flatnonzero(still & ~tried)
        todo = todo[keep(idx[todo], out, exact=True)]
        if not todo.size:
            return
        _settle_exact(inputs, shape, out, flags, idx[todo], max_resolve, counts)
        tried[todo] = True
        counts["exact_rounds"] += 1


@contextlib.contextmanager
def host_first(limit: int):
    """In this thread, while the later-tier programs have not yet run in this process, a first
    pass leaving at most ``limit`` points open sends them to the exact tier (instead of
    :data:`HOST_POINTS`): a first session's certified boundary overlay sends 773 points to the
    later tiers over 639 calls, at most 107 in one, where compiling the five later-tier programs
    costs about 9 s.  The verdicts are the same (every tier is certified); the counts of the
    points each tier received differ, so only callers that keep no counts use it."""
    before = getattr(_HOST, "limit", 0)
    _HOST.limit = limit
    try:
        yield
    finally:
        _HOST.limit = before


def _host_limit(resolve: bool, max_resolve) -> int:
    """Open points the first pass may leave to the exact tier directly: :data:`HOST_POINTS`, or
    the :func:`host_first` limit until both later tiers have run in this process; within the
    budget ``max_resolve``; 0 without exact settlement."""
    if not resolve:
        return 0
    cold = getattr(_HOST, "limit", 0) if not {"tier2", "roots"} <= _LATER_RAN else 0
    fits = [m for m in (cold, HOST_POINTS) if max_resolve is None or max_resolve >= m]
    return max(fits, default=0)


def _fast_tiers(inputs, shape, dtype, flags, undamped_q, counts, host_limit=0, keep=None):
    """Tiers 1-3 (first pass, tier 2, enclosures) for the verdicts ``flags``; returns the verdict
    arrays, the flat indices the first pass left open (where every later tier works, and where
    any undecided point lies) and ``None``, or, when the first pass left at most ``host_limit``
    points open, the later tiers not run (a function of flat indices, :data:`HOST_POINTS`).
    ``keep`` (:func:`_needed_filter`) narrows the points each later tier sees."""
    if not flags:
        return {}, np.zeros(0, np.intp), None
    want_ss = "stable_SS" in flags
    want_ii = any(k in flags for k in ("consistent_II", "stable_II"))
    damped = True if not undamped_q.any() else (False if undamped_q.all() else None)
    code = _first_pass(inputs, shape, dtype, ss=want_ss, ii=want_ii, damped=damped)
    ss, cons, stab, later, open_ = rootfree.unpack(code)
    verdict = {"stable_SS": ss, "consistent_II": cons, "stable_II": stab}
    # the kernel's "open" bit (a superset where it computed more than was asked), narrowed
    open_idx = np.flatnonzero(open_)
    undecided = [verdict[k].reshape(-1)[open_idx] == _UND for k in flags]
    open_idx = open_idx[np.logical_or.reduce(undecided)]

    def later_tiers(idx):  # every later tier works inside open_idx (small): no whole-grid pass
        if keep is not None:
            idx = idx[keep(idx, verdict)]
        tier2_idx = idx[later.reshape(-1)[idx]]
        _second_pass(inputs, shape, verdict, tier2_idx, counts)
        if want_ii:
            if keep is not None:
                idx = idx[keep(idx, verdict)]
            _roots_pass(inputs, shape, cons, stab, idx, counts)

    if open_idx.size <= host_limit:
        return {k: verdict[k] for k in flags}, open_idx, later_tiers
    later_tiers(open_idx)
    return {k: verdict[k] for k in flags}, open_idx, None


def _fill(arr, idx, new):
    """``arr.flat[idx] = new`` where ``arr`` is still undecided (in place)."""
    flat = arr.reshape(-1)
    flat[idx] = np.where(flat[idx] == _UND, new, flat[idx])


def _second_pass(inputs, shape, verdict, idx, counts):
    """Tier 2 (:func:`atlas.core.rootfree.tier2`) on the flat indices ``idx`` flagged by the first
    pass, in place."""
    counts["tier2_points"] = int(idx.size)
    if idx.size:  # both verdicts whatever was asked: one program pair for every caller
        kern = _kernel("tier2", ss=True, ii=True)
        res = _run_later(kern, _gather(inputs, shape, idx))
        _LATER_RAN.add("tier2")
        for i, k in enumerate(("stable_SS", "consistent_II", "stable_II")):
            _fill(verdict[k], idx, res[i])


def _roots_pass(inputs, shape, cons, stab, open_idx, counts):
    """Tier 3: root enclosures where an II verdict is still undecided (inside the flat indices
    ``open_idx``), in place."""
    still = (cons.reshape(-1)[open_idx] == _UND) | (stab.reshape(-1)[open_idx] == _UND)
    idx = open_idx[still]
    counts["roots_points"] = int(idx.size)
    if idx.size:
        kern = _kernel("roots", ("consistent_II", "stable_II"))
        res = _run_later(kern, _gather(inputs, shape, idx))
        _LATER_RAN.add("roots")
        _fill(cons, idx, res["consistent_II"])
        _fill(stab, idx, res["stable_II"])


def _abscissa(inputs, shape, dtype, chunk, undamped_q):
    """Spectral abscissa: closed form where ``q1 = q2 = 0``, root enclosures elsewhere."""
    absc = np.empty(shape, np.float64)
    und = np.broadcast_to(undamped_q, shape)
    if und.any():
        kern = _kernel("undamped_abscissa", ("spectral_abscissa",))
        if math.prod(shape) <= FLAT_LIMIT:
            absc[...] = _on_flat(lambda *a: kern(*a)["spectral_abscissa"], inputs, shape)
        else:
            absc[...] = np.broadcast_to(np.asarray(kern(*inputs)["spectral_abscissa"]), shape)
    idx = np.flatnonzero(~und)
    if idx.size:
        cols = _gather(inputs, shape, idx)
        res = _run_chunked(enclosures.abscissa, cols, dtype, chunk, (FLAT_BATCH,))
        absc.reshape(-1)[idx] = res[0]
    return absc


def _settle_exact(inputs, shape, out, flags, idx, max_resolve, counts):
    """Tier 4: exact verdicts (:func:`atlas.core.exact.resolve`) at the flat indices ``idx``
    where a flag is still undecided."""
    # points undecided only in stable_SS need only the rational Hurwitz test (microseconds)
    und_ii = np.zeros(idx.size, bool)
    for k in flags:
        if k != "stable_SS":
            und_ii |= out[k].reshape(-1)[idx] == _UND
    budget = max_resolve
    for sel, sel_names in ((idx[~und_ii], ("stable_SS",)), (idx[und_ii], tuple(flags))):
        if budget is not None:
            sel, budget = sel[:budget], max(0, budget - sel.size)
        if not sel.size:
            continue
        counts["exact_points"] = counts.get("exact_points", 0) + int(sel.size)
        cols = _gather(inputs, shape, sel)
        pts = {key: c.astype(np.float64) for key, c in zip(KEYS, cols)}
        try:
            ref = exact.resolve(pts, names=sel_names)
        except Exception:  # the exact tier must not raise; if it does, keep those points undecided
            ref = _resolve_each(exact, pts, sel_names, counts)
        for k in sel_names:
            _fill(out[k], sel, ref[k])


def _resolve_each(exact, pts, names, counts):
    """Point-by-point settlement after a failure: failing points stay undecided and are recorded
    in ``counts["exact_failures"]`` (a long atlas run is never aborted by one point)."""
    n = len(pts["c1"])
    ref = {k: np.full(n, _UND, np.int8) for k in names}
    for i in range(n):
        one = {key: v[i : i + 1] for key, v in pts.items()}
        try:
            res = exact.resolve(one, names=names)
        except Exception:
            counts.setdefault("exact_failures", []).append(tuple(float(v[0]) for v in one.values()))
            continue
        for k in names:
            ref[k][i] = res[k][0]
    return ref


def settle_codes(codes: dict, undecided: dict, c1, s1, c2, s2, ca=None, sa=None) -> dict:
    """Exact class/subclass codes and Table 1 flags where the fast kernels left them undecided
    (only these: a kernel settles through its own exact reference, ``PointKernel.exact`` and
    :mod:`atlas.core.settle`; this is the array form of the ``b1b2``/``b1b2a`` reference).

    ``codes``: arrays of one shape (``class_code``, ``subclass_code``, ``consistent_FF`` ...),
    replaced in place at the points where the matching mask of ``undecided`` holds; the inputs
    (direction components [1], ``ca, sa`` only for the ``alpha`` outputs) broadcast to that shape.
    The exact reference is :func:`atlas.core.exact.resolve_codes` (rational arithmetic).  A point on
    which it fails stays undecided and is recorded (a long atlas run is never aborted by one
    point).  Returns the diagnostics: ``resolved_points`` (points settled) and ``exact_failures``
    (the points the exact reference failed on).
    """
    stats = {"resolved_points": 0, "exact_failures": []}
    undecided = {k: np.asarray(u) for k, u in undecided.items() if k in codes}
    if not undecided:
        return stats
    shape = next(iter(undecided.values())).shape
    idx = np.flatnonzero(np.logical_or.reduce([u.reshape(-1) for u in undecided.values()]))
    if idx.size == 0:
        return stats
    args = (c1, s1, c2, s2) if ca is None else (c1, s1, c2, s2, ca, sa)
    pts = [np.broadcast_to(np.asarray(a), shape).reshape(-1)[idx] for a in args]
    try:
        ref, ok = exact.resolve_codes(*pts), np.ones(idx.size, bool)
    except Exception:  # settle point by point; failing points stay undecided
        ref, ok = _codes_each(pts, list(undecided), stats)
    for k, u in undecided.items():
        sel = u.reshape(-1)[idx] & ok
        codes[k].reshape(-1)[idx[sel]] = np.asarray(ref[k])[sel]
    stats["resolved_points"] = int(ok.sum())
    return stats


def _codes_each(pts, names, stats):
    """:func:`atlas.core.exact.resolve_codes` point by point, recording the points that fail."""
    n = pts[0].size
    ref = {k: np.zeros(n, np.int64) for k in names}
    ok = np.zeros(n, bool)
    for i in range(n):
        try:
            one = exact.resolve_codes(*(p[i : i + 1] for p in pts))
        except Exception:
            stats["exact_failures"].append(tuple(float(p[i]) for p in pts))
            continue
        ok[i] = True
        for k in names:
            ref[k][i] = one[k][0]
    return ref, ok
