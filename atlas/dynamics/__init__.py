"""Layer 3, time: the piecewise-linear compliant model, its exact event-driven simulator (numpy) and a
batched JAX engine, outcome classification and outcome maps (paper Sec. 5, Fig. 2).

Modules: :mod:`~atlas.dynamics.system` (modes, matrices, enumerations), :mod:`~atlas.dynamics.simulator`
(NumPy engine), :mod:`~atlas.dynamics.fast_engine` (batched event-to-event outcome engine) and
:mod:`~atlas.dynamics.jax_engine` (the same as a JAX kernel),
:mod:`~atlas.dynamics.classification`, :mod:`~atlas.dynamics.reference` (solve_ivp cross-check),
:mod:`~atlas.dynamics.outcome` (Fig. 2 cases, subclasses, initial states),
:mod:`~atlas.dynamics.outcomes` (outcome atlases beside the theory verdicts; chooses the engine),
:mod:`~atlas.dynamics.outcome_tiles` (the same tile by tile, resumable).

The names below load lazily (PEP 562, as :mod:`atlas`): importing one module of the package
(e.g. :mod:`~atlas.dynamics.fast_engine` in a worker process) does not load JAX or xarray."""

import lazy_loader

__getattr__, __dir__, _ = lazy_loader.attach(
    __name__,
    submod_attrs={
        "classification": [
            "TrajectoryStats",
            "classify",
            "classify_stats",
            "trajectory_stats",
        ],
        "outcome": [
            "NO_STABLE_SUBCLASSES",
            "fig2_cases",
            "initial_states",
            "no_stable_subclass",
            "outcome_grid",
            "perturbed_initial_states",
            "simulate_outcome",
            "standard_normals",
            "subclass_codes",
        ],
        "outcomes": [
            "Dynamics",
            "outcome_atlas",
            "outcome_map",
            "outcome_scene",
        ],
        "simulator": [
            "SimulationResult",
            "simulate",
        ],
        "system": [
            "FORCE_OFF",
            "FORCE_ON",
            "IMPACT",
            "LIFTOFF",
            "Outcome",
            "Status",
            "ss_equilibrium",
        ],
        "reference": [
            "simulate_solve_ivp",
        ],
    },
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
