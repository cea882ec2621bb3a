"""The arguments of :func:`atlas.data.boundaries.boundaries` and ``atlas boundaries``: defaults,
limits and their one check (:func:`check_args`), and the storage's column names.  Light (numpy
only), so that the command line refuses a bad argument before it imports JAX or xarray."""

from __future__ import annotations

import math

import numpy as np

from atlas.core import checks

__all__ = [
    "CHECK",
    "CHORD",
    "CLI_DEFAULTS",
    "CODE_MEANINGS",
    "CSV_COLUMNS",
    "FIELD_NAMES",
    "MAX_CHECK",
    "MAX_LEVELS",
    "MIN_CHORD",
    "MIN_TOL",
    "TOL",
    "check_args",
    "check_memory",
    "check_model_text",
]

#: default certified vertex tolerance (bracket length) [rad]
TOL = 1e-10
#: default chord tolerance (measured sagitta between vertices) [rad]
CHORD = 1e-6
#: the fields (:data:`atlas.core.brackets.FIELDS`)
FIELD_NAMES = ("SS", "II")
#: default resampling factor of the hidden-branch check
CHECK = 2
#: the defaults of ``atlas boundaries``' options for a slice's curves, by name (the parser leaves
#: them unset: ``--model-box`` refuses ``--chord`` and ``--check``)
CLI_DEFAULTS = dict(chord=CHORD, check=CHECK, fields=",".join(FIELD_NAMES))
#: the columns of :meth:`Boundaries.to_csv`: ``record`` ``vertex`` (one row per curve vertex, in
#: order along the curve) or ``point`` (a codimension-2 point); ``curve`` the curve's index;
#: ``field`` ``SS``/``II``/``class``; ``kind`` the curve kind (``SS_stability``,
#: ``II_consistency``, ``II_stability``, ``class_line``) or point kind; ``side_left``,
#: ``side_right``, ``side_on`` the codes left / right of the direction of travel and on the curve
#: (-1: none; SS 0 unstable, 1 stable, 2 neutral; II 0 inconsistent, 1 consistent and unstable,
#: 2 consistent and stable, 3 consistent and neutral); ``on_class_line`` 0/1; ``kappa, q1, q2``
#: the slice [1]; ``beta1, beta2`` [rad]; ``bracket`` the vertex's certified bracket length [rad]
#: (``nan``: a point where the curve crosses a seam, interpolated on its segment);
#: ``uncertainty`` a point's proven enclosure radius [rad] (empty: not proven); ``proven`` 0/1;
#: ``spliced`` 0/1: the vertex is a proven codimension-2 point (:attr:`atlas.data.boundary_curves.Curve.spliced`);
#: ``side_offset`` the curve's offset [rad] at which its side codes are proven (empty: the side
#: step, 4 tol; :attr:`atlas.data.boundary_curves.Curve.side_offset`); ``reason`` why a point
#: is left undecided (:data:`atlas.data.boundary_roots.REASONS`; empty otherwise)
CSV_COLUMNS = (
    "record",
    "curve",
    "field",
    "kind",
    "side_left",
    "side_right",
    "side_on",
    "on_class_line",
    "kappa",
    "q1",
    "q2",
    "beta1",
    "beta2",
    "bracket",
    "uncertainty",
    "proven",
    "spliced",
    "side_offset",
    "reason",
)


#: the meanings of the side codes, for the ``comment`` of the side variables
CODE_MEANINGS = (
    "-1: none; field SS: 0 unstable, 1 stable, 2 neutral; field II: 0 inconsistent, "
    "1 consistent and unstable, 2 consistent and stable, 3 consistent and neutral"
)


#: the smallest vertex tolerance [rad]: a bracket between float coordinates near ``2 pi``
#: (spacing 8.9e-16 rad) cannot be shrunk reliably below a few units in the last place
MIN_TOL = 2.0**-47
#: the largest resampling factor of the lost-branch check and its refinement levels
MAX_CHECK, MAX_LEVELS = 16, 4
#: the smallest chord tolerance [rad]: below it a curve needs ~1e6 vertices per radian
MIN_CHORD = 1e-9
#: bytes per point of the finest checked grid (nodes, codes, kernel batches), and the limit [B]
BYTES_PER_POINT, MEMORY_LIMIT = 64, 4 << 30


def check_memory(n1: int, n2: int, check: int, max_levels: int) -> int:
    """Worst-case bytes of the lost-branch check on an ``n1 x n2`` grid: the grid refined
    ``max_levels`` times by ``check`` and resampled once more."""
    k = max(check, 1) ** (max_levels + 1) if check > 1 else 1
    return BYTES_PER_POINT * (n1 * k) * (n2 * k)


def _integer(x) -> bool:
    return isinstance(x, int) and not isinstance(x, bool)


def check_args(tol, chord, check, max_levels, fields, shape=(2, 2)) -> tuple[str, ...]:
    """One-line ``ValueError`` naming the first bad argument; returns the fields as a tuple
    (``"SS"`` and ``"SS,II"`` are accepted as strings; numpy scalars as the numbers they hold)."""
    tol, chord, check, max_levels = map(checks.plain, (tol, chord, check, max_levels))
    num = (int, float)
    if not (isinstance(tol, num) and not isinstance(tol, bool) and MIN_TOL <= tol < 0.1):
        raise ValueError(
            f"tol: must be in [{MIN_TOL:.3g}, 0.1) rad (float coordinates near 2 pi cannot "
            f"resolve a smaller bracket), got {tol!r}"
        )
    if not (isinstance(chord, num) and max(tol, MIN_CHORD) <= chord <= 0.1):
        raise ValueError(f"chord: must be in [max(tol, {MIN_CHORD:g}), 0.1] rad, got {chord!r}")
    if not (_integer(check) and 0 <= check <= MAX_CHECK):
        raise ValueError(f"check: must be an integer in [0, {MAX_CHECK}], got {check!r}")
    if not (_integer(max_levels) and 0 <= max_levels <= MAX_LEVELS):
        raise ValueError(f"max_levels: must be an integer in [0, {MAX_LEVELS}], got {max_levels!r}")
    if isinstance(fields, str):  # "SS", "SS,II"
        fields = tuple(f.strip() for f in fields.split(",") if f.strip())
    fields = tuple(fields)
    bad = [f for f in fields if f not in FIELD_NAMES]
    if bad or not fields:
        raise ValueError(
            f"fields: must be a non-empty subset of {list(FIELD_NAMES)}, got {fields!r}"
        )
    for name, n in zip(("beta1", "beta2"), shape):
        if n < 2:
            raise ValueError(f"{name}: needs at least 2 values for a grid of cells, got {n}")
    need = check_memory(*shape, check, max_levels)
    if need > MEMORY_LIMIT:
        raise ValueError(
            f"check: {check} on a {shape[0]}x{shape[1]} grid may need {need / 2**30:.1f} GiB "
            f"(limit {MEMORY_LIMIT / 2**30:.0f} GiB); use a smaller check or grid"
        )
    return fields


def check_model_text(name: str, text) -> None:
    """The command line's refusal of a bad ``--kappa``/``--q``/``--q1``/``--q2`` written as plain
    numbers (one, or a comma list), without the range parser of :mod:`atlas.data.scene` (which
    imports JAX): the one-line ``ValueError`` of :func:`atlas.core.checks.model_values`
    (``kappa > 0``, ``q >= 0``, finite).  A range or an expression is left to the parser."""
    if text is None:
        return
    items = str(text).split(",")
    if len(items) > 1 and not items[-1].strip():
        items = items[:-1]  # "0.5," is a one-value range
    try:
        values = [float(p) for p in items]
    except ValueError:
        return
    if not all(math.isfinite(v) for v in values):
        raise ValueError(f"{name}: must be finite, got {str(text).strip()!r}")
    checks.model_values(name, np.array(values))
