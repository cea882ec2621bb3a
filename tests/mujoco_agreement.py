"""Agreement of the bridge's verdicts with what MuJoCo does (a measurement, run by
``test_agreement.py`` with ``-m slow`` or as ``python tests/mujoco_agreement.py``).

States: seeded random built-in bodies (ladder, two_legged, leaning_rod) and general bodies (two
vertex contacts on planes of any direction), sliding.  Prediction from the verdicts at the state:
``SS`` (only SS consistent), ``SF`` / ``FS`` / ``FF`` (only that lift-off mode consistent),
``jam`` (no sliding or lift-off mode consistent: only impacts without collision), else
``several``.  MuJoCo's outcome over ``HORIZON`` (timestep 1e-4 s, ``solref = (tc, 1)`` on every
geom): the first contact whose distance exceeds ``LIFT`` -> ``SF`` (contact 2 lifts) / ``FS`` /
``FF``; else a contact whose sliding speed falls below a tenth of its start: a stop, a ``jam``
where halving the time constant shortens its time by more than 1.5x, else a friction stop (the
sliding mode ending by friction: agrees with ``SS``); else ``SS``.  Where MuJoCo separates a
contact, the verdicts are also taken at the state where it actually separates (the last sample,
every 0.5 ms from 0.1 ms, or the start, at which the lifting contact still touched, ``dist <= 1e-6`` m): the prediction
``at separation`` (the start's prediction where nothing separates; ``n/a`` where the bridge cannot
judge that state, e.g. a contact there not touching or not sliding).
"""

from __future__ import annotations

import math
import sys
from collections import Counter
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))  # mjcf_bodies

import mujoco  # noqa: E402
from mjcf_bodies import mjcf  # noqa: E402

from atlas.bridges import mujoco as bridge  # noqa: E402
from atlas.core.rigid_body import Mechanism  # noqa: E402

HORIZON = 0.03  # [s]
LIFT = 1e-3  # [m]
TIMECONSTANTS = (0.002, 0.001)


def _random_states(rng, n):
    out = []
    for _ in range(n):
        out.append(
            Mechanism.ladder(
                theta=rng.uniform(0.3, 1.4),
                mu_floor=rng.uniform(0, 2),
                mu_wall=rng.uniform(0, 1),
                speed=rng.uniform(0.2, 2),
            )
        )
        out.append(
            Mechanism.two_legged(
                h=rng.uniform(0.1, 1),
                mu1=rng.uniform(0, 2.5),
                mu2=rng.uniform(0, 2.5),
                speed=rng.uniform(0.2, 2),
            )
        )
        out.append(
            Mechanism.leaning_rod(
                theta=rng.uniform(0.3, 1.3),
                e=rng.uniform(-0.4, 0.4),
                mu_floor=rng.uniform(0, 1.5),
                mu_edge=rng.uniform(0, 1.5),
                speed=rng.uniform(0.2, 2),
            )
        )
        ang = rng.uniform(0.25, 0.75, 2) * math.pi  # surfaces whose normals point up-ish
        try:
            out.append(Mechanism(
                m=rng.uniform(0.5, 5), I=rng.uniform(0.05, 1), r1=tuple(rng.uniform(-1, 1, 2)),
                r2=tuple(rng.uniform(-1, 1, 2)), n1=(math.cos(ang[0]), math.sin(ang[0])),
                n2=(math.cos(ang[1]), math.sin(ang[1])), mu1=rng.uniform(0, 2),
                mu2=rng.uniform(0, 2), s1=int(rng.choice([1, -1])), speed=rng.uniform(0.2, 2),
                name="general",
            ))  # fmt: skip
        except ValueError:
            pass
    return out


def predict(v) -> str:
    modes = [m for m in ("SS", "SF", "FS", "FF") if v[f"consistent_{m}"]]
    if len(modes) == 1:
        return modes[0]
    if not modes:
        return "jam"
    return "several"


def outcome(model, qvel):
    """``(kind, time, separation)``: ``SF`` / ``FS`` / ``FF`` / ``stop`` / ``SS``, when, and for
    a lift-off ``(t, qpos, qvel)`` where the (first) lifting contact last touched."""
    data = bridge.state(model, None, None, qvel)
    start = bridge.contact_data(model, data, contacts="c1,c2")
    v0 = start.speeds
    scratch = bridge.state(model)
    stopped = False
    touched = [(0.0, data.qpos.copy(), data.qvel.copy())] * 2
    for i in range(int(round(HORIZON / model.opt.timestep))):
        mujoco.mj_step(model, data)
        if i % 5:
            continue
        found = bridge.collide(model, scratch, data.qpos, 0.05)
        lifted = []
        for j, c in enumerate(start.contacts):
            same = [x for x in found if x.ids == c.ids]
            if not same or bridge.same_contact(found, c).dist > LIFT:
                lifted.append(j)
                continue
            x = bridge.same_contact(found, c)
            if x.dist <= bridge.TOUCH_TOL:
                touched[j] = (data.time, data.qpos.copy(), data.qvel.copy())
            scratch.qvel[:] = data.qvel
            vel = bridge.relative_jacobian(mujoco, model, scratch, x) @ data.qvel
            if np.linalg.norm(vel - (x.n @ vel) * x.n) < 0.1 * v0[j]:
                stopped = True
        if lifted:
            kind = {(0,): "FS", (1,): "SF", (0, 1): "FF"}[tuple(lifted)]
            return kind, data.time, min((touched[j] for j in lifted), key=lambda x: x[0])
        if stopped:
            return "stop", data.time, None
    return "SS", HORIZON, None


def predict_at(model, separation, pred):
    """The prediction at the separation state (``pred`` where nothing separates)."""
    if separation is None:
        return pred
    try:
        v = bridge.contact_data(model, qpos=separation[1], qvel=separation[2], contacts="c1,c2")
        return predict(v.verdicts())
    except ValueError:
        return "n/a"


def _classify(got):
    """Stops told apart: a jam's stop time scales with the time constant."""
    kinds = [g[0] for g in got]
    if kinds == ["stop", "stop"]:
        jam = got[0][1] > 1.5 * got[1][1]
        return ["jam" if jam else "SS"] * 2
    return ["SS" if k == "stop" else k for k in kinds]


def measure(n=16, seed=40):
    """``rows``: (body name, prediction, outcome per time constant, prediction at separation
    per time constant, separation time [s] per time constant or ``None``)."""
    rng = np.random.default_rng(seed)
    rows = []
    for body in _random_states(rng, n):
        text, qvel = mjcf(body, rho=0.005)
        got, models = [], []
        for tc in TIMECONSTANTS:
            models.append(mujoco.MjModel.from_xml_string(text.replace(
                "<option ", '<option timestep="1e-4" ').replace(
                "<geom ", f'<geom solref="{tc} 1" ')))  # fmt: skip
            got.append(outcome(models[-1], qvel))
        model = mujoco.MjModel.from_xml_string(text)
        pred = predict(bridge.contact_data(model, qvel=qvel, contacts="c1,c2").verdicts())
        sep = [predict_at(m, g[2], pred) for m, g in zip(models, got)]
        when = [None if g[2] is None else g[2][0] for g in got]
        rows.append((body.name, pred, *_classify(got), *sep, *when))
    return rows


def _agree(sel, k, at_separation=False):
    nt = len(TIMECONSTANTS)
    pred = [r[2 + nt + k] if at_separation else r[1] for r in sel]
    return sum(p == r[2 + k] for p, r in zip(pred, sel))


def table(rows) -> str:
    """The table by body and prediction at the start; agreement of the start's and of the
    separation state's predictions per time constant, and the totals over decided states."""
    tcs = [f"{tc * 1e3:g} ms" for tc in TIMECONSTANTS]
    heads = [f"agree at tc = {t}" for t in tcs] + [f"at separation, tc = {t}" for t in tcs]
    lines = ["| body | predicted | n | " + " | ".join(heads) + " | MuJoCo outcomes |",
             "|---|---|---|" + "---|" * len(heads) + "---|"]  # fmt: skip
    for name, pred in sorted({(r[0], r[1]) for r in rows}):
        sel = [r for r in rows if (r[0], r[1]) == (name, pred)]
        cells = [f"{_agree(sel, k, s)}/{len(sel)}" for s in (False, True) for k in range(len(tcs))]
        cells[: len(tcs)] = ["-"] * len(tcs) if pred == "several" else cells[: len(tcs)]
        seen = Counter(f"{r[2]}/{r[3]}" for r in sel)
        lines.append(f"| {name} | {pred} | {len(sel)} | " + " | ".join(cells) + " | " + ", ".join(
            f"{k} x{v}" for k, v in sorted(seen.items())) + " |")  # fmt: skip
    return "\n".join(lines + [totals(rows)])


def totals(rows) -> str:
    """Agreement over the decided states, at the start and at separation, per time constant."""
    nt, out = len(TIMECONSTANTS), []
    for k, tc in enumerate(TIMECONSTANTS):
        start = [r for r in rows if r[1] != "several"]
        sep = [r for r in rows if r[2 + nt + k] not in ("several", "n/a")]
        when = [r[2 + 2 * nt + k] for r in rows if r[2 + 2 * nt + k] is not None]
        out.append(f"tc = {tc * 1e3:g} ms: {_agree(start, k)}/{len(start)} at the start, "
                   f"{_agree(sep, k, True)}/{len(sep)} at separation ({len(when)} lift-offs, "
                   f"{when.count(0.0)} of them apart at the first sample)")  # fmt: skip
    return "\n" + "; ".join(out)


if __name__ == "__main__":
    print(table(measure()))
