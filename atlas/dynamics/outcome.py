"""Outcomes of the simulated dynamics: the paper's Fig. 2 cases, the subclasses where the paper
predicts no stable mode (Sec. 6.4-6.5), and outcome maps over ``(beta1, beta2)`` from either
engine (:mod:`atlas.dynamics.simulator` run by run, or the batched :mod:`atlas.dynamics.jax_engine`).
"""

from __future__ import annotations

import dataclasses
import functools
import math
import time as _time

import jax.numpy as jnp
import numpy as np
import xarray as xr

from atlas.core import mechanics
from atlas.dynamics import fast_engine, jax_engine
from atlas.dynamics.classification import classify, needs_longer_run
from atlas.dynamics.simulator import simulate
from atlas.dynamics.system import Outcome, check_finite

__all__ = [
    "fig2_cases",
    "NO_STABLE_SUBCLASSES",
    "subclass_codes",
    "no_stable_subclass",
    "outcome_grid",
    "perturbed_initial_states",
    "simulate_outcome",
    "outcome_map",
]


def fig2_cases() -> dict:
    """Parameters of the paper's Fig. 2 panels a-e (caption), as keyword arguments of simulate.

    ``|b_1| = |b_2| = 1``, ``|a| = 1``, ``k = (100, 200)``.  ``t_end`` is chosen here (the paper
    does not state its time axis).
    """
    pi = math.pi
    base = {"k": (100.0, 200.0), "b_norm": (1.0, 1.0), "a_norm": 1.0}
    a = dict(
        base,
        beta1=0.2 * pi,
        beta2=0.65 * pi,
        alpha=0.35 * pi,
        q=(0.0, 0.0),
        g0=(-0.008, -0.004, 0.0, 0.0),
        t_end=10.0,
    )
    b = dict(a, beta1=0.05 * pi)
    c = dict(b, g0=(-0.05, -0.05, 0.0, 0.0))
    d = dict(
        base,
        beta1=0.15 * pi,
        beta2=1.07 * pi,
        alpha=0.2 * pi,
        q=(20.0, 20.0),
        g0=(0.0, 0.0, 0.0, 0.0),
        t_end=10.0,
    )
    e = dict(d, beta2=1.1 * pi)
    return {"a": a, "b": b, "c": c, "d": d, "e": e}


# ----------------------------------------------------------------------------- outcome map

#: engines of :func:`outcome_map`
ENGINES = ("fast", "numpy", "jax")

#: subclasses (and their duals) where the paper predicts no stable mode or impact (Sec. 6.4-6.5)
NO_STABLE_SUBCLASSES = (132, 133, 142, 143)


def _code_args(beta1, beta2, alpha):
    vec = [mechanics.direction(np.asarray(x, dtype=float)) for x in (beta1, beta2, alpha)]
    return [jnp.asarray(v) for cs in vec for v in cs]


def subclass_codes(beta1, beta2, alpha) -> np.ndarray:
    """Subclass codes ``ijk`` (SPEC §1) of angles [rad] via :func:`atlas.core.mechanics.subclass_code`
    (the reference implementation; 0 degenerate, -1 undecided); arrays broadcast."""
    return np.asarray(mechanics.subclass_code(*_code_args(beta1, beta2, alpha))).astype(np.int16)


def no_stable_subclass(beta1, beta2, alpha) -> np.ndarray:
    """True in subclasses 132, 133, 142, 143 or their duals (paper Sec. 6.4-6.5); arrays broadcast.

    The dual (contacts swapped) is :func:`atlas.core.mechanics.dual_vectors` of the direction vectors.
    """
    args = _code_args(beta1, beta2, alpha)
    code = np.asarray(mechanics.subclass_code(*args))
    dual = np.asarray(mechanics.subclass_code(*mechanics.dual_vectors(*args)))
    return np.isin(code, NO_STABLE_SUBCLASSES) | np.isin(dual, NO_STABLE_SUBCLASSES)


def outcome_grid(n: int) -> tuple[np.ndarray, np.ndarray]:
    """``beta1 = (i + 1/3) 2 pi / n``, ``beta2 = (j + 2/3) 2 pi / n`` [rad], ``i, j < n``.

    One sample per cell of the uniform ``n x n`` grid of ``[0, 2 pi)^2`` (the Fig. 1 cells for the
    same ``n``), offset so that no sample is degenerate for any ``n``: no angle is a multiple of
    ``pi / 2`` and ``beta2 - beta1`` is never a multiple of ``pi``.
    """
    n = int(n)
    if n < 1:
        raise ValueError(f"n must be >= 1, got {n!r}")
    step = 2 * math.pi / n
    return (np.arange(n) + 1 / 3) * step, (np.arange(n) + 2 / 3) * step


def perturbed_initial_states(
    beta1_values, beta2_values, alpha, kappa, n_perturb=1, seed=0, perturbation=1e-2
) -> np.ndarray:
    """Initial states of :func:`outcome_map`, shape ``(n1, n2, n_perturb, 4)``.

    Seeded perturbations of the SS equilibrium ``d* = -K^{-1} B^{-1} a`` (paper eq. 8):
    ``d = d* + perturbation * |d*| * xi``, ``d' = perturbation * |d*| * xi'`` with standard normal
    ``xi``; where the SS mode is inconsistent, ``d = -perturbation * |xi| / min(kappa, 1)``
    (both gaps pushed into contact), ``d' = perturbation * xi' / min(kappa, 1)``.
    """
    rng = np.random.default_rng(seed)
    b1 = np.atleast_1d(np.asarray(beta1_values, dtype=float))
    b2 = np.atleast_1d(np.asarray(beta2_values, dtype=float))
    # one draw of 4 normals per run, in the order (beta1, beta2, run)
    xi = rng.standard_normal((b1.size, b2.size, int(n_perturb), 4))
    B = np.empty((b1.size, b2.size, 2, 2))
    B[..., 0, 0], B[..., 1, 0] = np.cos(b1)[:, None], np.sin(b1)[:, None]
    B[..., 0, 1], B[..., 1, 1] = np.cos(b2)[None, :], np.sin(b2)[None, :]
    a = np.array([math.cos(alpha), math.sin(alpha)])
    # f = B^-1 a (SS forces, LAPACK as in ss_equilibrium); the SS mode is consistent where f > 0
    det = B[..., 0, 0] * B[..., 1, 1] - B[..., 0, 1] * B[..., 1, 0]
    regular = det != 0
    Bs = np.where(regular[..., None, None], B, np.eye(2))
    f = np.linalg.solve(Bs, np.broadcast_to(a, Bs.shape[:-1])[..., None])[..., 0]
    consistent = regular & np.all(f > 0, axis=-1)
    d_eq = -f / np.array([kappa, 1.0])
    s_eq = np.abs(d_eq).max(axis=-1)[..., None, None]
    s_in = 1.0 / min(kappa, 1.0)
    inside = np.concatenate([d_eq[:, :, None, :] + perturbation * s_eq * xi[..., :2],
                             perturbation * s_eq * xi[..., 2:]], axis=-1)  # fmt: skip
    outside = np.concatenate([-perturbation * s_in * np.abs(xi[..., :2]),
                              perturbation * s_in * xi[..., 2:]], axis=-1)  # fmt: skip
    return np.where(consistent[:, :, None, None], inside, outside)


def simulate_outcome(*args, t_end: float = 150.0, horizon_cap: float = 8.0, **kwargs):
    """:func:`simulate` then :func:`classify`, doubling ``t_end`` (up to ``horizon_cap * t_end``)
    while the outcome is undetermined and the run simply ran out of time (status ``"t_end"``,
    at least one event: e.g. long flights between few impacts).

    Returns
    -------
    (Outcome, SimulationResult)
        The outcome and the last run.
    """
    t_max = horizon_cap * float(t_end)
    T = float(t_end)
    while True:
        res = simulate(*args, t_end=T, **kwargs)
        out = classify(res)
        if not needs_longer_run(out, res.status, res.n_events, T, t_max):
            return out, res
        T *= 2


def outcome_map(
    beta1_values,
    beta2_values,
    kappa: float = 0.5,
    q=0.0,
    alpha: float = 0.35 * math.pi,
    n_perturb: int = 1,
    seed: int = 0,
    perturbation: float = 1e-2,
    t_end: float = 150.0,
    horizon_cap: float = 8.0,
    max_events: int = 2000,
    engine: str = "fast",
    progress=None,
):
    """Simulated outcome over a ``(beta1, beta2)`` grid (what the dynamics actually do).

    Scaled parameters (SPEC §1): ``|b_1| = |b_2| = |a| = 1``, ``k = (kappa, 1)``,
    ``q = (q1_hat, q2_hat)``; time in units of ``1 / sqrt(k2 |b2|)``.  Initial conditions from
    :func:`perturbed_initial_states`.  Each run is classified by :func:`classify`; undetermined
    runs that ran out of time are extended (``t_end`` doubled, up to ``horizon_cap * t_end``, see
    :func:`simulate_outcome`).

    Parameters
    ----------
    beta1_values, beta2_values : array_like
        Grid of contact directions [rad] (e.g. :func:`outcome_grid`).
    kappa : float
        ``k1 |b1| / (k2 |b2|)`` [1].
    q : float or (float, float)
        Scaled damping ``q_j_hat`` [1].
    alpha : float
        Direction of ``a`` [rad].
    n_perturb : int
        Initial conditions per grid point; ``outcome`` is the most frequent class and
        ``agreement`` the fraction of runs that gave it.
    seed : int
        Seed of ``numpy.random.default_rng``.
    perturbation : float
        Relative size of the perturbation [1].
    t_end, horizon_cap, max_events
        Horizon [scaled time], its extension factor, and event cap per trajectory.
    engine : {"fast", "numpy", "jax"}
        ``"fast"``: the batched event-to-event engine :mod:`atlas.dynamics.fast_engine` (modal
        form per configuration, certified early decisions; the exact simulator for the runs it
        cannot serve); ``"numpy"``: :func:`simulate` run by run (the reference); ``"jax"``: the
        batched stepper of :mod:`atlas.dynamics.jax_engine`.
    progress : callable, optional
        Called with ``(done, total)`` after each grid point (numpy engine).

    Returns
    -------
    xarray.Dataset
        ``outcome`` (int8, CF flags from :class:`Outcome`) and ``agreement`` (float32) over
        ``(beta1, beta2)``; ``no_stable_subclass`` (bool): subclasses 132, 133, 142, 143 or duals.
        Attributes record the parameters, ``trajectories``, ``seconds`` and
        ``trajectories_per_second``; with the fast engine ``runs_stepped``, ``runs_early_settle``,
        ``runs_early_iwc``, ``runs_fallback`` (how each run was decided).
    """
    b1, b2, p = _map_args(
        beta1_values, beta2_values, kappa, q, alpha, n_perturb, seed, perturbation, t_end,
        horizon_cap, max_events, engine,
    )  # fmt: skip
    g0 = perturbed_initial_states(b1, b2, p.alpha, p.kappa, n_perturb, seed, p.perturbation)
    t0 = _time.perf_counter()
    codes, how = _outcome_codes(b1, b2, g0, p, progress)
    wall = _time.perf_counter() - t0
    ds = _map_dataset(b1, b2, codes, p, wall)
    ds.attrs.update(how)
    return ds


@dataclasses.dataclass(frozen=True)
class _MapParams:
    """The checked scalar parameters of :func:`outcome_map` (``n_perturb``, ``seed`` and
    ``max_events`` as given)."""

    kappa: float
    q: np.ndarray
    alpha: float
    n_perturb: int
    seed: int
    perturbation: float
    t_end: float
    horizon_cap: float
    max_events: int
    engine: str

    def attrs(self, trajectories: int, seconds: float) -> dict:
        """The map's attributes: the parameters, ``trajectories`` run and ``seconds`` taken."""
        return {
            "kappa": self.kappa,
            "q1": float(self.q[0]),
            "q2": float(self.q[1]),
            "alpha": self.alpha,
            "alpha_units": "rad",
            "n_perturb": int(self.n_perturb),
            "seed": int(self.seed),
            "perturbation": self.perturbation,
            "t_end": self.t_end,
            "horizon_cap": self.horizon_cap,
            "max_events": int(self.max_events),
            "engine": self.engine,
            "trajectories": int(trajectories),
            "seconds": seconds,
            "trajectories_per_second": trajectories / seconds if seconds > 0 else float("nan"),
        }


def _map_args(beta1_values, beta2_values, kappa, q, alpha, n_perturb, seed, perturbation, t_end,
              horizon_cap, max_events, engine):  # fmt: skip
    """Checked grid and :class:`_MapParams` of :func:`outcome_map` (one-line errors naming the
    parameter)."""
    b1 = np.atleast_1d(check_finite("beta1_values", beta1_values)).astype(float)
    b2 = np.atleast_1d(check_finite("beta2_values", beta2_values)).astype(float)
    if b1.ndim != 1 or b2.ndim != 1 or b1.size == 0 or b2.size == 0:
        raise ValueError("beta1_values and beta2_values must be non-empty 1-D arrays")
    kappa = float(check_finite("kappa", kappa, positive=True))
    qq = check_finite("q", np.broadcast_to(np.asarray(q, dtype=float), (2,)), nonneg=True)
    alpha = float(check_finite("alpha", alpha))
    if int(n_perturb) < 1:
        raise ValueError(f"n_perturb must be >= 1, got {n_perturb!r}")
    perturbation = float(check_finite("perturbation", perturbation, positive=True))
    t_end = float(check_finite("t_end", t_end, positive=True))
    horizon_cap = float(check_finite("horizon_cap", horizon_cap, positive=True))
    if horizon_cap < 1:
        raise ValueError(f"horizon_cap must be >= 1, got {horizon_cap!r}")
    if engine not in ENGINES:
        raise ValueError(f"engine must be one of {', '.join(ENGINES)}, got {engine!r}")
    params = _MapParams(kappa, qq, alpha, n_perturb, seed, perturbation, t_end, horizon_cap,
                        max_events, engine)  # fmt: skip
    return b1, b2, params


def _outcome_codes(b1, b2, g0, p: _MapParams, progress):
    """Outcome codes ``(n1, n2, n_perturb)`` from the chosen engine, and attributes of the run
    (fast engine: how many runs were stepped, decided early, run by the exact simulator)."""
    k = (p.kappa, 1.0)
    if p.engine == "fast":
        reference = functools.partial(
            simulate_outcome, t_end=p.t_end, horizon_cap=p.horizon_cap, max_events=p.max_events
        )
        codes, res = fast_engine.outcomes(
            b1, b2, p.alpha, k, p.q, g0, reference, t_end=p.t_end, horizon_cap=p.horizon_cap,
            max_events=p.max_events,
        )  # fmt: skip
        if progress is not None:
            progress(b1.size * b2.size, b1.size * b2.size)
        how = np.bincount(res.decided_by, minlength=len(fast_engine.DECIDED_BY))
        return codes, {f"runs_{name}": int(c) for name, c in zip(fast_engine.DECIDED_BY, how)}
    if p.engine == "jax":
        return jax_engine.outcomes(
            b1, b2, p.alpha, k, p.q, g0, t_end=p.t_end, horizon_cap=p.horizon_cap,
            max_events=p.max_events,
        ), {}  # fmt: skip
    return _numpy_outcomes(
        b1, b2, p.alpha, k, p.q, g0, p.t_end, p.horizon_cap, p.max_events, progress
    ), {}


def _numpy_outcomes(b1, b2, alpha, k, q, g0, t_end, horizon_cap, max_events, progress):
    """Outcome codes ``(n1, n2, n_perturb)`` by :func:`simulate_outcome`, run by run."""
    codes = np.zeros(g0.shape[:3], dtype=np.int8)
    total = b1.size * b2.size
    for i, x1 in enumerate(b1):
        for j, x2 in enumerate(b2):
            for m in range(g0.shape[2]):
                out, _ = simulate_outcome(
                    x1,
                    x2,
                    alpha,
                    k=k,
                    q=q,
                    g0=g0[i, j, m],
                    t_end=t_end,
                    horizon_cap=horizon_cap,
                    max_events=max_events,
                )
                codes[i, j, m] = int(out)
            if progress is not None:
                progress(i * b2.size + j + 1, total)
    return codes


def _most_frequent(codes):
    """Most frequent class per pixel over the last axis (ties: the smallest code) and the
    fraction of runs that gave it."""
    counts = np.stack([(codes == int(o)).sum(axis=2) for o in Outcome], axis=-1)
    out = np.array([int(o) for o in Outcome], dtype=np.int8)[counts.argmax(axis=-1)]
    agree = (counts.max(axis=-1) / codes.shape[2]).astype(np.float32)
    return out, agree


def _map_dataset(b1, b2, codes, p: _MapParams, seconds: float) -> xr.Dataset:
    """The outcome map of the codes ``(n1, n2, n_perturb)`` as a CF dataset over
    ``(beta1, beta2)`` (flags from :class:`Outcome`)."""
    out, agree = _most_frequent(codes)
    B1, B2 = np.meshgrid(b1, b2, indexing="ij")
    region = no_stable_subclass(B1, B2, np.full(B1.shape, p.alpha))
    flags = {
        "long_name": "simulated outcome of perturbed SS equilibrium",
        "flag_values": np.array([int(m) for m in Outcome], dtype=np.int8),
        "flag_meanings": " ".join(m.label for m in Outcome),
    }
    dims = ("beta1", "beta2")
    return xr.Dataset(
        {
            "outcome": (dims, out, flags),
            "agreement": (
                dims,
                agree,
                {"units": "1", "long_name": "fraction of perturbed runs giving outcome"},
            ),
            "no_stable_subclass": (
                dims,
                region,
                {"long_name": "subclass 132, 133, 142, 143 or dual (paper Sec. 6.4-6.5)"},
            ),
        },
        coords={
            "beta1": ("beta1", b1, {"units": "rad", "long_name": "direction of b1"}),
            "beta2": ("beta2", b2, {"units": "rad", "long_name": "direction of b2"}),
        },
        attrs={
            "title": "Outcome map of the compliant two-contact dynamics",
            "references": "Varkonyi, P. L.: Dynamics of mechanical systems with multiple sliding "
            "contacts: new faces of Painleve's paradox (Sec. 4.1, 6.4-6.5, Fig. 2)",
            "method": f"exact event-driven simulation ({p.engine} engine), atlas.dynamics.classify",
            **p.attrs(codes.size, seconds),
        },
    )
