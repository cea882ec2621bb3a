"""Boundary curves as objects: :class:`Curve`, :class:`Point`, :class:`Boundaries` and their storage.

:mod:`atlas.data.boundaries` computes them; this module holds what a result is and how it is
written: a CF-1.10 geometry container (``geometry_type = "line"``, one ``node_count`` per curve,
node coordinates ``node_beta1``/``node_beta2`` [rad]) plus the codimension-2 points
(:meth:`Boundaries.to_dataset`), one CSV row per vertex, or GeoJSON.
"""

from __future__ import annotations

import collections
import datetime
import json
import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from atlas.core import brackets
from atlas.core.config import __version__
from atlas.data.boundary_args import CHORD, CODE_MEANINGS, CSV_COLUMNS, TOL
from atlas.data.engine import REFERENCES
from atlas.data.io import atomic_path, atomic_write_text

if TYPE_CHECKING:
    import xarray as xr

__all__ = ["CHORD", "CSV_COLUMNS", "TOL", "Boundaries", "Curve", "Point", "summary"]


@dataclass
class Curve:
    """One boundary polyline: ``vertices`` ``(m, 2)`` of ``(beta1, beta2)`` [rad].

    ``field``: ``"SS"``, ``"II"`` or ``"class"``; ``kind``: ``SS_stability``, ``II_consistency``,
    ``II_stability`` or ``class_line``; ``side_left``/``side_right``: the certified field codes
    (:data:`atlas.core.brackets.FIELD_LABELS`) found just off every vertex to the left and to the
    right of the direction of travel, the higher code on the left (-1 for class lines);
    ``side_on``: the code on the piece itself where it lies on a class line and differs from both
    sides, else -1 (:mod:`atlas.data.boundary_sides`); ``bracket``: per vertex, the length of its
    certified bracket [rad] (0 for the closed-form class lines; NaN for a point where the curve
    crosses a seam of the torus, interpolated on its segment); ``ends``: per vertex the
    bracket's two ends ``(m, 2, 2)`` (the vertex is their midpoint; NaN at a seam point),
    ``None`` for class lines; ``spliced``: the indices of vertices that are proven
    codimension-2 points spliced in after labelling (:func:`atlas.data.boundary_points.attach_points`:
    ``bracket`` twice the point's proven radius, ``ends`` NaN; three codes meet there, so the side
    labels hold next to them, not at them); ``side_offset``: NaN where the side labels hold the
    run's side step off every vertex (:func:`atlas.data.boundary_sides.side_step`), else the
    smaller offset [rad] at which they are proven (a class-line piece along which another
    boundary runs closer to the line than the side step: :func:`atlas.data.boundary_cover.cover_lines`).
    """

    field: str
    kind: str
    side_left: int
    side_right: int
    vertices: np.ndarray
    bracket: np.ndarray
    on_class_line: bool = False
    kappa: float = math.nan
    q1: float = math.nan
    q2: float = math.nan
    ends: np.ndarray | None = None
    side_on: int = -1
    spliced: tuple[int, ...] = ()
    side_offset: float = math.nan


@dataclass
class Point:
    """A codimension-2 point: where boundaries meet, cross or touch a class line, or end.

    ``proven``: the true point lies within ``uncertainty`` [rad] (Euclidean) of ``(beta1,
    beta2)``, a proven enclosure; else ``uncertainty`` is NaN and the position is an estimate
    (no bound is claimed).  ``field``: the field whose boundary it is on (``""``: both).
    ``reason``: why an ``undecided_line_root`` is left undecided (a key of
    :data:`atlas.data.boundary_roots.REASONS`), else ``""``."""

    beta1: float
    beta2: float
    kind: str
    uncertainty: float
    kappa: float = math.nan
    q1: float = math.nan
    q2: float = math.nan
    proven: bool = False
    field: str = ""
    reason: str = ""


@dataclass
class Boundaries:
    """The curves and codimension-2 points of one or more slices, with run diagnostics."""

    curves: list[Curve] = field(default_factory=list)
    points: list[Point] = field(default_factory=list)
    attrs: dict = field(default_factory=dict)

    def select(self, *, field=None, kind=None) -> list[Curve]:
        """The curves of a field and/or kind."""
        return [
            c
            for c in self.curves
            if (field is None or c.field == field) and (kind is None or c.kind == kind)
        ]

    def to_dataset(self) -> xr.Dataset:
        """CF-1.10 geometry container (``geometry_type = "line"``) of the curves, plus the points."""
        return _to_dataset(self)

    def to_netcdf(self, path) -> None:
        """Write :meth:`to_dataset` (atomically)."""
        with atomic_path(path) as tmp:
            self.to_dataset().to_netcdf(tmp)

    def to_csv(self, path) -> None:
        """One row per curve vertex, then one per codimension-2 point (:data:`CSV_COLUMNS`)."""
        rows = [",".join(CSV_COLUMNS)]
        for i, c in enumerate(self.curves):
            head = (
                f"vertex,{i},{c.field},{c.kind},{c.side_left},{c.side_right},{c.side_on},"
                f"{int(c.on_class_line)},{float(c.kappa)!r},{float(c.q1)!r},{float(c.q2)!r}"
            )
            off = "" if math.isnan(c.side_offset) else repr(float(c.side_offset))
            rows += [
                f"{head},{x!r},{y!r},{w!r},,,{int(k in c.spliced)},{off},"
                for k, ((x, y), w) in enumerate(zip(c.vertices.tolist(), c.bracket.tolist()))
            ]
        for p in self.points:
            unc = "" if not p.proven else repr(float(p.uncertainty))
            rows.append(
                f"point,,{p.field},{p.kind},,,,,{float(p.kappa)!r},{float(p.q1)!r},"
                f"{float(p.q2)!r},{float(p.beta1)!r},{float(p.beta2)!r},,{unc},{int(p.proven)},,,"
                f"{p.reason}"
            )
        atomic_write_text(path, "\n".join(rows) + "\n")

    def to_geojson(self, path) -> None:
        """A GeoJSON ``FeatureCollection``: ``LineString`` curves and ``Point`` points, coordinates
        ``[beta1, beta2]`` [rad] (not geographic)."""
        feats = [_feature("LineString", c.vertices.tolist(), _curve_props(c)) for c in self.curves]
        feats += [
            _feature("Point", [p.beta1, p.beta2], {k: _json(v) for k, v in vars(p).items()})
            for p in self.points
        ]
        doc = {"type": "FeatureCollection", "features": feats, "properties": _json(self.attrs)}
        atomic_write_text(path, json.dumps(doc) + "\n")


# --- storage helpers -----------------------------------------------------------------------------


def _json(v):
    if isinstance(v, dict):
        return {k: _json(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [_json(x) for x in v]
    if isinstance(v, (np.generic,)):
        v = v.item()
    if isinstance(v, float) and not math.isfinite(v):
        return None
    return v


def _side_labels(field: str) -> dict:
    """The words of a curve's side codes: field SS / II, else the output's declared codes."""
    if field in brackets.FIELD_LABELS:
        return brackets.FIELD_LABELS[field]
    from atlas.data.outputs import OUTPUTS  # noqa: PLC0415 - region curves of box verdicts

    codes = OUTPUTS[field].codes if field in OUTPUTS else None
    return {c.value: c.label for c in codes.codes} if codes is not None else {}


def _curve_props(c: Curve) -> dict:
    labels = _side_labels(c.field)
    props = {
        "field": c.field,
        "kind": c.kind,
        "side_left": labels.get(c.side_left, ""),
        "side_right": labels.get(c.side_right, ""),
        "side_on": labels.get(c.side_on, ""),
        "on_class_line": bool(c.on_class_line),
        "kappa": c.kappa,
        "q1": c.q1,
        "q2": c.q2,
        "max_bracket": float(np.nanmax(c.bracket, initial=0.0)),
        "spliced": [int(k) for k in c.spliced],
        "side_offset": c.side_offset,
    }
    return _json(props)


def _feature(kind, coords, props) -> dict:
    return {
        "type": "Feature",
        "geometry": {"type": kind, "coordinates": coords},
        "properties": props,
    }


_GEO, _RAD, _ONE = {"geometry": "boundary_geometry"}, {"units": "rad"}, {"units": "1"}
_FLAG = {"flag_values": np.array([0, 1], np.int8), "flag_meanings": "no yes"}


def _model_vars(of, items) -> dict:
    """``<of>_kappa``, ``<of>_q1``, ``<of>_q2`` of the curves or points ``items``."""
    return {
        f"{of}_{k}": (
            of,
            np.array([getattr(x, k) for x in items], float),
            _ONE | {"long_name": f"{k} of the {of}'s slice"},
        )
        for k in ("kappa", "q1", "q2")
    }


def _node_vars(cs) -> dict:
    """The geometry container's nodes: coordinates, brackets, and which are spliced points."""
    nodes = np.concatenate([c.vertices for c in cs]) if cs else np.zeros((0, 2))
    spliced = [np.isin(np.arange(len(c.vertices)), c.spliced) for c in cs]
    return {
        "node_beta1": ("node", nodes[:, 0], _RAD | {"axis": "X", "long_name": "beta1"}),
        "node_beta2": ("node", nodes[:, 1], _RAD | {"axis": "Y", "long_name": "beta2"}),
        "node_bracket": (
            "node",
            np.concatenate([c.bracket for c in cs]) if cs else np.zeros(0),
            _RAD
            | {
                "long_name": "length of the certified bracket of the vertex",
                "comment": "NaN: a point where the curve crosses a seam of the torus, "
                "interpolated on its segment (no bracket); at a spliced vertex twice the "
                "proven radius of the codimension-2 point",
            },
        ),
        "node_spliced": (
            "node",
            np.concatenate(spliced).astype(np.int8) if cs else np.zeros(0, np.int8),
            _FLAG
            | {
                "long_name": "the vertex is a proven codimension-2 point spliced into the curve",
                "comment": "three codes meet there: the side codes hold next to it, not at it",
            },
        ),
    }


def _curve_vars(cs) -> dict:
    """Per curve: vertex count, field, kind, side codes, on a class line, slice."""
    per = lambda attr: np.array([getattr(c, attr) for c in cs])  # noqa: E731

    def side(which):
        where = " (direction of travel)" if which != "on" else " where it differs from both"
        return (
            "curve",
            per(f"side_{which}").astype(np.int8),
            _GEO
            | {"long_name": f"certified field code {which} of the curve{where}"}
            | {"comment": CODE_MEANINGS},
        )

    return {
        "node_count": (
            "curve",
            np.array([len(c.vertices) for c in cs], np.int32),
            {"long_name": "number of vertices of each curve"},
        ),
        "curve_field": ("curve", per("field").astype(str), _GEO | {"long_name": "field"}),
        "curve_kind": ("curve", per("kind").astype(str), _GEO | {"long_name": "boundary kind"}),
        "curve_side_left": side("left"),
        "curve_side_right": side("right"),
        "curve_side_on": side("on"),
        "curve_on_class_line": (
            "curve",
            per("on_class_line").astype(np.int8),
            _GEO | _FLAG | {"long_name": "the curve lies on a class line"},
        ),
        "curve_side_offset": (
            "curve",
            per("side_offset").astype(float),
            _GEO
            | _RAD
            | {
                "long_name": "offset at which the side codes are proven",
                "comment": "NaN: the side step (4 tolerance) off every vertex",
            },
        ),
    } | _model_vars("curve", cs)


def _point_vars(ps) -> dict:
    """Per codimension-2 point: position, kind, field, proven enclosure, slice."""
    pp = lambda attr: np.array([getattr(p, attr) for p in ps])  # noqa: E731
    return {
        "point_beta1": ("point", pp("beta1").astype(float), _RAD | {"long_name": "beta1"}),
        "point_beta2": ("point", pp("beta2").astype(float), _RAD | {"long_name": "beta2"}),
        "point_kind": ("point", pp("kind").astype(str), {"long_name": "point kind"}),
        "point_field": ("point", pp("field").astype(str), {"long_name": "field"}),
        "point_uncertainty": (
            "point",
            pp("uncertainty").astype(float),
            _RAD
            | {
                "long_name": "proven bound on the distance to the true point",
                "comment": "NaN where point_proven is 0: the position is an estimate",
            },
        ),
        "point_proven": (
            "point",
            pp("proven").astype(np.int8),
            _FLAG | {"long_name": "the point has a proven enclosure"},
        ),
        "point_reason": (
            "point",
            pp("reason").astype(str),
            {
                "long_name": "why the point is left undecided",
                "comment": "a key of atlas.data.boundary_roots.REASONS; empty where not undecided",
            },
        ),
    } | _model_vars("point", ps)


def _to_dataset(bd: Boundaries) -> xr.Dataset:
    import xarray as xr  # noqa: PLC0415 - a run writing no netCDF loads no xarray (pandas: ~1 s)

    container = {
        "geometry_type": "line",
        "node_count": "node_count",
        "node_coordinates": "node_beta1 node_beta2",
        "long_name": "geometry container of the boundary curves",
    }
    ds = xr.Dataset(
        {"boundary_geometry": ((), np.int32(0), container)}
        | _node_vars(bd.curves)
        | _curve_vars(bd.curves)
        | _point_vars(bd.points)
    )
    for v in ds.variables.values():
        if v.dtype.kind == "f":
            v.encoding["_FillValue"] = None  # no missing values: NaN means "not proven"
    now = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")
    ds.attrs.update(
        Conventions="CF-1.10",
        title="painleve-atlas boundary curves",
        source=f"painleve-atlas {__version__}",
        history=f"{now}: {bd.attrs.get('history', 'atlas.boundaries')}",
        references=REFERENCES,
        tolerance=float(bd.attrs.get("tolerance", TOL)),
        chord_tolerance=float(bd.attrs.get("chord_tolerance", CHORD)),
        field_labels=json.dumps({k: v for k, v in brackets.FIELD_LABELS.items()}),
        slices=json.dumps(_json(bd.attrs.get("slices", []))),
        complete=int(bd.attrs.get("complete", 0)),
        uncovered_line_length=float(bd.attrs.get("uncovered_line_length", math.nan)),
    )
    return ds


def summary(bd: Boundaries) -> str:
    """A few lines: curves and points per field and kind, tolerances, time."""
    lines = [
        f"boundaries: {len(bd.curves)} curves, {sum(len(c.vertices) for c in bd.curves)} vertices,"
        f" {len(bd.points)} codimension-2 points; vertex brackets <= {bd.attrs.get('tolerance')}"
        f" rad, chords <= {bd.attrs.get('chord_tolerance')} rad, {bd.attrs.get('seconds', 0):.1f} s"
    ]
    kinds = collections.Counter((c.kind, bool(c.on_class_line)) for c in bd.curves)
    lines += [
        f"  {k}{' (on a class line)' if on else ''}: {n}" for (k, on), n in sorted(kinds.items())
    ]
    pts = collections.Counter(p.kind for p in bd.points)
    lines += [f"  point {k}: {n}" for k, n in sorted(pts.items())]
    for s in bd.attrs.get("slices", []):
        counts = [v for k, v in s.items() if k.endswith("hidden_cells")]
        hidden = "not checked" if None in counts else sum(counts)
        added = sum(v for k, v in s.items() if k.endswith("_uncovered_line_length"))
        left = sum(v for k, v in s.items() if k.endswith("_line_length_left_uncovered"))
        lines.append(
            f"  slice kappa={s['kappa']:g} q1={s['q1']:g} q2={s['q2']:g}: hidden cells {hidden};"
            f" class-line stretches: {added:.3g} rad not traced (added as curves), {left:.3g} rad"
            " left uncovered"
        )
    return "\n".join(lines)
