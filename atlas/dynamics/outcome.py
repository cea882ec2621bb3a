"""Outcomes of the simulated dynamics: the paper's Fig. 2 cases, the subclasses where the paper
predicts no stable mode (Sec. 6.4-6.5), the grid and the perturbed initial states of outcome maps,
and one classified run with its horizon extended (:func:`simulate_outcome`).  The outcome atlases
built from them are in :mod:`atlas.dynamics.outcomes`.
"""

from __future__ import annotations

import math

import numpy as np

from atlas.core import contact_modes
from atlas.dynamics.classification import classify, needs_longer_run
from atlas.dynamics.simulator import simulate

__all__ = [
    "fig2_cases",
    "NO_STABLE_SUBCLASSES",
    "subclass_codes",
    "no_stable_subclass",
    "outcome_grid",
    "standard_normals",
    "initial_states",
    "perturbed_initial_states",
    "simulate_outcome",
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

#: subclasses (and their duals) where the paper predicts no stable mode or impact (Sec. 6.4-6.5)
NO_STABLE_SUBCLASSES = (132, 133, 142, 143)


def _code_args(beta1, beta2, alpha):
    vec = [contact_modes.direction(np.asarray(x, dtype=float)) for x in (beta1, beta2, alpha)]
    return [np.asarray(v) for cs in vec for v in cs]


def subclass_codes(beta1, beta2, alpha) -> np.ndarray:
    """Subclass codes ``ijk`` (SPEC §1) of angles [rad] via :func:`atlas.core.contact_modes.subclass_code`
    (the reference implementation; 0 degenerate, -1 undecided); arrays broadcast."""
    return np.asarray(contact_modes.subclass_code(*_code_args(beta1, beta2, alpha))).astype(
        np.int16
    )


def no_stable_subclass(beta1, beta2, alpha) -> np.ndarray:
    """True in subclasses 132, 133, 142, 143 or their duals (paper Sec. 6.4-6.5); arrays broadcast.

    The dual (contacts swapped) is :func:`atlas.core.contact_modes.dual_vectors` of the direction vectors.
    """
    args = _code_args(beta1, beta2, alpha)
    code = np.asarray(contact_modes.subclass_code(*args))
    dual = np.asarray(contact_modes.subclass_code(*contact_modes.dual_vectors(*args)))
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


def standard_normals(seed, rows, n2: int, n_perturb: int) -> np.ndarray:
    """The standard normals of :func:`perturbed_initial_states` for the ``beta1`` rows ``rows``
    (a ``range``) of a grid with ``n2`` ``beta2`` values, shape ``(len(rows), n2, n_perturb, 4)``.

    One stream ``numpy.random.default_rng(seed)`` drawn in the order ``(beta1, beta2, run,
    component)``; the rows before ``rows.start`` are drawn and discarded, so any range of rows gets
    the values the whole grid would (tiles equal the single draw).
    """
    rng = np.random.default_rng(seed)
    shape = (int(n2), int(n_perturb), 4)
    for _ in range(rows.start):
        rng.standard_normal(shape)
    return rng.standard_normal((len(rows), *shape))


def initial_states(beta1, beta2, alpha, kappa, xi, perturbation=1e-2) -> np.ndarray:
    """Perturbed SS equilibria (paper eq. 8) of cells with angles ``beta1, beta2, alpha`` [rad] and
    stiffness ratio ``kappa`` [1] (broadcast to the cell shape ``C``) from standard normals ``xi``
    of shape ``C + (n_perturb, 4)``; returns states ``(d1, d2, d1', d2')`` of that shape.

    ``d = d* + perturbation * |d*| * xi``, ``d' = perturbation * |d*| * xi'`` around
    ``d* = -K^{-1} B^{-1} a``; where the SS mode is inconsistent, ``d = -perturbation * |xi| /
    min(kappa, 1)`` (both gaps pushed into contact), ``d' = perturbation * xi' / min(kappa, 1)``.
    """
    xi = np.asarray(xi, dtype=float)
    b1, b2, al, ka = np.broadcast_arrays(
        *(np.asarray(x, dtype=float) for x in (beta1, beta2, alpha, kappa))
    )
    B = np.empty((*b1.shape, 2, 2))
    B[..., 0, 0], B[..., 1, 0] = np.cos(b1), np.sin(b1)
    B[..., 0, 1], B[..., 1, 1] = np.cos(b2), np.sin(b2)
    a = np.stack([np.cos(al), np.sin(al)], axis=-1)
    # f = B^-1 a (SS forces, LAPACK as in ss_equilibrium); the SS mode is consistent where f > 0
    det = B[..., 0, 0] * B[..., 1, 1] - B[..., 0, 1] * B[..., 1, 0]
    regular = det != 0
    Bs = np.where(regular[..., None, None], B, np.eye(2))
    f = np.linalg.solve(Bs, a[..., None])[..., 0]
    consistent = regular & np.all(f > 0, axis=-1)
    d_eq = -f / np.stack([ka, np.ones_like(ka)], axis=-1)
    s_eq = np.abs(d_eq).max(axis=-1)[..., None, None]
    s_in = (1.0 / np.minimum(ka, 1.0))[..., None, None]
    inside = np.concatenate([d_eq[..., None, :] + perturbation * s_eq * xi[..., :2],
                             perturbation * s_eq * xi[..., 2:]], axis=-1)  # fmt: skip
    outside = np.concatenate([-perturbation * s_in * np.abs(xi[..., :2]),
                              perturbation * s_in * xi[..., 2:]], axis=-1)  # fmt: skip
    return np.where(consistent[..., None, None], inside, outside)


def perturbed_initial_states(
    beta1_values, beta2_values, alpha, kappa, n_perturb=1, seed=0, perturbation=1e-2
) -> np.ndarray:
    """Initial states of an outcome map over the grid ``beta1_values x beta2_values`` [rad], shape
    ``(n1, n2, n_perturb, 4)``: :func:`initial_states` of the normals :func:`standard_normals`
    ``(seed)``."""
    b1 = np.atleast_1d(np.asarray(beta1_values, dtype=float))
    b2 = np.atleast_1d(np.asarray(beta2_values, dtype=float))
    xi = standard_normals(seed, range(b1.size), b2.size, n_perturb)
    return initial_states(b1[:, None], b2[None, :], alpha, kappa, xi, perturbation)


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
