"""Tiles of a scene -> an xarray.Dataset following the data contract (SPEC §2).

Architecture
------------
Each output names its point kernel in the registry (:mod:`atlas.data.outputs`,
:mod:`atlas.core.kernels`); the outputs of one kernel form a *group* sharing the parameters they
depend on (``stable_SF`` depends on ``beta1`` only, class codes on ``beta1, beta2``, the consistency
outputs also on ``alpha``, the spectral verdicts on ``beta1, beta2`` and the model parameters).  Each
group is computed over the *varied* parameters it depends on, in hyperslab *tiles* of at most
``tile_points`` points (:func:`tile_blocks`: trailing dimensions whole, one leading dimension
partial).  For each tile the host gathers the kernel's inputs from direction vectors computed
**once per coordinate** (:func:`atlas.core.contact_modes.direction`) and hands them,
broadcastable, to the kernel in shape buckets (:mod:`atlas.core.buckets`: flat columns of
65,536, 4,096 and 512 points whatever the tile, so at most three programs per kernel and dtype), dispatched
asynchronously; the previous tile is finished (undecided points settled by the kernel's exact
reference, codes converted to the stored types) while the next one computes.  A
kernel with a certified driver (the spectral verdicts) instead hands each hyperslab, as
broadcastable per-axis inputs, to that driver (:func:`atlas.core.points.spectral_points`: its tiers
and its exact settlement, the one copy of that logic).  Finished tiles go to a *sink* (:class:`Sink`):
:func:`generate` keeps them in memory and returns a Dataset; :func:`atlas.data.io.generate_to_file`
writes each tile straight into a netCDF4 file, so memory is bounded by the tile, not the atlas.
How a run computes is one :class:`RunOptions`; :func:`run` returns the sink's result with the run's
diagnostics (:class:`Run`).

Undecided points.  With ``resolve=True`` every value the certified fast path leaves undecided
(``Verdict.UNDECIDED``/``Consistency.UNDECIDED`` = 3, code -1) is recomputed by the exact reference
:mod:`atlas.core.exact` on the same floating-point inputs; ``resolve=False`` keeps them (3 or -1; boolean
outputs store ``False``).  Each variable carries ``undecided_fast`` (values left undecided by the fast
path) and ``undecided`` (after resolution); the global attributes carry the totals.

Model dependence (the registry's reductions: ``needs`` + ``state``).  ``model_dependent_SS``
(``model_dependent_II``) is ``True`` at a ``(beta1, beta2)`` point iff the set of *decided* verdicts
over the scene's model samples (``kappa``, ``q`` or ``q1, q2``) has more than one element.  For SS, *neutral counts as stable* (the paper's Fig. 1 draws
the ``q = 0`` neutral region as stable), so the SS verdict set is a subset of {stable, unstable}.
For II the verdict is the combined state {inconsistent, consistent & unstable, consistent & stable}.
Undecided samples (only with ``resolve=False``) are ignored.

Stored types.  ``stable_SF``/``stable_FS`` are ``True`` iff the verdict is *stable* (``b11 = 0``
exactly is neutral and stored as ``False``); the consistency outputs are ``True`` iff consistent.
"""

from __future__ import annotations

import dataclasses
import datetime
import itertools
import math
import sys
import time
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, NamedTuple, Protocol, runtime_checkable

import jax
import numpy as np

from atlas.core import backend, buckets, checks, config, kernels
from atlas.core import contact_modes as mech
from atlas.data.outputs import (
    OUTPUTS,
    coord_attrs,
    reductions,
    storage_dtype,
    to_storage,
    undecided,
    variable_attrs,
)
from atlas.data.scene import Scene

if TYPE_CHECKING:
    import xarray as xr

__all__ = [
    "generate",
    "RunOptions",
    "run",
    "Run",
    "Sink",
    "schema",
    "tile_blocks",
    "block_shape",
    "DEFAULT_TILE_POINTS",
    "METHODS",
    "DTYPES",
    "REFERENCES",
]

#: default number of points per tile (kernel memory ~1 kB per point for the II kernel)
DEFAULT_TILE_POINTS = 1 << 16
METHODS = ("certified", "eig")
DTYPES = ("float64", "float32")
REFERENCES = (
    "Varkonyi, P. L.: Dynamics of mechanical systems with multiple sliding contacts: "
    "new faces of Painleve's paradox."
)


@dataclass(frozen=True)
class RunOptions:
    """How an atlas is computed: the one set of options of :func:`generate`, :func:`run`,
    :func:`schema`, :func:`atlas.data.io.generate_to_file` and
    :func:`atlas.data.distributed.generate_distributed` (validated on construction: one-line
    ``ValueError`` naming the option).

    Attributes
    ----------
    method : {"certified", "eig"}
        ``certified``: proven signs, undecided where floating point cannot certify (then exact
        resolution); ``eig``: the uncertified batched-``eig`` baseline (never undecided).
    dtype : {"float64", "float32"}
        Working precision of the kernels (direction vectors are rounded to it).
    resolve : bool
        Recompute undecided values exactly with :mod:`atlas.core.exact` (slow per point, few points).
    tile_points : int
        Points per tile: bounds the memory of a tile (the elementwise kernels' programs do not
        depend on it).
    progress : bool
        tqdm progress bar on stderr.
    history : str, optional
        Command recorded in the ``history`` attribute (default: the Python call).
    """

    method: str = "certified"
    dtype: str = "float64"
    resolve: bool = True
    tile_points: int = DEFAULT_TILE_POINTS
    progress: bool = False
    history: str | None = None

    def __post_init__(self):
        if self.method not in METHODS:
            raise ValueError(f"method: must be one of {', '.join(METHODS)}, got {self.method!r}")
        object.__setattr__(self, "dtype", checks.float_dtype(self.dtype))
        object.__setattr__(
            self, "tile_points", checks.positive_int("tile_points", self.tile_points)
        )
        object.__setattr__(self, "resolve", checks.boolean("resolve", self.resolve))

    @classmethod
    def of(cls, options: RunOptions | None = None, **changes) -> RunOptions:
        """``options`` (default: the defaults) with some options changed by name."""
        if options is None:
            options = cls()
        elif not isinstance(options, cls):
            raise ValueError(f"options: expected RunOptions, got {options!r}")
        known = [f.name for f in dataclasses.fields(cls)]
        for name in changes:
            if name not in known:
                raise ValueError(f"{name}: not a run option (known: {', '.join(known)})")
        return dataclasses.replace(options, **changes) if changes else options

    def stored(self) -> dict:
        """The options that decide the stored values (``method, dtype, resolve, tile_points``)."""
        return dict(
            method=self.method, dtype=self.dtype, resolve=self.resolve, tile_points=self.tile_points
        )


# --- tiling -------------------------------------------------------------------------------------


def block_shape(shape: tuple[int, ...], tile_points: int) -> tuple[int, ...]:
    """Shape of the hyperslab tiles of an array of ``shape`` with at most ``tile_points`` points.

    Trailing dimensions are taken whole while they fit, the next one partially, leading ones 1.
    Also used as the netCDF chunk shape, so tiles write whole chunks.
    """
    out = [1] * len(shape)
    prod = 1
    for i in range(len(shape) - 1, -1, -1):
        n = shape[i]
        if prod * n <= tile_points:
            out[i] = n
            prod *= n
        else:
            out[i] = max(1, tile_points // prod)
            break
    return tuple(out)


def tile_blocks(shape: tuple[int, ...], tile_points: int):
    """Yield tuples of slices (hyperslabs of :func:`block_shape`) covering an array of ``shape``."""
    bs = block_shape(shape, tile_points)
    starts = [range(0, n, b) for n, b in zip(shape, bs)]
    for st in itertools.product(*starts):
        yield tuple(slice(s, min(s + b, n)) for s, b, n in zip(st, bs, shape))


# --- the groups of outputs ----------------------------------------------------------------------


@dataclass(frozen=True)
class _Group:
    kernel: kernels.PointKernel
    params: tuple[str, ...]  # parameters (scalar or varied) the kernel needs, canonical order
    outputs: tuple[str, ...]  # outputs it can produce

    @property
    def name(self) -> str:
        return self.kernel.name


def _groups(scene: Scene, outputs) -> list[_Group]:
    """One group per kernel (:data:`atlas.core.kernels.KERNELS`) the wanted ``outputs`` and the
    reductions they include read, in kernel-table order."""
    used = {}
    for o in outputs:
        for n in OUTPUTS[o].needs or (o,):
            used.setdefault(OUTPUTS[n].kernel, []).append(n)
    out = []
    for name, k in kernels.KERNELS.items():
        if name in used:
            names = tuple(r for r in k.results if r in OUTPUTS)
            out.append(_Group(k, scene.depends(names[0]), names))
    return out


def _needed(group: _Group, outputs: tuple[str, ...]) -> tuple[str, ...]:
    """Kernel results a group must compute for the wanted outputs (incl. what reductions read)."""
    need = {o for o in group.outputs if o in outputs}
    for o in outputs:
        need.update(n for n in OUTPUTS[o].needs if n in group.outputs)
    return tuple(o for o in group.outputs if o in need)


# --- schema: coordinates, variables, attributes ------------------------------------------------


@dataclass
class Schema:
    """Everything a sink needs to lay out an atlas before the first tile arrives."""

    coords: dict  # name -> (dims, values, attrs)
    variables: dict  # name -> (dims, numpy dtype, attrs, chunk shape or None)
    attrs: dict  # global attributes
    shape: dict = field(default_factory=dict)  # dim -> size


@runtime_checkable
class Sink(Protocol):
    """Where :func:`run` puts an atlas: laid out once, written tile by tile, then finished (its
    result is what :func:`run` returns) or, on any error or interrupt, aborted (nothing left)."""

    def begin(self, sch: Schema) -> None:
        """Lay out every coordinate and variable of ``sch`` before the first tile."""

    def write(self, name: str, index: tuple, block: np.ndarray) -> None:
        """Store ``block`` (the stored dtype) at the hyperslab ``index`` of variable ``name``."""

    def finish(self, attrs: dict, var_attrs: dict) -> Any:
        """Add the run's global and per-variable attributes; return the finished atlas."""

    def abort(self) -> None:
        """Discard everything written (called once, from an error or interrupt)."""


class Run(NamedTuple):
    """What :func:`run` returns: the sink's ``result`` and the run's diagnostics ``stats``:
    ``scene``, ``points``, ``values`` (computed values over all groups), ``seconds``,
    ``points_per_second``, ``undecided_fast``, ``undecided`` (after exact resolution),
    ``resolved_points``, ``exact_failures`` (the points the exact tier failed on)."""

    result: Any
    stats: dict


def _versions() -> str:
    return config.source()


def _default_history(scene: Scene, method: str, dtype: str) -> str:
    return f"atlas.generate(scene={scene.describe()!r}, method={method!r}, dtype={dtype!r})"


def schema(scene: Scene, options: RunOptions | None = None) -> Schema:
    """Coordinates, variables (dims, dtype, attributes, chunks) and global attributes of an atlas."""
    opts = RunOptions.of(options)
    method, dtype, history = opts.method, opts.dtype, opts.history
    coords = {}
    for key, ax in scene.axes.items():
        dims = (key,) if ax.is_dim else ()
        coords[key] = (dims, ax.values, coord_attrs(key))
    variables = {}
    for name in scene.output_names:
        dims = scene.output_dims(name)
        shape = tuple(scene.axes[d].size for d in dims)
        chunks = block_shape(shape, opts.tile_points) if dims else None
        variables[name] = (dims, storage_dtype(name, dtype), variable_attrs(name), chunks)
    now = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")
    attrs = {
        "Conventions": "CF-1.10",
        "title": f"Painleve paradox atlas of two sliding contacts: scene {scene.name}",
        "source": _versions(),
        "history": f"{now}: {history or _default_history(scene, method, dtype)}",
        "references": REFERENCES,
        "scene": scene.name,
        "scene_description": scene.describe(),
        "method": method,
        "dtype": dtype,
        "exact_resolution": int(opts.resolve),
        "model_parameters": " ".join(scene.model_names),
    }
    for key, val in scene.fixed().items():
        attrs[key] = val
    if any(n in variables for n in reductions()):
        attrs["model_dependent_definition"] = (
            "True iff the set of decided verdicts over the model samples has more than one "
            "element; SS: neutral counted as stable"
        )
    shape = {d: scene.axes[d].size for d in scene.dims}
    return Schema(coords, variables, attrs, shape)


# --- sinks --------------------------------------------------------------------------------------


class MemorySink(Sink):
    """Collects tiles in numpy arrays and builds the :class:`xarray.Dataset`."""

    def begin(self, sch: Schema):
        self.schema = sch
        self.arrays = {}
        for name, (dims, dt, _, _) in sch.variables.items():
            shape = tuple(sch.shape[d] for d in dims)
            self.arrays[name] = np.zeros(shape, dt)

    def write(self, name: str, index: tuple, block: np.ndarray):
        self.arrays[name][index] = block

    def finish(self, attrs: dict, var_attrs: dict):
        import xarray as xr  # noqa: PLC0415 - the streaming path (atlas generate) needs no xarray

        sch = self.schema
        coords = {k: xr.Variable(d, v, a) for k, (d, v, a) in sch.coords.items()}
        data = {}
        for name, (dims, _, a, _) in sch.variables.items():
            data[name] = xr.Variable(dims, self.arrays[name], {**a, **var_attrs.get(name, {})})
        return xr.Dataset(data, coords=coords, attrs={**sch.attrs, **attrs})

    def abort(self):
        pass


# --- the engine ---------------------------------------------------------------------------------


def _axis_inputs(scene: Scene, dtype) -> dict:
    """Per-parameter 1-D (or 0-d) kernel inputs, computed once per coordinate array."""
    dt = np.dtype(dtype)
    src = {}
    for key, ax in scene.axes.items():
        if key in ("beta1", "beta2", "alpha"):
            c, s = mech.direction(ax.values, dt)
            tag = kernels.PARAM_INPUTS[key]
            src[tag[0]] = (key, np.asarray(c, dt))
            src[tag[1]] = (key, np.asarray(s, dt))
        else:
            src[key] = (key, np.asarray(ax.values, dt))
    if "q" in src:
        src["q1"] = src["q2"] = src.pop("q")
    return src


def _block_inputs(src, inputs, dims, index, block):
    """Broadcastable (block-shaped) inputs of one hyperslab: each varied parameter along its axis."""
    out = []
    for key in inputs:
        param, vals = src[key]
        if vals.ndim == 0:
            out.append(vals)
            continue
        ax = dims.index(param)
        shp = [1] * len(dims)
        shp[ax] = block[ax]
        out.append(vals[index[ax]].reshape(shp))
    return out


def _driver_tile(kernel, src, dims, index, block, need, dtype, resolve, stats):
    """Certified verdicts of one tile through the kernel's driver (all tiers, exact settlement)."""
    args = _block_inputs(src, kernel.inputs, dims, index, block)
    res = kernel.driver(*args, names=need, dtype=dtype, resolve=resolve)
    st = res.stats
    settled = st["undecided_before"] - st["undecided_after"] if resolve else 0
    stats["resolved_points"] = stats.get("resolved_points", 0) + settled
    stats.setdefault("exact_failures", []).extend(st.get("exact_failures", []))
    res = {k: np.broadcast_to(v, block).reshape(-1) for k, v in res.items()}
    return res, st["undecided_by_name"]


def _resolve(kernel, res: dict, args: list, block: tuple, stats: dict):
    """Settle the undecided codes of one tile exactly, in place (the kernel's ``settle``; a kernel
    with a driver is settled by the driver): ``res`` flat, ``args`` broadcastable to ``block``."""
    codes = {k: v.reshape(block) for k, v in res.items()}
    st = kernels.settle(kernel, codes, dict(zip(kernel.inputs, args)))
    stats["resolved_points"] = stats.get("resolved_points", 0) + st["resolved_points"]
    stats.setdefault("exact_failures", []).extend(st["exact_failures"])


def run(scene: Scene, sink: Sink, options: RunOptions | None = None) -> Run:
    """Compute every output of ``scene`` tile by tile into ``sink`` (a :class:`Sink`, e.g.
    :class:`MemorySink` or :class:`atlas.data.io.NetCDFSink`); returns ``sink.finish(...)`` with
    the run's diagnostics (:class:`Run`)."""
    opts = RunOptions.of(options)
    if not isinstance(scene, Scene):
        raise ValueError("scene: expected an atlas.Scene")
    method, dtype, resolve, tile_points = opts.method, opts.dtype, opts.resolve, opts.tile_points
    sch = schema(scene, opts)
    outputs = scene.output_names
    src = _axis_inputs(scene, dtype)
    plan = _plan(scene, outputs)
    if method == "certified" and any(g.kernel.driver is not None for g, *_ in plan):
        backend.require_trusted()  # before any work: a backend that failed selftest certifies nothing
    total = sum(math.prod(shape) for _, _, _, shape in plan)
    t0 = time.perf_counter()
    counts = {"undecided_fast": {}, "undecided": {}}
    md = _ModelDependence(scene, outputs)
    bar = progress_bar(opts.progress, total, f"atlas {scene.name}")
    writer = _TileWriter(sink, outputs, dtype, resolve, counts, md, bar)
    try:
        sink.begin(sch)  # inside: an interrupt while the header is written still aborts
        for g, need, dims, shape in plan:
            if g.kernel.driver is not None and method == "certified":
                _certified_group(writer, src, g, need, dims, shape, tile_points)
            else:
                _kernel_group(writer, src, g, need, dims, shape, tile_points)
        for name, block in md.results().items():
            sink.write(name, tuple(slice(None) for _ in block.shape), block)
        result = sink.finish(*_final_attrs(counts, sch))
        seconds = time.perf_counter() - t0
    except BaseException:
        sink.abort()
        raise
    finally:
        if bar is not None:
            bar.close()
    return Run(result, _summary(scene, total, seconds, counts))


@dataclass
class _TileWriter:
    """Where the finished tiles of a run go: the sink (the wanted ``outputs``, stored as ``dtype``),
    the undecided ``counts``, the model dependence and the progress bar."""

    sink: object
    outputs: tuple
    dtype: str
    resolve: bool
    counts: dict
    md: _ModelDependence
    bar: object


def _certified_group(writer: _TileWriter, src, g, need, dims, shape, T):
    """The certified spectral verdicts of one group, hyperslab by hyperslab."""
    for index in tile_blocks(shape, T):
        block = tuple(s.stop - s.start for s in index)
        res, fast = _driver_tile(
            g.kernel, src, dims, index, block, need, writer.dtype, writer.resolve, writer.counts
        )
        _store_tile(writer, g, dims, index, block, res, fast)
        if writer.bar is not None:
            writer.bar.update(math.prod(block))


def _kernel_group(writer: _TileWriter, src, g, need, dims, shape, T):
    """One group through its jitted kernel in shape buckets (:mod:`atlas.core.buckets`): each
    tile is dispatched asynchronously and the previous one finished (resolved, stored) while it
    computes."""
    kern = kernels.jitted(g.kernel)
    pending = None
    try:
        for index in tile_blocks(shape, T):
            block = tuple(s.stop - s.start for s in index)
            args = _block_inputs(src, g.kernel.inputs, dims, index, block)
            run = buckets.submit(kern, *args, ahead=None)  # overlaps with finishing the last tile
            if pending is not None:
                _finish_tile(writer, g, need, dims, *pending)
            pending = (index, block, args, run)
        if pending is not None:
            _finish_tile(writer, g, need, dims, *pending)
    except BaseException:
        try:  # let in-flight kernels finish before unwinding (exiting under them can crash XLA)
            if pending is not None:
                jax.block_until_ready(pending[3].out)
        except BaseException:  # pragma: no cover - best effort
            pass
        raise


def _final_attrs(counts: dict, sch: Schema) -> tuple[dict, dict]:
    """Global and per-variable undecided counts of a run (``sink.finish`` arguments)."""
    fast = sum(counts["undecided_fast"].values())
    final = sum(counts["undecided"].values())
    attrs = {"undecided_fast": fast, "undecided_after_resolve": final}
    failures = counts.get("exact_failures", [])
    if failures:
        attrs["exact_failures"] = len(failures)
        attrs["exact_failure_example"] = repr(failures[0])
    var_attrs = {
        k: {"undecided_fast": counts["undecided_fast"].get(k, 0), "undecided": v}
        for k, v in counts["undecided"].items()
        if k in sch.variables
    }
    return attrs, var_attrs


def _plan(scene: Scene, outputs) -> list[tuple]:
    """``(group, kernel results needed, varied dims, shape)`` of every group with work to do."""
    plan = []
    for g in _groups(scene, outputs):
        need = _needed(g, outputs)
        if need:
            dims = tuple(p for p in g.params if scene.axes[p].is_dim)
            plan.append((g, need, dims, tuple(scene.axes[d].size for d in dims)))
    return plan


def _summary(scene: Scene, values: int, seconds: float, counts: dict) -> dict:
    """The run's summary handed to the caller (see :func:`run`)."""
    points = scene.points()
    return {
        "scene": scene.name,
        "points": points,
        "values": values,
        "seconds": seconds,
        "points_per_second": points / seconds if seconds > 0 else float("inf"),
        "undecided_fast": sum(counts["undecided_fast"].values()),
        "undecided": sum(counts["undecided"].values()),
        "resolved_points": counts.get("resolved_points", 0),
        "exact_failures": counts.get("exact_failures", []),
    }


def _finish_tile(writer: _TileWriter, g, need, dims, index, block, args, run):
    """Finish one kernel tile: count, resolve undecided values exactly, store."""
    out = run.result()
    res = {k: out[k].reshape(-1) for k in need}  # fresh arrays of the tile's shape
    fast = {k: int(undecided(k, v).sum()) for k, v in res.items()}
    if writer.resolve:
        _resolve(g.kernel, res, args, block, writer.counts)
    _store_tile(writer, g, dims, index, block, res, fast)
    if writer.bar is not None:
        writer.bar.update(math.prod(block))


def _store_tile(writer: _TileWriter, g, dims, index, block, res, fast):
    """Count, record model dependence and write the finished (flat) results of one tile."""
    stats = writer.counts
    for k, v in res.items():
        stats["undecided_fast"][k] = stats["undecided_fast"].get(k, 0) + fast.get(k, 0)
        stats["undecided"][k] = stats["undecided"].get(k, 0) + int(undecided(k, v).sum())
    writer.md.update(dims, index, block, res)
    for k, v in res.items():
        if k in writer.outputs:
            writer.sink.write(k, index, to_storage(k, v.reshape(block), writer.dtype))


class _ModelDependence:
    """Accumulates, per point of a reduction's dims, the set of decided states seen over the model
    samples (the reduction's ``state``, :mod:`atlas.data.outputs`)."""

    def __init__(self, scene: Scene, outputs):
        self.want = [o for o in reductions() if o in outputs]
        self.dims = {o: scene.output_dims(o) for o in self.want}
        self.bits = {
            o: np.zeros(tuple(scene.axes[d].size for d in self.dims[o]), np.uint8)
            for o in self.want
        }

    def update(self, dims, index, block, res):
        for o in self.want:
            needs = OUTPUTS[o].needs
            if not all(n in res for n in needs):
                continue
            keep_dims = self.dims[o]
            red = tuple(i for i, d in enumerate(dims) if d not in keep_dims)
            keep = tuple(index[i] for i, d in enumerate(dims) if d in keep_dims)
            bits = OUTPUTS[o].state({n: res[n].reshape(block) for n in needs})
            bits = np.bitwise_or.reduce(bits.astype(np.uint8), axis=red) if red else bits
            self.bits[o][keep] |= bits.astype(np.uint8)

    def results(self) -> dict:
        out = {}
        for o, b in self.bits.items():
            count = sum((b >> i) & 1 for i in range(8))
            out[o] = count > 1
        return out


def progress_bar(progress, total, desc, unit="pt"):
    """A tqdm bar on stderr, or ``None`` when ``progress`` is false."""
    if not progress:
        return None
    from tqdm import tqdm

    return tqdm(total=total, unit=unit, unit_scale=True, desc=desc, file=sys.stderr, leave=False)


def generate(scene: Scene, options: RunOptions | None = None, **changes) -> xr.Dataset:
    """Compute an atlas in memory (SPEC §2).

    Parameters
    ----------
    scene : atlas.Scene
        Parameters, ranges and wanted outputs.
    options : RunOptions, optional
        How to compute it (method, dtype, exact resolution, tile size, progress bar, history).
    **changes
        Options changed by name, e.g. ``generate(scene, dtype="float32")`` (see
        :class:`RunOptions`; an unknown name is refused).  ``model_box=`` (a
        :class:`atlas.core.model_box.ModelBox`, its text ``"kappa=0.01:100,q1=0:1,q2=0:1"`` or a
        dict) adds ``ss_over_models``, ``ii_consistent_over_models``, ``ii_stable_over_models``
        and their witnesses (:mod:`atlas.data.over_models`).

    Returns
    -------
    xarray.Dataset
        Each variable spans only the varied parameters it depends on; see :mod:`atlas.data.engine`.
        The undecided counts are its attributes; :func:`run` also returns the run's diagnostics.
        For atlases larger than memory use :func:`atlas.data.io.generate_to_file`.
    """
    box = changes.pop("model_box", None)
    if box is None:
        return run(scene, MemorySink(), RunOptions.of(options, **changes)).result
    from atlas.data import over_models  # noqa: PLC0415 - only on request

    box = over_models.as_model_box(box)  # refused before any work
    ds = run(scene, MemorySink(), RunOptions.of(options, **changes)).result
    return over_models.add_all_over_models(ds, box)
