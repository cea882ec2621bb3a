"""The maps behind Fig. 1 of the paper: verdicts and smooth margins on the beta1-beta2 plane.

Data flows one way: the registry's point kernels (:mod:`atlas.data.plane`, :mod:`atlas.core.kernels`)
give the verdicts, :mod:`atlas.core.exact` settles the few points the fast path leaves undecided,
this module arranges them in Datasets (:func:`stability_map`, :func:`class_representatives`) and
:mod:`atlas.paper.plots` draws them.  Model-dependent boundaries are drawn dashed: on Fig. 1 of
``atlas paper`` from the certified curves of :func:`atlas.boundaries`, else as zero contours of the
*smooth margins* computed here (never of 0/1 masks):

* SS stability: :func:`atlas.core.hurwitz.ss_margin` (``G/|G|`` when damped, the discriminant of the
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

import numpy as np

from atlas.core import baseline, contact_modes, expressions, warm
from atlas.core.points import spectral_points
from atlas.data.outputs import OUTPUTS, coord_attrs, default_outputs, to_storage, variable_attrs
from atlas.data.plane import map_dims, plane_outputs

__all__ = [
    "evaluate_points",
    "stability_map",
    "map_outputs",
    "class_representatives",
    "VARIANTS",
    "MAX_RESOLVE",
]

#: at most this many undecided points of a map are settled by the exact reference
MAX_RESOLVE = 5000
#: (kappa, q1, q2) of the variant maps (Fig. 1 at other model parameters)
VARIANTS = (
    (0.5, 0.0, 0.0),
    (2.0, 0.0, 0.0),
    (0.5, 0.1, 0.1),
    (0.5, 1.0, 1.0),
    (2.0, 1.0, 1.0),
    (0.5, 1.0, 0.01),
)


# --------------------------------------------------------------------------- computing the maps


def evaluate_points(
    c1, s1, c2, s2, kappa, q1, q2, *, resolve=True, max_resolve=MAX_RESOLVE
) -> dict:
    """Certified spectral verdicts (via :func:`atlas.core.points.spectral_points`) for
    broadcastable arrays.

    Returns numpy arrays of the broadcast shape: ``stable_SS``, ``consistent_II``, ``stable_II``,
    ``spectral_abscissa`` [(time of contact 2)^-1]; ints ``n_resolved`` (points settled exactly)
    and ``n_undecided`` (left undecided).
    """
    res = spectral_points(c1, s1, c2, s2, kappa, q1, q2, resolve=resolve, max_resolve=max_resolve)
    counts = res.stats
    res["n_resolved"] = counts["undecided_before"] - counts["undecided_after"] if resolve else 0
    res["n_undecided"] = counts["undecided_after"]
    return res


def _offset_grid(n):
    """Cell centres ``(i + 1/2) 2 pi / n`` [rad] (no centre lies on an axis or on beta2 = beta1)."""
    return (np.arange(n) + 0.5) * (2 * np.pi / n)


def _quartic_discriminant(a3, a2, a1, a0):
    """Discriminant of the monic quartic, divided by a positive degree-12 scale (smooth, bounded)."""
    b, c, d, e = a3, a2, a1, a0
    disc = expressions.quartic_discriminant(b, c, d, e, sub=np.subtract)
    scale = (np.abs(b) + np.abs(c) ** 0.5 + np.abs(d) ** (1 / 3) + np.abs(e) ** 0.25) ** 12
    return disc / np.where(scale > 0, scale, 1.0)


def _ss_margin_full(margin, c1, s2, kappa, q1, q2):
    """SS margin whose zero set is *every* model-dependent SS boundary.

    :func:`atlas.core.hurwitz.ss_margin` covers ``G`` (damped) and the discriminant (``Q = 0``); the
    other condition that depends on the model is ``a2 = kappa c1 + s2 >= 0`` (``Q = 0``) or
    ``a3 = c1 q1 + s2 q2 > 0`` (damped), whose sign changes inside classes 23 and 46.  The minimum
    of the normalised quantities is continuous and its zero set is the boundary.
    """
    c1, s2 = np.asarray(c1, float), np.asarray(s2, float)
    if q1 == 0 and q2 == 0:

        def part(c, s, sub):
            return expressions.a2_undamped(kappa, c, 1, s, sub=sub)
    else:

        def part(c, s, sub):
            return expressions.a3(c, s, q1, q2, sub=sub)

    a = part(c1, s2, np.subtract) / (part(np.abs(c1), np.abs(s2), np.add) + 1e-300)
    return np.minimum(np.asarray(margin, float), a)


#: :func:`atlas.core.baseline.build_M` as one kept program (products and negations only: the
#: same numbers as its operations one by one)
_build_M = warm.jit(baseline.build_M)


def _ii_root_margin(c1, s1, c2, s2, kappa, q1, q2):
    """``Re(l_II) - max Re(other roots)`` (NaN where no II root), scaled by the root magnitude."""
    M = np.asarray(_build_M(*(np.asarray(a, np.float64) for a in (c1, s1, c2, s2, kappa, q1, q2))))
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

    Returns an ``xarray.Dataset`` with every atlas output of the registry that needs no ``alpha``
    (:func:`map_outputs`: ``class_code``, ``stable_SF`` ... ``stable_SS``, ``consistent_II``,
    ``stable_II``, ``spectral_abscissa``) plus the smooth margins ``margin_SS``,
    ``margin_II_consistent``, ``margin_II_stable`` used for the dashed contours, with the stored
    types and attributes of :mod:`atlas.data.outputs` (an atlas slice: ``stable_SF`` is ``True``
    iff stable).  ``kappa``, ``q1``, ``q2`` are scalar coordinates.
    """
    import xarray as xr

    b = _offset_grid(n)
    names = map_outputs() + (("margin_SS",) if margins else ())
    raw = plane_outputs(names, b, (kappa, q1, q2), max_resolve=MAX_RESOLVE)
    counts = raw.stats
    if margins:
        c, s = contact_modes.direction(b)
        C1, S1, C2, S2 = c[:, None], s[:, None], c[None, :], s[None, :]
        raw.update(_margin_layers(raw["margin_SS"], C1, S1, C2, S2, kappa, q1, q2))
    coords = {k: (k, b, coord_attrs(k)) for k in ("beta1", "beta2")}
    coords.update({k: ((), float(v), coord_attrs(k)) for k, v in zip(_MODEL, (kappa, q1, q2))})
    data = {
        k: (map_dims(k), to_storage(k, v, np.float64), variable_attrs(k)) for k, v in raw.items()
    }
    ds = xr.Dataset(data, coords=coords)
    if margins:
        ds["margin_SS"].attrs["comment"] = _MARGIN_SS_COMMENT
    n_undecided = counts.get("undecided_after", 0)
    ds.attrs.update(
        n_resolved=counts.get("undecided_before", 0) - n_undecided, n_undecided=n_undecided
    )
    return ds


def map_outputs() -> tuple[str, ...]:
    """The verdicts of a Fig. 1 map: the registry's default outputs with a point kernel that need
    no ``alpha``, in registry order."""
    return tuple(
        n
        for n in default_outputs()
        if OUTPUTS[n].kernel is not None and "alpha" not in OUTPUTS[n].depends
    )


_MODEL = ("kappa", "q1", "q2")
_MARGIN_SS_COMMENT = (
    "min(atlas.core.hurwitz.ss_margin, a2 (q = 0) or a3 (damped) normalised): "
    "zero on every model-dependent SS boundary"
)


def _margin_layers(ss_margin, C1, S1, C2, S2, kappa, q1, q2) -> dict:
    """The smooth margins whose zero contours are drawn as the model-dependent boundaries."""
    n = C1.size
    if q1 == 0 and q2 == 0:
        mii = ss_margin  # the mu-discriminant (see module docstring)
    else:
        # :func:`atlas.core.spectral.coefficients` in NumPy: the same roundings, no op dispatch
        D = expressions.det(C1, S1, C2, S2, sub=np.subtract)
        k, q1, q2 = float(kappa), float(q1), float(q2)
        a3, a2, a1, a0 = expressions.coefficients(
            C1, S1, C2, S2, k, 1.0, q1, q2, D, sub=np.subtract
        )
        mii = np.broadcast_to(_quartic_discriminant(a3, a2, a1, a0), (n, n))
    return {
        "margin_SS": _ss_margin_full(ss_margin, C1, S2, kappa, q1, q2),
        "margin_II_consistent": np.array(mii),
        "margin_II_stable": _ii_root_margin(C1, S1, C2, S2, kappa, q1, q2),
    }


# --------------------------------------------------------------------------- Fig. 1, classes


def class_representatives(n: int = 96, n_alpha: int = 1440) -> dict:
    """One interior ``(beta1, beta2)`` per class and one ``alpha`` per subclass ``k = 1..6`` [rad].

    The class point is the class sample (:func:`atlas.paper.tables.class_samples`) farthest from the
    class boundaries (largest minimum angular gap to beta1, beta1*, and the axes); alpha for
    subclass ``k`` is the middle of the arc of ``k`` found by :func:`atlas.core.contact_modes.subclass_code`.
    """
    from atlas.paper.tables import class_samples

    samples = class_samples(n, per_class=10_000)
    alpha = _offset_grid(n_alpha)
    ca, sa = (np.asarray(v) for v in contact_modes.direction(alpha))
    out = {}
    for cls, pts in samples.items():
        b1, b2 = pts[:, 0], pts[:, 1]
        refs = [np.pi / 2, np.pi, 1.5 * np.pi, 0.0]
        gap1 = np.min([np.abs(np.angle(np.exp(1j * (b1 - r)))) for r in refs], 0)
        refs2 = [b1, b1 + np.pi] + refs
        gap2 = np.min([np.abs(np.angle(np.exp(1j * (b2 - r)))) for r in refs2], 0)
        best = int(np.argmax(np.minimum(gap1, gap2)))
        beta1, beta2 = float(b1[best]), float(b2[best])
        # the class point's directions spread over the alpha grid: the program of Table 1's
        # columns (one trace fewer in a run), the same certified codes
        pair = (*contact_modes.direction(beta1), *contact_modes.direction(beta2))
        sub = np.asarray(contact_modes.subclass_code(*(np.full_like(ca, v) for v in pair), ca, sa))
        alphas = {}
        for k in range(1, 7):
            hit = alpha[sub == 10 * cls + k]
            if hit.size:
                alphas[k] = float(np.median(hit))
        out[cls] = {"beta1": beta1, "beta2": beta2, "alpha": alphas}
    return out
