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
sliding mode ending by friction: agrees with ``SS``); else ``SS``.
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
        out.append(Mechanism.ladder(theta=rng.uniform(0.3, 1.4), mu_floor=rng.uniform(0, 2),
                                    mu_wall=rng.uniform(0, 1), speed=rng.uniform(0.2, 2)))
        out.append(Mechanism.two_legged(h=rng.uniform(0.1, 1), mu1=rng.uniform(0, 2.5),
                                        mu2=rng.uniform(0, 2.5), speed=rng.uniform(0.2, 2)))
        out.append(Mechanism.leaning_rod(theta=rng.uniform(0.3, 1.3), e=rng.uniform(-0.4, 0.4),
                                         mu_floor=rng.uniform(0, 1.5),
                                         mu_edge=rng.uniform(0, 1.5), speed=rng.uniform(0.2, 2)))
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
    """``(kind, time)``: ``SF`` / ``FS`` / ``FF`` / ``stop`` / ``SS`` and when."""
    data = bridge.state(model, None, None, qvel)
    start = bridge.contact_data(model, data, contacts="c1,c2")
    v0 = start.speeds
    scratch = bridge.state(model)
    stopped = False
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
            scratch.qvel[:] = data.qvel
            vel = bridge.relative_jacobian(mujoco, model, scratch, x) @ data.qvel
            if np.linalg.norm(vel - (x.n @ vel) * x.n) < 0.1 * v0[j]:
                stopped = True
        if lifted:
            return {(0,): "FS", (1,): "SF", (0, 1): "FF"}[tuple(lifted)], data.time
        if stopped:
            return "stop", data.time
    return "SS", HORIZON


def _classify(got):
    """Stops told apart: a jam's stop time scales with the time constant."""
    kinds = [k for k, _t in got]
    if kinds == ["stop", "stop"]:
        jam = got[0][1] > 1.5 * got[1][1]
        return ["jam" if jam else "SS"] * 2
    return ["SS" if k == "stop" else k for k in kinds]


def measure(n=16, seed=40):
    """``rows``: (body name, prediction, outcome per time constant)."""
    rng = np.random.default_rng(seed)
    rows = []
    for body in _random_states(rng, n):
        text, qvel = mjcf(body, rho=0.005)
        got = []
        for tc in TIMECONSTANTS:
            model = mujoco.MjModel.from_xml_string(text.replace(
                "<option ", '<option timestep="1e-4" ').replace(
                "<geom ", f'<geom solref="{tc} 1" '))  # fmt: skip
            got.append(outcome(model, qvel))
        model = mujoco.MjModel.from_xml_string(text)
        pred = predict(bridge.contact_data(model, qvel=qvel, contacts="c1,c2").verdicts())
        rows.append((body.name, pred, *_classify(got)))
    return rows


def table(rows) -> str:
    lines = ["| body | predicted | n | " + " | ".join(
        f"agree at tc = {tc * 1e3:g} ms" for tc in TIMECONSTANTS) + " | MuJoCo outcomes |",
        "|---|---|---|" + "---|" * len(TIMECONSTANTS) + "---|"]  # fmt: skip
    keys = sorted({(r[0], r[1]) for r in rows})
    for name, pred in keys:
        sel = [r for r in rows if (r[0], r[1]) == (name, pred)]
        agree = [sum(r[2 + k] == pred for r in sel) for k in range(len(TIMECONSTANTS))]
        seen = Counter(f"{r[2]}/{r[3]}" for r in sel)
        lines.append(f"| {name} | {pred} | {len(sel)} | " + " | ".join(
            f"{a}/{len(sel)}" for a in agree) + " | " + ", ".join(
            f"{k} x{v}" for k, v in sorted(seen.items())) + " |")  # fmt: skip
    return "\n".join(lines)


if __name__ == "__main__":
    print(table(measure()))
