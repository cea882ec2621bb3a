"""Boundary curves as objects: :class:`Curve`, :class:`Point`, :class:`Boundaries` and their storage.

:mod:`atlas.data.boundaries` computes them; this module holds what a result is and how it is
written: a CF-1.10 geometry container (``geometry_type = "line"``, one ``node_count`` per curve,
node coordinates ``node_beta1``/``node_beta2`` [rad]) plus the codimension-2 points
(:meth:`Boundaries.to_dataset`), one CSV row per vertex, or GeoJSON.
"""

from __future__ import annotations

import collections
import json
import math
from dataclasses import dataclass, field

import numpy as np
import xarray as xr

from atlas.core import brackets
from atlas.core.config import __version__
from atlas.data.io import atomic_path, atomic_write_text

__all__ = ["CHORD", "TOL", "Boundaries", "Curve", "Point", "summary"]

#: default certified vertex tolerance (bracket length) [rad]
TOL = 1e-10
#: default chord tolerance (measured sagitta between vertices) [rad]
CHORD = 1e-6


@dataclass
class Curve:
    """One boundary polyline: ``vertices`` ``(m, 2)`` of ``(beta1, beta2)`` [rad].

    ``field``: ``"SS"``, ``"II"`` or ``"class"``; ``kind``: ``SS_stability``, ``II_consistency``,
    ``II_stability`` or ``class_line``; ``side_a``/``side_b``: the field codes on its two sides
    (:data:`atlas.core.brackets.FIELD_LABELS`; -1 for class lines); ``bracket``: per vertex, the
    length of its certified bracket [rad] (0 for the closed-form class lines); ``ends``: per
    vertex the bracket's two ends ``(m, 2, 2)`` (the vertex is their midpoint), ``None`` for
    class lines.
    """

    field: str
    kind: str
    side_a: int
    side_b: int
    vertices: np.ndarray
    bracket: np.ndarray
    on_class_line: bool = False
    kappa: float = math.nan
    q1: float = math.nan
    q2: float = math.nan
    ends: np.ndarray | None = None


@dataclass
class Point:
    """A codimension-2 point: where boundaries meet, cross a class line, or end."""

    beta1: float
    beta2: float
    kind: str
    uncertainty: float
    kappa: float = math.nan
    q1: float = math.nan
    q2: float = math.nan


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
        """One row per vertex: ``curve,field,kind,side_a,side_b,kappa,q1,q2,beta1,beta2,bracket``."""
        rows = ["curve,field,kind,side_a,side_b,on_class_line,kappa,q1,q2,beta1,beta2,bracket"]
        for i, c in enumerate(self.curves):
            head = (
                f"{i},{c.field},{c.kind},{c.side_a},{c.side_b},{int(c.on_class_line)},"
                f"{float(c.kappa)!r},{float(c.q1)!r},{float(c.q2)!r}"
            )
            rows += [
                f"{head},{x!r},{y!r},{w!r}"
                for (x, y), w in zip(c.vertices.tolist(), c.bracket.tolist())
            ]
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


def _curve_props(c: Curve) -> dict:
    labels = brackets.FIELD_LABELS.get(c.field, {})
    props = {
        "field": c.field,
        "kind": c.kind,
        "side_a": labels.get(c.side_a, ""),
        "side_b": labels.get(c.side_b, ""),
        "on_class_line": bool(c.on_class_line),
        "kappa": c.kappa,
        "q1": c.q1,
        "q2": c.q2,
        "max_bracket": float(np.max(c.bracket)),
    }
    return _json(props)


def _feature(kind, coords, props) -> dict:
    return {
        "type": "Feature",
        "geometry": {"type": kind, "coordinates": coords},
        "properties": props,
    }


def _to_dataset(bd: Boundaries) -> xr.Dataset:
    cs, ps = bd.curves, bd.points
    geo = {"geometry": "boundary_geometry"}
    rad = {"units": "rad"}
    per = lambda attr: np.array([getattr(c, attr) for c in cs])  # noqa: E731
    pp = lambda attr: np.array([getattr(p, attr) for p in ps])  # noqa: E731
    nodes = np.concatenate([c.vertices for c in cs]) if cs else np.zeros((0, 2))
    ds = xr.Dataset(
        {
            "boundary_geometry": (
                (),
                np.int32(0),
                {
                    "geometry_type": "line",
                    "node_count": "node_count",
                    "node_coordinates": "node_beta1 node_beta2",
                },
            ),
            "node_count": ("curve", np.array([len(c.vertices) for c in cs], np.int32)),
            "node_beta1": ("node", nodes[:, 0], rad | {"axis": "X", "long_name": "beta1"}),
            "node_beta2": ("node", nodes[:, 1], rad | {"axis": "Y", "long_name": "beta2"}),
            "node_bracket": (
                "node",
                np.concatenate([c.bracket for c in cs]) if cs else np.zeros(0),
                rad | {"long_name": "length of the certified bracket of the vertex"},
            ),
            "curve_field": ("curve", per("field").astype(str), geo),
            "curve_kind": ("curve", per("kind").astype(str), geo),
            "curve_side_a": ("curve", per("side_a").astype(np.int8), geo),
            "curve_side_b": ("curve", per("side_b").astype(np.int8), geo),
            "curve_on_class_line": ("curve", per("on_class_line").astype(np.int8), geo),
            "curve_kappa": ("curve", per("kappa").astype(float), geo),
            "curve_q1": ("curve", per("q1").astype(float), geo),
            "curve_q2": ("curve", per("q2").astype(float), geo),
            "point_beta1": ("point", pp("beta1").astype(float), rad),
            "point_beta2": ("point", pp("beta2").astype(float), rad),
            "point_kind": ("point", pp("kind").astype(str)),
            "point_uncertainty": ("point", pp("uncertainty").astype(float), rad),
            "point_kappa": ("point", pp("kappa").astype(float)),
            "point_q1": ("point", pp("q1").astype(float)),
            "point_q2": ("point", pp("q2").astype(float)),
        }
    )
    ds.attrs.update(
        Conventions="CF-1.10",
        title="painleve-atlas boundary curves",
        source=f"painleve-atlas {__version__}",
        tolerance=float(bd.attrs.get("tolerance", TOL)),
        chord_tolerance=float(bd.attrs.get("chord_tolerance", CHORD)),
        field_labels=json.dumps({k: v for k, v in brackets.FIELD_LABELS.items()}),
        slices=json.dumps(_json(bd.attrs.get("slices", []))),
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
        hidden = sum(v for k, v in s.items() if k.endswith("hidden_cells"))
        lines.append(
            f"  slice kappa={s['kappa']:g} q1={s['q1']:g} q2={s['q2']:g}: hidden cells {hidden}"
        )
    return "\n".join(lines)
