"""Table 2 of the paper, regenerated from the kernels (never typed in).

For each of the 24 classes: the dual class, the subclasses in which FF, SS, SF, FS are consistent, each
mode's stability over the class (``stable`` / ``unstable`` / ``model-dependent``: the verdict changes
over the class's sample of (beta1, beta2) and of the kappa-q sample :data:`KAPPA_Q_SAMPLE`, with
``neutral`` counted as stable as in Fig. 1), the IF, FI, II markers (``x`` consistent throughout,
``(x)`` model-dependent, ``-`` never; II also gets a stability word) and the CC marker (``?`` where the
necessary condition ``b11 > 0, b22 > 0`` holds).

The SS word, the II marker and the II stability word (the light shading: model-dependent) are then
taken from the verdicts over *every* contact model (:mod:`atlas.core.model_box`,
:mod:`atlas.core.ii_over_models`: proved, or witnessed on both sides) at the class's sample of
geometries wherever those decide the word (:func:`over_models_words`); where they do not (a
geometry left undecided), the finite sample's word stays and the row's ``notes`` say so, as they
say where the two differ.

Sampling: class interiors come from an offset grid of ``n x n`` angles (no grid point lies on an axis;
those on ``beta2 = beta1`` or ``beta2 = beta1 + pi`` are left out), closed under the dual map; each subclass is sampled with ``n_alpha`` offset values of alpha.  Points the
fast kernels leave undecided are settled by :mod:`atlas.core.exact`.
"""

from __future__ import annotations

import csv
import io
import math
import os
from dataclasses import dataclass, field

import jax.numpy as jnp
import numpy as np

from atlas.core import buckets, checks, contact_modes, exact
from atlas.core import ii_over_models as iim
from atlas.core import model_box as mb
from atlas.core.points import spectral_points
from atlas.core.verdicts import Consistency, OverModels, Verdict

__all__ = [
    "table2",
    "class_samples",
    "class_kernel",
    "dual_kq",
    "to_markdown",
    "to_csv",
    "run_cli",
    "KAPPA_Q_SAMPLE",
    "over_models_words",
    "over_models_codes",
    "Row",
    "KEY",
]


def dual_kq(kappa, q1, q2):
    """``(kappa, q1, q2)`` of the dual system (contact indices swapped, SPEC §1).

    ``kappa = k1|b1|/(k2|b2|)`` becomes ``1/kappa``; the damping is scaled by contact 2, which is
    the old contact 1 after the swap, so ``q1' = q2/sqrt(kappa)`` and ``q2' = q1/sqrt(kappa)``
    (time rescaled by ``sqrt(kappa)``: eigenvalues scale, stability verdicts do not change).
    """
    r = math.sqrt(kappa)
    return (1.0 / kappa, q2 / r, q1 / r)


def _closed_under_dual(base) -> tuple:
    out = []
    for t in base:
        for u in (t, dual_kq(*t)):
            u = tuple(float(f"{x:.12g}") for x in u)  # 1/(1/k) etc. land on the same values
            if u not in out:
                out.append(u)
    return tuple(out)


#: kappa ladder of the model-dependence sample (symmetric under kappa -> 1/kappa)
KAPPAS = (1e-5, 1e-3, 0.1, 0.5, 1.0, 2.0, 10.0, 1e3, 1e5)
#: damping pairs (q1, q2) of the sample before closing it under the dual map
Q_PAIRS = (
    (0.0, 0.0),
    (0.01, 0.01),
    (0.3, 0.3),
    (2.0, 2.0),
    (30.0, 30.0),
    (0.01, 1.0),
    (1.0, 0.01),
    (1e-3, 10.0),
    (10.0, 1e-3),
)

#: (kappa, q1, q2) sample over which "model-dependent" is judged: ``KAPPAS x Q_PAIRS`` closed under
#: :func:`dual_kq`, so a class and its dual are judged on the same systems (seen from either contact)
KAPPA_Q_SAMPLE = _closed_under_dual((k, q1, q2) for k in KAPPAS for (q1, q2) in Q_PAIRS)

MODES = ("FF", "SS", "SF", "FS")


@dataclass
class Row:
    cls: int
    dual: int
    subclasses: dict = field(default_factory=dict)  # mode -> list of k
    stability: dict = field(default_factory=dict)  # mode -> word
    IF: str = "-"
    FI: str = "-"
    II: str = "-"
    II_stability: str = "-"
    CC: str = ""
    notes: list = field(default_factory=list)  # where the words come from, where they differ


def _grid(n):
    return (np.arange(n) + 0.5) * (2 * np.pi / n)


def class_samples(n: int = 96, per_class: int = 24, seed: int = 0) -> dict:
    """Up to ``per_class`` interior (beta1, beta2) points [rad] of each class, from an offset grid.

    The samples are closed under the dual map (:func:`atlas.core.contact_modes.dual_angles`): the sample of
    a class's dual is the dual image of the class's sample (a self-dual class's sample contains
    the dual of each of its points), so a class and its dual are judged on the same systems.
    ``n`` must be a multiple of 4, which makes the offset grid itself closed under the dual map:
    grid index ``i`` maps to ``n/4 - 1 - i`` (mod ``n``), exactly.
    """
    if n % 4:
        raise ValueError(f"n: must be a multiple of 4 (dual-closed grid), not {n}")
    b = _grid(n)
    c, s = contact_modes.direction(b)
    code = np.asarray(
        contact_modes.class_code(
            np.asarray(c)[:, None],
            np.asarray(s)[:, None],
            np.asarray(c)[None, :],
            np.asarray(s)[None, :],
        )
    )
    # beta2 = beta1 (det B = 0) and beta2 = beta1 + pi (the tie with beta1*) are grid points for
    # even n; they are degenerate (code 0) whatever the rounded cos/sin say
    ii, jj = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
    code = np.where(np.isin((jj - ii) % n, (0, n // 2)), 0, code)
    rng = np.random.default_rng(seed)

    def dual_idx(idx):
        return np.stack([(n // 4 - 1 - idx[:, 1]) % n, (n // 4 - 1 - idx[:, 0]) % n], -1)

    out = {}
    for cls in contact_modes.ALL_CLASSES:
        if cls in out:
            continue
        idx = np.argwhere(code == cls)
        if not len(idx):
            out[cls] = np.zeros((0, 2))
            continue
        dcls = {int(x) for x in code[tuple(dual_idx(idx).T)]}
        if len(dcls) != 1:
            raise RuntimeError(f"class {cls}: dual grid points in classes {sorted(dcls)}")
        dcls = dcls.pop()
        if dcls == cls:  # self-dual: half the points, plus their duals
            take = min(len(idx), max(1, per_class // 2))
            idx = idx[rng.choice(len(idx), take, replace=False)] if len(idx) > take else idx
            idx = np.unique(np.concatenate([idx, dual_idx(idx)]), axis=0)
            out[cls] = np.stack([b[idx[:, 0]], b[idx[:, 1]]], -1)
            continue
        if len(idx) > per_class:
            idx = idx[rng.choice(len(idx), per_class, replace=False)]
        out[cls] = np.stack([b[idx[:, 0]], b[idx[:, 1]]], -1)
        didx = dual_idx(idx)
        out[dcls] = np.stack([b[didx[:, 0]], b[didx[:, 1]]], -1)
    return {cls: out[cls] for cls in contact_modes.ALL_CLASSES}


def _word(verdicts) -> str:
    v = set(int(x) for x in np.ravel(verdicts))
    v = {Verdict.STABLE if x == Verdict.NEUTRAL else x for x in v}
    if v == {Verdict.STABLE}:
        return "stable"
    if v == {Verdict.UNSTABLE}:
        return "unstable"
    return "model-dependent"


def padded(points: np.ndarray, size: int) -> np.ndarray:
    """``points`` (rows) with its last row repeated up to ``size`` rows: one array shape for
    every class sample, so that a kernel compiles once (the sets of verdicts are unchanged)."""
    return np.concatenate([points, np.repeat(points[-1:], size - len(points), 0)])


@buckets.elementwise
def class_kernel(c1, s1, c2, s2, ca, sa):
    """Dual class code, subclass code and Table 1 consistency of every mode (a kept kernel in
    shape buckets, :func:`atlas.core.buckets.elementwise`; broadcast, numpy results).

    Shared with the audit's Sec. 6.2 check: the same programs for every class and both.
    """
    dual = contact_modes.class_code(*contact_modes.dual_vectors(c1, s1, c2, s2))
    sub = contact_modes.subclass_code(c1, s1, c2, s2, ca, sa)
    cons = contact_modes.consistent_modes(c1, s1, c2, s2, ca, sa)
    cons = {m: jnp.broadcast_to(v, sub.shape) for m, v in cons.items()}
    return dual, sub, cons


def table2(
    n: int = 96, per_class: int = 24, n_alpha: int = 720, dtype=np.float64, over_models=True
) -> list[Row]:
    """Regenerate Table 2 (all 24 classes) from the kernels; ``over_models``: the SS and II words
    from the verdicts over every model where they decide them (module docstring)."""
    n, per_class, n_alpha = (
        checks.positive_int(k, v)
        for k, v in (("n", n), ("per_class", per_class), ("n_alpha", n_alpha))
    )
    checks.float_dtype(dtype)
    samples = class_samples(n, per_class)
    alpha = _grid(n_alpha)
    ca, sa = (np.asarray(v) for v in contact_modes.direction(alpha, dtype))
    rows = []
    # one array shape for every class (repeat the last point; sets of verdicts are unchanged), so
    # each jitted kernel compiles once instead of once per distinct class sample size
    size = max(len(p) for p in samples.values())
    for cls in contact_modes.ALL_CLASSES:
        pts = padded(samples[cls], size)
        c1, s1 = (np.asarray(v)[:, None] for v in contact_modes.direction(pts[:, 0], dtype))
        c2, s2 = (np.asarray(v)[:, None] for v in contact_modes.direction(pts[:, 1], dtype))
        # dual class (contact indices swapped; exact in vector form), subclasses, Table 1
        dual, sub, cons = class_kernel(c1, s1, c2, s2, ca[None, :], sa[None, :])
        duals = set(np.asarray(dual).ravel().tolist())
        if len(duals) != 1:
            raise RuntimeError(f"class {cls}: dual not unique: {duals}")
        row = Row(cls=cls, dual=int(duals.pop()))
        sub = np.asarray(sub)
        cons = {m: np.asarray(v) for m, v in cons.items()}
        for m in MODES:
            if (cons[m] == Consistency.UNDECIDED).any():
                raise RuntimeError(f"class {cls}: undecided {m} consistency on the sample")
            ks = []
            for k in range(1, 7):
                sel = sub == 10 * cls + k
                if not sel.any():
                    raise RuntimeError(f"subclass {10 * cls + k} not sampled")
                vals = set(cons[m][sel].tolist())
                if len(vals) != 1:
                    raise RuntimeError(f"{m} consistency not constant in subclass {10 * cls + k}")
                if vals == {1}:
                    ks.append(k)
            row.subclasses[m] = ks
        row.stability["FF"] = "stable"
        row.stability["SF"] = _word(contact_modes.stable_SF(c1))
        row.stability["FS"] = _word(contact_modes.stable_FS(s2))
        # SS and II over the kappa-q sample (undecided points settled exactly)
        kq = np.array(KAPPA_Q_SAMPLE)
        v = spectral_points(
            c1,
            s1,
            c2,
            s2,
            kq[None, :, 0],
            kq[None, :, 1],
            kq[None, :, 2],
            names=("stable_SS", "consistent_II", "stable_II"),
            dtype=dtype,
        )
        ss, ci, si = v["stable_SS"], v["consistent_II"], v["stable_II"]
        row.stability["SS"] = _word(ss)
        if_ = np.asarray(contact_modes.consistent_IF(c1, s1))
        fi = np.asarray(contact_modes.consistent_FI(c2, s2))
        row.IF = _marker(if_)
        row.FI = _marker(fi)
        row.II = _marker(ci)
        row.II_stability = _word(si[ci == 1]) if (ci == 1).any() else "-"
        cc = np.asarray(contact_modes.cc_possible(c1, s2))  # NumPy reductions: no JAX program
        row.CC = "?" if cc.all() else ("" if not cc.any() else "(?)")
        rows.append(row)
    if over_models:
        _apply_over_models(rows, samples, dtype)
    return rows


# --- the words over every contact model ---------------------------------------------------------

_NO, _YES, _DEP, _UND = (int(v) for v in OverModels)
_WORDS = {_YES: "stable", _NO: "unstable"}
#: verdicts over the whole model space of geometries already computed (by their components)
_MEMO: dict = {}


def over_models_codes(pts: np.ndarray, dtype=np.float64) -> list[dict]:
    """Per point of ``pts`` (angles [rad]): ``SS`` (``ss_over_models``), the II codes over the
    whole model space (:data:`atlas.core.ii_over_models.SIDES`), the II stability's unstable
    witness, ``geometry`` (direction components) and ``beta`` (the angles); memoised per
    geometry (``atlas paper`` asks twice)."""
    (c1, s1), (c2, s2) = (contact_modes.direction(pts[:, j], dtype) for j in (0, 1))
    res = _over_models(*(np.asarray(v, np.float64) for v in (c1, s1, c2, s2)))
    return [dict(r, beta=(float(a), float(b))) for r, (a, b) in zip(res, pts)]


def _over_models(c1, s1, c2, s2) -> list[dict]:
    keys = list(zip(c1.tolist(), s1.tolist(), c2.tolist(), s2.tolist()))
    new = [k for k in dict.fromkeys(keys) if k not in _MEMO]
    if new:
        g = np.array(new).T
        box = mb.model_box()
        ss = mb.ss_over_models(*g, box)
        ii = iim.ii_over_models(*g, box, settle=False)
        for n, k in enumerate(new):
            _MEMO[k] = {"SS": int(ss["ss_over_models"][n])}
            _MEMO[k].update({name: int(ii[name][n]) for name in iim.SIDES})
            w = [float(ii[x][n]) for x in iim.witness_names("ii_stable_over_models")[3:]]
            _MEMO[k]["unstable_witness"] = tuple(w)
    return [dict(_MEMO[k], geometry=k) for k in keys]


def _class_word(codes: set) -> str | None:
    """``stable`` / ``unstable`` / ``model-dependent`` of a class from its geometries' codes
    over every model; ``None`` where an undecided geometry leaves it open."""
    if _DEP in codes or {_YES, _NO} <= codes:
        return "model-dependent"
    if _UND in codes or not codes:
        return None
    return _WORDS[codes.pop()]


def over_models_words(pts: np.ndarray, dtype=np.float64) -> dict:
    """``{"SS": word, "II": marker, "II_stability": word}`` of a class from the verdicts over
    every model at its sample ``pts`` (angles [rad]); ``None`` where they leave one open.

    The II stability word is Table 2's: over the models where II is consistent.  Where
    consistency itself depends on the model, "model-dependent" needs an unstable witness at which
    II is consistent (checked by the exact tier), and "stable" is left open."""
    res = over_models_codes(pts, dtype)
    cons = {r["ii_consistent_over_models"] for r in res}
    marker = _class_word(set(cons))
    out = {"SS": _class_word({r["SS"] for r in res}), "II": None}
    if marker is not None:
        out["II"] = {"stable": "x", "unstable": "-", "model-dependent": "(x)"}[marker]
    stab = set()
    for r in res:
        code, c = r["ii_stable_over_models"], r["ii_consistent_over_models"]
        if c == _NO:
            continue
        if c != _YES and code != _NO:
            code = _DEP if code == _DEP and consistent_unstable(r) else _UND
        stab.add(code)
    out["II_stability"] = _class_word(stab) if stab else "-"
    return out


def consistent_unstable(r) -> bool:
    """Whether the unstable witness of a geometry has II consistent (exact tier)."""
    v = exact.point_spectral(*r["geometry"], *r["unstable_witness"])
    return int(v["consistent_II"]) == 1 and int(v["stable_II"]) != int(Verdict.STABLE)


def _apply_over_models(rows, samples, dtype) -> None:
    """Replace the sample's SS word, II marker and II stability word of each row by the words
    over every model where those decide them; notes where they do not, or differ."""
    for row in rows:
        words = over_models_words(samples[row.cls], dtype)
        pairs = (("SS", row.stability["SS"]), ("II", row.II), ("II_stability", row.II_stability))
        for key, old in pairs:
            new = words[key]
            if new is None:
                row.notes.append(f"{key} {old}: from the model sample (open over every model)")
                continue
            if new != old:
                row.notes.append(f"{key} {new} over every model (the model sample: {old})")
            if key == "SS":
                row.stability["SS"] = new
            else:
                setattr(row, key, new)


def _marker(flags) -> str:
    f = np.asarray(flags).ravel()
    if np.all(f == 1):
        return "x"
    if np.all(f == 0):
        return "-"
    return "(x)"


_SHADE = {"stable": "", "unstable": "**", "model-dependent": "_"}

#: the key printed under the Markdown table
KEY = (
    "Key: a subclass list (FF, SS, SF, FS) or the II marker in **bold** = unstable (the paper's dark "
    "background), in _italics_ = model-dependent (light: the verdict changes with the contact model, "
    "i.e. with (kappa, q1, q2) or within the class), plain = stable (white; the neutral q = 0 case "
    "counts as stable, as in Fig. 1). IF, FI, II markers: x = consistent throughout the class, "
    "(x) = model-dependent, - = never; IF and FI are stable whenever consistent. CC: ? = the "
    "necessary condition b11 > 0, b22 > 0 holds. Class (dual): the class obtained by swapping the "
    "contact indices ('same' = self-dual)."
)


def to_markdown(rows: list[Row]) -> str:
    """Markdown table; unstable entries in **bold** (paper: dark), model-dependent in _italics_
    (paper: light), stable plain (paper: white)."""
    head = "| class (dual) | FF | SS | SF | FS | IF | FI | II | CC |\n|---|---|---|---|---|---|---|---|---|"
    lines = [head]
    for r in rows:
        dual = "same" if r.dual == r.cls else str(r.dual)
        cells = []
        for m in MODES:
            ks = " ".join(str(k) for k in r.subclasses[m])
            sh = _SHADE[r.stability[m]] if ks else ""
            cells.append(f"{sh}{ks}{sh}")
        ii = r.II
        if ii != "-":
            ii = f"{_SHADE[r.II_stability]}{ii}{_SHADE[r.II_stability]}"
        lines.append(
            f"| {r.cls} ({dual}) | " + " | ".join(cells) + f" | {r.IF} | {r.FI} | {ii} | {r.CC} |"
        )
    notes = [f"* {r.cls}: {n}" for r in rows for n in r.notes]
    tail = "\n\nNotes (the words over every contact model, proved or witnessed):\n" + "\n".join(
        notes
    )
    return "\n".join(lines) + "\n\n" + KEY + (tail if notes else "") + "\n"


def to_csv(rows: list[Row]) -> str:
    buf = io.StringIO()
    w = csv.writer(buf)
    w.writerow(
        ["class", "dual"]
        + [f"{m}_subclasses" for m in MODES]
        + [f"{m}_stability" for m in MODES]
        + ["IF", "FI", "II", "II_stability", "CC"]
    )
    for r in rows:
        w.writerow(
            [r.cls, r.dual]
            + [" ".join(map(str, r.subclasses[m])) for m in MODES]
            + [r.stability[m] for m in MODES]
            + [r.IF, r.FI, r.II, r.II_stability, r.CC]
        )
    return buf.getvalue()


#: the format each ending of ``atlas table --out`` names (``.txt``: whichever ``--format`` says)
_FORMAT_OF = {".md": "markdown", ".csv": "csv"}


def run_cli(format: str | None = None, out: str | None = None, overwrite: bool = False):
    """``atlas table``: print Table 2 or write it to ``out`` (an existing file is replaced only
    with ``overwrite``), as Markdown or CSV: ``format``, else the ending of ``out`` (``.md``,
    ``.csv``), else Markdown; a ``format`` the ending contradicts is refused."""
    from atlas.data.io import atomic_write_text, check_output_path

    named = _FORMAT_OF.get(os.path.splitext(out)[1].lower()) if out else None
    if format is not None and named is not None and format != named:
        raise ValueError(f"format: --format {format} but --out {out} names {named}")
    format = format or named or "markdown"
    if out:
        check_output_path(out, overwrite)
    rows = table2()
    text = to_markdown(rows) if format == "markdown" else to_csv(rows)
    if out:
        atomic_write_text(out, text, overwrite=overwrite)
    else:
        print(text, end="")
    return 0
