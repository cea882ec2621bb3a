"""Fig. 1 (class diagram, stability maps) and the Table 2 figure of the paper, from the kernels.

Data flows one way: the certified kernels (:mod:`atlas.core.mechanics`, :mod:`atlas.core.spectral`) give the
verdicts, :mod:`atlas.core.exact` settles the few points the fast path leaves undecided, and this module
only arranges and draws them.  Colours and legends come from :class:`atlas.core.verdicts.Verdict` and
:class:`atlas.core.verdicts.Consistency`; categorical layers are ``pcolormesh`` with ``ListedColormap`` +
``BoundaryNorm``.  Model-dependent boundaries are drawn dashed: on Fig. 1 of ``atlas paper`` from the
certified curves of :func:`atlas.boundaries` (``curves=``), else as zero contours of *smooth margins*
(never of 0/1 masks):

* SS stability: :func:`atlas.core.spectral.ss_margin` (``G/|G|`` when damped, the discriminant of the
  ``mu``-quadratic when ``Q = 0``).
* II consistency: inside a class the eigenvector sign ``x1 x2`` of a positive real root cannot change
  (``h1(l) = 0`` at a root forces ``c2 s1 = 0``, a class boundary), and a positive root cannot reach 0
  (``det B != 0``), so the II root can only appear or disappear by colliding with another real root:
  the boundary lies on the zero set of the quartic's discriminant.  At ``Q = 0`` the quartic is
  ``p(l) = mu^2 + a2 mu + a0`` with ``mu = l^2`` and its discriminant has the ``mu``-discriminant as a
  squared factor, so the margin used there is the ``mu``-discriminant itself (the same function as
  the undamped SS margin).  The discriminant also vanishes where *other* real roots collide, so the
  contour is drawn only in cells next to a change of the certified ``consistent_II`` verdict.
* II stability (within the II-consistent region): ``Re(l_II) - max Re(other roots)``, with ``l_II``
  the largest positive real root meeting the eigenvector condition (roots from ``eig`` of ``M`` --
  used only to *place* the line; the verdicts themselves are certified).
"""

from __future__ import annotations

import math
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np

from atlas.core import mechanics, spectral
from atlas.core.points import SPECTRAL_NAMES, settle_codes, spectral_points
from atlas.core.verdicts import Consistency, Verdict
from atlas.data.io import savefig
from atlas.data.outputs import OUTPUTS, coord_attrs, to_storage, undecided, variable_attrs
from atlas.paper import drawing

__all__ = [
    "evaluate_points",
    "stability_map",
    "class_representatives",
    "plot_fig1_classes",
    "plot_fig1_stability",
    "plot_fig1_variants",
    "plot_table2",
    "draw_class_diagram",
    "draw_fig1_classes",
    "draw_fig1_layer",
    "draw_fig1_stability",
    "draw_fig1_variant",
    "draw_fig1_variants",
    "draw_table2",
    "FIG1_LAYERS",
    "VARIANTS",
]

#: (kappa, q1, q2) of the variant maps (Fig. 1 at other model parameters)
VARIANTS = (
    (0.5, 0.0, 0.0),
    (2.0, 0.0, 0.0),
    (0.5, 0.1, 0.1),
    (0.5, 1.0, 1.0),
    (2.0, 1.0, 1.0),
    (0.5, 1.0, 0.01),
)
_margin_jit = jax.jit(spectral.ss_margin)
DPI = 110


# --------------------------------------------------------------------------- computing the maps


def evaluate_points(
    c1, s1, c2, s2, kappa, q1, q2, *, margin=False, resolve=True, max_resolve=5000
) -> dict:
    """Certified spectral verdicts (via :func:`atlas.core.points.spectral_points`) plus, optionally,
    the smooth SS margin :func:`atlas.core.spectral.ss_margin`, for broadcastable arrays.

    Returns numpy arrays of the broadcast shape: ``stable_SS``, ``consistent_II``, ``stable_II``,
    ``spectral_abscissa`` [(time of contact 2)^-1], optionally ``margin_SS``; ints ``n_resolved``
    (points settled exactly) and ``n_undecided`` (left undecided).
    """
    res = spectral_points(c1, s1, c2, s2, kappa, q1, q2, resolve=resolve, max_resolve=max_resolve)
    counts = res.stats
    if margin:
        args = [jnp.asarray(np.asarray(a, np.float64)) for a in (c1, s1, c2, s2, kappa, q1, q2)]
        shape = res["stable_SS"].shape
        res["margin_SS"] = np.broadcast_to(np.asarray(_margin_jit(*args)), shape).copy()
    res["n_resolved"] = counts["undecided_before"] - counts["undecided_after"] if resolve else 0
    res["n_undecided"] = counts["undecided_after"]
    return res


def _offset_grid(n):
    """Cell centres ``(i + 1/2) 2 pi / n`` [rad] (no centre lies on an axis or on beta2 = beta1)."""
    return (np.arange(n) + 0.5) * (2 * np.pi / n)


def _quartic_discriminant(a3, a2, a1, a0):
    """Discriminant of the monic quartic, divided by a positive degree-12 scale (smooth, bounded)."""
    b, c, d, e = a3, a2, a1, a0
    disc = (
        256 * e**3
        - 192 * b * d * e**2
        - 128 * c**2 * e**2
        + 144 * c * d**2 * e
        - 27 * d**4
        + 144 * b**2 * c * e**2
        - 6 * b**2 * d**2 * e
        - 80 * b * c**2 * d * e
        + 18 * b * c * d**3
        + 16 * c**4 * e
        - 4 * c**3 * d**2
        - 27 * b**4 * e**2
        + 18 * b**3 * c * d * e
        - 4 * b**3 * d**3
        - 4 * b**2 * c**3 * e
        + b**2 * c**2 * d**2
    )
    scale = (np.abs(b) + np.abs(c) ** 0.5 + np.abs(d) ** (1 / 3) + np.abs(e) ** 0.25) ** 12
    return disc / np.where(scale > 0, scale, 1.0)


def _ss_margin_full(margin, c1, s2, kappa, q1, q2):
    """SS margin whose zero set is *every* model-dependent SS boundary.

    :func:`atlas.core.spectral.ss_margin` covers ``G`` (damped) and the discriminant (``Q = 0``); the
    other condition that depends on the model is ``a2 = kappa c1 + s2 >= 0`` (``Q = 0``) or
    ``a3 = c1 q1 + s2 q2 > 0`` (damped), whose sign changes inside classes 23 and 46.  The minimum
    of the normalised quantities is continuous and its zero set is the boundary.
    """
    c1, s2 = np.asarray(c1, float), np.asarray(s2, float)
    if q1 == 0 and q2 == 0:
        a = (kappa * c1 + s2) / (kappa * np.abs(c1) + np.abs(s2) + 1e-300)
    else:
        a = (c1 * q1 + s2 * q2) / (np.abs(c1) * q1 + np.abs(s2) * q2 + 1e-300)
    return np.minimum(np.asarray(margin, float), a)


def _ii_root_margin(c1, s1, c2, s2, kappa, q1, q2):
    """``Re(l_II) - max Re(other roots)`` (NaN where no II root), scaled by the root magnitude."""
    M = np.asarray(
        spectral.build_M(
            *(jnp.asarray(np.asarray(a, np.float64)) for a in (c1, s1, c2, s2, kappa, q1, q2))
        )
    )
    w = np.linalg.eigvals(M)
    shape = w.shape[:-1]
    bc = [
        np.broadcast_to(np.asarray(a, np.float64), shape)[..., None]
        for a in (c1, s1, c2, s2, kappa, q1, q2)
    ]
    C1, S1, C2, S2, K, Q1, Q2 = bc
    scale = np.max(np.abs(w), -1, keepdims=True) + 1e-300
    re = w.real
    real = np.abs(w.imag) <= 1e-7 * scale
    lam = re
    h1 = lam**2 + C1 * (K + lam * Q1)
    h2 = lam**2 + S2 * (1 + lam * Q2)
    cond = np.where(C2 != 0, C2 * h1 < 0, S1 * h2 < 0)
    ii = real & (re > 0) & cond
    cand = np.where(ii, re, -np.inf)
    top = np.argmax(cand, -1)
    has = np.any(ii, -1)
    l_ii = np.take_along_axis(re, top[..., None], -1)[..., 0]
    others = re.copy()
    np.put_along_axis(others, top[..., None], -np.inf, -1)
    g = (l_ii - np.max(others, -1)) / scale[..., 0]
    return np.where(has, g, np.nan)


def stability_map(
    n: int = 361, kappa: float = 0.5, q1: float = 0.0, q2: float = 0.0, margins: bool = True
):
    """Fig. 1 map on an ``n x n`` offset grid of ``(beta1, beta2)`` in ``[0, 2 pi)``.

    Returns an ``xarray.Dataset`` with the SPEC §2 variables (``class_code``, ``stable_SF``,
    ``stable_FS``, ``consistent_IF``, ``consistent_FI``, ``cc_possible``, ``stable_SS``,
    ``consistent_II``, ``stable_II``, ``spectral_abscissa``) plus the smooth margins
    ``margin_SS``, ``margin_II_consistent``, ``margin_II_stable`` used for the dashed contours,
    with the stored types and attributes of :mod:`atlas.data.outputs` (an atlas slice: ``stable_SF``
    is ``True`` iff stable).  ``kappa``, ``q1``, ``q2`` are scalar coordinates.
    """
    import xarray as xr

    b = _offset_grid(n)
    c, s = mechanics.direction(b)
    C1, S1 = c[:, None], s[:, None]
    C2, S2 = c[None, :], s[None, :]
    ev = evaluate_points(C1, S1, C2, S2, kappa, q1, q2, margin=True)
    raw = {**_mechanics_layers(c, s), **{k: ev[k] for k in SPECTRAL_NAMES}}
    if margins:
        raw.update(_margin_layers(ev["margin_SS"], C1, S1, C2, S2, kappa, q1, q2))
    coords = {k: (k, b, coord_attrs(k)) for k in ("beta1", "beta2")}
    coords.update({k: ((), float(v), coord_attrs(k)) for k, v in zip(_MODEL, (kappa, q1, q2))})
    data = {
        k: (_map_dims(k), to_storage(k, v, np.float64), variable_attrs(k)) for k, v in raw.items()
    }
    ds = xr.Dataset(data, coords=coords)
    if margins:
        ds["margin_SS"].attrs["comment"] = _MARGIN_SS_COMMENT
    ds.attrs.update(n_resolved=ev["n_resolved"], n_undecided=ev["n_undecided"])
    return ds


_MODEL = ("kappa", "q1", "q2")
_MARGIN_SS_COMMENT = (
    "min(atlas.core.spectral.ss_margin, a2 (q = 0) or a3 (damped) normalised): "
    "zero on every model-dependent SS boundary"
)


def _map_dims(name: str) -> tuple[str, ...]:
    """Dimensions of an output on the map: its angles (the model is a scalar coordinate)."""
    return tuple(d for d in OUTPUTS[name].depends if d in ("beta1", "beta2"))


def _mechanics_layers(c, s) -> dict:
    """Raw codes of the model-independent layers on the offset grid (class codes settled exactly)."""
    n = c.size
    C1, S1, C2, S2 = c[:, None], s[:, None], c[None, :], s[None, :]
    j = [jnp.asarray(a) for a in (C1, S1, C2, S2)]
    raw = {
        "class_code": np.broadcast_to(np.asarray(mechanics.class_code(*j)), (n, n)).copy(),
        "stable_SF": np.asarray(mechanics.stable_SF(jnp.asarray(c))),
        "stable_FS": np.asarray(mechanics.stable_FS(jnp.asarray(s))),
        "consistent_IF": np.asarray(mechanics.consistent_IF(jnp.asarray(c), jnp.asarray(s))),
        "consistent_FI": np.asarray(mechanics.consistent_FI(jnp.asarray(c), jnp.asarray(s))),
        "cc_possible": np.broadcast_to(np.asarray(mechanics.cc_possible(j[0], j[3])), (n, n)),
    }
    masks = {"class_code": undecided("class_code", raw["class_code"])}
    settle_codes(raw, masks, C1, S1, C2, S2)
    return raw


def _margin_layers(ss_margin, C1, S1, C2, S2, kappa, q1, q2) -> dict:
    """The smooth margins whose zero contours are drawn as the model-dependent boundaries."""
    n = C1.size
    if q1 == 0 and q2 == 0:
        mii = ss_margin  # the mu-discriminant (see module docstring)
    else:
        a3, a2, a1, a0 = (
            np.asarray(x)
            for x in spectral.coefficients(
                *(jnp.asarray(v) for v in (C1, S1, C2, S2)),
                jnp.asarray(float(kappa)),
                jnp.asarray(float(q1)),
                jnp.asarray(float(q2)),
            )
        )
        mii = np.broadcast_to(_quartic_discriminant(a3, a2, a1, a0), (n, n))
    return {
        "margin_SS": _ss_margin_full(ss_margin, C1, S2, kappa, q1, q2),
        "margin_II_consistent": np.array(mii),
        "margin_II_stable": _ii_root_margin(C1, S1, C2, S2, kappa, q1, q2),
    }


# --------------------------------------------------------------------------- Fig. 1, classes

_subclass_jit = jax.jit(mechanics.subclass_code)  # eager, the 24 calls took ~20 s of op dispatch


def class_representatives(n: int = 96, n_alpha: int = 1440) -> dict:
    """One interior ``(beta1, beta2)`` per class and one ``alpha`` per subclass ``k = 1..6`` [rad].

    The class point is the class sample (:func:`atlas.paper.tables.class_samples`) farthest from the
    class boundaries (largest minimum angular gap to beta1, beta1*, and the axes); alpha for
    subclass ``k`` is the middle of the arc of ``k`` found by :func:`atlas.core.mechanics.subclass_code`.
    """
    from atlas.paper.tables import class_samples

    samples = class_samples(n, per_class=10_000)
    alpha = _offset_grid(n_alpha)
    ca, sa = (jnp.asarray(v) for v in mechanics.direction(alpha))
    out = {}
    for cls, pts in samples.items():
        b1, b2 = pts[:, 0], pts[:, 1]
        refs = [np.pi / 2, np.pi, 1.5 * np.pi, 0.0]
        gap1 = np.min([np.abs(np.angle(np.exp(1j * (b1 - r)))) for r in refs], 0)
        refs2 = [b1, b1 + np.pi] + refs
        gap2 = np.min([np.abs(np.angle(np.exp(1j * (b2 - r)))) for r in refs2], 0)
        best = int(np.argmax(np.minimum(gap1, gap2)))
        beta1, beta2 = float(b1[best]), float(b2[best])
        c1, s1 = mechanics.direction(beta1)
        c2, s2 = mechanics.direction(beta2)
        sub = np.asarray(_subclass_jit(*(jnp.asarray(v) for v in (c1, s1, c2, s2)), ca, sa))
        alphas = {}
        for k in range(1, 7):
            hit = alpha[sub == 10 * cls + k]
            if hit.size:
                alphas[k] = float(np.median(hit))
        out[cls] = {"beta1": beta1, "beta2": beta2, "alpha": alphas}
    return out


def draw_class_diagram(ax, cls: int, rep: dict) -> list:
    """One class of Fig. 1 on ``ax``: ``b1``, ``b2`` (arrows), ``-b1`` (dotted) and ``a`` for each
    subclass ``k`` (dashed), at the representative point ``rep`` of :func:`class_representatives`.

    Returns the artists drawn.
    """
    t = np.linspace(0, 2 * np.pi, 200)
    art = ax.plot(np.cos(t), np.sin(t), color="0.85", lw=0.6)
    art += [ax.axhline(0, color="0.6", lw=0.5), ax.axvline(0, color="0.6", lw=0.5)]
    b1s = rep["beta1"] + np.pi
    art += ax.plot([0, np.cos(b1s)], [0, np.sin(b1s)], ls=":", color="C3", lw=0.9)
    for k, a in rep["alpha"].items():
        art += ax.plot([0, 0.78 * np.cos(a)], [0, 0.78 * np.sin(a)], ls="--", color="0.35", lw=0.8)
        art.append(
            ax.text(
                0.93 * np.cos(a),
                0.93 * np.sin(a),
                str(k),
                ha="center",
                va="center",
                fontsize=7,
                color="0.2",
            )
        )
    for j, (key, col) in enumerate((("beta1", "C3"), ("beta2", "C0"))):
        b = rep[key]
        art.append(
            ax.annotate(
                "",
                xy=(np.cos(b), np.sin(b)),
                xytext=(0, 0),
                arrowprops=dict(arrowstyle="-|>", color=col, lw=1.6, mutation_scale=9),
            )
        )
        art.append(
            ax.text(
                1.22 * np.cos(b),
                1.22 * np.sin(b),
                f"$b_{j + 1}$",
                color=col,
                fontsize=8,
                ha="center",
                va="center",
            )
        )
    ax.set_xlim(-1.4, 1.4)
    ax.set_ylim(-1.4, 1.4)
    ax.set_aspect("equal")
    ax.set_xticks([])
    ax.set_yticks([])
    dual = mechanics.class_code(
        *(
            jnp.asarray(v)
            for v in mechanics.dual_vectors(
                *mechanics.direction(rep["beta1"]), *mechanics.direction(rep["beta2"])
            )
        )
    )
    dual = int(dual)
    art.append(ax.set_title(f"class {cls} ({'same' if dual == cls else dual})", fontsize=9))
    return art


def draw_fig1_classes(fig, reps: dict | None = None) -> list:
    """Fig. 1 (class diagram) on ``fig``: a 4 x 6 grid of :func:`draw_class_diagram`."""
    reps = reps or class_representatives()
    axes = fig.subplots(4, 6)
    art = []
    for ax, cls in zip(axes.ravel(), mechanics.ALL_CLASSES, strict=True):
        art += draw_class_diagram(ax, cls, reps[cls])
    art.append(
        fig.suptitle(
            "Fig. 1 (classes): directions of $b_1$, $b_2$ (solid) and of $a$ for subclasses "
            "k = 1..6 (dashed); dotted: $-b_1$; at representative points found by the kernels; "
            "(dual) in brackets",
            fontsize=10,
        )
    )
    fig.tight_layout(rect=(0, 0, 1, 0.97))
    return art


def plot_fig1_classes(path, reps: dict | None = None):
    """Write Fig. 1 (class diagram, :func:`draw_fig1_classes`) to ``path``."""
    fig = drawing.new_figure(figsize=(13, 9.2))
    draw_fig1_classes(fig, reps)
    return _save(fig, path)


def _save(fig, path) -> Path:
    savefig(fig, path, dpi=DPI)
    return Path(path)


# --------------------------------------------------------------------------- Fig. 1, stability

_NEUTRAL_LABEL = {Verdict.NEUTRAL: "neutral (drawn as stable in the paper)"}

#: the layers of Fig. 1 (stability map), in panel order
FIG1_LAYERS = ("SF", "FS", "SS", "IF", "FI", "II_consistency", "II_stability", "nothing_stable")

_LAYER_TITLES = {
    "SF": "SF stability ($b_{11} > 0$)",
    "FS": "FS stability ($b_{22} > 0$)",
    "SS": "SS stability",
    "IF": "IF consistent (then stable)",
    "FI": "FI consistent (then stable)",
    "II_consistency": "II consistency",
    "II_stability": "II stability (hatched: II inconsistent)",
    "nothing_stable": "SS unstable, no stable IWC (orange; Sec. 6.4)",
}


def _layer_fields(ds) -> dict:
    """The fields of the Fig. 1 layers on the full ``(beta1, beta2)`` grid."""
    n = ds.sizes["beta1"]
    IF = np.broadcast_to(ds["consistent_IF"].values[:, None], (n, n)).astype(np.int8)
    FI = np.broadcast_to(ds["consistent_FI"].values[None, :], (n, n)).astype(np.int8)
    ss, si = ds["stable_SS"].values, ds["stable_II"].values
    ss_ok = (ss == Verdict.STABLE) | (ss == Verdict.NEUTRAL)
    return {
        "SF": np.broadcast_to(ds["stable_SF"].values[:, None], (n, n)),
        "FS": np.broadcast_to(ds["stable_FS"].values[None, :], (n, n)),
        "SS": ss,
        "IF": IF,
        "FI": FI,
        "II_consistency": ds["consistent_II"].values,
        "II_stability": si,
        "nothing_stable": ~ss_ok & (IF == 0) & (FI == 0) & (si != Verdict.STABLE),
    }


def _layer_boundaries(ds, layer) -> list:
    """``(margin, cells)`` of the dashed model-dependent boundaries of a layer."""
    cls = ds["class_code"].values
    ci = ds["consistent_II"].values
    if layer in ("SS", "nothing_stable"):
        return [("margin_SS", drawing.ss_boundary_cells(ds))]
    if layer == "II_consistency":
        return [("margin_II_consistent", drawing.near_change(ci, cls))]
    if layer == "II_stability":
        si_cells = drawing.near_change(ds["stable_II"].values, cls) & (ci == Consistency.CONSISTENT)
        return [
            ("margin_II_stable", si_cells),
            ("margin_II_consistent", drawing.near_change(ci, cls)),
        ]
    return []


#: the boundary kinds (:mod:`atlas.data.boundaries`) drawn dashed on each Fig. 1 layer
LAYER_CURVES = {
    "SS": ("SS_stability",),
    "nothing_stable": ("SS_stability",),
    "II_consistency": ("II_consistency",),
    "II_stability": ("II_stability", "II_consistency"),
}


def _dashed_curves(ax, curves, layer) -> list:
    """The certified model-dependent boundaries of ``layer`` (pieces off the class lines) dashed."""
    kinds = LAYER_CURVES.get(layer, ())
    arts = []
    for c in curves.curves:
        if c.kind in kinds and not c.on_class_line:
            arts += ax.plot(*c.vertices.T, color="k", lw=1.1, ls="--", zorder=7)
    return arts


@drawing.hatch_style
def draw_fig1_layer(ax, ds, layer: str, pos: dict | None = None, curves=None) -> list:
    """One panel of Fig. 1 (stability map) on ``ax``: the layer (one of :data:`FIG1_LAYERS`) of a
    :func:`stability_map` dataset, its dashed model-dependent boundaries, the class boundaries and
    (if ``pos``, from :func:`atlas.paper.drawing.label_positions`) the class labels.

    The dashed boundaries are the certified curves ``curves`` (:func:`atlas.boundaries` of the
    same slice) if given, else the zero contours of the dataset's smooth margins.  Returns the
    artists drawn.
    """
    if layer not in FIG1_LAYERS:
        raise ValueError(f"layer: expected one of {FIG1_LAYERS}, got {layer!r}")
    field = _layer_fields(ds)[layer]
    ci = ds["consistent_II"].values
    ax.set_facecolor("white")
    if layer in ("SF", "FS", "SS"):
        art = [drawing.categorical(ax, ds, field, Verdict)]
    elif layer in ("IF", "FI", "II_consistency"):
        art = [drawing.categorical(ax, ds, field, Consistency)]
    elif layer == "II_stability":
        art = [
            drawing.categorical(ax, ds, field, Verdict, mask=ci == Consistency.CONSISTENT),
            drawing.hatch(ax, ds, ci != Consistency.CONSISTENT),
        ]
    else:
        art = [drawing.boolean(ax, ds, field, drawing.NOTHING_COLOR)]
    n = ds.sizes["beta1"]
    if curves is not None:
        art += _dashed_curves(ax, curves, layer)
    else:
        for m, cells in _layer_boundaries(ds, layer):
            if m in ds:
                art.append(drawing.dashed(ax, ds, m, where=cells & np.ones((n, n), bool)))
    art += drawing.class_lines(ax)
    if pos is not None:
        art += drawing.class_labels(ax, pos)
    drawing.pi_axis(ax)
    art.append(ax.set_title(_LAYER_TITLES[layer], fontsize=9))
    ax.tick_params(labelsize=7)
    return [a for a in art if a is not None]


def _param_text(kappa, q1, q2):
    q = f"q = {q1:g}" if q1 == q2 else f"q1 = {q1:g}, q2 = {q2:g}"
    return rf"$\kappa$ = {kappa:g}, {q}"


def _fig1_legend(fig, ds, certified: bool = False):
    from matplotlib.lines import Line2D

    present_v = (
        set(np.unique(ds["stable_SS"].values).tolist())
        | {0, 1}
        | set(np.unique(ds["stable_II"].values).tolist())
    )
    handles = drawing.legend_patches(Verdict, present_v, _NEUTRAL_LABEL)
    handles += drawing.legend_patches(
        Consistency, set(np.unique(ds["consistent_II"].values).tolist()) | {0, 1}
    )
    handles += [
        Line2D([], [], color="k", lw=0.6, label="class boundary (model-independent)"),
        Line2D(
            [],
            [],
            color="k",
            lw=1.1,
            ls="--",
            label="model-dependent boundary ("
            + (
                "certified curve, vertices within 1e-10 rad"
                if certified
                else "zero of smooth margin"
            )
            + ")",
        ),
    ]
    return fig.legend(handles=handles, loc="lower center", ncol=5, fontsize=8.5, frameon=False)


def draw_fig1_stability(fig, ds, curves=None) -> list:
    """Fig. 1 (stability map) on ``fig``: the 8 layers of :func:`draw_fig1_layer` in a 2 x 4 grid
    (dashed boundaries from the certified ``curves`` if given), legend from the verdict
    enumerations, title with the parameters and decision counts."""
    axes = fig.subplots(2, 4).ravel()
    pos = drawing.label_positions(ds)
    art = []
    for ax, layer in zip(axes, FIG1_LAYERS, strict=True):
        art += draw_fig1_layer(ax, ds, layer, pos, curves)
    for ax in axes[-4:]:
        ax.set_xlabel(r"$\beta_1$", fontsize=9)
    for ax in axes[::4]:
        ax.set_ylabel(r"$\beta_2$", fontsize=9)
    kappa, q1, q2 = (float(ds[k]) for k in ("kappa", "q1", "q2"))
    art.append(_fig1_legend(fig, ds, certified=curves is not None))
    und = int(ds.attrs.get("n_undecided", 0))
    art.append(
        fig.suptitle(
            f"Fig. 1 (stability map), {_param_text(kappa, q1, q2)}; grid "
            f"{ds.sizes['beta1']}$^2$, {ds.attrs.get('n_resolved', 0)} cells settled by the "
            f"exact reference, {und} undecided. FF (always stable when consistent) not shown.",
            fontsize=10,
        )
    )
    # explicit margins: tight_layout mis-sizes the equal-aspect panels, so the bottom row's titles
    # ran into the top row's tick labels; hspace leaves room for tick labels + title
    fig.subplots_adjust(left=0.045, right=0.99, bottom=0.13, top=0.92, wspace=0.2, hspace=0.34)
    return art


def plot_fig1_stability(path, ds, curves=None):
    """Write Fig. 1 (stability map, :func:`draw_fig1_stability`) to ``path``."""
    fig = drawing.new_figure(figsize=(15.5, 9.4))
    draw_fig1_stability(fig, ds, curves)
    return _save(fig, path)


@drawing.hatch_style
def draw_fig1_variant(ax, ds, ref, pos: dict | None = None) -> list:
    """SS stability and II consistency (hatched) of one :func:`stability_map` on ``ax``, with the
    reference map ``ref``'s SS boundary in red (how the model-dependent boundaries move)."""
    ss = ds["stable_SS"].values
    art = [drawing.categorical(ax, ds, ss, Verdict)]
    ci = ds["consistent_II"].values
    b = ds["beta1"].values
    hatch = np.where(ci == Consistency.CONSISTENT, 1.0, 0.0)
    art.append(
        ax.contourf(b, b, hatch.T, levels=[0.5, 1.5], colors="none", hatches=["////"], zorder=3)
    )
    art.append(
        ax.contourf(
            b,
            b,
            np.where(ci == Consistency.CONSISTENT, 1.0, np.nan).T,
            levels=[0.5, 1.5],
            colors=[Consistency.CONSISTENT.color],
            alpha=0.25,
            zorder=2,
        )
    )
    ref_cells = drawing.ss_boundary_cells(ref)
    art.append(drawing.dashed(ax, ref, "margin_SS", where=ref_cells, color="C3", lw=0.9, ls="-"))
    art.append(drawing.dashed(ax, ds, "margin_SS", where=drawing.ss_boundary_cells(ds)))
    art.append(
        drawing.dashed(
            ax,
            ds,
            "margin_II_consistent",
            where=drawing.near_change(ci, ds["class_code"].values),
            color=Consistency.CONSISTENT.color,
            lw=1.3,
        )
    )
    art += drawing.class_lines(ax, lw=0.5)
    if pos is not None:
        art += drawing.class_labels(ax, pos, fs=5.5)
    drawing.pi_axis(ax)
    ax.tick_params(labelsize=7)
    art.append(
        ax.set_title(_param_text(*(float(ds[k]) for k in ("kappa", "q1", "q2"))), fontsize=9)
    )
    return [a for a in art if a is not None]


@drawing.hatch_style
def _variants_legend(fig):
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    handles = drawing.legend_patches(
        Verdict,
        {0, 1, 2},
        {
            Verdict.STABLE: "SS stable",
            Verdict.UNSTABLE: "SS unstable",
            Verdict.NEUTRAL: "SS neutral (q = 0)",
        },
    )
    handles += [
        Patch(
            facecolor=Consistency.CONSISTENT.color, alpha=0.4, hatch="////", label="II consistent"
        ),
        Line2D([], [], color="k", ls="--", label="SS boundary (margin zero)"),
        Line2D(
            [], [], color=Consistency.CONSISTENT.color, ls="--", label="II consistency boundary"
        ),
        Line2D([], [], color="C3", label=r"SS boundary at $\kappa$=0.5, q=0 (reference)"),
    ]
    return fig.legend(handles=handles, loc="lower center", ncol=4, fontsize=8.5, frameon=False)


def draw_fig1_variants(fig, maps: list) -> list:
    """SS stability + II consistency at several (kappa, q1, q2) on ``fig``, 3 per row
    (:func:`draw_fig1_variant`); the reference (first map)'s SS boundary repeated in red."""
    ncol = 3
    nrow = math.ceil(len(maps) / ncol)
    axes = fig.subplots(nrow, ncol, squeeze=False).ravel()
    pos = drawing.label_positions(maps[0])
    art = []
    for ax, ds in zip(axes, maps, strict=False):
        art += draw_fig1_variant(ax, ds, maps[0], pos)
    for ax in axes[len(maps) :]:
        ax.axis("off")
    art.append(_variants_legend(fig))
    art.append(
        fig.suptitle(
            "Fig. 1 at other model parameters: the dashed (model-dependent) boundaries move; "
            "the straight class boundaries do not",
            fontsize=10,
        )
    )
    fig.subplots_adjust(left=0.05, right=0.99, bottom=0.1, top=0.93, wspace=0.18, hspace=0.3)
    return art


def plot_fig1_variants(path, maps: list):
    """Write the Fig. 1 variants (:func:`draw_fig1_variants`) to ``path``."""
    nrow = math.ceil(len(maps) / 3)
    fig = drawing.new_figure(figsize=(4.6 * 3, 4.7 * nrow + 0.8))
    draw_fig1_variants(fig, maps)
    return _save(fig, path)


# --------------------------------------------------------------------------- Table 2 figure

#: the paper's Table 2 shading (the reverse of the maps: there *stable* is dark)
TABLE_SHADE = {
    "unstable": "#4d4d4d",
    "model-dependent": "#c8c8c8",
    "stable": "#ffffff",
    "-": "#ffffff",
}


def _table2_cells(rows):
    """Cell texts, background colours and text colours of the Table 2 figure."""
    cells, colours, textc = [], [], []
    for r in rows:
        dual = "same" if r.dual == r.cls else str(r.dual)
        line = [f"{r.cls} ({dual})"]
        shade = ["#eeeeee"]
        for m in ("FF", "SS", "SF", "FS"):
            ks = " ".join(map(str, r.subclasses[m]))
            line.append(ks)
            shade.append(TABLE_SHADE[r.stability[m]] if ks else "#ffffff")
        line += [r.IF, r.FI, r.II, r.CC]
        shade += [
            "#ffffff",
            "#ffffff",
            TABLE_SHADE[r.II_stability] if r.II != "-" else "#ffffff",
            "#ffffff",
        ]
        cells.append(line)
        colours.append(shade)
        textc.append(["white" if c == TABLE_SHADE["unstable"] else "black" for c in shade])
    return cells, colours, textc


def draw_table2(ax, rows) -> list:
    """Table 2 on ``ax`` (axis off): unstable dark, model-dependent light, stable white (the
    paper's shading); ``rows`` from :func:`atlas.paper.tables.table2`.  Returns [table, title]."""
    cols = ["class (dual)", "FF", "SS", "SF", "FS", "IF", "FI", "II", "CC"]
    cells, colours, textc = _table2_cells(rows)
    ax.axis("off")
    tab = ax.table(
        cellText=cells,
        colLabels=cols,
        cellColours=colours,
        loc="upper center",
        cellLoc="center",
        colWidths=[0.16] + [0.105] * 8,
    )
    tab.auto_set_font_size(False)
    tab.set_fontsize(8.5)
    tab.scale(1, 1.25)
    for (i, j), cell in tab.get_celld().items():
        cell.set_edgecolor("0.6")
        if i == 0:
            cell.set_text_props(weight="bold")
        elif j > 0:
            cell.get_text().set_color(textc[i - 1][j])
    title = ax.set_title(
        "Table 2 (regenerated): subclasses k where a mode is consistent; background: "
        "dark = unstable,\nlight = model-dependent, white = stable. IWC markers: x "
        "consistent, (x) model-dependent, - never; CC: ? = necessary condition holds",
        fontsize=8.5,
    )
    return [tab, title]


def plot_table2(path, rows):
    """Write Table 2 as a figure (:func:`draw_table2`) to ``path``."""
    fig = drawing.new_figure(figsize=(8.4, 0.27 * len(rows) + 1.0))
    draw_table2(fig.subplots(), rows)
    fig.tight_layout()
    return _save(fig, path)
