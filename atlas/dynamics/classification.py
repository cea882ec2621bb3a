"""Outcome classification of a simulated trajectory (paper Sec. 6.4-6.5, Fig. 2): what the
dynamics did over the simulated horizon, from the events and the gaps a simulator recorded."""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from atlas.dynamics.simulator import SimulationResult
from atlas.dynamics.system import (
    IMPACT,
    MODE_NAMES,
    Mode,
    Outcome,
    Status,
    System,
    iwc_aligned,
)

__all__ = [
    "TrajectoryStats",
    "trajectory_stats",
    "impacts",
    "classify",
    "classify_stats",
    "needs_longer_run",
]


@dataclasses.dataclass(frozen=True)
class TrajectoryStats:
    """What :func:`classify` reads from a trajectory (any simulator can fill it in).

    Attributes
    ----------
    t_final : float
        End of the run ``T`` [time].
    status : Status
    mode_final : str
        Contact configuration at ``T``.
    g_final : ndarray (4,)
        State at ``T``.
    scale : float
        Length scale of the run (:attr:`SimulationResult.scale`) [1].
    last_event : float
        Time of the last event (0 if none) [time].
    t_imp, v_imp : ndarray
        Impact times [time] and impact speeds ``|d_i'|`` [1/time], in time order, including the
        return of a gap in free flight (FF, falling back) dated ``T``.
    c_imp : ndarray of int
        Contact (1, 2) of each impact.
    late_amplitude : ndarray (2,)
        ``max |d_i|`` over the sub-step ends and events in ``[2T/3, T]`` [1].
    """

    t_final: float
    status: Status
    mode_final: str
    g_final: np.ndarray
    scale: float
    last_event: float
    t_imp: np.ndarray
    v_imp: np.ndarray
    c_imp: np.ndarray
    late_amplitude: np.ndarray


def impacts(sysm: System, mode_final, g_final, t_final, kinds, t_events, contacts, states):
    """Impact times [time], speeds ``|d_i'|`` [1/time] and contacts (1, 2) of a run, in time
    order, plus the return of a gap in free flight (FF, falling back) dated ``t_final``."""
    mask = MODE_NAMES.index(mode_final)
    g = g_final
    acc = sysm.modes[mask].E[2:4] @ np.append(g, 1.0)
    imp = np.array([k == IMPACT for k in kinds], dtype=bool)
    t_imp = t_events[imp]
    c_imp = contacts[imp]
    v_imp = np.abs(states[imp][np.arange(imp.sum()), c_imp + 1])
    # a free gap in flight that will come back: its impact speed, dated at the end of the run
    for i in range(2):
        if mask == 0 and g[i] > 0 and acc[i] < 0:  # FF: constant acceleration -a_i
            t_imp = np.append(t_imp, t_final)
            c_imp = np.append(c_imp, i + 1)
            v_imp = np.append(v_imp, math.sqrt(g[i + 2] ** 2 + 2 * abs(acc[i]) * g[i]))
    return t_imp, v_imp, c_imp


def trajectory_stats(res: SimulationResult) -> TrajectoryStats:
    """:class:`TrajectoryStats` of a :func:`simulate` result."""
    T = res.t_final
    g = res.g_final
    t_imp, v_imp, c_imp = impacts(
        res._system, res.mode_final, g, T, res.kinds, res.t_events, res.contacts, res.states
    )
    late = res._env_t >= 2 * T / 3
    amp = np.abs(res._env_d[late]).max(axis=0) if late.any() else np.abs(g[:2])
    return TrajectoryStats(
        t_final=T,
        status=res.status,
        mode_final=res.mode_final,
        g_final=g,
        scale=res.scale,
        last_event=float(res.t_events[-1]) if res.n_events else 0.0,
        t_imp=t_imp,
        v_imp=v_imp,
        c_imp=c_imp,
        late_amplitude=amp,
    )


def classify(
    res: SimulationResult,
    *,
    min_impacts: int = 6,
    growth_ratio: float = 1.25,
    small_amplitude: float = 10.0,
    align_tol: float = 1e-2,
) -> Outcome:
    """Outcome class of a simulated trajectory (the label depends on the simulated horizon).

    With ``T = t_final``, the impact speeds ``|d_i'|`` at the impacts (gap ``d_i`` closing),
    ``m2`` / ``m3`` = the largest impact speed with impact time in ``[T/3, 2T/3)`` /
    ``[2T/3, T]``, ``s`` the run's length scale (:attr:`SimulationResult.scale`: the larger of the
    initial gaps and the resting penetration ``|a| / min k_i |b_i|``) and ``A3`` the largest
    ``|d_i|`` in ``[2T/3, T]`` over the contacts with an impact there, the criteria are checked in
    this order:

    * ``settles_XY`` -- either the run stopped with status ``"settled"`` in mode XY (a stable mode
      is reached, the active gaps are within ``settle_rtol`` of their equilibrium and the free gaps
      move away, so no further event can occur; see :func:`simulate`), or it reached ``t_end``
      in mode XY with no event in the second half of the run and no eigenvalue of the active
      subsystem with positive real part (this admits the *neutral* ``q = 0`` SS mode, which
      oscillates forever without leaving the mode, as in the paper's Fig. 2b).
    * ``IWC`` -- impact without collision (paper Sec. 4.3): the run diverged and the state's
      deviation from the current mode's equilibrium is aligned (``1 - |cos| < align_tol``) with the
      eigenvector of a real positive eigenvalue of ``A_S`` along which every active gap goes to
      ``-inf`` (so its force goes to ``+inf``), with every free gap open and opening.
    * ``growing_bouncing`` -- the run diverged (a gap beyond ``1e4 s``) after at least 3 impacts
      with an event in its last 20 % or a gap in flight falling back; otherwise a diverged run is
      ``undetermined``.
    * ``undetermined`` if fewer than ``min_impacts`` impacts (too short a run: see
      :func:`simulate_outcome`, which extends the horizon).
    * ``growing_bouncing`` -- ``m3 > growth_ratio * m2`` (still growing late in the run); or
      ``A3 > small_amplitude * s``: the bouncing amplified the initial excursion more than
      ``small_amplitude`` times and keeps bouncing (this includes bouncing that grew and then
      saturated at a large amplitude, as the paper's Fig. 2c does after t ~ 300).
    * ``sustained_oscillation`` -- small (``A3 <= small_amplitude * s``) non-growing
      (``m2 / growth_ratio <= m3 <= growth_ratio * m2``) bouncing with an impact in the last 10 %
      of the run, status ``"t_end"`` or ``"event_cap"`` with the impacts spread over more than half
      of ``[0, T]``.
    * ``undetermined`` -- anything else (a Zeno-like burst at the event cap, decaying bouncing
      not yet settled, a slowly drifting mode at ``t_end``, ...).
    """
    return classify_stats(
        trajectory_stats(res),
        res._system,
        min_impacts=min_impacts,
        growth_ratio=growth_ratio,
        small_amplitude=small_amplitude,
        align_tol=align_tol,
    )


def classify_stats(
    st: TrajectoryStats,
    sysm: System,
    *,
    min_impacts: int = 6,
    growth_ratio: float = 1.25,
    small_amplitude: float = 10.0,
    align_tol: float = 1e-2,
) -> Outcome:
    """:func:`classify` from the :class:`TrajectoryStats` of a run of the system ``sysm``."""
    T = st.t_final
    if st.status == Status.SETTLED:
        return Outcome[f"SETTLES_{st.mode_final}"]
    mask = MODE_NAMES.index(st.mode_final)
    mode = sysm.modes[mask]
    g = st.g_final
    if st.status == Status.DIVERGED and mask and iwc_aligned(sysm, mask, g, align_tol):
        return Outcome.IWC
    acc = mode.E[2:4] @ np.append(g, 1.0)
    if st.status in (Status.T_END, Status.DIVERGED) and st.last_event <= 0.5 * T:
        lam = mode.eig
        neutral_or_stable = lam.size == 0 or np.all(lam.real <= 1e-9 * np.abs(lam).max())
        if neutral_or_stable and _free_gaps_leaving(mode, g):
            return Outcome[f"SETTLES_{st.mode_final}"]
    t_imp, speeds = st.t_imp, st.v_imp
    if st.status == Status.DIVERGED:
        # a gap beyond the amplitude limit (1e4 x scale) after repeated impacts, with an event
        # late or a gap in flight falling back: growing bouncing
        in_flight = any(not mask >> i & 1 and acc[i] < 0 for i in range(2))
        if t_imp.size >= min(3, min_impacts) and (st.last_event >= 0.8 * T or in_flight):
            return Outcome.GROWING_BOUNCING
        return Outcome.UNDETERMINED
    if t_imp.size < min_impacts:
        return Outcome.UNDETERMINED
    mid = speeds[(t_imp >= T / 3) & (t_imp < 2 * T / 3)]
    late_sel = t_imp >= 2 * T / 3
    late = speeds[late_sel]
    if mid.size == 0 or late.size == 0:
        return Outcome.UNDETERMINED
    m2, m3 = mid.max(), late.max()
    if m3 > growth_ratio * m2:
        return Outcome.GROWING_BOUNCING
    bouncing = np.unique(st.c_imp[late_sel]) - 1
    if st.late_amplitude[bouncing].max() > small_amplitude * st.scale:
        return Outcome.GROWING_BOUNCING
    if m3 >= m2 / growth_ratio and t_imp[-1] >= 0.9 * T:
        if st.status == Status.T_END or (
            st.status == Status.EVENT_CAP and t_imp[-1] - t_imp[0] > 0.5 * T
        ):
            return Outcome.SUSTAINED_OSCILLATION
    return Outcome.UNDETERMINED


def needs_longer_run(outcome: Outcome, status: Status, n_events: int, t_end, t_max) -> bool:
    """The horizon-extension rule of :func:`atlas.dynamics.simulate_outcome`: undetermined, ran
    out of time (status ``"t_end"``) with at least one event, and ``2 t_end <= t_max``."""
    return (
        outcome == Outcome.UNDETERMINED
        and status == Status.T_END
        and n_events > 0
        and 2 * t_end <= t_max * (1 + 1e-12)
    )


def _free_gaps_leaving(mode: Mode, g) -> bool:
    """Every free gap open, opening, and accelerating away once the active gaps sit at their
    equilibrium (the mean acceleration of an oscillating neutral mode)."""
    z = np.append(g, 1.0)
    if mode.mask and mode.z_eq is not None:
        idx = [i for i in range(2) if mode.mask >> i & 1]
        z[idx] = mode.z_eq[idx]
        z[[i + 2 for i in idx]] = 0.0
    elif mode.mask:
        return False
    acc = mode.E[2:4] @ z
    return all(
        g[i] > 0 and g[i + 2] >= 0 and acc[i] > 0 for i in range(2) if not mode.mask >> i & 1
    )
