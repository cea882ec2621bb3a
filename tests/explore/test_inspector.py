"""The point inspector (:func:`atlas.explore.inspect_point`) against the exact reference and the map."""

from __future__ import annotations

import math
import re

import numpy as np

from atlas.core.verdicts import OverModels, Verdict
from atlas.explore import inspector, maps

ALPHA = 0.35 * math.pi


def test_inspector_agrees_with_exact_and_map():
    ds = maps.compute_map(
        0.5, 2**0.5, n=33, layers=("class_code", "stable_SS", "consistent_II", "stable_II")
    )
    for i, j in ((3, 20), (10, 5), (25, 30)):
        b1, b2 = float(ds.beta1[i]), float(ds.beta2[j])
        info = inspector.inspect_point(b1, b2, ALPHA, kappa=0.5, q1=2**0.5)
        assert (
            info["class_code"] == int(ds["class_code"][i, j]) == info["exact_codes"]["class_code"]
        )
        assert info["spectral"] == info["spectral_exact"]
        for k in ("stable_SS", "consistent_II", "stable_II"):
            assert info["spectral"][k] == int(ds[k][i, j])
            assert info["spectral_fast"][k] in (info["spectral"][k], 3)
        assert len(info["eigenvalues"]) == 4
        np.testing.assert_allclose(
            np.sort_complex(info["eigenvalues"]),
            np.sort_complex(info["eigenvalues_exact"]),
            atol=1e-9,
        )
        assert "class" in inspector.format_inspection(info)


def test_roots_print_zero_parts_as_zero():
    """A float eig's rounding residue of an exact zero part prints like the exact root's 0."""
    eig = [-1.94e-16 + 0.96j, -1.94e-16 - 0.96j, -2.5 + 3e-17j, 1e-3]
    exact = [0.96j, -0.96j, -2.5, 1e-3]
    assert inspector.format_roots(eig) == inspector.format_roots(exact)
    assert inspector.format_roots(exact) == "+0+0.96i, +0-0.96i, -2.5+0i, +0.001+0i"
    # 6 significant digits of the largest modulus: small nonzero parts above that stay
    assert inspector.format_roots([1.0, 2e-5j]) == "+1+0i, +0+2e-05i"


def test_margins_line_prints_no_negative_zero():
    """Undamped (q = 0): the quartic's odd coefficients a3, a1 vanish (eq. 9: they carry Q);
    they print as +0, never -0, whatever sign the float zero has (a product with q = 0 can give
    -0.0)."""
    info = inspector.inspect_point(0.25 * math.pi, 0.75 * math.pi, ALPHA, kappa=0.5, q1=0.0)
    for sign in (1.0, -1.0):
        info["margins"]["a1"] = info["margins"]["a3"] = sign * 0.0
        line = next(s for s in inspector.format_inspection(info).splitlines() if "margins" in s)
        assert "a3 = +0," in line and "a1 = +0," in line, line
        assert not re.search(r"= -0(,|$)", line), line


def test_inspector_shows_the_witness_models_where_the_verdict_depends():
    """At a point of class 13 (``c1 > 0``, ``s2 > 0``, ``s1 c2 < 0``: SS depends on the model
    over the whole model space, closed form of ``atlas.core.model_box``) the inspection over the
    box says 'depends' and gives one model on each side, each on its side by the independent
    sympy/mpmath reference, and the text prints both; at a point of class 12 (stable for every
    model) no witness is shown; without a box nothing over models is shown."""
    from reference_sympy import point_spectral

    b1, b2 = 0.25 * math.pi, 0.6 * math.pi
    d = (math.cos(b1), math.sin(b1), math.cos(b2), math.sin(b2))
    assert d[0] > 0 and d[3] > 0 and d[1] * d[2] < 0 and d[0] * d[3] > d[1] * d[2]
    info = inspector.inspect_point(b1, b2, ALPHA, model_box=maps.WHOLE_BOX)
    v = info["over_models"]["verdicts"]["ss_over_models"]
    assert v["code"] == OverModels.DEPENDS and set(v["witnesses"]) == {"stable", "unstable"}
    text = inspector.format_inspection(info)
    assert f"ss_over_models over the model box {maps.WHOLE_BOX}: depends on the model" in text
    for side, w in v["witnesses"].items():
        ref = int(point_spectral(*d, *w["model"])["stable_SS"])
        assert (ref in (Verdict.STABLE, Verdict.NEUTRAL)) == (side == "stable"), (side, w, ref)
        assert w["exact"]["stable_SS"] == ref
        k, q1, q2 = w["model"]
        assert f"{side} witness: kappa = {k:.6g}, q1 = {q1:.6g}, q2 = {q2:.6g}" in text
    info = inspector.inspect_point(0.1 * math.pi, 0.4 * math.pi, model_box="kappa=1:2")
    v = info["over_models"]["verdicts"]["ss_over_models"]
    assert v == {"code": OverModels.STABLE, "witnesses": {}}
    assert "witness" not in inspector.format_inspection(info)
    assert "over_models" not in inspector.inspect_point(b1, b2)
