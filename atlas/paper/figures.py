"""Fig. 1 (class diagram, stability maps) and the Table 2 figure of the paper, from the kernels.

Data flows one way: the certified kernels (:mod:`atlas.core.mechanics`, :mod:`atlas.core.spectral`) give the
verdicts, :mod:`atlas.core.exact` settles the few points the fast path leaves undecided, and this module
only arranges and draws them.  Colours and legends come from :class:`atlas.core.verdicts.Verdict` and
:class:`atlas.core.verdicts.Consistency`; categorical layers are ``pcolormesh`` with ``ListedColormap`` +
``BoundaryNorm``.  Model-dependent boundaries are dashed zero contours of *smooth margins*, never of
0/1 masks:

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
from atlas.core import points as evaluate
from atlas.core.verdicts import Consistency, Verdict
from atlas.data.io import savefig
from atlas.data.outputs import OUTPUTS, coord_attrs, to_storage, undecided, variable_attrs

__all__ = [
    "evaluate_points",
    "stability_map",
    "class_representatives",
    "plot_fig1_classes",
    "plot_fig1_stability",
    "plot_fig1_variants",
    "plot_table2",
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
    counts: dict = {}
    res = evaluate.spectral_points(
        c1, s1, c2, s2, kappa, q1, q2, resolve=resolve, max_resolve=max_resolve, stats=counts
    )
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
    raw = {**_mechanics_layers(c, s), **{k: ev[k] for k in evaluate.SPECTRAL_NAMES}}
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
    evaluate.settle_codes(raw, masks, C1, S1, C2, S2)
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


# --------------------------------------------------------------------------- plotting helpers


def _plt():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    plt.rcParams.update({"hatch.color": "0.55", "hatch.linewidth": 0.5})
    return plt


def _pi_axis(ax, which="both"):
    ticks = np.arange(5) * np.pi / 2
    labels = ["0", r"$\pi/2$", r"$\pi$", r"$3\pi/2$", r"$2\pi$"]
    if which in ("both", "x"):
        ax.set_xticks(ticks, labels)
    if which in ("both", "y"):
        ax.set_yticks(ticks, labels)
    ax.set_xlim(0, 2 * np.pi)
    ax.set_ylim(0, 2 * np.pi)
    ax.set_aspect("equal")


def _class_lines(ax, lw=0.6):
    """Straight class boundaries: axis directions of b1, b2 and beta2 = beta1, beta1 +- pi."""
    kw = dict(color="k", lw=lw, zorder=5)
    for v in (np.pi / 2, np.pi, 1.5 * np.pi):
        ax.axvline(v, **kw)
        ax.axhline(v, **kw)
    t = np.array([0, 2 * np.pi])
    ax.plot(t, t, **kw)
    ax.plot(t, t + np.pi, **kw)
    ax.plot(t, t - np.pi, **kw)


def _label_positions(ds):
    """Most interior cell of each class (max distance to the class's complement)."""
    from scipy.ndimage import distance_transform_edt

    cls = ds["class_code"].values
    b1, b2 = ds["beta1"].values, ds["beta2"].values
    pos = {}
    for code in mechanics.ALL_CLASSES:
        mask = cls == code
        if not mask.any():
            continue
        d = distance_transform_edt(np.pad(mask, 1))[1:-1, 1:-1]
        i, j = np.unravel_index(np.argmax(d), d.shape)
        pos[code] = (b1[i], b2[j])
    return pos


def _class_labels(ax, pos, fs=6.5):
    for code, (x, y) in pos.items():
        ax.text(
            x,
            y,
            str(code),
            ha="center",
            va="center",
            fontsize=fs,
            zorder=6,
            clip_on=True,
            bbox=dict(boxstyle="round,pad=0.1", fc="white", ec="none", alpha=0.75),
        )


def _categorical(ax, ds, field, enum, mask=None):
    """``pcolormesh`` of a categorical field with colours from the verdict enumeration."""
    from matplotlib.colors import BoundaryNorm, ListedColormap

    members = list(enum)
    codes = [int(m) for m in members]
    cmap = ListedColormap([m.color for m in members])
    bounds = np.array(codes + [codes[-1] + 1], float) - 0.5
    norm = BoundaryNorm(bounds, cmap.N)
    vals = np.asarray(field, float)
    if mask is not None:
        vals = np.ma.masked_where(~mask, vals)
    edges = np.linspace(0, 2 * np.pi, ds.sizes["beta1"] + 1)
    return ax.pcolormesh(edges, edges, vals.T, cmap=cmap, norm=norm, rasterized=True)


NOTHING_COLOR = "#fdae6b"


def _boolean(ax, ds, flag, color):
    """Two-colour ``pcolormesh`` of a boolean layer (white / ``color``)."""
    from matplotlib.colors import BoundaryNorm, ListedColormap

    edges = np.linspace(0, 2 * np.pi, ds.sizes["beta1"] + 1)
    return ax.pcolormesh(
        edges,
        edges,
        np.asarray(flag, float).T,
        cmap=ListedColormap(["white", color]),
        norm=BoundaryNorm([-0.5, 0.5, 1.5], 2),
        rasterized=True,
    )


def _hatch(ax, ds, flag):
    """Light hatching over the cells where ``flag`` holds (fill only; boundaries are drawn apart)."""
    b = ds["beta1"].values
    ax.contourf(
        b,
        b,
        np.where(flag, 1.0, np.nan).T,
        levels=[0.5, 1.5],
        colors="none",
        hatches=["///"],
        zorder=2,
    )


def _near_change(field, cls, width=2):
    """Cells within ``width`` of a change of ``field`` between cells of the same class."""
    from scipy.ndimage import binary_dilation

    ch = np.zeros(field.shape, bool)
    for axis in (0, 1):
        d = np.diff(field, axis=axis) != 0
        same = np.diff(cls, axis=axis) == 0
        e = d & same
        sl_a = [slice(None)] * 2
        sl_b = [slice(None)] * 2
        sl_a[axis] = slice(0, -1)
        sl_b[axis] = slice(1, None)
        ch[tuple(sl_a)] |= e
        ch[tuple(sl_b)] |= e
    return binary_dilation(ch, iterations=width) if ch.any() else ch


def _dashed(ax, ds, margin, where=None, color="k", lw=1.1, ls="--"):
    """Dashed zero contour of a smooth margin (optionally restricted to cells ``where``)."""
    m = np.array(ds[margin].values, float)
    m[ds["class_code"].values == 0] = np.nan  # degenerate cells (beta2 = beta1, b2 = -b1)
    if where is not None:
        m = np.where(where, m, np.nan)
    if not np.isfinite(m).any() or np.nanmin(m) >= 0 or np.nanmax(m) <= 0:
        return None
    b = ds["beta1"].values
    return ax.contour(b, b, m.T, levels=[0.0], colors=color, linewidths=lw, linestyles=ls, zorder=7)


def _ss_boundary_cells(ds):
    """Cells next to a change of the SS verdict inside one class (neutral counted as stable)."""
    v = ds["stable_SS"].values.copy()
    v[v == Verdict.NEUTRAL] = Verdict.STABLE
    return _near_change(v, ds["class_code"].values)


def _legend_patches(enum, present=None, relabel=None):
    from matplotlib.patches import Patch

    out = []
    for m in enum:
        if present is not None and int(m) not in present:
            continue
        label = (relabel or {}).get(m, m.label)
        out.append(Patch(facecolor=m.color, edgecolor="0.4", lw=0.5, label=label))
    return out


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


def plot_fig1_classes(path, reps: dict | None = None):
    """Fig. 1 (class diagram): ``b1``, ``b2`` (solid) and ``a`` for each subclass (dashed, k)."""
    plt = _plt()
    reps = reps or class_representatives()
    fig, axes = plt.subplots(4, 6, figsize=(13, 9.2))
    t = np.linspace(0, 2 * np.pi, 200)
    for ax, cls in zip(axes.ravel(), mechanics.ALL_CLASSES, strict=True):
        r = reps[cls]
        ax.plot(np.cos(t), np.sin(t), color="0.85", lw=0.6)
        ax.axhline(0, color="0.6", lw=0.5)
        ax.axvline(0, color="0.6", lw=0.5)
        b1s = r["beta1"] + np.pi
        ax.plot([0, np.cos(b1s)], [0, np.sin(b1s)], ls=":", color="C3", lw=0.9)
        for k, a in r["alpha"].items():
            ax.plot([0, 0.78 * np.cos(a)], [0, 0.78 * np.sin(a)], ls="--", color="0.35", lw=0.8)
            ax.text(
                0.93 * np.cos(a),
                0.93 * np.sin(a),
                str(k),
                ha="center",
                va="center",
                fontsize=7,
                color="0.2",
            )
        for j, (key, col) in enumerate((("beta1", "C3"), ("beta2", "C0"))):
            b = r[key]
            ax.annotate(
                "",
                xy=(np.cos(b), np.sin(b)),
                xytext=(0, 0),
                arrowprops=dict(arrowstyle="-|>", color=col, lw=1.6, mutation_scale=9),
            )
            ax.text(
                1.22 * np.cos(b),
                1.22 * np.sin(b),
                f"$b_{j + 1}$",
                color=col,
                fontsize=8,
                ha="center",
                va="center",
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
                    *mechanics.direction(r["beta1"]), *mechanics.direction(r["beta2"])
                )
            )
        )
        dual = int(dual)
        ax.set_title(f"class {cls} ({'same' if dual == cls else dual})", fontsize=9)
    fig.suptitle(
        "Fig. 1 (classes): directions of $b_1$, $b_2$ (solid) and of $a$ for subclasses "
        "k = 1..6 (dashed); dotted: $-b_1$; at representative points found by the kernels; (dual) in "
        "brackets",
        fontsize=10,
    )
    fig.tight_layout(rect=(0, 0, 1, 0.97))
    savefig(fig, path, dpi=DPI)
    plt.close(fig)
    return Path(path)


# --------------------------------------------------------------------------- Fig. 1, stability

_NEUTRAL_LABEL = {Verdict.NEUTRAL: "neutral (drawn as stable in the paper)"}


def _panels(axes, ds, pos, *, labels=True):
    """The seven layers of Fig. 1 plus the 'nothing stable' overview, one per axis."""
    cls = ds["class_code"].values
    n = ds.sizes["beta1"]
    ones = np.ones((n, n), bool)
    sf = np.broadcast_to(ds["stable_SF"].values[:, None], (n, n))
    fs = np.broadcast_to(ds["stable_FS"].values[None, :], (n, n))
    IF = np.broadcast_to(ds["consistent_IF"].values[:, None], (n, n)).astype(np.int8)
    FI = np.broadcast_to(ds["consistent_FI"].values[None, :], (n, n)).astype(np.int8)
    ss, ci, si = (ds[k].values for k in ("stable_SS", "consistent_II", "stable_II"))
    ss_ok = (ss == Verdict.STABLE) | (ss == Verdict.NEUTRAL)
    nothing = ~ss_ok & (IF == 0) & (FI == 0) & (si != Verdict.STABLE)
    kappa, q1, q2 = (float(ds[k]) for k in ("kappa", "q1", "q2"))
    ss_cells = _ss_boundary_cells(ds)
    ci_cells = _near_change(ci, cls)
    si_cells = _near_change(si, cls) & (ci == Consistency.CONSISTENT)
    layers = [
        ("SF stability ($b_{11} > 0$)", lambda ax: _categorical(ax, ds, sf, Verdict), []),
        ("FS stability ($b_{22} > 0$)", lambda ax: _categorical(ax, ds, fs, Verdict), []),
        ("SS stability", lambda ax: _categorical(ax, ds, ss, Verdict), [("margin_SS", ss_cells)]),
        ("IF consistent (then stable)", lambda ax: _categorical(ax, ds, IF, Consistency), []),
        ("FI consistent (then stable)", lambda ax: _categorical(ax, ds, FI, Consistency), []),
        (
            "II consistency",
            lambda ax: _categorical(ax, ds, ci, Consistency),
            [("margin_II_consistent", ci_cells)],
        ),
        (
            "II stability (hatched: II inconsistent)",
            lambda ax: (
                _categorical(ax, ds, si, Verdict, mask=ci == Consistency.CONSISTENT),
                _hatch(ax, ds, ci != Consistency.CONSISTENT),
            ),
            [("margin_II_stable", si_cells), ("margin_II_consistent", ci_cells)],
        ),
        (
            "SS unstable, no stable IWC (orange; Sec. 6.4)",
            lambda ax: _boolean(ax, ds, nothing, NOTHING_COLOR),
            [("margin_SS", ss_cells)],
        ),
    ]
    for ax, (title, draw, dashed) in zip(axes, layers, strict=True):
        ax.set_facecolor("white")
        draw(ax)
        for m, cells in dashed:
            if m in ds:
                _dashed(ax, ds, m, where=cells & ones)
        _class_lines(ax)
        if labels:
            _class_labels(ax, pos)
        _pi_axis(ax)
        ax.set_title(title, fontsize=9)
        ax.tick_params(labelsize=7)
    for ax in axes[-4:]:
        ax.set_xlabel(r"$\beta_1$", fontsize=9)
    for ax in axes[::4]:
        ax.set_ylabel(r"$\beta_2$", fontsize=9)
    return kappa, q1, q2


def _param_text(kappa, q1, q2):
    q = f"q = {q1:g}" if q1 == q2 else f"q1 = {q1:g}, q2 = {q2:g}"
    return rf"$\kappa$ = {kappa:g}, {q}"


def plot_fig1_stability(path, ds):
    """Fig. 1 (stability map): 8 panels in the beta1-beta2 plane, legend from the verdict enums."""
    from matplotlib.lines import Line2D

    plt = _plt()
    fig, axes = plt.subplots(2, 4, figsize=(15.5, 9.4))
    pos = _label_positions(ds)
    kappa, q1, q2 = _panels(axes.ravel(), ds, pos)
    present_v = (
        set(np.unique(ds["stable_SS"].values).tolist())
        | {0, 1}
        | set(np.unique(ds["stable_II"].values).tolist())
    )
    handles = _legend_patches(Verdict, present_v, _NEUTRAL_LABEL)
    handles += _legend_patches(
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
            label="model-dependent boundary (zero of smooth margin)",
        ),
    ]
    fig.legend(handles=handles, loc="lower center", ncol=5, fontsize=8.5, frameon=False)
    und = int(ds.attrs.get("n_undecided", 0))
    fig.suptitle(
        f"Fig. 1 (stability map), {_param_text(kappa, q1, q2)}; grid "
        f"{ds.sizes['beta1']}$^2$, {ds.attrs.get('n_resolved', 0)} cells settled by the "
        f"exact reference, {und} undecided. FF (always stable when consistent) not shown.",
        fontsize=10,
    )
    # explicit margins: tight_layout mis-sizes the equal-aspect panels, so the bottom row's titles
    # ran into the top row's tick labels; hspace leaves room for tick labels + title
    fig.subplots_adjust(left=0.045, right=0.99, bottom=0.13, top=0.92, wspace=0.2, hspace=0.34)
    savefig(fig, path, dpi=DPI)
    plt.close(fig)
    return Path(path)


def plot_fig1_variants(path, maps: list):
    """SS stability + II consistency at several (kappa, q1, q2); the reference (first map)'s
    dashed SS boundary is repeated in red in every panel to show how the boundaries move."""
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    plt = _plt()
    ncol = 3
    nrow = math.ceil(len(maps) / ncol)
    fig, axes = plt.subplots(nrow, ncol, figsize=(4.6 * ncol, 4.7 * nrow + 0.8), squeeze=False)
    ref = maps[0]
    ref_cells = _ss_boundary_cells(ref)
    pos = _label_positions(ref)
    for ax, ds in zip(axes.ravel(), maps, strict=False):
        ss = ds["stable_SS"].values
        _categorical(ax, ds, ss, Verdict)
        ci = ds["consistent_II"].values
        b = ds["beta1"].values
        hatch = np.where(ci == Consistency.CONSISTENT, 1.0, 0.0)
        ax.contourf(b, b, hatch.T, levels=[0.5, 1.5], colors="none", hatches=["////"], zorder=3)
        ax.contourf(
            b,
            b,
            np.where(ci == Consistency.CONSISTENT, 1.0, np.nan).T,
            levels=[0.5, 1.5],
            colors=[Consistency.CONSISTENT.color],
            alpha=0.25,
            zorder=2,
        )
        _dashed(ax, ref, "margin_SS", where=ref_cells, color="C3", lw=0.9, ls="-")
        _dashed(ax, ds, "margin_SS", where=_ss_boundary_cells(ds))
        _dashed(
            ax,
            ds,
            "margin_II_consistent",
            where=_near_change(ci, ds["class_code"].values),
            color=Consistency.CONSISTENT.color,
            lw=1.3,
        )
        _class_lines(ax, lw=0.5)
        _class_labels(ax, pos, fs=5.5)
        _pi_axis(ax)
        ax.tick_params(labelsize=7)
        ax.set_title(_param_text(*(float(ds[k]) for k in ("kappa", "q1", "q2"))), fontsize=9)
    for ax in axes.ravel()[len(maps) :]:
        ax.axis("off")
    handles = _legend_patches(
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
    fig.legend(handles=handles, loc="lower center", ncol=4, fontsize=8.5, frameon=False)
    fig.suptitle(
        "Fig. 1 at other model parameters: the dashed (model-dependent) boundaries move; "
        "the straight class boundaries do not",
        fontsize=10,
    )
    fig.subplots_adjust(left=0.05, right=0.99, bottom=0.1, top=0.93, wspace=0.18, hspace=0.3)
    savefig(fig, path, dpi=DPI)
    plt.close(fig)
    return Path(path)


# --------------------------------------------------------------------------- Table 2 figure

#: the paper's Table 2 shading (the reverse of the maps: there *stable* is dark)
TABLE_SHADE = {
    "unstable": "#4d4d4d",
    "model-dependent": "#c8c8c8",
    "stable": "#ffffff",
    "-": "#ffffff",
}


def plot_table2(path, rows):
    """Table 2 as a figure: unstable dark, model-dependent light, stable white (paper's shading)."""
    plt = _plt()
    cols = ["class (dual)", "FF", "SS", "SF", "FS", "IF", "FI", "II", "CC"]
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
    fig, ax = plt.subplots(figsize=(8.4, 0.27 * len(rows) + 1.0))
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
    ax.set_title(
        "Table 2 (regenerated): subclasses k where a mode is consistent; background: "
        "dark = unstable,\nlight = model-dependent, white = stable. IWC markers: x "
        "consistent, (x) model-dependent, - never; CC: ? = necessary condition holds",
        fontsize=8.5,
    )
    fig.tight_layout()
    savefig(fig, path, dpi=DPI)
    plt.close(fig)
    return Path(path)
