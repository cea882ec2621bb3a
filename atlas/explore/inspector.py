"""The point inspector: everything the theory says about one point ``(beta1, beta2, alpha)``.

:func:`inspect_point` gives the class and subclass codes, Table 1 consistency, SF/FS stability,
IF/FI, CC, the SS and II verdicts of the certified path *and* of the exact reference, the
eigenvalues of ``M`` and the margins and, given a model box, the verdicts over the box with their
witness models (:func:`over_models_at`); :func:`format_inspection` is the widget's text for it.
"""

from __future__ import annotations

import math
import operator

import numpy as np

from atlas.core import baseline, exact, expressions, hurwitz, points, spectral, warm
from atlas.core import contact_modes as mech
from atlas.core.rigid_body import verdicts_at
from atlas.data.outputs import OUTPUTS, kernel_of, verdict_outputs
from atlas.explore.colors import raw_label, value_label
from atlas.explore.maps import box_layers, box_values, checked_model, witness_outputs

__all__ = ["inspect_point", "format_inspection", "format_roots", "over_models_at"]

#: the spectral verdicts (those the certified path may leave undecided: stable_SS, consistent_II,
#: stable_II), from the registry
_FLAGS = tuple(kernel_of("stable_SS").undecided)
#: the outputs the inspector shows in its own lines; every other verdict of the registry is listed
#: under ``others``
_SHOWN = (
    "class_code",
    "subclass_code",
    "consistent_FF",
    "consistent_SF",
    "consistent_FS",
    "consistent_SS",
    "stable_SF",
    "stable_FS",
    "consistent_IF",
    "consistent_FI",
    "cc_possible",
    "spectral_abscissa",
    *_FLAGS,
)
_SOURCES = (
    ("spectral_fast", "certified fast path"),
    ("spectral", "certified + exact"),
    ("spectral_exact", "exact reference"),
)


def _direction(angle, dt) -> tuple[np.ndarray, np.ndarray]:
    c, s = (np.asarray(x, dt) for x in mech.direction(float(angle), dt))
    return c, s


@warm.jit
def _point_arrays(c1, s1, c2, s2, ca, sa, kappa, q1, q2) -> dict:
    """The float kernels' values at one point, as one compiled program (kept across sessions by
    :mod:`atlas.core.warm`; one call instead of ~80 small programs compiled on the first click):
    class and subclass codes, SF/FS stability, IF/FI, CC, Table 1 consistency, the smooth SS
    margin, the quartic's coefficients and ``M`` (eq. 9)."""
    j = (c1, s1, c2, s2)
    model = (kappa, q1, q2)
    return {
        "class_code": mech.class_code(*j),
        "subclass_code": mech.subclass_code(*j, ca, sa),
        "consistency": mech.consistent_modes(*j, ca, sa),
        "stable_SF": mech.stable_SF(c1),
        "stable_FS": mech.stable_FS(s2),
        "consistent_IF": mech.consistent_IF(c1, s1),
        "consistent_FI": mech.consistent_FI(c2, s2),
        "cc_possible": mech.cc_possible(c1, s2),
        "ss_margin": hurwitz.ss_margin(*j, *model),
        "coefficients": spectral.coefficients(*j, *model),
        "M": baseline.build_M(*j, *model),
    }


def _angle_verdicts(arr: dict) -> dict:
    """Class code, SF/FS stability, IF/FI consistency and CC of ``b1 = (c1, s1)``, ``b2``."""
    return {
        "class_code": int(arr["class_code"]),
        **{k: int(arr[k]) for k in ("stable_SF", "stable_FS")},
        **{k: bool(arr[k]) for k in ("consistent_IF", "consistent_FI", "cc_possible")},
    }


def _alpha_verdicts(alpha, dirs: tuple, a: tuple, arr: dict) -> dict:
    """Subclass code and Table 1 consistency (fast and exact); without ``alpha`` the class only."""
    if alpha is None:
        return {
            "subclass_code": None,
            "consistency": None,
            "exact_codes": exact.point_codes(*dirs),
        }
    return {
        "a": (float(a[0]), float(a[1])),
        "subclass_code": int(arr["subclass_code"]),
        "consistency": {k: int(v) for k, v in arr["consistency"].items()},
        "exact_codes": exact.point_codes(*dirs, *a),
    }


def _sorted_by_real_part(w) -> np.ndarray:
    w = np.asarray(w)
    return w[np.argsort(-w.real, kind="stable")]


def _margins(arr: dict, dirs, fast, ref) -> dict:
    """The smooth SS margin, ``det B``, the quartic's coefficients and the spectral abscissa."""
    c1, s1, c2, s2 = (float(v) for v in dirs)
    a3, a2, a1, a0 = (float(x) for x in arr["coefficients"])
    return {
        "ss_margin": float(arr["ss_margin"]),
        "det_B": expressions.det(c1, s1, c2, s2, sub=operator.sub),
        "a3": a3,
        "a2": a2,
        "a1": a1,
        "a0": a0,
        "spectral_abscissa": float(fast["spectral_abscissa"]),
        "spectral_abscissa_exact": float(ref["spectral_abscissa"]),
    }


def _spectrum(dirs: tuple, model: tuple, arr: dict, dt) -> dict:
    """SS and II verdicts of the fast path, the settled path and the exact reference; ``M``, its
    eigenvalues (``numpy`` and exact) and the margins."""
    pt = [np.asarray(v, dt) for v in dirs] + [dt.type(v) for v in model]
    fast = points.spectral_points(*pt, names=points.SPECTRAL_NAMES, dtype=dt, resolve=False)
    settled = points.spectral_points(*pt, names=points.SPECTRAL_NAMES, dtype=dt, resolve=True)
    ref = exact.point_spectral(*(float(v) for v in pt))
    M = np.asarray(arr["M"])
    return {
        "spectral_fast": {k: int(fast[k]) for k in _FLAGS},
        "spectral": {k: int(settled[k]) for k in _FLAGS},
        "spectral_exact": {k: int(ref[k]) for k in _FLAGS},
        "M": M,
        "eigenvalues": _sorted_by_real_part(np.linalg.eigvals(M.astype(np.float64))),
        "eigenvalues_exact": _sorted_by_real_part(np.asarray(ref["roots"], complex)),
        "margins": _margins(arr, dirs, fast, ref),
    }


def _labels(out: dict) -> dict:
    """The verdicts of an inspection in words (the registry's declared words for each output's
    raw codes, :func:`atlas.explore.colors.raw_label`)."""
    lab = {k: raw_label(k, out[k]) for k in ("class_code", "stable_SF", "stable_FS")}
    if out["subclass_code"] is not None:
        lab["subclass_code"] = raw_label("subclass_code", out["subclass_code"])
    for src, _ in _SOURCES:
        lab[src] = {k: raw_label(k, v) for k, v in out[src].items()}
    if out["consistency"] is not None:
        lab["consistency"] = {
            k: raw_label(f"consistent_{k}", v) for k, v in out["consistency"].items()
        }
    return lab


def _others(point: tuple, alpha, model: tuple, dt) -> dict:
    """The registry's other verdicts at the point (stored values; those needing ``alpha`` only
    with it)."""
    names = tuple(
        n
        for n in verdict_outputs()
        if n not in _SHOWN and (alpha is not None or "alpha" not in OUTPUTS[n].depends)
    )
    if not names:
        return {}
    a = 0.0 if alpha is None else float(alpha)
    res = verdicts_at(*point, a, *model, dtype=dt, names=names)
    return {k: v[()] for k, v in res.items()}


def _witness(dirs: tuple, model: tuple) -> dict:
    """A witness model and the exact reference's SS and II verdicts there."""
    ref = exact.point_spectral(*(float(v) for v in dirs), *model)
    return {"model": model, "exact": {k: int(ref[k]) for k in _FLAGS}}


def over_models_at(beta1, beta2, model_box=None, dtype="float64") -> dict:
    """The verdicts over ``model_box`` (every box layer, :func:`atlas.explore.maps.box_layers`) at
    ``(beta1, beta2)`` [rad]: ``{"model_box": text, "verdicts": {name: {"code", "witnesses"}}}``,
    ``witnesses`` (where the code is "depends") mapping each side to its model ``(kappa, q1,
    q2)`` and the exact reference's ``stable_SS``, ``consistent_II``, ``stable_II`` there (an
    independent look at the witness)."""
    dt = np.dtype(dtype)
    names = box_layers()
    ds = box_values([float(beta1)], [float(beta2)], names, model_box, dt)
    dirs = _direction(beta1, dt) + _direction(beta2, dt)
    verdicts = {}
    for name in names:
        wit = {}
        for side, var in witness_outputs(name).items():
            m = tuple(float(ds[v].values.ravel()[0]) for v in var)
            if all(math.isfinite(x) for x in m):
                wit[side] = _witness(dirs, m)
        verdicts[name] = {"code": int(ds[name].values.ravel()[0]), "witnesses": wit}
    return {"model_box": ds.attrs["model_box"], "verdicts": verdicts}


def inspect_point(
    beta1, beta2, alpha=None, kappa=0.5, q1=0.0, q2=None, dtype="float64", model_box=None
) -> dict:
    """Everything the theory says about one point ``(beta1, beta2, alpha)`` [rad] at ``(kappa, q)``.

    Returns a dict with

    * ``class_code``, ``subclass_code`` (certified fast path) and ``exact_codes`` (exact reference:
      class, subclass and Table 1 consistency),
    * ``consistency``: Table 1 verdicts of FF, SF, FS, SS (``Consistency`` codes; needs ``alpha``),
    * ``stable_SF``, ``stable_FS`` (``Verdict`` codes), ``consistent_IF``, ``consistent_FI``,
      ``cc_possible`` (bool),
    * ``spectral_fast`` (certified kernels, not settled: may hold ``undecided``),
      ``spectral`` (certified + exact settlement) and ``spectral_exact`` (the exact reference alone),
      each with ``stable_SS``, ``consistent_II``, ``stable_II``,
    * ``eigenvalues`` of ``M`` (``numpy.linalg.eigvals``, sorted by real part) and
      ``eigenvalues_exact`` (>= 60-digit roots of the characteristic polynomial),
    * ``margins``: ``ss_margin`` (smooth SS margin), ``det_B``, the quartic's coefficients
      ``a3 a2 a1 a0``, ``spectral_abscissa``,
    * ``others``: every other verdict of the output registry (stored values),
    * ``labels``: the verdicts in words,
    * ``over_models`` (only with ``model_box``, text or :class:`~atlas.core.model_box.ModelBox`):
      :func:`over_models_at`, the verdicts over the box and the witness models.
    """
    dt = np.dtype(dtype)
    kappa, q1, q2 = model = checked_model(kappa, q1, q2)
    dirs = _direction(beta1, dt) + _direction(beta2, dt)  # c1, s1, c2, s2
    c1, s1, c2, s2 = dirs
    a = _direction(0.0 if alpha is None else alpha, dt)  # (1, 0) without alpha: results unused
    arr = _point_arrays(*dirs, *a, *(np.asarray(v, dt) for v in model))
    out = {
        "beta1": float(beta1),
        "beta2": float(beta2),
        "alpha": None if alpha is None else float(alpha),
        "kappa": kappa,
        "q1": q1,
        "q2": q2,
        "b1": (float(c1), float(s1)),
        "b2": (float(c2), float(s2)),
        **_angle_verdicts(arr),
        **_alpha_verdicts(alpha, dirs, a, arr),
        **_spectrum(dirs, model, arr, dt),
        "others": _others((float(beta1), float(beta2)), alpha, model, dt),
    }
    if model_box is not None:
        out["over_models"] = over_models_at(beta1, beta2, model_box, dt)
    out["labels"] = _labels(out)
    return out


def format_roots(roots, digits: int = 6) -> str:
    """Complex roots to ``digits`` significant digits of the largest modulus: parts below that
    resolution (a float ``eig``'s ``-1.9e-16`` for an exact 0) print as ``+0``, like the exact
    reference's."""
    z = np.asarray(roots, complex)
    scale = float(np.max(np.abs(z))) if z.size else 0.0
    unit = 10.0 ** (math.floor(math.log10(scale)) - digits + 1) if scale > 0 else 1.0

    def part(x: float) -> str:
        v = round(x / unit) * unit
        return f"{v if v != 0 else 0.0:+.{digits}g}"

    return ", ".join(f"{part(w.real)}{part(w.imag)}i" for w in z)


def _codes_lines(info: dict) -> list[str]:
    """Point, model, class and subclass codes, Table 1 consistency."""
    pi = math.pi
    ex, lab = info["exact_codes"], info["labels"]
    lines = [
        f"beta1 = {info['beta1']:.6g} ({info['beta1'] / pi:.4f} pi), "
        f"beta2 = {info['beta2']:.6g} ({info['beta2'] / pi:.4f} pi)"
        + ("" if info["alpha"] is None else f", alpha = {info['alpha'] / pi:.4f} pi"),
        f"kappa = {info['kappa']:.6g}, q1 = {info['q1']:.6g}, q2 = {info['q2']:.6g}",
        f"{_named('class_code', lab)} (exact {ex['class_code']})"
        + (
            ""
            if info["subclass_code"] is None
            else f", {_named('subclass_code', lab)} (exact {ex['subclass_code']})"
        ),
    ]
    if info["consistency"] is not None:
        cons = ", ".join(
            f"{m}: {lab['consistency'][m]} (exact {bool(ex['consistent_' + m])})"
            for m in ("FF", "SF", "FS", "SS")
        )
        lines.append(f"Table 1 consistency -- {cons}")
    return lines


def _named(name: str, labels: dict) -> str:
    """The label of output ``name``, led by the name where the label does not say it (``class
    23``, but ``class_code: degenerate``)."""
    label = labels[name]
    return label if label.split()[0] == name.split("_")[0] else f"{name}: {label}"


def _stability_lines(info: dict) -> list[str]:
    """One-contact modes, IF/FI/CC, and the SS and II verdicts of the three sources."""
    lab = info["labels"]
    lines = [
        f"SF: {lab['stable_SF']} (b11 = {_signed(info['b1'][0])}); "
        f"FS: {lab['stable_FS']} (b22 = {_signed(info['b2'][1])}); FF: stable when consistent",
        f"IF consistent (and stable): {info['consistent_IF']}; FI: {info['consistent_FI']}; "
        f"CC possible: {info['cc_possible']}",
    ]
    for src, name in _SOURCES:
        d = lab[src]
        lines.append(
            f"{name:>20}: SS {d['stable_SS']}, II {d['consistent_II']}, "
            f"II stability {d['stable_II']}"
        )
    return lines


def _signed(x: float, spec: str = "+.4g") -> str:
    """``x`` with its sign, a zero as ``+0`` (never ``-0``)."""
    return f"{float(x) + 0.0:{spec}}"  # -0.0 + 0.0 is +0.0


def _spectrum_lines(info: dict) -> list[str]:
    m = info["margins"]
    others = ", ".join(f"{k}: {value_label(k, v)}" for k, v in info["others"].items())
    return ([f"other outputs -- {others}"] if others else []) + [
        "eigenvalues of M (eig): " + format_roots(info["eigenvalues"]),
        "eigenvalues (exact ref): " + format_roots(info["eigenvalues_exact"]),
        f"margins: ss_margin = {_signed(m['ss_margin'])}, det B = {_signed(m['det_B'])}, "
        f"a3 = {_signed(m['a3'])}, a2 = {_signed(m['a2'])}, a1 = {_signed(m['a1'])}, "
        f"a0 = {_signed(m['a0'])}, "
        f"spectral abscissa = {_signed(m['spectral_abscissa_exact'], '+.6g')}",
    ]


def _over_models_lines(info: dict) -> list[str]:
    """Each verdict over the model box, and its witness models (with the exact reference's
    verdicts there) where it depends on the model."""
    om = info.get("over_models")
    if om is None:
        return []
    lines = []
    for name, v in om["verdicts"].items():
        lines.append(f"{name} over the model box {om['model_box']}: {value_label(name, v['code'])}")
        for side, w in v["witnesses"].items():
            k, q1, q2 = w["model"]
            e = w["exact"]
            lines.append(
                f"  {side} witness: kappa = {k:.6g}, q1 = {q1:.6g}, q2 = {q2:.6g} (exact "
                f"reference there: SS {raw_label('stable_SS', e['stable_SS'])}, II "
                f"{raw_label('consistent_II', e['consistent_II'])}, II stability "
                f"{raw_label('stable_II', e['stable_II'])})"
            )
    return lines


def format_inspection(info: dict) -> str:
    """The inspector's text for a result of :func:`inspect_point`."""
    return "\n".join(
        _codes_lines(info) + _over_models_lines(info) + _stability_lines(info)
        + _spectrum_lines(info)
    )  # fmt: skip
