"""Outcome atlases: what the compliant dynamics do over the parameters of an atlas, beside what the
theory says there (paper Sec. 4.1, 6.4-6.5).

The parameters are those of an :class:`atlas.data.scene.Scene` (``beta1, beta2, alpha, kappa``
and ``q`` or ``q1, q2``, each a scalar or a range, the syntax of ``atlas generate``); ``alpha`` is
required (default ``0.35 pi``, the Fig. 2 a-c value).  Every cell runs ``n_perturb`` perturbed SS
equilibria (:func:`atlas.dynamics.outcome.initial_states`; the standard normals depend on the
``(beta1, beta2)`` cell and the run only, so cells that differ only in the model see the same
perturbations) through one engine and classifies each run (:func:`atlas.dynamics.classify`).

Stored per cell: ``outcome_count`` (runs per outcome class along the ``outcome_class``
dimension), ``outcome`` (the most frequent class; ties: the smallest code), ``agreement`` (its
fraction of the runs) and ``no_stable_subclass``; beside them, the certified theory verdicts of the
same cells (every output :func:`atlas.generate` computes for the scene, from the output registry
:mod:`atlas.data.outputs`), so the two compare cell by cell.

The outcomes are computed in ``beta1`` slabs (:func:`outcome_slab`); each cell's runs depend on
the cell alone, so any split into slabs gives the same arrays (:mod:`atlas.dynamics.outcome_tiles`
writes them tile by tile, resumably).
"""

from __future__ import annotations

import dataclasses
import functools
import math
import time

import numpy as np
import xarray as xr

from atlas.core import checks, config
from atlas.data.engine import REFERENCES, generate
from atlas.data.outputs import coord_attrs
from atlas.data.scene import Scene
from atlas.dynamics import fast_engine, jax_engine, stop_rule
from atlas.dynamics.lane_pool import LanePool
from atlas.dynamics.outcome import (
    initial_states,
    no_stable_subclass,
    simulate_outcome,
    standard_normals,
)
from atlas.dynamics.system import Outcome

__all__ = [
    "ENGINES",
    "DEFAULT_ALPHA",
    "Dynamics",
    "outcome_scene",
    "outcome_slab",
    "outcome_dataset",
    "outcome_atlas",
    "outcome_map",
]

#: engines of the outcome atlases
ENGINES = ("fast", "numpy", "jax")
#: direction of ``a`` when the scene gives none: the paper's Fig. 2 a-c [rad]
DEFAULT_ALPHA = 0.35 * math.pi
#: the outcome classes, in code order (the ``outcome_class`` coordinate)
CLASSES = np.array([int(o) for o in Outcome], dtype=np.int8)
#: largest ``n_perturb`` (the counts are stored as int16)
MAX_PERTURB = np.iinfo(np.int16).max
#: largest ``seed``: numpy's seed range (``numpy.random.seed``, 32-bit), kept as an integer
#: attribute of the netCDF file
MAX_SEED = 2**32 - 1
#: largest ``t_end`` [scaled time]: the exact simulator (the reference, and the fast engine's
#: fallback) advances in sub-steps of about 1/12 of the fastest period, about 2 per unit of scaled
#: time at kappa = 1 and more for stiffer contacts, so a run to ``horizon_cap * t_end`` = 8e4
#: already takes ~1e5-1e6 sub-steps (seconds per run); far beyond it a run ends at the
#: simulator's 1e7 sub-step cap, undetermined, after minutes
MAX_T_END = 1e4


@dataclasses.dataclass(frozen=True)
class Dynamics:
    """How each cell is simulated: ``n_perturb`` initial conditions (seeded, relative size
    ``perturbation`` [1]), horizon ``t_end`` [scaled time] extended up to ``horizon_cap`` times
    while undetermined, ``max_events`` per run, and the ``engine`` (``"fast"``: the batched
    event-to-event engine :mod:`atlas.dynamics.fast_engine`; ``"numpy"``: the exact simulator run
    by run, the reference; ``"jax"``: the fast engine's algorithm as a JAX kernel,
    :mod:`atlas.dynamics.jax_engine`).  Checked on creation
    (one-line ``ValueError`` naming the parameter)."""

    n_perturb: int = 1
    seed: int = 0
    perturbation: float = 1e-2
    t_end: float = 150.0
    horizon_cap: float = 8.0
    max_events: int = 2000
    engine: str = "fast"

    def __post_init__(self):
        for name, lo, hi in (("n_perturb", 1, MAX_PERTURB), ("seed", 0, MAX_SEED),
                             ("max_events", 1, None)):  # fmt: skip
            object.__setattr__(self, name, integer(name, getattr(self, name), lo, hi))
        for name in ("perturbation", "t_end", "horizon_cap"):
            v = float(checks.real(name, getattr(self, name)))
            if not v > 0:
                raise ValueError(f"{name}: must be > 0, got {v!r}")
            object.__setattr__(self, name, v)
        if self.t_end > MAX_T_END:
            raise ValueError(
                f"t_end: must be <= {MAX_T_END:g} (scaled time; the default is 150), "
                f"got {self.t_end!r}"
            )
        if self.horizon_cap < 1:
            raise ValueError(f"horizon_cap: must be >= 1, got {self.horizon_cap!r}")
        if self.engine not in ENGINES:
            raise ValueError(f"engine: must be one of {', '.join(ENGINES)}, got {self.engine!r}")

    def attrs(self) -> dict:
        """The options as global attributes."""
        return dataclasses.asdict(self)

    def reference(self):
        """The exact simulator with these options: ``(Outcome, result)`` of one run."""
        return functools.partial(
            simulate_outcome, t_end=self.t_end, horizon_cap=self.horizon_cap,
            max_events=self.max_events,
        )  # fmt: skip


def integer(name: str, value, lo: int = 1, hi: int | None = None) -> int:
    """``value`` as an ``int`` in ``[lo, hi]``, or a one-line ``ValueError`` naming ``name``
    (:func:`atlas.core.checks.integer`)."""
    return checks.integer(name, value, lo, hi)


def outcome_scene(
    beta1, beta2, alpha=None, kappa=0.5, q=None, q1=None, q2=None, name="outcome"
) -> Scene:
    """The :class:`~atlas.data.scene.Scene` of an outcome atlas (``alpha`` default
    :data:`DEFAULT_ALPHA`; ``q`` default 0 unless ``q1, q2`` are given)."""
    alpha = DEFAULT_ALPHA if alpha is None else alpha
    return Scene(beta1=beta1, beta2=beta2, alpha=alpha, kappa=kappa, q=q, q1=q1, q2=q2, name=name)


def check_scene(scene) -> Scene:
    if not isinstance(scene, Scene):
        raise ValueError("scene: expected an atlas.Scene")
    if "alpha" not in scene.axes:
        raise ValueError("alpha: an outcome atlas needs alpha (a value or a range)")
    return scene


def _grid(scene: Scene, rows: range) -> dict:
    """Every parameter over the cells of the ``beta1`` rows ``rows``: arrays of the full grid
    shape (scalars as axes of length 1), ``q1``/``q2`` both present."""
    vals = {k: np.atleast_1d(ax.values) for k, ax in scene.axes.items()}
    vals["beta1"] = vals["beta1"][rows.start : rows.stop]
    grids = dict(zip(vals, np.meshgrid(*vals.values(), indexing="ij"), strict=True))
    if "q" in grids:
        grids["q1"] = grids["q2"] = grids.pop("q")
    return grids


def outcome_slab(
    scene: Scene, rows: range, dyn: Dynamics, pool: LanePool | None = None
) -> tuple[np.ndarray, dict]:
    """Outcome counts of the ``beta1`` rows ``rows`` of an outcome atlas (fast engine: on the
    processes of ``pool``, :class:`atlas.dynamics.lane_pool.LanePool`, if given).

    Returns
    -------
    counts : numpy.ndarray
        int16, shape ``(len(rows), n_beta2, ...model sizes..., len(Outcome))``: the full grid of
        the scene's parameters in canonical order (scalars as axes of length 1), runs per class.
    info : dict
        ``trajectories``, ``seconds`` (wall time, a pool's start included) and, with the fast engine, ``runs_stepped``,
        ``runs_early_settle``, ``runs_early_iwc``, ``runs_fallback`` (how each run was decided).
    """
    scene = check_scene(scene)
    g = _grid(scene, rows)
    shape = g["beta1"].shape
    xi = standard_normals(dyn.seed, rows, shape[1], dyn.n_perturb)
    xi = xi.reshape(shape[:2] + (1,) * (len(shape) - 2) + xi.shape[2:])
    g0 = initial_states(g["beta1"], g["beta2"], g["alpha"], g["kappa"], xi, dyn.perturbation)
    t0 = time.perf_counter()
    codes, how = _codes(g, g0, dyn, pool)
    seconds = time.perf_counter() - t0
    counts = np.stack([(codes == c).sum(axis=-1) for c in CLASSES], axis=-1).astype(np.int16)
    return counts, {"trajectories": int(codes.size), "seconds": seconds, **how}


def _codes(g: dict, g0: np.ndarray, dyn: Dynamics, pool=None) -> tuple[np.ndarray, dict]:
    """Outcome codes, shape ``grid + (n_perturb,)``, from the chosen engine."""
    shape = g0.shape[:-1]
    lane = {k: np.broadcast_to(v[..., None], shape).ravel() for k, v in g.items()}
    k = np.stack([lane["kappa"], np.ones_like(lane["kappa"])], axis=1)
    q = np.stack([lane["q1"], lane["q2"]], axis=1)
    flat = g0.reshape(-1, 4)
    opts = dict(t_end=dyn.t_end, horizon_cap=dyn.horizon_cap, max_events=dyn.max_events)
    if dyn.engine in ("fast", "jax"):
        if dyn.engine == "fast":
            run = functools.partial(fast_engine.run_batch, pool=pool)
        else:
            run = jax_engine.run_batch
        res = run(lane["beta1"], lane["beta2"], lane["alpha"], k, q, flat,
                  reference=dyn.reference(), **opts)  # fmt: skip
        how = np.bincount(res.decided_by, minlength=len(fast_engine.DECIDED_BY))
        info = {f"runs_{n}": int(c) for n, c in zip(fast_engine.DECIDED_BY, how, strict=True)}
        info["runs_within_rounding"] = int(res.within_rounding.sum())
        return np.asarray(res.code, dtype=np.int8).reshape(shape), info
    ref = dyn.reference()
    codes = np.empty(flat.shape[0], dtype=np.int8)
    near = 0
    for n in range(flat.shape[0]):
        out, run = ref(lane["beta1"][n], lane["beta2"][n], lane["alpha"][n], k=tuple(k[n]),
                       q=tuple(q[n]), g0=flat[n])  # fmt: skip
        codes[n] = int(out)
        near += stop_rule.run_within_rounding(run)
    return codes.reshape(shape), {"runs_within_rounding": int(near)}


def sum_info(infos) -> dict:
    """The ``info`` of several slabs, summed (``seconds`` too)."""
    out: dict = {}
    for info in infos:
        for key, v in info.items():
            out[key] = out.get(key, 0) + v
    return out


def outcome_dataset(
    scene: Scene, counts: np.ndarray, dyn: Dynamics, info: dict, *, theory=True, history=None
) -> xr.Dataset:
    """The CF-1.10 outcome atlas of the counts of every ``beta1`` row (:func:`outcome_slab`,
    concatenated along ``beta1``) and, with ``theory``, the certified theory verdicts of the same
    cells (:func:`atlas.generate` of ``scene``)."""
    shape = tuple(scene.axes[d].size for d in scene.dims)
    counts = counts.reshape(shape + (CLASSES.size,))
    coords = {
        k: ((k,) if ax.is_dim else (), ax.values, coord_attrs(k)) for k, ax in scene.axes.items()
    }
    coords["outcome_class"] = (
        ("outcome_class",),
        CLASSES.copy(),
        {"long_name": "outcome class of a simulated run", **_flags()},
    )
    attrs = _attrs(scene, dyn, info, math.prod(shape), history)
    ds = xr.Dataset(_data_vars(scene, counts, dyn.n_perturb), coords=coords, attrs=attrs)
    if theory:
        th = generate(scene)
        for name in th.data_vars:
            ds[name] = th[name]
        ds.attrs["theory"] = "certified verdicts of atlas.generate over the same cells"
        ds.attrs["theory_undecided_fast"] = int(th.attrs["undecided_fast"])
        ds.attrs["theory_undecided"] = int(th.attrs["undecided_after_resolve"])
    return ds


def _flags() -> dict:
    """The CF flags of the outcome classes (a fresh copy)."""
    return {"flag_values": CLASSES.copy(), "flag_meanings": " ".join(o.label for o in Outcome)}


def _data_vars(scene: Scene, counts: np.ndarray, n: int) -> dict:
    """``outcome``, ``outcome_count``, ``agreement`` and ``no_stable_subclass`` of the counts
    (grid shape + classes) of ``n`` runs per cell."""
    dims = scene.dims
    g = _grid(scene, range(scene.axes["beta1"].size))
    region = no_stable_subclass(g["beta1"], g["beta2"], g["alpha"])
    region = region.reshape(g["beta1"].shape)[(...,) + (0,) * (region.ndim - 3)]
    region_dims = tuple(d for d in ("beta1", "beta2", "alpha") if d in dims)
    region = region.reshape(tuple(scene.axes[d].size for d in region_dims))
    return {
        "outcome": (
            dims,
            CLASSES[counts.argmax(axis=-1)],
            {
                "long_name": "most frequent simulated outcome of the perturbed SS equilibria",
                **_flags(),
            },
        ),
        "outcome_count": (
            dims + ("outcome_class",),
            counts,
            {"long_name": "number of perturbed runs per outcome class", "units": "1"},
        ),
        "agreement": (
            dims,
            (counts.max(axis=-1) / n).astype(np.float32),
            {"units": "1", "long_name": "fraction of perturbed runs giving outcome"},
        ),
        "no_stable_subclass": (
            region_dims,
            region,
            {"long_name": "subclass 132, 133, 142, 143 or dual (paper Sec. 6.4-6.5)"},
        ),
    }


def _attrs(scene: Scene, dyn: Dynamics, info: dict, cells: int, history) -> dict:
    """The global attributes of an outcome atlas of ``cells`` cells (``info``: trajectories,
    seconds, how the runs were decided)."""
    seconds = float(info.get("seconds", 0.0))
    trajectories = int(info.get("trajectories", cells * dyn.n_perturb))
    attrs = {
        "Conventions": "CF-1.10",
        "title": "Outcome atlas of the compliant two-contact dynamics",
        "source": config.source(),
        "history": config.history(history or _default_history(scene, dyn)),
        "references": REFERENCES + " Sec. 4.1, 6.4-6.5, Fig. 2",
        "method": f"event-driven simulation ({dyn.engine} engine), atlas.dynamics.classify",
        "scene_description": scene.describe(),
        "model_parameters": " ".join(scene.model_names),
        **scene.fixed(),
        **dyn.attrs(),
        "alpha_units": "rad",
        "trajectories": trajectories,
        "seconds": seconds,
        "trajectories_per_second": trajectories / seconds if seconds > 0 else float("nan"),
        **{k: v for k, v in info.items() if k.startswith("runs_") or k == "workers"},
    }
    if "q" in scene.axes and not scene.axes["q"].is_dim:
        attrs["q1"] = attrs["q2"] = float(scene.axes["q"].values)
    return attrs


def _default_history(scene: Scene, dyn: Dynamics) -> str:
    opts = ", ".join(f"{k}={v!r}" for k, v in dyn.attrs().items())
    return f"atlas.dynamics.outcome_atlas(scene={scene.describe()!r}, {opts})"


def outcome_atlas(
    scene: Scene,
    *,
    n_perturb: int = 1,
    seed: int = 0,
    perturbation: float = 1e-2,
    t_end: float = 150.0,
    horizon_cap: float = 8.0,
    max_events: int = 2000,
    engine: str = "fast",
    theory: bool = True,
    slab: int | None = None,
    workers: int | None = 1,
    progress=None,
    history: str | None = None,
) -> xr.Dataset:
    """Simulated outcomes over a scene, in memory (see the module docstring).

    Parameters
    ----------
    scene : atlas.Scene
        The parameters (:func:`outcome_scene`); ``alpha`` required.
    n_perturb, seed, perturbation, t_end, horizon_cap, max_events, engine
        See :class:`Dynamics`.
    theory : bool
        Add the certified theory verdicts of the same cells.
    slab : int, optional
        ``beta1`` values per batch (default: all at once).
    workers : int or None
        Processes of the fast engine (:class:`atlas.dynamics.lane_pool.LanePool`; ``None``: the
        usable cores); 1 runs in this process.  The result does not depend on it.  More than 1
        spawns processes: a script calling this needs ``if __name__ == "__main__":``.
    progress : callable, optional
        Called with ``(done, total)`` trajectories after each slab.
    history : str, optional
        Command recorded in ``history`` (default: the Python call).

    Returns
    -------
    xarray.Dataset
        ``outcome`` (int8 flags), ``outcome_count`` (int16, ``... x outcome_class``),
        ``agreement`` (float32), ``no_stable_subclass`` (bool) and the theory verdicts.
    """
    scene = check_scene(scene)
    theory = checks.boolean("theory", theory)
    dyn = Dynamics(n_perturb, seed, perturbation, t_end, horizon_cap, max_events, engine)
    n1 = scene.axes["beta1"].size
    step = n1 if slab is None else integer("slab", slab)
    parts, infos = [], []
    total = math.prod(a.size for a in scene.axes.values()) * dyn.n_perturb
    with LanePool(workers) as pool:
        for a in range(0, n1, step):
            counts, info = outcome_slab(scene, range(a, min(a + step, n1)), dyn, pool)
            parts.append(counts)
            infos.append(info)
            if progress is not None:
                progress(sum(i["trajectories"] for i in infos), total)
    info = sum_info(infos)
    if dyn.engine == "fast":
        info["workers"] = pool.workers
    return outcome_dataset(scene, np.concatenate(parts), dyn, info, theory=theory, history=history)


def outcome_map(
    beta1_values,
    beta2_values,
    kappa: float = 0.5,
    q=0.0,
    alpha: float = DEFAULT_ALPHA,
    *,
    theory: bool = False,
    **kwargs,
) -> xr.Dataset:
    """The outcome atlas of one ``(kappa, q, alpha)`` over the grid ``beta1_values x
    beta2_values`` [rad] (e.g. :func:`atlas.dynamics.outcome_grid`); ``q`` a number (``q1 = q2``)
    or a pair ``(q1, q2)`` [1].  ``kwargs``: the options of :func:`outcome_atlas`."""
    b1 = np.atleast_1d(checks.real("beta1_values", beta1_values))
    b2 = np.atleast_1d(checks.real("beta2_values", beta2_values))
    qq = checks.pair("q", q)
    model = {"q": float(qq[0])} if qq[0] == qq[1] else {"q1": float(qq[0]), "q2": float(qq[1])}
    for name, v in (("kappa", kappa), ("alpha", alpha), *model.items()):
        checks.real(name, v)
    scene = outcome_scene(b1, b2, alpha=float(alpha), kappa=float(kappa), **model, name="map")
    return outcome_atlas(scene, theory=theory, **kwargs)
