"""Tiles of a scene -> an xarray.Dataset following the data contract (SPEC §2).

Architecture
------------
The outputs of a :class:`~atlas.data.scene.Scene` fall into *groups* that share the parameters they
depend on (``stable_SF`` depends on ``beta1`` only, class codes on ``beta1, beta2``, the consistency
outputs also on ``alpha``, the spectral verdicts on ``beta1, beta2`` and the model parameters).  Each
group is computed over the *varied* parameters it depends on, in hyperslab *tiles* of at most
``tile_points`` points (:func:`tile_blocks`: trailing dimensions whole, one leading dimension
partial).  For each tile the host gathers the inputs from direction vectors computed **once per
coordinate** (:func:`atlas.core.mechanics.direction`), flattens and pads them to exactly ``tile_points``
values (so the jitted kernel compiles once per ``tile_points`` and dtype), and dispatches the kernel
asynchronously; the previous tile is finished (undecided points resolved exactly, codes converted to
the stored types) while the next one computes.  The certified spectral group instead hands each
hyperslab, as broadcastable per-axis inputs, to :func:`atlas.core.points.spectral_points` (its tiers
and its exact settlement: the one copy of that logic).  Finished tiles go to a *sink*:
:func:`generate` keeps them in memory and returns a Dataset; :func:`atlas.data.io.generate_to_file`
writes each tile straight into a netCDF4 file, so memory is bounded by the tile, not the atlas.

Undecided points.  With ``resolve=True`` every value the certified fast path leaves undecided
(``Verdict.UNDECIDED``/``Consistency.UNDECIDED`` = 3, code -1) is recomputed by the exact reference
:mod:`atlas.core.exact` on the same floating-point inputs; ``resolve=False`` keeps them (3 or -1; boolean
outputs store ``False``).  Each variable carries ``undecided_fast`` (values left undecided by the fast
path) and ``undecided`` (after resolution); the global attributes carry the totals.

Model dependence.  ``model_dependent_SS`` (``model_dependent_II``) is ``True`` at a ``(beta1, beta2)``
point iff the set of *decided* verdicts over the scene's model samples (``kappa``, ``q`` or
``q1, q2``) has more than one element.  For SS, *neutral counts as stable* (the paper's Fig. 1 draws
the ``q = 0`` neutral region as stable), so the SS verdict set is a subset of {stable, unstable}.
For II the verdict is the combined state {inconsistent, consistent & unstable, consistent & stable}.
Undecided samples (only with ``resolve=False``) are ignored.

Stored types.  ``stable_SF``/``stable_FS`` are ``True`` iff the verdict is *stable* (``b11 = 0``
exactly is neutral and stored as ``False``); the consistency outputs are ``True`` iff consistent.
"""

from __future__ import annotations

import datetime
import functools
import itertools
import math
import sys
import time
from dataclasses import dataclass, field

import jax
import numpy as np
import xarray as xr

from atlas.core import config, spectral
from atlas.core import mechanics as mech
from atlas.core import points as evaluate
from atlas.core.verdicts import UNDECIDED_CODE, Consistency, Verdict, flag_attrs
from atlas.data.scene import Scene

__all__ = [
    "generate",
    "run",
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
U3 = int(Verdict.UNDECIDED)

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
    name: str
    params: tuple[str, ...]  # parameters (scalar or varied) the kernel needs, canonical order
    outputs: tuple[str, ...]  # outputs it can produce


_CONSISTENCY = ("consistent_FF", "consistent_SF", "consistent_FS", "consistent_SS")
_SPECTRAL = ("stable_SS", "consistent_II", "stable_II", "spectral_abscissa")
_MODEL_DEP = ("model_dependent_SS", "model_dependent_II")


def _groups(scene: Scene) -> list[_Group]:
    model = scene.model_names
    return [
        _Group("b1", ("beta1",), ("stable_SF", "consistent_IF")),
        _Group("b2", ("beta2",), ("stable_FS", "consistent_FI")),
        _Group("b1b2", ("beta1", "beta2"), ("class_code", "cc_possible")),
        _Group("b1b2a", ("beta1", "beta2", "alpha"), ("subclass_code",) + _CONSISTENCY),
        _Group("spectral", ("beta1", "beta2") + model, _SPECTRAL),
    ]


def _needed(group: _Group, outputs: tuple[str, ...]) -> tuple[str, ...]:
    """Kernel results a group must compute for the wanted outputs (incl. model dependence)."""
    need = [o for o in group.outputs if o in outputs]
    if group.name == "spectral":
        if "model_dependent_SS" in outputs and "stable_SS" not in need:
            need.append("stable_SS")
        if "model_dependent_II" in outputs:
            need += [o for o in ("consistent_II", "stable_II") if o not in need]
    return tuple(o for o in group.outputs if o in need)


# --- kernels (pure jnp on 1-D arrays of tile_points values) -------------------------------------


def _kernel_b1(c1, s1):
    return {"stable_SF": mech.stable_SF(c1), "consistent_IF": mech.consistent_IF(c1, s1)}


def _kernel_b2(c2, s2):
    return {"stable_FS": mech.stable_FS(s2), "consistent_FI": mech.consistent_FI(c2, s2)}


def _kernel_b1b2(c1, s1, c2, s2):
    return {"class_code": mech.class_code(c1, s1, c2, s2), "cc_possible": mech.cc_possible(c1, s2)}


def _kernel_b1b2a(c1, s1, c2, s2, ca, sa):
    out = {f"consistent_{k}": v for k, v in mech.consistent_modes(c1, s1, c2, s2, ca, sa).items()}
    out["subclass_code"] = mech.subclass_code(c1, s1, c2, s2, ca, sa)
    return out


@functools.cache
def _jitted(group: str):
    """One jitted kernel per group (the spectral group: the uncertified ``eig`` baseline; the
    certified spectral verdicts go through :func:`atlas.core.points.spectral_points`).  Every output
    of the group is returned, so scenes asking for different subsets share one compilation."""
    kernels = {
        "b1": _kernel_b1,
        "b2": _kernel_b2,
        "b1b2": _kernel_b1b2,
        "b1b2a": _kernel_b1b2a,
        "spectral": spectral.eig_verdicts,
    }
    return jax.jit(kernels[group])


# --- schema: coordinates, variables, attributes ------------------------------------------------

_COORD_ATTRS = {
    "beta1": dict(
        units="rad", long_name="direction angle of b1 (response of the gaps to contact 1)"
    ),
    "beta2": dict(
        units="rad", long_name="direction angle of b2 (response of the gaps to contact 2)"
    ),
    "alpha": dict(units="rad", long_name="direction angle of a (free relative acceleration)"),
    "kappa": dict(units="1", long_name="stiffness ratio k1 |b1| / (k2 |b2|)"),
    "q": dict(units="1", long_name="dimensionless damping q1_hat = q2_hat = q |b| / sqrt(k2 |b2|)"),
    "q1": dict(units="1", long_name="dimensionless damping q1_hat = q1 |b1| / sqrt(k2 |b2|)"),
    "q2": dict(units="1", long_name="dimensionless damping q2_hat = q2 |b2| / sqrt(k2 |b2|)"),
}


def _bool_flags(long_name: str, false: str, true: str, comment: str | None = None) -> dict:
    out = {
        "long_name": long_name,
        "flag_values": np.array([0, 1], np.int8),
        "flag_meanings": f"{false} {true}",
    }
    if comment:
        out["comment"] = comment
    return out


def _code_flags(codes: list[int], prefix: str, dtype) -> dict:
    values = [UNDECIDED_CODE, 0] + codes
    meanings = ["undecided", "degenerate"] + [f"{prefix}_{c}" for c in codes]
    return {"flag_values": np.array(values, dtype), "flag_meanings": " ".join(meanings)}


_SUBCLASSES = [10 * c + k for c in mech.ALL_CLASSES for k in range(1, 7)]


def _variable_attrs(name: str) -> dict:
    if name == "class_code":
        return {
            "long_name": "class code ij (rank of beta1, beta2; paper Sec. 3)",
            **_code_flags(list(mech.ALL_CLASSES), "class", np.int8),
        }
    if name == "subclass_code":
        return {
            "long_name": "subclass code ijk (rank of alpha; paper Sec. 3)",
            **_code_flags(_SUBCLASSES, "subclass", np.int16),
        }
    if name in _CONSISTENCY:
        mode = name[-2:]
        return _bool_flags(
            f"consistency of the {mode} contact mode (paper Table 1, Appendix A)",
            "inconsistent",
            "consistent",
        )
    if name in ("stable_SF", "stable_FS"):
        mode, b = ("SF", "b11") if name == "stable_SF" else ("FS", "b22")
        return _bool_flags(
            f"stability of the {mode} contact mode (paper Sec. 4.2)",
            "not_stable",
            "stable",
            f"stable iff {b} > 0; {b} = 0 (neutral) is stored as not_stable",
        )
    if name in ("consistent_IF", "consistent_FI"):
        cond = "b11 < 0 and b21 > 0" if name == "consistent_IF" else "b22 < 0 and b12 > 0"
        return _bool_flags(
            f"consistency of the {name[-2:]} impact without collision (paper Sec. 4.3)",
            "inconsistent",
            "consistent",
            f"consistent iff {cond}; stable whenever consistent",
        )
    if name == "cc_possible":
        return _bool_flags(
            "CC inverse chattering possible (paper Sec. 5.2)",
            "impossible",
            "possible",
            "necessary condition b11 > 0 and b22 > 0",
        )
    if name == "stable_SS":
        a = flag_attrs(
            Verdict, "stability verdict of the SS contact mode (eigenvalues of M, eq. 9)"
        )
        a["comment"] = "neutral: no eigenvalue with Re > 0, some with Re = 0 (q = 0; Fig. 1 stable)"
        return a
    if name == "consistent_II":
        return flag_attrs(Consistency, "consistency of the II impact without collision (Sec. 4.3)")
    if name == "stable_II":
        a = flag_attrs(Verdict, "stability verdict of the II impact without collision (Sec. 4.3)")
        a["comment"] = "stable iff the strictly dominant eigenvalue of M is a II eigenvalue"
        return a
    if name == "spectral_abscissa":
        return {
            "long_name": "spectral abscissa of M: max real part of its eigenvalues",
            "units": "1",
            "comment": "time scaled by contact 2 (unit 1/sqrt(k2 |b2|)); approximate, not certified",
        }
    if name == "model_dependent_SS":
        return _bool_flags(
            "SS stability verdict varies over the model samples (kappa, q)",
            "model_independent",
            "model_dependent",
            "more than one decided verdict over the samples; neutral counted as stable",
        )
    if name == "model_dependent_II":
        return _bool_flags(
            "II verdict varies over the model samples (kappa, q)",
            "model_independent",
            "model_dependent",
            "more than one decided state among inconsistent, consistent-unstable, "
            "consistent-stable over the samples",
        )
    raise KeyError(name)


def _storage_dtype(name: str, dtype: str):
    if name == "class_code":
        return np.dtype(np.int8)
    if name == "subclass_code":
        return np.dtype(np.int16)
    if name in ("stable_SS", "consistent_II", "stable_II"):
        return np.dtype(np.int8)
    if name == "spectral_abscissa":
        return np.dtype(dtype)
    return np.dtype(bool)


@dataclass
class Schema:
    """Everything a sink needs to lay out an atlas before the first tile arrives."""

    coords: dict  # name -> (dims, values, attrs)
    variables: dict  # name -> (dims, numpy dtype, attrs, chunk shape or None)
    attrs: dict  # global attributes
    shape: dict = field(default_factory=dict)  # dim -> size


def _versions() -> str:
    return config.source()


def _default_history(scene: Scene, method: str, dtype: str) -> str:
    return f"atlas.generate(scene={scene.describe()!r}, method={method!r}, dtype={dtype!r})"


def schema(
    scene: Scene,
    *,
    method: str = "certified",
    dtype: str = "float64",
    resolve: bool = True,
    tile_points: int = DEFAULT_TILE_POINTS,
    history: str | None = None,
) -> Schema:
    """Coordinates, variables (dims, dtype, attributes, chunks) and global attributes of an atlas."""
    coords = {}
    for key, ax in scene.axes.items():
        dims = (key,) if ax.is_dim else ()
        coords[key] = (dims, ax.values, dict(_COORD_ATTRS[key]))
    variables = {}
    for name in scene.output_names:
        dims = scene.output_dims(name)
        shape = tuple(scene.axes[d].size for d in dims)
        chunks = block_shape(shape, tile_points) if dims else None
        variables[name] = (dims, _storage_dtype(name, dtype), _variable_attrs(name), chunks)
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
        "exact_resolution": int(bool(resolve)),
        "model_parameters": " ".join(scene.model_names),
    }
    for key, val in scene.fixed().items():
        attrs[key] = val
    if any(n in variables for n in _MODEL_DEP):
        attrs["model_dependent_definition"] = (
            "True iff the set of decided verdicts over the model samples has more than one "
            "element; SS: neutral counted as stable"
        )
    shape = {d: scene.axes[d].size for d in scene.dims}
    return Schema(coords, variables, attrs, shape)


# --- sinks --------------------------------------------------------------------------------------


class MemorySink:
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
            tag = {"beta1": ("c1", "s1"), "beta2": ("c2", "s2"), "alpha": ("ca", "sa")}[key]
            src[tag[0]] = (key, np.asarray(c, dt))
            src[tag[1]] = (key, np.asarray(s, dt))
        else:
            src[key] = (key, np.asarray(ax.values, dt))
    if "q" in src:
        src["q1"] = src["q2"] = src.pop("q")
    return src


_GROUP_INPUTS = {
    "b1": ("c1", "s1"),
    "b2": ("c2", "s2"),
    "b1b2": ("c1", "s1", "c2", "s2"),
    "b1b2a": ("c1", "s1", "c2", "s2", "ca", "sa"),
    "spectral": ("c1", "s1", "c2", "s2", "kappa", "q1", "q2"),
}


def _gather(src, inputs, dims, index, block, T):
    """Flat, padded (length T) kernel inputs for one hyperslab ``index`` of the group ``dims``.

    Fixed (scalar) parameters stay 0-d: the kernel broadcasts them (2-3x faster than full arrays).
    """
    n = math.prod(block)
    out = []
    for key in inputs:
        param, vals = src[key]
        if vals.ndim == 0:
            out.append(vals)
            continue
        ax = dims.index(param)
        shp = [1] * len(dims)
        shp[ax] = block[ax]
        arr = np.broadcast_to(vals[index[ax]].reshape(shp), block)
        buf = np.empty(T, vals.dtype)
        buf[:n] = arr.reshape(-1)
        buf[n:] = buf[0]
        out.append(buf)
    return out


def _to_storage(name: str, codes: np.ndarray, dtype: str) -> np.ndarray:
    if name in ("stable_SF", "stable_FS"):
        return codes == int(Verdict.STABLE)
    if name in _CONSISTENCY or name in ("consistent_IF", "consistent_FI"):
        return codes == 1
    if name == "cc_possible":
        return codes.astype(bool)
    return codes.astype(_storage_dtype(name, dtype))


def _undecided(name: str, codes: np.ndarray) -> np.ndarray:
    if name in ("class_code", "subclass_code"):
        return codes == UNDECIDED_CODE
    if name in _CONSISTENCY or name in ("stable_SS", "consistent_II", "stable_II"):
        return codes == U3
    return np.zeros(codes.shape, bool)


def _exact():
    try:
        from atlas.core import exact
    except ImportError:  # pragma: no cover - exact.py not available
        return None
    return exact


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


def _spectral_tile(src, dims, index, block, need, dtype, resolve, stats):
    """Certified spectral verdicts of one tile (all tiers and the exact settlement)."""
    args = _block_inputs(src, _GROUP_INPUTS["spectral"], dims, index, block)
    st = {}
    res = evaluate.spectral_points(*args, names=need, dtype=dtype, resolve=resolve, stats=st)
    settled = st["undecided_before"] - st["undecided_after"] if resolve else 0
    stats["resolved_points"] = stats.get("resolved_points", 0) + settled
    stats.setdefault("exact_failures", []).extend(st.get("exact_failures", []))
    res = {k: np.broadcast_to(v, block).reshape(-1) for k, v in res.items()}
    return res, st["undecided_by_name"]


def _resolve(group: str, res: dict, flat_inputs: list, n: int, stats: dict):
    """Replace undecided class/subclass codes of one tile by the exact reference, in place."""
    exact = _exact()
    names = [k for k in res if k != "spectral_abscissa"]
    und = {k: _undecided(k, res[k]) for k in names}
    anyu = np.zeros(n, bool)
    for k in names:
        anyu |= und[k]
    idx = np.flatnonzero(anyu)
    if idx.size == 0 or exact is None:
        return
    pts = [np.broadcast_to(a, (n,))[idx] if a.ndim == 0 else a[:n][idx] for a in flat_inputs]

    def solve(p, i):
        return exact.resolve_codes(*p)

    # one point at a time (the reference loops over points anyway): a point on which the reference
    # itself fails stays undecided and is recorded instead of aborting the whole atlas
    ok = []
    for i in range(idx.size):
        try:
            one = solve([p[i : i + 1] for p in pts], i)
        except Exception:
            fail = stats.setdefault("exact_failures", [])
            fail.append(tuple(float(p[i]) for p in pts))
            continue
        ok.append(idx[i])
        for k, v in one.items():
            if k in und and und[k][idx[i]]:
                res[k][idx[i]] = np.asarray(v)[0]
    stats["resolved_points"] = stats.get("resolved_points", 0) + int(len(ok))


def run(
    scene: Scene,
    sink,
    *,
    method: str = "certified",
    dtype: str = "float64",
    resolve: bool = True,
    tile_points: int = DEFAULT_TILE_POINTS,
    progress=False,
    history: str | None = None,
):
    """Compute every output of ``scene`` tile by tile into ``sink``; returns ``sink.finish(...)``.

    ``sink`` has ``begin(schema)``, ``write(name, index, block)``, ``finish(attrs, var_attrs)`` and
    ``abort()``; see :class:`MemorySink` and :class:`atlas.data.io.NetCDFSink`.  After the run,
    ``run.last_stats`` holds the summary (points, seconds, points per second, undecided counts).
    """
    method, dtype, tile_points = _check_options(method, dtype, tile_points)
    if not isinstance(scene, Scene):
        raise ValueError("scene: expected an atlas.Scene")
    sch = schema(
        scene, method=method, dtype=dtype, resolve=resolve, tile_points=tile_points, history=history
    )
    outputs = scene.output_names
    src = _axis_inputs(scene, dtype)
    plan = []
    for g in _groups(scene):
        need = _needed(g, outputs)
        if not need:
            continue
        dims = tuple(p for p in g.params if scene.axes[p].is_dim)
        shape = tuple(scene.axes[d].size for d in dims)
        plan.append((g, need, dims, shape))
    total = sum(math.prod(shape) for _, _, _, shape in plan)
    t0 = time.perf_counter()
    stats = {"undecided_fast": {}, "undecided": {}}
    md = _ModelDependence(scene, outputs)
    bar = progress_bar(progress, total, f"atlas {scene.name}")
    pending = None
    sink.begin(sch)
    try:
        for g, need, dims, shape in plan:
            kern = _jitted(g.name)
            inputs = _GROUP_INPUTS[g.name]
            # small groups: pad to the next power of two only (same blocks, few distinct shapes)
            T = min(tile_points, 1 << max(0, math.prod(shape) - 1).bit_length())
            pending = None
            for index in tile_blocks(shape, T):
                block = tuple(s.stop - s.start for s in index)
                if g.name == "spectral" and method == "certified":
                    res, fast = _spectral_tile(src, dims, index, block, need, dtype, resolve, stats)
                    _store_tile(g, dims, index, block, res, fast, sink, outputs, dtype, stats, md)
                    if bar is not None:
                        bar.update(math.prod(block))
                    continue
                flat = _gather(src, inputs, dims, index, block, T)
                out = kern(*flat)  # asynchronous dispatch: overlaps with finishing the last tile
                if pending is not None:
                    _finish_tile(g, dims, *pending, sink, outputs, dtype, resolve, stats, md, bar)
                pending = (index, block, flat, {k: out[k] for k in need})
            if pending is not None:
                _finish_tile(g, dims, *pending, sink, outputs, dtype, resolve, stats, md, bar)
        for name, block in md.results().items():
            sink.write(name, tuple(slice(None) for _ in block.shape), block)
        fast = sum(stats["undecided_fast"].values())
        final = sum(stats["undecided"].values())
        attrs = {"undecided_fast": fast, "undecided_after_resolve": final}
        failures = stats.get("exact_failures", [])
        if failures:
            attrs["exact_failures"] = len(failures)
            attrs["exact_failure_example"] = repr(failures[0])
        var_attrs = {
            k: {"undecided_fast": stats["undecided_fast"].get(k, 0), "undecided": v}
            for k, v in stats["undecided"].items()
            if k in sch.variables
        }
        result = sink.finish(attrs, var_attrs)
        seconds = time.perf_counter() - t0
    except BaseException:
        try:  # let in-flight kernels finish before unwinding (exiting under them can crash XLA)
            if pending is not None:
                jax.block_until_ready(pending[3])
        except BaseException:  # pragma: no cover - best effort
            pass
        sink.abort()
        raise
    finally:
        if bar is not None:
            bar.close()
    points = scene.points()
    run.last_stats = {
        "scene": scene.name,
        "points": points,
        "values": total,
        "seconds": seconds,
        "points_per_second": points / seconds if seconds > 0 else float("inf"),
        "undecided_fast": fast,
        "undecided": final,
        "resolved_points": stats.get("resolved_points", 0),
        "exact_failures": stats.get("exact_failures", []),
    }
    return result


run.last_stats = {}


def _finish_tile(g, dims, index, block, flat, out, sink, outputs, dtype, resolve, stats, md, bar):
    n = math.prod(block)
    size = max(a.size for a in flat)  # outputs may not depend on every input (FF: alpha only)
    res = {
        k: np.array(np.broadcast_to(np.asarray(v).reshape(-1), (size,))[:n]) for k, v in out.items()
    }
    fast = {k: int(_undecided(k, v).sum()) for k, v in res.items()}
    if resolve:
        _resolve(g.name, res, flat, n, stats)
    _store_tile(g, dims, index, block, res, fast, sink, outputs, dtype, stats, md)
    if bar is not None:
        bar.update(n)


def _store_tile(g, dims, index, block, res, fast, sink, outputs, dtype, stats, md):
    """Count, record model dependence and write the finished (flat) results of one tile."""
    for k, v in res.items():
        stats["undecided_fast"][k] = stats["undecided_fast"].get(k, 0) + fast.get(k, 0)
        stats["undecided"][k] = stats["undecided"].get(k, 0) + int(_undecided(k, v).sum())
    if g.name == "spectral":
        md.update(dims, index, block, res)
    for k, v in res.items():
        if k in outputs:
            sink.write(k, index, _to_storage(k, v.reshape(block), dtype))


class _ModelDependence:
    """Accumulates, per (beta1, beta2), the set of decided verdicts seen over the model samples."""

    def __init__(self, scene: Scene, outputs):
        self.want = [o for o in _MODEL_DEP if o in outputs]
        self.dims = scene.output_dims("model_dependent_SS")
        shape = tuple(scene.axes[d].size for d in self.dims)
        self.bits = {o: np.zeros(shape, np.uint8) for o in self.want}

    def update(self, dims, index, block, res):
        if not self.want:
            return
        red = tuple(i for i, d in enumerate(dims) if d not in self.dims)
        keep = tuple(index[i] for i, d in enumerate(dims) if d in self.dims)
        for o in self.want:
            if o == "model_dependent_SS":
                v = res["stable_SS"].reshape(block)
                bits = np.where(
                    (v == int(Verdict.STABLE)) | (v == int(Verdict.NEUTRAL)),
                    1,
                    np.where(v == int(Verdict.UNSTABLE), 2, 0),
                )
            else:
                c = res["consistent_II"].reshape(block)
                s = res["stable_II"].reshape(block)
                bits = np.where(
                    (c == U3) | (s == U3),
                    0,
                    np.where(c == 0, 1, np.where(s == int(Verdict.STABLE), 4, 2)),
                )
            bits = np.bitwise_or.reduce(bits.astype(np.uint8), axis=red) if red else bits
            self.bits[o][keep] |= bits.astype(np.uint8)

    def results(self) -> dict:
        out = {}
        for o, b in self.bits.items():
            count = (b & 1) + ((b >> 1) & 1) + ((b >> 2) & 1)
            out[o] = count > 1
        return out


def progress_bar(progress, total, desc, unit="pt"):
    """A tqdm bar on stderr, or ``None`` when ``progress`` is false."""
    if not progress:
        return None
    from tqdm import tqdm

    return tqdm(total=total, unit=unit, unit_scale=True, desc=desc, file=sys.stderr, leave=False)


def _check_options(method, dtype, tile_points):
    if method not in METHODS:
        raise ValueError(f"method: must be one of {', '.join(METHODS)}, got {method!r}")
    dtype = str(np.dtype(dtype)) if dtype in DTYPES or dtype in (np.float32, np.float64) else dtype
    if dtype not in DTYPES:
        raise ValueError(f"dtype: must be one of {', '.join(DTYPES)}, got {dtype!r}")
    try:
        tp = int(tile_points)
    except (TypeError, ValueError):
        raise ValueError(f"tile_points: must be a positive integer, got {tile_points!r}") from None
    if tp < 1 or tp != tile_points:
        raise ValueError(f"tile_points: must be a positive integer, got {tile_points!r}")
    return method, dtype, tp


def generate(
    scene: Scene,
    *,
    method: str = "certified",
    dtype: str = "float64",
    resolve: bool = True,
    tile_points: int = DEFAULT_TILE_POINTS,
    progress=False,
    history: str | None = None,
) -> xr.Dataset:
    """Compute an atlas in memory (SPEC §2).

    Parameters
    ----------
    scene : atlas.Scene
        Parameters, ranges and wanted outputs.
    method : {"certified", "eig"}
        ``certified``: proven signs, undecided where floating point cannot certify (then exact
        resolution); ``eig``: the uncertified batched-``eig`` baseline (never undecided).
    dtype : {"float64", "float32"}
        Working precision of the kernels (direction vectors are rounded to it).
    resolve : bool
        Recompute undecided values exactly with :mod:`atlas.core.exact` (slow per point, few points).
    tile_points : int
        Points per tile: bounds the kernel's memory; one compilation per value.
    progress : bool
        tqdm progress bar on stderr.
    history : str, optional
        Command recorded in the ``history`` attribute (default: the Python call).

    Returns
    -------
    xarray.Dataset
        Each variable spans only the varied parameters it depends on; see :mod:`atlas.data.engine`.
        For atlases larger than memory use :func:`atlas.data.io.generate_to_file`.
    """
    return run(
        scene,
        MemorySink(),
        method=method,
        dtype=dtype,
        resolve=resolve,
        tile_points=tile_points,
        progress=progress,
        history=history,
    )


def last_stats() -> dict:
    """Summary of the last :func:`run` in this process (points, seconds, points/s, undecided)."""
    return dict(run.last_stats)
