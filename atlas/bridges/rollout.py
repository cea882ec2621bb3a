"""Verdicts along a MuJoCo trajectory: step the model and judge each sampled state where it is.

Every ``every`` steps (``mj_step``, the model's own integrator and timestep) the chosen contacts'
signed distances (``mj_geomDistance``) and sliding speeds are read; where the touching contacts
(``dist <= tol`` [m]) all slide (speed ``> stop_speed`` [m/s], or frictionless) the bridge's
verdicts are taken at that state (:func:`atlas.bridges.mujoco.contact_data`).  The events are the
sampled states where the engine's mode changes (a contact lifts off or touches, stops or starts
sliding) or a verdict of the theory changes (sliding on both consistent or stable, which lift-off
modes and jams are consistent): the first state where the sliding mode stops being consistent is
where the theory says the engine must leave it.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from atlas.bridges import mujoco as bridge

__all__ = ["Rollout", "rollout", "jam_test", "KEYS", "MAX_SAMPLES"]

#: the most states a rollout keeps (each a dict of the state and its verdicts, about 1 kB)
MAX_SAMPLES = 10**6

#: the verdicts recorded along a rollout (two contacts; one contact: all of its four)
KEYS = (
    "consistent_SS", "stable_SS", "consistent_SF", "consistent_FS", "consistent_FF",
    "consistent_IF", "consistent_FI", "consistent_II", "subclass_code", "cc_possible",
)  # fmt: skip


@dataclasses.dataclass(frozen=True)
class Rollout:
    """``samples``: dicts ``t`` [s], ``qpos``, ``qvel``, ``dist`` [m], ``speed`` [m/s], ``touching``,
    ``sliding`` per contact, ``verdicts`` (``None`` where the sliding analysis does not apply,
    ``why`` says why); ``events``: ``(t, text)`` where the mode or a verdict changes; ``contacts``:
    the contacts' names; ``step_time``: wall time per sampled state [s]."""

    contacts: tuple
    samples: list
    events: list
    step_time: float

    def first(self, key, value):
        """The first sample whose verdict ``key`` equals ``value`` (``None`` if none)."""
        for s in self.samples:
            if s["verdicts"] is not None and s["verdicts"].get(key) == value:
                return s
        return None


def rollout(
    model, data=None, duration=1.0, *, contacts=None, qpos=None, qvel=None, every=10,
    tol=1e-4, stop_speed=1e-2, judge=True,
) -> Rollout:  # fmt: skip
    """Step ``model`` for ``duration`` [s] from the state (``data`` / ``qpos`` / ``qvel`` as in
    :func:`atlas.bridges.mujoco.contact_data`, which also chooses ``contacts`` at the start) and
    judge every ``every``-th state (module docstring; ``judge=False``: modes only, no verdicts).
    ``data`` is not changed."""
    import time  # noqa: PLC0415  (wall time of the sampled states only)

    mj = bridge.require()
    if not (math.isfinite(duration) and duration > 0):
        raise ValueError(f"duration: must be > 0 s, got {duration} (and finite)")
    if int(every) < 1:
        raise ValueError(f"every: must be >= 1 step, got {every}")
    judged = int(duration / model.opt.timestep) // int(every) + 1
    if judged > MAX_SAMPLES:
        raise ValueError(
            f"duration: {duration:g} s is {judged:,} judged states of {model.opt.timestep:g} s "
            f"steps every {int(every)}, at most {MAX_SAMPLES:,} (raise every)"
        )
    work = bridge.state(model, data, qpos, qvel)
    start = bridge.contact_data(model, work, contacts=contacts, tol=tol, slip=_any_slip(2))
    chosen = start.contacts
    steps = int(round(duration / model.opt.timestep))
    samples, spent = [], 0.0
    for i in range(steps + 1):
        if i % int(every) == 0:
            t0 = time.perf_counter()
            samples.append(_sample(mj, model, work, chosen, tol, stop_speed, judge))
            spent += time.perf_counter() - t0
        if i < steps:
            mj.mj_step(model, work)
    names = tuple(c.name for c in chosen)
    return Rollout(names, samples, _events(samples, names), spent / len(samples))


def _any_slip(n):
    """Placeholder slip directions at the start (the state may be at rest)."""
    return [(1.0, 0.0, 0.0)] * n


def _sample(mj, model, work, chosen, tol, stop_speed, judge=True) -> dict:
    """One sampled state: distances, speeds, modes and (where they apply) the verdicts."""
    scratch = bridge.state(model, work)
    margin = 0.05 * (float(model.stat.extent) or 1.0)
    found = bridge.collide(model, scratch, work.qpos, margin)
    dist, speed = [], []
    for c in chosen:
        if not any(x.ids == c.ids for x in found):
            dist.append(float("inf"))
            speed.append(0.0)
            continue
        x = bridge.same_contact(found, c)
        v = bridge.relative_jacobian(mj, model, scratch, x) @ scratch.qvel
        dist.append(x.dist)
        speed.append(float(np.linalg.norm(v - (x.n @ v) * x.n)))
    touching = [d <= tol for d in dist]
    sliding = [t and (s > stop_speed or c.mu == 0.0) for t, s, c in zip(touching, speed, chosen)]
    out = dict(t=float(work.time), qpos=work.qpos.tolist(), qvel=work.qvel.tolist(), dist=dist, speed=speed,
               touching=touching, sliding=sliding, verdicts=None, why=None)  # fmt: skip
    active = [c.name for c, t in zip(chosen, touching) if t]
    if not judge:
        out["why"] = "not judged"
    elif not active:
        out["why"] = "no contact touches"
    elif not all(s for s, t in zip(sliding, touching) if t):
        out["why"] = "a touching contact does not slide"
    else:
        try:
            res = bridge.contact_data(model, work, contacts=active, tol=tol)
            v = res.verdicts(names=KEYS if len(active) == 2 else None)
            out["verdicts"] = {k: _plain(x) for k, x in v.items()}
        except ValueError as err:
            out["why"] = str(err)
    return out


def _plain(v):
    v = np.asarray(v)
    return bool(v) if v.dtype == bool else int(v)


def _signature(s, names):
    """What an event compares: the engine's mode and the verdicts."""
    mode = tuple(
        f"{n}: " + ("sliding" if sl else "stuck" if t else "free")
        for n, t, sl in zip(names, s["touching"], s["sliding"])
    )
    return mode, tuple(sorted((s["verdicts"] or {}).items()))


def _events(samples, names) -> list:
    """``(t, text)`` at the first sample and wherever the signature changes."""
    out, last = [], None
    for s in samples:
        sig = _signature(s, names)
        if last is None or sig != last:
            prev = dict(last[1]) if last is not None else {}
            changed = [f"{k} = {v}" for k, v in sig[1] if prev.get(k) != v]
            mode = ", ".join(sig[0]) if last is None or sig[0] != last[0] else ""
            text = "; ".join(x for x in (mode, ", ".join(changed)) if x)
            out.append((s["t"], text or (s["why"] or "verdicts not applicable")))
        last = sig
    return out


def _stop(res):
    """Time [s] of the first sample after the start where a touching contact does not slide."""
    for s in res.samples[1:]:
        if any(t and not sl for t, sl in zip(s["touching"], s["sliding"])):
            return s["t"]
    return None


def jam_test(model, data=None, duration=0.5, **kw) -> dict:
    """Tell a jam from a friction stop: the stop time at the model's constraint time constants
    and at half of them (``solref[0]`` of the geoms and pairs halved; a direct ``(-k, -b)``
    becomes ``(-4k, -2b)``).  A jam (an impact without collision, resolved by the constraint's
    own dynamics) stops in proportion to the time constant; a friction stop does not.  Returns
    ``stop``, ``stop_halved`` [s] (``None``: no stop within ``duration``), their ``ratio`` and
    ``kind`` (``"jam"`` where the ratio exceeds 1.5, else ``"friction stop"``)."""
    kw = dict(kw, judge=False)
    first = _stop(rollout(model, data, duration, **kw))
    saved = model.geom_solref.copy(), model.pair_solref.copy()
    try:
        for arr in (model.geom_solref, model.pair_solref):
            pos = arr[:, 0] > 0
            arr[pos, 0] *= 0.5
            arr[~pos, 0] *= 4.0
            arr[~pos, 1] *= 2.0
        halved = _stop(rollout(model, data, duration, **kw))
    finally:
        model.geom_solref[:], model.pair_solref[:] = saved
    out = dict(stop=first, stop_halved=halved, ratio=None, kind=None)
    if first is not None and halved:
        out["ratio"] = first / halved
        out["kind"] = "jam" if out["ratio"] > 1.5 else "friction stop"
    return out
