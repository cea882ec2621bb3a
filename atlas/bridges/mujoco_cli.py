"""``atlas mujoco MODEL.xml``: the contact-space data and every verdict of a MuJoCo model at a
state, as text or one JSON object (``B``, ``a``, every verdict under its output name).

What the verdicts mean for a regularised engine (docs/mujoco.md): consistency of the contact
modes, lift-off and jams (impact without collision) are properties of the rigid body and carry
over; SS stability and the II verdicts depend on the contact model, which MuJoCo only approximates
(``k``, ``c`` flagged approximate).
"""

from __future__ import annotations

import json

import numpy as np

from atlas.bridges import mujoco as bridge
from atlas.core.verdicts import Consistency, Verdict

__all__ = ["run_cli", "report", "meaning"]


def _numbers(name, text):
    if text is None:
        return None
    try:
        return [float(x) for x in text.replace(",", " ").split()]
    except ValueError:
        raise ValueError(f"{name}: expected comma-separated numbers, got {text!r}") from None


def _slips(text):
    """``"x,y,z;x,y,z"`` -> per-contact 3-vectors (``None``: not given)."""
    if text is None:
        return None
    out = [_numbers("slip", part) for part in text.split(";")]
    if any(len(v) != 3 for v in out):
        raise ValueError(f"slip: expected x,y,z per contact separated by ';', got {text!r}")
    return out


def _plain(v):
    """JSON-ready value of a verdict (numpy scalars -> bool / int / float)."""
    v = np.asarray(v)
    if v.dtype == bool:
        return bool(v)
    if np.issubdtype(v.dtype, np.integer):
        return int(v)
    return float(v)


def report(res, model_path=None) -> dict:
    """The answer as one JSON-ready dict: ``B``, ``a``, ``k``, ``c``, the contacts, the
    invariants (two contacts) and every verdict under its output name."""
    sp = res.space
    out = {
        "model": None if model_path is None else str(model_path),
        "contacts": [
            {"name": c.name, "mu": c.mu, "dist": c.dist, "slip": t.tolist(), "speed": float(v)}
            for c, t, v in zip(res.contacts, res.slip, res.speeds)
        ],
        "B": sp.B.tolist(),
        "a": sp.a.tolist(),
        "k": sp.k.tolist(),
        "c": sp.c.tolist(),
        "approximate_model": sp.approximate_model,
    }
    if sp.n_contacts == 2:
        out["invariants"] = sp.invariants()
    out.update({k: _plain(v) for k, v in res.verdicts().items()})
    return out


def _yes(v):
    return "consistent" if v else "inconsistent"


def meaning(rep) -> list[str]:
    """Short lines: what the verdicts say about the engine's behaviour at this state."""
    if len(rep["contacts"]) == 1:
        return [
            f"sliding: {_yes(rep['consistent_S'])}, "
            f"{'stable' if rep['stable_S'] else 'unstable (Painleve: b11 < 0)'}",
            f"lift-off: {_yes(rep['consistent_F'])}",
            f"jam (impact without collision): {_yes(rep['consistent_I'])}",
        ]
    lift = [m for m in ("FF", "SF", "FS") if rep[f"consistent_{m}"]]
    jams = [m for m in ("IF", "FI") if rep[f"consistent_{m}"]]
    if rep["consistent_II"] == Consistency.CONSISTENT:
        jams.append("II")
    ss = Verdict(rep["stable_SS"]).name.lower()
    return [
        f"both sliding (SS): {_yes(rep['consistent_SS'])}; stable for the approximate contact "
        f"model: {ss} (model-dependent: not a property of the rigid body)",
        "lift-off consistent: "
        + (", ".join(lift) or "none")
        + (
            " (a separation the engine shows in these modes is physical)"
            if lift
            else " (a separation the engine shows here is an artefact of its contact model)"
        ),
        "jam consistent: "
        + (", ".join(jams) or "none")
        + ("" if jams else " (a dead stop here is friction's, not a jam)"),
    ]


def _flag_name(key, v) -> str:
    """`` (stable)`` etc. for the verdict flags of SPEC §2."""
    if key in ("stable_SS", "stable_II"):
        return f" ({Verdict(v).name.lower()})"
    if key == "consistent_II":
        return f" ({Consistency(v).name.lower()})"
    return ""


def _text(rep) -> str:
    fmt = lambda xs: "[" + ", ".join(f"{x:.6g}" for x in xs) + "]"  # noqa: E731
    lines = [f"model: {rep['model']}"] if rep["model"] else []
    for c in rep["contacts"]:
        lines.append(
            f"contact {c['name']}: mu {c['mu']:.4g}, sliding {c['speed']:.4g} m/s along "
            f"{fmt(c['slip'])}, dist {c['dist']:.3g} m"
        )
    lines.append("B [1/kg] = [" + ", ".join(fmt(row) for row in rep["B"]) + "]")
    lines.append(f"a [m/s^2] = {fmt(rep['a'])}")
    lines.append(f"k [N/m] = {fmt(rep['k'])}, c [N s/m] = {fmt(rep['c'])} (approximate)")
    if "invariants" in rep:
        lines.append(", ".join(f"{k} = {v:.6g}" for k, v in rep["invariants"].items()))
    skip = {"model", "contacts", "B", "a", "k", "c", "approximate_model", "invariants"}
    lines += [f"{k} = {v}{_flag_name(k, v)}" for k, v in rep.items() if k not in skip]
    return "\n".join(lines + meaning(rep))


def run_cli(
    model, contacts=None, qpos=None, qvel=None, json_out=False, tol=bridge.TOUCH_TOL,
    rollout=None, every=None, jam_test=False, slip=None,
):  # fmt: skip
    """``atlas mujoco``: load, compute at the state (or along ``rollout`` seconds of MuJoCo's
    trajectory, judged every ``every`` steps, default 10), print (text or ``--json``); returns 0.
    An option of the other mode (``--every``, ``--jam-test`` without ``--rollout``; ``--slip``
    with it) is refused in one line naming it."""
    _check_mode(rollout, every, jam_test, slip)
    bridge.check_tol(tol)
    every = 10 if every is None else every
    mj_model, data = bridge.load(model)
    state = dict(qpos=_numbers("qpos", qpos), qvel=_numbers("qvel", qvel))
    if rollout is not None:
        from atlas.bridges import chatter  # noqa: PLC0415  (only with --rollout)
        from atlas.bridges import rollout as roll  # noqa: PLC0415

        tol = max(tol, 1e-4)  # a rollout's contacts penetrate: touching within 0.1 mm
        kw = dict(contacts=contacts, every=every, tol=tol, **state)
        try:
            res = roll.rollout(mj_model, data, rollout, **kw)
        except ValueError as err:  # the API's duration is the command line's --rollout
            if not str(err).startswith("duration:"):
                raise
            raise ValueError("rollout:" + str(err)[len("duration:") :]) from None
        rep = _rollout_report(res, model)
        rep["behaviour"] = chatter.behaviour(res)
        text = _rollout_text(res) + "\n" + chatter.text(rep["behaviour"])
        if jam_test:
            rep["jam_test"] = roll.jam_test(mj_model, data, rollout, **kw)
            text += "\n" + _jam_text(rep["jam_test"])
        print(json.dumps(rep) if json_out else text)
        return 0
    res = bridge.contact_data(
        mj_model, data, contacts=contacts, tol=tol, slip=_slips(slip), **state
    )
    rep = report(res, model)
    print(json.dumps(rep) if json_out else _text(rep))
    return 0


def _check_mode(rollout, every, jam_test, slip) -> None:
    """Refuse the options that the chosen mode (a state, or ``--rollout``) would ignore."""
    if rollout is None:
        for name, given in (("every", every is not None), ("jam_test", jam_test)):
            if given:
                raise ValueError(f"{name}: only with --rollout T (it applies to a rollout)")
    elif slip is not None:
        raise ValueError("slip: not with --rollout (a rollout takes its slip directions from "
                         "the trajectory)")  # fmt: skip


def _rollout_report(res, model) -> dict:
    return {
        "model": str(model),
        "contacts": list(res.contacts),
        "events": [{"t": t, "event": e} for t, e in res.events],
        "samples": res.samples,
        "seconds_per_sample": res.step_time,
    }


def _jam_text(jt) -> str:
    ms = lambda t: "none" if t is None else f"{t * 1e3:.1f} ms"  # noqa: E731
    line = f"stop: {ms(jt['stop'])}, with the time constants halved: {ms(jt['stop_halved'])}"
    if jt["kind"] is None:
        return line
    return line + f" (ratio {jt['ratio']:.2f}: {jt['kind']})"


def _rollout_text(res) -> str:
    lines = [f"contacts: {', '.join(res.contacts)}; {len(res.samples)} states judged"]
    lines += [f"t = {t:.4f} s: {e}" for t, e in res.events]
    return "\n".join(lines)
