"""What a simulator does along a rollout -- lift-off, chatter, stop -- set against the theory.

**The engine's side**, from a :class:`atlas.bridges.rollout.Rollout` (its sampled states, every
``every`` steps: a make or break between two samples is not seen).  A contact *breaks* at a sample
where it touched (``dist <= tol``) at the previous sample and does not now, and *makes* contact
where it did not and does.  **Lift-off**: a contact breaks.  **Chatter**: a contact breaks and
makes contact again at least ``repeats`` times (default 2): repeated make / break.  **Stop**: a
touching contact stops sliding (a jam or a friction stop: ``jam_test`` tells them apart).

**The theory's side**, at the last judged sample before the first break (the sliding state the
engine leaves; paper Sec. 3-5):

* a separation the rigid body allows: a consistent lift-off mode (two contacts: SF, FS, FF; one:
  F); after it, bounces of decreasing height are ordinary chattering, which is physical;
* inverse chattering (bounces of increasing height, Sec. 5.2): with one contact never (CF, FC need
  a restitution above 1); with two, CC only where ``b11 > 0`` and ``b22 > 0`` (``cc_possible``, a
  necessary condition only);
* sliding: consistent and stable (two contacts: ``consistent_SS`` and ``stable_SS`` stable for the
  bridge's approximate contact model; one: ``consistent_S`` and ``stable_S``).

**Judgement** of a lift-off or chatter: ``"solver"`` where sliding is consistent and stable and
the rigid body allows no separation (no lift-off mode consistent, inverse chattering excluded):
the rigid body keeps sliding, so the make / break is the solver's; ``"allowed"`` where a lift-off
mode is consistent or CC's necessary condition holds: the theory does not exclude it, and cannot
confirm it (the condition is only necessary); ``"open"`` otherwise (sliding inconsistent or
unstable and no separation consistent: a contact dynamics outside the modes the theory lists, as
the paper's Sec. 6.5); ``"unjudged"`` where no judged sample precedes the first break.
"""

from __future__ import annotations

__all__ = ["behaviour", "text", "REPEATS"]

#: make / break cycles of one contact that count as chatter
REPEATS = 2


def _changes(samples, j):
    """Times [s] where contact ``j`` breaks and where it makes contact again."""
    breaks, makes = [], []
    for prev, s in zip(samples, samples[1:]):
        was, now = prev["touching"][j], s["touching"][j]
        if was and not now:
            breaks.append(s["t"])
        elif now and not was:
            makes.append(s["t"])
    return breaks, makes


def _engine(res, repeats):
    """Per contact: breaks, makes, and whether it chatters; the first stop [s] (``None``)."""
    contacts = []
    for j, name in enumerate(res.contacts):
        breaks, makes = _changes(res.samples, j)
        remade = [t for t in makes if breaks and t > breaks[0]]
        contacts.append(
            dict(name=name, breaks=len(breaks), makes=len(remade),
                 first_break=breaks[0] if breaks else None, chatter=len(remade) >= repeats)
        )  # fmt: skip
    stop = next(
        (s["t"] for s in res.samples[1:]
         if any(t and not sl for t, sl in zip(s["touching"], s["sliding"]))),
        None,
    )  # fmt: skip
    return contacts, stop


def _theory(v) -> dict:
    """The theory's side at one judged sample's verdicts ``v`` (module docstring)."""
    if "consistent_S" in v:  # one contact
        return dict(lift_off=["F"] if v["consistent_F"] else [], inverse_chattering=False,
                    sliding=bool(v["consistent_S"] and v["stable_S"]))  # fmt: skip
    return dict(
        lift_off=[m for m in ("SF", "FS", "FF") if v[f"consistent_{m}"]],
        inverse_chattering=bool(v["cc_possible"]),
        sliding=bool(v["consistent_SS"] and v["stable_SS"] == 1),
    )


def _judge(theory) -> str:
    if theory is None:
        return "unjudged"
    if theory["lift_off"] or theory["inverse_chattering"]:
        return "allowed"
    return "solver" if theory["sliding"] else "open"


def behaviour(res, repeats=REPEATS) -> dict:
    """The engine's lift-offs, chatter and stop along the rollout ``res`` and the theory's
    judgement of the first separation (module docstring).  Returns ``kind`` (``"chatter"``,
    ``"lift-off"``, ``"stop"`` or ``"sliding"``), ``contacts`` (per contact: ``breaks``,
    ``makes`` after the first break, ``first_break`` [s], ``chatter``), ``stop`` [s],
    ``judged_at`` [s] and ``theory`` (the verdicts' side there) and ``judgement``."""
    contacts, stop = _engine(res, repeats)
    first = min((c["first_break"] for c in contacts if c["breaks"]), default=None)
    if any(c["chatter"] for c in contacts):
        kind = "chatter"
    elif first is not None:
        kind = "lift-off"
    else:
        kind = "stop" if stop is not None else "sliding"
    out = dict(kind=kind, repeats=repeats, contacts=contacts, stop=stop, judged_at=None,
               theory=None, judgement=None)  # fmt: skip
    if first is None:
        return out
    before = [s for s in res.samples if s["t"] < first and s["verdicts"] is not None]
    if before:
        out["judged_at"] = before[-1]["t"]
        out["theory"] = _theory(before[-1]["verdicts"])
    out["judgement"] = _judge(out["theory"])
    return out


def text(b) -> str:
    """One line: what the engine did and the theory's judgement of it."""
    moving = [c for c in b["contacts"] if c["breaks"]]
    what = ", ".join(
        f"{c['name']} breaks {c['breaks']}x, makes contact again {c['makes']}x "
        f"(first break {c['first_break'] * 1e3:.1f} ms)"
        for c in moving
    )
    line = f"engine: {b['kind']}" + (f" ({what})" if what else "")
    if b["judgement"] is None:
        return line
    words = {
        "solver": "the rigid body keeps sliding (no lift-off consistent, inverse chattering "
        "excluded): the make/break is the solver's",
        "allowed": "the rigid body does not exclude it (lift-off consistent: "
        + (", ".join(b["theory"]["lift_off"]) or "none")
        + f"; CC's necessary condition b11, b22 > 0: {b['theory']['inverse_chattering']})",
        "open": "sliding inconsistent or unstable and no separation consistent: outside the "
        "modes the theory lists",
        "unjudged": "no judged sliding state before the first break",
    }
    at = "" if b["judged_at"] is None else f" at {b['judged_at'] * 1e3:.1f} ms"
    return f"{line}; theory{at}: {words[b['judgement']]}"
