"""Certified boundary curves: closed forms, exact re-check of vertices, no lost branch, CLI."""

import numpy as np
import pytest
import shapely
import xarray as xr

from atlas.cli import main
from atlas.core import brackets, contact_modes, exact
from atlas.data import boundaries as bd
from atlas.data.scene import Scene

PI = np.pi
GRID = np.arange(32) * 2 * PI / 32


def _closed_forms(v, kappa):
    """|f| at vertices ``v`` of the closed forms of the SS boundary (SPEC §1, audit claim Z):
    the q = 0 neutral boundary ``disc = (kappa C1 - S2)^2 + 4 kappa S1 C2``, its small-damping
    limit ``glim = S1 C2 (1 + kappa)^2 + (kappa C1 - S2)^2`` and the trace ``kappa C1 + S2``."""
    c1, s1, c2, s2 = np.cos(v[:, 0]), np.sin(v[:, 0]), np.cos(v[:, 1]), np.sin(v[:, 1])
    k = np.arange(5) * PI / 2  # and the distance to the class lines (where pieces join them)
    lines = np.concatenate(
        [np.abs(v[:, :1] - k), np.abs(v[:, 1:] - k)]
        + [np.abs(v[:, 1:] - v[:, :1] - j * PI) / np.sqrt(2) for j in (-1, 0, 1)],
        axis=1,
    )
    return {
        "disc": np.abs((kappa * c1 - s2) ** 2 + 4 * kappa * s1 * c2),
        "glim": np.abs(s1 * c2 * (1 + kappa) ** 2 + (kappa * c1 - s2) ** 2),
        "trace": np.abs(kappa * c1 + s2),
        "line": lines.min(1),
    }


def _curved(b):
    return np.concatenate([c.vertices for c in b.curves if not c.on_class_line])


@pytest.mark.parametrize("kappa", [0.5, 2.0])
def test_q0_boundary_is_the_discriminant_curve(kappa):
    b = bd.slice_boundaries(GRID, GRID, kappa, 0.0, 0.0, fields=("SS",), check=0, chord=1e-3)
    v = _curved(b)
    f = _closed_forms(v, kappa)
    # every certified vertex lies within 1e-10 rad of the zero set: |f| <= |grad f| 1e-10 < 1e-9
    assert len(v) > 50
    assert np.min([f["disc"], f["trace"], f["line"]], axis=0).max() < 1e-9
    assert np.mean(f["disc"] < 1e-9) > 0.5  # the curved boundary is mostly the discriminant


def test_small_damping_boundary_is_claim_Z_limit():
    """With q1 = q2 = q -> 0+, the SS boundary tends to glim = 0, not to Fig. 1's disc = 0."""
    kappa = 0.5
    b = bd.slice_boundaries(GRID, GRID, kappa, 1e-7, 1e-7, fields=("SS",), check=0, chord=1e-3)
    f = _closed_forms(_curved(b), kappa)
    assert np.min([f["glim"], f["trace"], f["line"]], axis=0).max() < 1e-9
    assert np.median(f["disc"]) > 1e-3  # and away from the undamped curve


def test_class_lines_are_the_class_code_ties():
    """Each closed-form class line separates two class codes and is degenerate (code 0) on it."""
    rng = np.random.default_rng(3)
    for c in bd.class_lines():
        (x0, y0), (x1, y1) = c.vertices
        t = rng.uniform(0.05, 0.95, 5)
        p = np.stack([x0 + t * (x1 - x0), y0 + t * (y1 - y0)], 1)
        n = np.array([-(y1 - y0), x1 - x0]) / np.hypot(x1 - x0, y1 - y0)
        codes = []
        for off in (0.0, 1e-7, -1e-7):
            q = p + off * n
            c1, s1 = contact_modes.direction(q[:, 0])
            c2, s2 = contact_modes.direction(q[:, 1])
            codes.append(np.asarray(contact_modes.class_code(c1, s1, c2, s2)))
        on, plus, minus = codes
        assert (plus != minus).all() and (plus > 0).all() and (minus > 0).all()
        # on the line: a tie (0, or -1 where rounding leaves it undecided) or a side's code
        assert set(on.tolist()) <= {0, -1} | set(plus.tolist()) | set(minus.tolist())
    assert len(bd.class_lines()) == 13  # 5 + 5 axis lines, 3 diagonals of the box


@pytest.fixture(scope="module")
def damped():
    return bd.slice_boundaries(GRID, GRID, 2.0, 0.1, 0.1, check=2, chord=1e-4)


def _code(field, point, model):
    c1, s1 = (float(x) for x in contact_modes.direction(point[0]))
    c2, s2 = (float(x) for x in contact_modes.direction(point[1]))
    v = exact.point_spectral(c1, s1, c2, s2, *model)
    if field == "SS":
        return v["stable_SS"]
    return 0 if v["consistent_II"] == 0 else 1 + v["stable_II"]


def test_vertices_rechecked_by_the_exact_tier(damped):
    """A sample of vertices: the bracket ends carry different codes in exact arithmetic alone,
    and the bracket is at most the tolerance long."""
    model = (2.0, 0.1, 0.1)
    rng = np.random.default_rng(1)
    curves = [c for c in damped.curves if c.ends is not None]
    assert {c.field for c in curves} == {"SS", "II"}
    for c in (curves[i] for i in rng.choice(len(curves), 8, replace=False)):
        # NaN bracket: a point on a seam; spliced: a proven point (its enclosure, no bracket)
        certified = np.setdiff1d(np.flatnonzero(np.isfinite(c.bracket)), c.spliced)
        for k in rng.choice(certified, 3):
            p, q = c.ends[k]
            assert np.hypot(*(q - p)) <= bd.TOL
            assert np.allclose(0.5 * (p + q), c.vertices[k], rtol=0, atol=1e-15)
            assert _code(c.field, p, model) != _code(c.field, q, model)


def test_curves_are_simple_paths_on_the_torus(damped):
    """Every piece is a simple LineString with coordinates in [0, 2 pi) (a polyline that
    doubled back over a stretch crossed itself up to 201 times), and the class lines of an
    atlas over the whole torus cover it."""
    for c in damped.curves:
        assert shapely.is_simple(shapely.LineString(c.vertices))
        assert (c.vertices >= 0).all() and (c.vertices < 2 * PI).all()
    scene = Scene(beta1="0:2pi:8", beta2="0:2pi:8", kappa=0.5, q=0.0)
    lines = bd.boundaries(scene, fields=("SS",), check=0, chord=1e-3).select(field="class")
    xy = np.concatenate([c.vertices for c in lines])
    assert (xy >= 0).all() and (xy < 2 * PI).all() and xy.max() > 2 * PI - 1e-12
    assert len(lines) == 11  # beta1, beta2 = k pi / 2 (k < 4), beta2 = beta1 (+- pi)


def test_curves_carry_their_kinds(damped):
    kinds = {c.kind for c in damped.curves}
    assert {"SS_stability", "II_consistency"} <= kinds
    assert damped.attrs["SS_max_bracket"] <= bd.TOL
    assert all(c.side_left > c.side_right for c in damped.curves)


def _torus_distance(points, curves):
    """Distance [rad] from each point to the polylines, on the torus (shifts by 2 pi)."""
    a = np.concatenate([c[:-1] for c in curves])
    b = np.concatenate([c[1:] for c in curves])
    shifts = [np.array([x, y]) for x in (-2 * PI, 0, 2 * PI) for y in (-2 * PI, 0, 2 * PI)]
    a, b = np.concatenate([a + s for s in shifts]), np.concatenate([b + s for s in shifts])
    d = b - a
    dd = np.maximum(np.sum(d * d, 1), 1e-300)
    out = []
    for p in points:
        t = np.clip(np.sum((p - a) * d, 1) / dd, 0, 1)
        out.append(np.min(np.hypot(*(a + t[:, None] * d - p).T)))
    return np.array(out)


def _reached(b):
    """The curves and the proven points of ``b`` (as one-vertex polylines): the last stretch
    of a needle thinner than the side step carries no side codes and is not a piece, but its
    tip is a proven point where the boundary meets the class line."""
    return [c.vertices for c in b.curves] + [
        np.array([[p.beta1, p.beta2]] * 2) for p in b.points if p.proven
    ]


#: the one-q = 0 slice (kappa, q1, q2) of the grid comparison and the checkerboard corner
ONE_Q0 = (0.5, 0.35, 0.0)
ONE_Q0_OPTS = dict(fields=("SS", "II"), check=2, chord=1e-4)


@pytest.fixture(scope="module")
def one_q0_64():
    """The one-q = 0 slice on a 64 x 64 grid, traced once for the two tests below."""
    g = np.arange(64) * 2 * PI / 64
    return bd.slice_boundaries(g, g, *ONE_Q0, **ONE_Q0_OPTS)


def test_coarse_grid_finds_every_branch_of_a_4x_finer_grid(one_q0_64):
    """Every curve the 4x finer grid finds (damped, one q = 0: II junctions, class-line pieces)
    passes within 2e-4 rad of a curve of the 16 x 16 grid (cell 0.39 rad; two chords: the
    segment where the side codes change, up to a chord long, belongs to no piece), and most of
    it lies within the chord tolerance scale of the coarse curves."""
    g16 = np.arange(16) * 2 * PI / 16
    coarse = bd.slice_boundaries(g16, g16, *ONE_Q0, **ONE_Q0_OPTS)
    fine = one_q0_64
    for field in ("SS", "II"):
        a = [c.vertices for c in coarse.curves if c.field == field]
        b = [c.vertices for c in fine.curves if c.field == field and len(c.vertices) >= 3]
        assert a and b
        for curve in b:
            assert _torus_distance(curve, a).min() < 2e-4
        d = _torus_distance(np.concatenate(b), a)
        assert np.median(d) < 1e-6


def test_corner_of_a_checkerboard_is_reached(one_q0_64):
    """Where two class lines cross with one SS code in opposite quadrants (one q = 0 slice at
    (2 pi, pi / 2), i.e. (0, pi / 2) on the torus), the curves reach the crossing itself: the
    chord through the middle of a corner-cutting segment runs through the saddle from the region
    into the region, so the quarter-point probes must find it (the curves stopped a grid cell
    short before)."""
    corners = np.array([[2 * PI, PI / 2], [0.0, PI / 2], [PI / 2, PI / 2]])
    curves = [c.vertices for c in one_q0_64.curves if c.field == "SS"]
    assert _torus_distance(corners, curves).max() < 1e-5


def test_wedge_tips_on_a_class_line_are_reached():
    """A damped SS boundary meets the diagonal beta2 = beta1 - pi at a shallow angle, leaving a
    wedge thinner than a cell; the curves reach its tip, found here independently by a dense
    scan just off the line (the grid's tracing alone stopped 0.065 rad short)."""
    model = (2.0, 0.1, 0.1)
    g = np.arange(64) * 2 * PI / 64
    b = bd.slice_boundaries(g, g, *model, fields=("SS",))
    t = np.linspace(4.3, 4.6, 30001)  # along the line, 1e-9 rad on its beta1 > beta2 + pi side
    off = 1e-9 / np.sqrt(2)
    codes = brackets.field_codes("SS", t + off, t - PI - off, *model)
    (i,) = np.flatnonzero(np.diff(codes))
    tip = np.array([[t[i] + off, t[i] - PI - off]])
    assert 4.4 < t[i] < 4.55
    assert _torus_distance(tip, _reached(b)).max() < 1e-6
    assert b.attrs["SS_tips_attached"] >= 1


def _band_edges(model, ts, width=0.01, n=1001):
    """Per ``t`` of ``ts``, the far edge (code 1 -> 2) of the II band along ``beta2 = beta1 - pi``
    at ``(t, t - pi)``, by a scan across the line towards ``beta2 > beta1 - pi``: ``n`` samples
    over ``width`` [rad] (step 1e-5), then ``n`` samples over the step where the code changes
    (step 1e-8; one change on each scan, and the band is code 1 from the first sample on)."""
    s = np.sqrt(2)
    lo, hi = np.zeros(len(ts)), np.full(len(ts), width)
    for first in (1, 0):  # the first scan starts on the line (its sample 0 is left out)
        d = lo[:, None] + np.linspace(0.0, 1.0, n) * (hi - lo)[:, None]
        t = np.asarray(ts)[:, None]
        codes = brackets.field_codes("II", t - d / s, t - PI + d / s, *model)
        for r, row in enumerate(codes):
            (i,) = np.flatnonzero(np.diff(row[first:])) + first  # 1 -> 2: the band's far edge
            assert (row[first], row[i], row[i + 1]) == (1, 1, 2)
            lo[r], hi[r] = d[r, i], d[r, i + 1]
    assert (lo > 5e-4).all()
    return np.stack([ts - lo / s, ts - PI + lo / s], 1)


def test_a_band_along_a_diagonal_class_line_is_traced_whole():
    """One q = 0, II: a band of code 1 at most 0.0066 rad wide runs along beta2 = beta1 - pi
    (beta1 from ~3.75 to 3 pi / 2), seen by a 32 x 32 grid (cell 0.2 rad) only at its nodes on
    the line.  Its far edge, located here independently by a scan across the line (to 1e-8 rad,
    :func:`_band_edges`), lies on the curves: the grid's diagonals join the nodes on the line
    into one strip (marching squares left separate diamonds, and the curves missed the edge by
    6e-3 rad), and the chord probes reach a band thinner than their fixed offsets by stepping
    towards the line."""
    model = (0.5, 0.35, 0.0)
    g = np.arange(32) * 2 * PI / 32
    b = bd.slice_boundaries(g, g, *model, fields=("II",), check=0)
    edges = _band_edges(model, np.array([3.9, 4.2, 4.5]))
    curves = [c.vertices for c in b.curves if (c.side_left, c.side_right) == (2, 1)]
    assert _torus_distance(edges, curves).max() < 2e-6


def test_a_boundary_tangent_to_a_class_line_is_followed_to_its_tip(slice_32):
    """Fig. 1 slice, SS: the boundary of code 2 touches the diagonal beta2 = beta1 tangentially
    near beta1 = 2.678 and leaves a needle along it, 1e-8 rad wide 1.6e-4 rad before its tip.
    The tip, found here by a dense scan 1e-12 rad off the line, lies on the curves of a 32 x 32
    grid to the chord tolerance: the polyline used to turn back 2e-5 to 1.6e-4 rad short of it
    (the tips were scanned 4 tol off the line, and none was inserted into the needle)."""
    model = (0.5, 0.0, 0.0)
    b = slice_32(model, fields=("SS",))  # 32 x 32, no check
    t = np.linspace(2.677, 2.679, 200001)
    off = 1e-12 / np.sqrt(2)
    codes = brackets.field_codes("SS", t - off, t + off, *model)
    (i,) = np.flatnonzero(np.diff(codes))
    assert (codes[i], codes[i + 1]) == (2, 0)
    tip = np.array([[t[i] - off, t[i] + off]])
    # the needle is 1e-12 wide 2.1e-6 rad before the tangency: the proven touching point lies
    # that far beyond the scanned tip, the curves (stepped 4e-10 off to label them) stop earlier
    assert _torus_distance(tip, _reached(b)).max() < 3e-6
    touch = [p for p in b.points if p.kind == "touches_class_line" and abs(p.beta1 - 2.678) < 1e-3]
    assert len(touch) == 1 and touch[0].proven and 0 < touch[0].beta1 - tip[0, 0] < 3e-6


def test_hidden_cells_are_found():
    """A cell whose corners agree but whose finer samples differ is flagged."""
    coarse = np.zeros((3, 3), np.int8)
    fine = np.zeros((5, 5), np.int8)
    fine[1, 1] = 1  # inside cell (0, 0) only
    hidden = bd._hidden_cells(coarse, fine, 2)
    assert hidden.tolist() == [[True, False], [False, False]]


def test_scene_and_dataset_give_the_same_curves(tmp_path, traced_once):
    from atlas.data.engine import generate

    scene = Scene(beta1="0:2pi:16", beta2="0:2pi:16", kappa=0.5, q=0.2, outputs=["stable_SS"])
    a = bd.boundaries(scene, fields=("SS",), check=0, chord=1e-3)
    b = bd.boundaries(generate(scene), fields=("SS",), check=0, chord=1e-3)
    assert len(a.curves) == len(b.curves)
    for x, y in zip(a.curves, b.curves):
        np.testing.assert_array_equal(x.vertices, y.vertices)


def test_cli_writes_and_refuses_bad_input(tmp_path, capsys):
    out = tmp_path / "b.nc"
    args = ["boundaries", "--beta1", "0:2pi:8", "--beta2", "0:2pi:8", "--kappa", "0.5"]
    run = ["--q", "0", "--fields", "SS", "--check", "0", "--chord", "1e-2"]  # a cheap slice
    assert main(args + run + ["--out", str(out)]) == 0
    assert out.exists() and "boundaries:" in capsys.readouterr().out
    assert main(args + ["--tol", "-1"]) == 2
    assert capsys.readouterr().err.strip().splitlines()[-1].startswith("atlas: error: tol:")
    assert main(args + ["--fields", "SS,XX"]) == 2
    assert "fields:" in capsys.readouterr().err
    assert main(args + ["--out", str(out)]) == 2  # exists, no --overwrite: untouched
    assert "exists" in capsys.readouterr().err


@pytest.mark.parametrize(
    "extra, message",
    [
        (["--tol", "1e-17"], "tol: must be in [7.11e-15"),  # below what the floats resolve
        (["--tol", "1e-300"], "tol: must be in [7.11e-15"),
        (["--check", "1000"], "check: must be an integer in [0, 16]"),
        (["--chord", "1e-12"], "chord: must be in"),
        (["--beta1", "0"], "beta1: needs at least 2 values"),  # a 1 x n grid
        (["--out", "{d}/b.nc", "--csv", "{d}/b.nc"], "csv: expected a file name ending in .csv"),
    ],
)
def test_cli_refuses_in_one_line(tmp_path, capsys, extra, message):
    args = ["boundaries", "--beta1", "0:2pi:8", "--beta2", "0:2pi:8", "--kappa", "0.5", "--q", "0"]
    extra = [x.format(d=tmp_path) for x in extra]
    assert main(args + extra) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0]
    assert not list(tmp_path.iterdir())  # nothing written


def test_check_memory_bound_is_refused_before_work():
    with pytest.raises(ValueError, match="GiB"):
        bd.slice_boundaries(np.zeros(2048), np.zeros(2048), 0.5, 0.0, 0.0, check=16, max_levels=4)


def test_smallest_tolerance_holds_in_the_file(tmp_path, capsys):
    """At the smallest accepted tol every stored bracket is <= tol (1e-17 was accepted and gave
    brackets of 1.26e-15); --check 0 says the grid was not checked."""
    out = tmp_path / "b.nc"
    args = ["boundaries", "--beta1", "0:2pi:8", "--beta2", "0:2pi:8", "--kappa", "2", "--q", "0.1"]
    args += ["--fields", "SS", "--chord", "1e-2", "--check", "0", "--tol", str(bd.MIN_TOL)]
    assert main(args + ["--out", str(out)]) == 0
    assert "hidden cells not checked" in capsys.readouterr().out
    with xr.open_dataset(out) as ds:
        assert np.nanmax(ds["node_bracket"].values) <= ds.attrs["tolerance"] == bd.MIN_TOL
        assert '"SS_hidden_cells": null' in ds.attrs["slices"]


def test_fields_as_a_string_and_float16_refused():
    """``fields="SS"`` is the one field SS (it was refused as "not a subset"); float16 refused."""
    scene = Scene(beta1="0:2pi:8", beta2="0:2pi:8", kappa=2, q=0.1)
    ss = bd.boundaries(scene, fields="SS")
    assert {c.field for c in ss.curves} <= {"SS", "class"}
    assert any(c.field == "SS" for c in ss.curves)
    with pytest.raises(ValueError, match="^dtype: must be float32 or float64"):
        bd.boundaries(scene, dtype="float16")
    with pytest.raises(ValueError, match="^fields: "):
        bd.boundaries(scene, fields="SS,XX")


def _cli_error(capsys, argv) -> str:
    assert main(["boundaries", "--beta1", "0:2pi:8", "--beta2", "0:2pi:8", *argv]) == 2
    return capsys.readouterr().err.strip().splitlines()[-1].removeprefix("atlas: error: ")


@pytest.mark.parametrize(
    "coords, argv",
    [
        (dict(kappa=[-1.0], q=[0.0]), ["--kappa", "-1", "--q", "0"]),
        (dict(kappa=[0.0], q=[0.0]), ["--kappa", "0", "--q", "0"]),
        (dict(kappa=[0.5], q=[-0.1]), ["--kappa", "0.5", "--q", "-0.1"]),
        (dict(kappa=[0.5], q1=[0.1], q2=[-0.2]), ["--kappa", "0.5", "--q1", "0.1", "--q2", "-0.2"]),
    ],
)
def test_dataset_refused_with_the_cli_message(capsys, coords, argv):
    """An atlas Dataset with a bad model value is refused with the command line's message (it
    returned curves)."""
    g = np.arange(8) * 2 * PI / 8
    ds = xr.Dataset(coords=dict(beta1=g, beta2=g) | coords)
    with pytest.raises(ValueError) as err:
        bd.boundaries(ds, fields="SS", check=0, chord=1e-2)
    assert str(err.value) == _cli_error(capsys, argv)


def test_numpy_scalars_accepted_and_nan_named():
    """tol as np.float32 and check as np.int64 are valid values (refused before); a NaN angle
    names its parameter (the message said "angle")."""
    scene = Scene(beta1="0:2pi:8", beta2="0:2pi:8", kappa=2, q=0.1)
    b = bd.boundaries(scene, fields="SS", tol=np.float32(1e-10), check=np.int64(2), chord=1e-2)
    assert any(c.field == "SS" for c in b.curves)
    g = np.arange(8) * 2 * PI / 8
    for name in ("beta1", "beta2"):
        bad = dict(beta1=g, beta2=g) | {name: np.r_[g[:-1], np.nan]}
        ds = xr.Dataset(coords=bad | dict(kappa=[0.5], q=[0.0]))
        with pytest.raises(ValueError, match=f"^{name}: must be finite"):
            bd.boundaries(ds, fields="SS", check=0)
        with pytest.raises(ValueError, match=f"^{name}: must be finite"):
            bd.slice_boundaries(bad["beta1"], bad["beta2"], 0.5, 0.0, 0.0, check=0)


def test_api_size_refusal_is_the_cli_one(capsys, monkeypatch):
    """A grid that cannot fit in the memory available is refused by the API with the command
    line's one line (the API went on until the check's own limit or a MemoryError)."""
    from atlas.data import limits

    monkeypatch.setattr(limits, "available_memory", lambda: 1 << 10)  # 1 KiB free
    argv = ["--kappa", "0.5", "--q", "0", "--check", "0"]
    want = _cli_error(capsys, argv)
    assert want.startswith("size: ")
    scene = Scene(beta1="0:2pi:8", beta2="0:2pi:8", kappa=0.5, q=0.0)
    with pytest.raises(MemoryError) as err:
        bd.boundaries(scene, check=0)
    assert str(err.value) == want


def test_a_run_writing_no_netcdf_loads_neither_xarray_nor_scipy():
    """A slice's curves need neither xarray (with pandas, ~1 s of imports) nor
    scipy (~0.8 s): a fresh process computes them without loading either."""
    import subprocess
    import sys

    code = (
        "import sys, numpy as np; from atlas.data import boundaries as bd; "
        "g = np.arange(8) * np.pi / 4; "
        "b = bd.slice_boundaries(g, g, 2.0, 0.1, 0.1, fields=('SS',), check=0); "
        "print(len(b.curves) > 0, 'xarray' in sys.modules, 'scipy' in sys.modules)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.split() == ["True", "False", "False"]
