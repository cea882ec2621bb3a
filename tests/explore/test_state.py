"""The widget's state without ipywidgets (:class:`atlas.explore.Explorer`): what a control change
recomputes, the capped settlement and the one-line errors; the kept kernels' switches."""

from __future__ import annotations

import json
import math
import subprocess
import sys

import numpy as np
import pytest

from atlas.explore import maps, state

_SWITCH_PROBE = """
import json, sys, jax
from atlas.explore import state
assert "ipywidgets" not in sys.modules  # the explorer's state imports without the widgets
print(json.dumps(dict(kept=state.keep_kernels(), cache=jax.config.jax_compilation_cache_dir)))
"""


def test_keep_kernels_follows_the_cli_switches(tmp_path, probe_env):
    """``ATLAS_KERNEL_CACHE=0`` leaves an explorer's kept kernels off, ``ATLAS_JAX_CACHE=0`` the
    compilation cache too (with neither, its sessions keep kernels in ``<cache>/kernels`` and use
    the compilation cache: tests/explore/test_widget.py's fresh sessions, e2e).  The same fresh
    processes show that :mod:`atlas.explore` imports without ipywidgets."""
    cases = {
        "no kept kernels": ({"ATLAS_KERNEL_CACHE": "0"}, None, str(tmp_path)),
        "no caches": ({}, None, None),
    }
    procs = {}
    for name, (switches, _, _) in cases.items():
        cache = "0" if name == "no caches" else tmp_path
        cmd = [sys.executable, "-c", _SWITCH_PROBE]
        env = probe_env(cache, **switches)
        procs[name] = subprocess.Popen(
            cmd, env=env, cwd=tmp_path, stdout=subprocess.PIPE, text=True
        )
    for name, (_, kept, cache) in cases.items():
        out, _ = procs[name].communicate(timeout=300)
        assert procs[name].returncode == 0, name
        got = json.loads(out.strip().splitlines()[-1])
        assert (got["kept"], got["cache"] or None) == (kept, cache), name


def test_layers_of_a_group_share_one_computation():
    ex = state.Explorer(n=9, layer="consistent_II", kappa=0.5, q1=0.3, overlays=())
    ds = ex.update()
    assert set(ds.data_vars) == {"consistent_II", "stable_II"}
    assert ex.update(layer="stable_II") is ds and ex.timings["compute_ms"] == 0.0
    assert ex.update(alpha=1.0) is ds  # the II verdicts do not depend on alpha
    assert ex.update(kappa=0.6) is not ds and ex.timings["compute_ms"] > 0  # the model moved
    cls = ex.update(layer="class_code")
    assert set(cls.data_vars) == {"class_code", "cc_possible"}
    assert ex.update(kappa=0.7, q1=0.1) is cls  # class codes do not depend on the model


def test_capped_redraw_then_settle_equals_the_settled_map(bounded_det_b):
    n, cap = 16, 2  # even: cells on det B = 0 are undecided (float-bounded sign det B)
    ex = state.Explorer(n=n, layer="stable_SS", kappa=0.5, q1=0.3, max_resolve=cap, overlays=())
    fast = ex.update().attrs["n_undecided_fast"]
    assert fast > cap and ex.ds.attrs["n_undecided"] == fast - cap
    settled = ex.settle()
    assert settled.attrs["n_undecided"] == 0 and settled.attrs["n_undecided_fast"] == fast
    want = maps.compute_map(0.5, 0.3, n=n, layers=("stable_SS",))
    assert (settled["stable_SS"].values == want["stable_SS"].values).all()


@pytest.mark.parametrize(
    "changes, name",
    [
        (dict(layer="nope"), "layer"),
        (dict(overlays=("nope",)), "overlays"),
        (dict(max_resolve=-1), "max_resolve"),
        (dict(kappa=0.0), "kappa"),
        (dict(q2=-0.1), "q2"),
        (dict(speed=1), "speed"),
        (dict(model_box="kappa=2:1"), "model_box"),
        (dict(layer="ss_over_models", model_box="q1=0:1,q=0:1"), "model_box"),
    ],
)
def test_bad_changes_name_the_parameter(changes, name):
    ex = state.Explorer(n=9, overlays=())
    with pytest.raises(ValueError, match=name):
        ex.update(**changes)
    assert ex.ds is None  # nothing computed, parameters unchanged
    assert ex.params["layer"] == "stable_SS"


def test_box_layer_follows_the_model_box_not_the_model():
    """``ss_over_models`` is computed over the model box: moving kappa, q or alpha recomputes
    nothing, a new box does; the status names the box; a click adds the verdict over the box
    to the inspection (and only on a box layer)."""
    ex = state.Explorer(n=9, layer="ss_over_models", overlays=())
    ds = ex.update()
    assert ds.attrs["model_box"] == maps.WHOLE_BOX
    assert ex.status().startswith(f"ss_over_models over the model box {maps.WHOLE_BOX}, 9^2")
    assert ex.update(kappa=3.0, q1=0.2, q2=0.7, alpha=1.0) is ds
    assert ex.timings["compute_ms"] == 0.0
    box = ex.update(model_box="kappa=0.5:2,q=0:1")
    assert box is not ds and box.attrs["model_box"] == "kappa=0.5:2,q=0:1"
    assert "over the model box kappa=0.5:2,q=0:1" in ex.status()
    assert ex.inspect(0.25 * math.pi, 0.6 * math.pi)["over_models"]["model_box"] == (
        "kappa=0.5:2,q=0:1"
    )
    ex.update(layer="stable_SS")
    assert "over_models" not in ex.inspect(0.25 * math.pi, 0.6 * math.pi)


def test_box_layer_certified_boundaries_and_a_click_next_to_one():
    """With a box layer the "certified boundaries" overlay computes the region curves over the
    model box (in the background); a click next to a closed vertex names its kind and the codes
    on its two sides in words, which the exact closed form of the whole model space gives at the
    vertex's bracket ends."""
    from fractions import Fraction

    from atlas.core import contact_modes as mech
    from atlas.core.verdicts import OverModels

    ex = state.Explorer(n=9, layer="ss_over_models", overlays=("certified boundaries",))
    ex.update()
    assert ex.boundary_key() == ("ss_over_models", maps.WHOLE_BOX)
    ex.boundaries()  # starts the computation
    b = ex._curves[ex.boundary_key()].result(timeout=900)
    assert b.curves and {c.field for c in b.curves} == {"ss_over_models"}
    c = max(b.curves, key=lambda c: int(np.sum(c.bracket <= 1e-8)))
    i = int(np.flatnonzero(c.bracket <= 1e-8)[0])
    v = c.vertices[i]
    ex.inspect(v[0] + 1e-3, v[1] + 1e-3)
    line = ex.last_near[-1]
    left, right = OverModels(c.side_left).label, OverModels(c.side_right).label
    assert "near the certified ss_over_models_region boundary" in line
    assert f"{left} | {right}" in line, line

    def closed_form(p):
        c1, s1 = (Fraction(float(x)) for x in mech.direction(p[0]))
        c2, s2 = (Fraction(float(x)) for x in mech.direction(p[1]))
        if c1 * s2 - s1 * c2 < 0 or (c1 <= 0 and s2 <= 0):
            return OverModels.UNSTABLE
        return OverModels.STABLE if c1 > 0 and s2 > 0 and s1 * c2 >= 0 else OverModels.DEPENDS

    got = ex.nearest_boundary(v[0] + 1e-3, v[1] + 1e-3)
    lo, hi = got[0].ends[got[1]]
    assert {closed_form(lo).label, closed_form(hi).label} == {left, right}


def test_a_first_overlay_does_not_wait_for_the_warm_up(monkeypatch):
    """The certified overlay is computed while the background warm-up still compiles the later
    tiers' programs: its small open point sets go to the exact tier meanwhile
    (:func:`atlas.core.points.host_first` with :data:`state.HOST_POINTS`)."""
    import threading

    from atlas.core import points

    gate, order = threading.Event(), []
    monkeypatch.setattr(state, "_warm_up", lambda **m: gate.wait(60) and order.append("warm-up"))

    def task():
        order.append(("overlay", points._host_limit(True, None)))
        return "curves"

    monkeypatch.setattr(points, "_LATER_RAN", set())
    monkeypatch.setattr(state, "_boundary_task", lambda key, dtype: (task,))
    ex = state.Explorer(n=9, overlays=("certified boundaries",))
    warm = ex.warm_up()
    try:
        ex.boundaries()  # starts the computation
        assert ex._curves[ex.boundary_key()].result(timeout=60) == "curves"
        assert order == [("overlay", state.HOST_POINTS)]  # the warm-up still waits
    finally:
        gate.set()
    warm.result(timeout=60)
    assert order[-1] == "warm-up"


def test_the_warm_up_waits_while_a_first_overlay_is_computed(monkeypatch):
    """The warm-up's later-tier programs wait for the overlay (their tracing holds the
    interpreter lock the overlay needs); its inspection does not, and a click waits for that
    inspection only."""
    import threading
    import time

    from atlas.core import points

    started, inspected, order = threading.Event(), threading.Event(), []

    def fake_inspect(*a, **k):
        order.append("inspection")
        inspected.set()
        return {}

    def fake_programs(dtype, before_each):
        before_each()
        order.append("programs")

    def task():
        started.set()
        inspected.wait(60)
        time.sleep(0.2)  # room for a warm-up that does not wait to run its programs first
        order.append("overlay")
        return "curves"

    monkeypatch.setattr(state, "inspect_point", fake_inspect)
    monkeypatch.setattr(points, "compile_programs", fake_programs)
    monkeypatch.setattr(state, "_boundary_task", lambda key, dtype: (task,))
    ex = state.Explorer(n=9, overlays=("certified boundaries",))
    ex.boundaries()
    started.wait(60)
    warm = ex.warm_up()
    assert ex._curves[ex.boundary_key()].result(timeout=60) == "curves"
    warm.result(timeout=60)
    assert order == ["inspection", "overlay", "programs"]
