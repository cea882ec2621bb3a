"""The curves that separate the regions of a verdict over a box of contact models, certified.

A verdict over a box (``ss_over_models``, :mod:`atlas.core.model_box`: stable for every model,
unstable for every model, depends on the model) splits a ``(beta1, beta2)`` slice into regions.
:func:`region_curves` returns their boundaries as :class:`atlas.data.boundary_curves.Curve`
polylines (``field`` the output's name, ``kind`` ``<name>_region``), certified the way
:mod:`atlas.data.boundaries` certifies its vertices:

1. **Grid.** The proven codes (settled) on the grid's nodes.
2. **Tracing.** Marching triangles (:mod:`atlas.data.marching`) on each code's region; each vertex
   is a grid edge whose two ends carry different proven codes: a bracket.  A polyline is cut where
   the code across it changes, each interface kept once (from the lower code's side).
3. **Certified vertices.** Every bracket is bisected on the proven verdict at its midpoint (the
   small budget of :mod:`atlas.core.model_box`, the settlement's for up to :data:`SETTLE`
   midpoints it leaves undecided) until it is ``<= tol`` long; the
   vertex is its midpoint, within ``bracket / 2`` of the true boundary.  A midpoint left undecided
   after the settlement (or of a third code: a junction inside the bracket; or no float left
   between the ends) stops that bracket: its length, per vertex
   in ``Curve.bracket``, is what is claimed, never less.  ``attrs["stopped"]`` counts them.
   ``Curve.ends[i]`` holds the bracket's ends: ``[0]`` of code ``side_right`` (the lower),
   ``[1]`` of code ``side_left``.

Between vertices the polyline is a chord of the grid's resolution (not refined, unlike
:mod:`atlas.data.boundaries`: no sagitta is claimed).  Side codes: ``side_left`` is the higher
code, left of the direction of travel (as for the other curves).  The verdict at a point comes
from :func:`atlas.data.box_points.point_values`.
"""

from __future__ import annotations

import math
import time

import numpy as np

from atlas.core.verdicts import OverModels
from atlas.data.boundary_curves import Boundaries, Curve
from atlas.data.box_points import box_outputs, point_values
from atlas.data.marching import region_boundaries
from atlas.data.over_models import as_model_box

__all__ = ["region_curves", "RegionCurves", "point_codes", "run_cli", "TOL", "labels"]

#: default length of a vertex's certified bracket [rad]
TOL = 1e-8
#: midpoints a run settles with the large budget (each can take seconds near a curved boundary)
SETTLE = 256


def labels(name: str) -> dict[int, str]:
    """The codes of box verdict ``name`` in words (its declared codes' labels)."""
    from atlas.data.outputs import OUTPUTS  # noqa: PLC0415

    return {c.value: c.label for c in OUTPUTS[name].codes.codes}


def point_codes(name: str, beta1, beta2, box, *, settle: bool, dtype="float64") -> np.ndarray:
    """The proven codes of box verdict ``name`` over ``box`` at the points ``(beta1[i],
    beta2[i])`` [rad] (:func:`atlas.data.box_points.point_values`)."""
    if name not in box_outputs():
        raise ValueError(f"fields: {name} has no point function in atlas.core.model_box")
    res = point_values(beta1, beta2, box, (name,), settle=settle, dtype=dtype)
    return np.asarray(res[name], np.int8)


def _bisect(name, lo, hi, code_lo, code_hi, box, tol, dtype, settle):
    """Shrink the brackets ``lo`` (code ``code_lo``) - ``hi`` (``code_hi``), rows ``(beta1,
    beta2)``, to ``<= tol`` on proven midpoint codes (the small budget, then the settlement's
    for at most ``settle`` midpoints it leaves undecided); returns ``(lo, hi, stopped,
    settled)``."""
    lo, hi = np.array(lo, np.float64).reshape(-1, 2), np.array(hi, np.float64).reshape(-1, 2)
    stopped, settled = np.zeros(len(lo), bool), 0
    while True:
        active = ~stopped & (np.hypot(*(hi - lo).T) > tol)
        if not active.any():
            return lo, hi, stopped, settled
        idx = np.flatnonzero(active)
        mid = 0.5 * (lo[idx] + hi[idx])
        code = point_codes(name, mid[:, 0], mid[:, 1], box, settle=False, dtype=dtype)
        und = np.flatnonzero(code == int(OverModels.UNDECIDED))[: max(settle - settled, 0)]
        if len(und):  # the settlement's budget, for at most ``settle`` midpoints a run
            code[und] = point_codes(name, *mid[und].T, box, settle=True, dtype=dtype)
            settled += len(und)
        flat = np.all((mid == lo[idx]) | (mid == hi[idx]), axis=1)  # no float between the ends
        to_lo, to_hi = code == code_lo[idx], code == code_hi[idx]
        lo[idx[to_lo]] = mid[to_lo]
        hi[idx[to_hi]] = mid[to_hi]
        stopped[idx[(~to_lo & ~to_hi) | flat]] = True


def _pieces(codes: np.ndarray):
    """``(in_nodes, out_nodes, code_in, code_out)`` per traced piece: the boundary of each
    code's region cut where the code across it changes, each interface once (lower code in)."""
    flat = codes.ravel()
    out = []
    for c in np.unique(flat):
        for p_in, p_out in region_boundaries(codes == c):
            across = flat[p_out]
            cuts = np.flatnonzero(np.diff(across)) + 1
            for a, b in zip(np.r_[0, cuts], np.r_[cuts, len(across)]):
                if across[a] > c and b - a >= 1:
                    out.append((p_in[a:b], p_out[a:b], int(c), int(across[a])))
    return out


def _oriented(v: np.ndarray, lo: np.ndarray, hi: np.ndarray, ends: np.ndarray):
    """The piece (and its ``ends``) reversed if the higher code's side (``hi``) is on the right
    of the direction of travel."""
    if len(v) < 2:
        return v, ends
    d = np.diff(v, axis=0)
    side = (hi[:-1] - v[:-1]) - (lo[:-1] - v[:-1])
    left = np.sum(np.sign(d[:, 0] * side[:, 1] - d[:, 1] * side[:, 0]))
    return (v, ends) if left >= 0 else (v[::-1], ends[::-1])


def region_curves(
    beta1, beta2, box, name: str = "ss_over_models", *, tol=TOL, dtype="float64", settle=SETTLE
):
    """The certified region boundaries of box verdict ``name`` over ``box`` on the grid ``beta1 x
    beta2`` [rad] (module docstring): :class:`RegionCurves` with one
    :class:`~atlas.data.boundary_curves.Curve` per piece, ``attrs``: ``model_box``, ``tolerance``,
    ``stopped`` (brackets stopped above ``tol``), ``grid_undecided``, ``seconds``, ``fields``.
    ``settle``: how many midpoints the small budget leaves undecided get the settlement's (the
    rest stop their brackets; ``attrs["settled"]``); 0: none."""
    t0 = time.perf_counter()
    box = as_model_box(box)  # a ModelBox, its text or a dict
    b1 = np.asarray(beta1, np.float64).ravel()
    b2 = np.asarray(beta2, np.float64).ravel()
    if b1.size < 2 or b2.size < 2:
        raise ValueError("beta1: the grid needs at least 2 x 2 nodes")
    if not (math.isfinite(tol) and tol > 0):
        raise ValueError(f"tol: must be a positive number, got {tol!r}")
    if isinstance(settle, bool) or not isinstance(settle, int) or settle < 0:
        raise ValueError(f"settle: must be an integer >= 0, got {settle!r}")
    g1, g2 = np.meshgrid(b1, b2, indexing="ij")
    codes = point_codes(name, g1.ravel(), g2.ravel(), box, settle=True, dtype=dtype)
    codes = codes.reshape(g1.shape)
    nodes = np.stack([g1.ravel(), g2.ravel()], axis=1)
    undecided = int(OverModels.UNDECIDED)
    pieces = [p for p in _pieces(codes) if undecided not in p[2:]]  # both ends proven
    cat = lambda f: np.concatenate([f(p) for p in pieces] or [np.zeros(0, int)])  # noqa: E731
    lo, hi, stop, settled = _bisect(  # every bracket of every piece at once: one proof batch a step
        name,
        nodes[cat(lambda p: p[0])],
        nodes[cat(lambda p: p[1])],
        cat(lambda p: np.full(len(p[0]), p[2])),
        cat(lambda p: np.full(len(p[0]), p[3])),
        box,
        tol,
        dtype,
        settle,
    )
    curves, at = [], 0
    for p_in, _, c_in, c_out in pieces:
        sl = slice(at, at + len(p_in))
        at += len(p_in)
        ends = np.stack([lo[sl], hi[sl]], axis=1)
        v, ends = _oriented(0.5 * (lo[sl] + hi[sl]), lo[sl], hi[sl], ends)
        br = np.hypot(*(ends[:, 1] - ends[:, 0]).T)
        curves.append(Curve(name, f"{name}_region", c_out, c_in, v, br, ends=ends))
    attrs = dict(
        model_box=str(box),
        tolerance=tol,
        chord_tolerance=math.nan,  # chords are not refined: no sagitta claimed
        stopped=int(stop.sum()),
        settled=settled,
        grid_undecided=int(np.sum(codes == undecided)),
        seconds=time.perf_counter() - t0,
        history=f"atlas.data.region_curves ({name} over {box})",
    )
    return RegionCurves(curves, [], attrs | {"fields": name})


class RegionCurves(Boundaries):
    """Region curves: :class:`~atlas.data.boundary_curves.Boundaries` whose netCDF side codes
    are those of the box verdicts (``region_labels``), not of field SS / II."""

    def to_netcdf(self, path) -> None:
        _write_netcdf(self, path)


def _fields(fields: str | None) -> tuple[str, ...]:
    """The box verdicts to trace: ``fields`` (comma-separated output names, or the fields of
    ``atlas boundaries``: ``SS`` for ``ss_over_models``, ``II`` for the II verdicts) or, for
    ``None``, every one (:func:`atlas.data.box_points.box_outputs`); one-line errors."""
    known = box_outputs()
    names = []
    for f in (fields or ",".join(known)).split(","):
        f = f.strip()
        if f in ("SS", "II"):
            names += [n for n in known if n.startswith(f.lower() + "_")]
        elif f:
            names.append(f)
    bad = [n for n in names if n not in known]
    if bad or not names:
        raise ValueError(f"fields: with --model-box, SS, II or among {', '.join(known)}; got {bad}")
    return tuple(dict.fromkeys(names))


def run_cli(
    out=None,
    csv=None,
    geojson=None,
    overwrite=False,
    fields=None,
    tol=TOL,
    dtype="float64",
    model_box=None,
    beta1=None,
    beta2=None,
    **ignored,
) -> int:
    """``atlas boundaries --model-box BOX --beta1 R --beta2 R [--tol T] [--out F.nc] [--csv F]
    [--geojson F] [--fields F]``: the region boundaries of the box verdicts ``fields``
    (:func:`_fields`; default every one, :func:`region_curves`); the model axes (``--kappa``,
    ``--q`` ...) are refused, the box replaces them, and so are ``--chord`` and ``--check``,
    which do not apply."""
    from atlas.data.boundary_curves import summary  # noqa: PLC0415
    from atlas.data.io import check_output_path  # noqa: PLC0415
    from atlas.data.over_models import as_model_box  # noqa: PLC0415
    from atlas.data.scene import Scene  # noqa: PLC0415

    for name in ("kappa", "q", "q1", "q2"):
        if ignored.get(name) is not None:
            raise ValueError(f"{name}: not with --model-box (the model box replaces the model)")
    for name in ("chord", "check"):
        if ignored.get(name) is not None:
            raise ValueError(f"{name}: not with --model-box (region curves are not refined)")
    box = as_model_box(model_box)
    names = _fields(fields)
    paths = [p for p in (out, csv, geojson) if p is not None]
    for path in paths:
        check_output_path(path, overwrite)
    scene = Scene(**{k: v for k, v in (("beta1", beta1), ("beta2", beta2)) if v is not None})
    b1, b2 = (np.atleast_1d(scene.axes[k].values).astype(float) for k in ("beta1", "beta2"))
    parts = [region_curves(b1, b2, box, n, tol=tol, dtype=dtype) for n in names]
    bd = RegionCurves([c for p in parts for c in p.curves], [], dict(parts[0].attrs))
    bd.attrs.update(stopped=sum(p.attrs["stopped"] for p in parts), fields=",".join(names))
    bd.attrs["settled"] = sum(p.attrs["settled"] for p in parts)
    print(
        summary(bd) + f"\n  model box {box}: {bd.attrs['stopped']} brackets stopped above tol "
        f"(a midpoint undecided or of a third code; {bd.attrs['settled']} midpoints settled); "
        "chords not refined (nan: none claimed)"
    )
    for path, write in ((out, bd.to_netcdf), (csv, bd.to_csv), (geojson, bd.to_geojson)):
        if path is not None:
            write(path)
            print(f"wrote {path}")
    return 0


def _write_netcdf(bd: Boundaries, path) -> None:
    """The curves' CF geometry container with the box and the region codes' meanings."""
    import json  # noqa: PLC0415

    from atlas.data.io import atomic_path  # noqa: PLC0415

    ds = bd.to_dataset()
    words = json.dumps({f: labels(f) for f in bd.attrs["fields"].split(",")})
    for k in ("curve_side_left", "curve_side_right"):
        ds[k].attrs["comment"] = "codes over the model box, per field: " + words
    ds.attrs.update(model_box=bd.attrs["model_box"], region_labels=words)
    ds.attrs.update(stopped_brackets=int(bd.attrs["stopped"]), fields=bd.attrs["fields"])
    with atomic_path(path) as tmp:
        ds.to_netcdf(tmp)
