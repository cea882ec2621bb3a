"""Layer 3, time: the piecewise-linear compliant model, its exact event-driven simulator (numpy) and a
batched JAX engine, outcome classification and outcome maps (paper Sec. 5, Fig. 2).

Modules: :mod:`~atlas.dynamics.system` (modes, matrices, enumerations), :mod:`~atlas.dynamics.simulator`
(NumPy engine), :mod:`~atlas.dynamics.fast_engine` (batched event-to-event outcome engine) and
:mod:`~atlas.dynamics.jax_engine` (the same as a JAX kernel),
:mod:`~atlas.dynamics.classification`, :mod:`~atlas.dynamics.reference` (solve_ivp cross-check),
:mod:`~atlas.dynamics.outcome` (Fig. 2 cases, subclasses, initial states),
:mod:`~atlas.dynamics.outcomes` (outcome atlases beside the theory verdicts; chooses the engine),
:mod:`~atlas.dynamics.outcome_tiles` (the same tile by tile, resumable)."""

from atlas.dynamics.classification import (
    TrajectoryStats,
    classify,
    classify_stats,
    trajectory_stats,
)
from atlas.dynamics.outcome import (
    NO_STABLE_SUBCLASSES,
    fig2_cases,
    initial_states,
    no_stable_subclass,
    outcome_grid,
    perturbed_initial_states,
    simulate_outcome,
    standard_normals,
    subclass_codes,
)
from atlas.dynamics.outcomes import (
    Dynamics,
    outcome_atlas,
    outcome_map,
    outcome_scene,
)
from atlas.dynamics.reference import simulate_solve_ivp
from atlas.dynamics.simulator import SimulationResult, simulate
from atlas.dynamics.system import (
    FORCE_OFF,
    FORCE_ON,
    IMPACT,
    LIFTOFF,
    Outcome,
    Status,
    ss_equilibrium,
)

__all__ = [
    "FORCE_OFF",
    "FORCE_ON",
    "IMPACT",
    "LIFTOFF",
    "NO_STABLE_SUBCLASSES",
    "Outcome",
    "SimulationResult",
    "Status",
    "TrajectoryStats",
    "classify",
    "classify_stats",
    "Dynamics",
    "fig2_cases",
    "initial_states",
    "no_stable_subclass",
    "outcome_atlas",
    "outcome_grid",
    "outcome_map",
    "outcome_scene",
    "perturbed_initial_states",
    "simulate",
    "simulate_outcome",
    "simulate_solve_ivp",
    "standard_normals",
    "ss_equilibrium",
    "subclass_codes",
    "trajectory_stats",
]
