"""Layer 3, time: the piecewise-linear compliant model, its exact event-driven simulator (numpy) and a
batched JAX engine, outcome classification and outcome maps (paper Sec. 5, Fig. 2)."""

from atlas.dynamics.model import (
    FORCE_OFF,
    FORCE_ON,
    IMPACT,
    LIFTOFF,
    NO_STABLE_SUBCLASSES,
    Outcome,
    SimulationResult,
    Status,
    TrajectoryStats,
    classify,
    classify_stats,
    fig2_cases,
    no_stable_subclass,
    outcome_grid,
    outcome_map,
    perturbed_initial_states,
    simulate,
    simulate_outcome,
    simulate_solve_ivp,
    ss_equilibrium,
    subclass_codes,
    trajectory_stats,
)

__all__ = [
    "FORCE_OFF", "FORCE_ON", "IMPACT", "LIFTOFF",
    "NO_STABLE_SUBCLASSES", "Outcome", "SimulationResult", "Status", "TrajectoryStats", "classify",
    "classify_stats", "fig2_cases", "no_stable_subclass", "outcome_grid", "outcome_map",
    "perturbed_initial_states", "simulate", "simulate_outcome", "simulate_solve_ivp", "ss_equilibrium",
    "subclass_codes", "trajectory_stats",
]
