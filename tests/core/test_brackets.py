"""Certified brackets: field codes against the exact tier, bisection invariants, bad input."""

import numpy as np
import pytest

from atlas.core import brackets, contact_modes, exact, points


def _exact_code(field, b1, b2, kappa, q1, q2):
    """The field code from the exact tier alone (FLINT rational arithmetic, no float kernel)."""
    c1, s1 = (float(v) for v in contact_modes.direction(b1))
    c2, s2 = (float(v) for v in contact_modes.direction(b2))
    v = exact.point_verdicts(c1, s1, c2, s2, kappa, q1, q2)
    if field == "SS":
        return v["stable_SS"]
    return 0 if v["consistent_II"] == 0 else 1 + v["stable_II"]


@pytest.mark.parametrize("field", ["SS", "II"])
@pytest.mark.parametrize("model", [(0.5, 0.0, 0.0), (2.0, 0.1, 0.1), (0.5, 0.3, 0.0)])
def test_field_codes_match_the_exact_tier(field, model):
    rng = np.random.default_rng(7)
    b1, b2 = rng.uniform(0, 2 * np.pi, (2, 40))
    b1[:4] = [0.0, np.pi / 2, np.pi, 1.0]  # axis lines and det B = 0 (b2 = b1)
    b2[:4] = [np.pi / 2, 0.3, np.pi, 1.0]
    got = brackets.field_codes(field, b1, b2, *model)
    want = [_exact_code(field, x, y, *model) for x, y in zip(b1, b2)]
    assert got.tolist() == want


@pytest.mark.parametrize(
    "model", [(0.5, 0, 0), (0.5, 0.35, 0), (0.5, 0, 0.35), (2, 0.1, 0.1), (1e-6, 1e-3, 10),
              (1e6, 10, 0), (1, 1e-12, 0), (0.5, 0.05, 0.2)],
)  # fmt: skip
def test_padding_point_is_decided_by_the_first_pass(model):
    """Batches are padded to MIN_BATCH with PAD_POINT: were it undecided, every copy would go
    through tier 2, root enclosures or the exact tier (a 4096-fold cost on a 1-point bisection)."""
    c1, s1 = contact_modes.direction(np.full(4, brackets.PAD_POINT[0]))
    c2, s2 = contact_modes.direction(np.full(4, brackets.PAD_POINT[1]))
    np.testing.assert_array_equal(
        np.stack([c1, s1, c2, s2]), np.array([[1], [0], [0], [1]]) * np.ones(4)
    )
    names = ("stable_SS", "consistent_II", "stable_II")
    stats = points.spectral_points(c1, s1, c2, s2, *model, names=names).stats
    assert stats["tier2_points"] == stats["roots_points"] == stats["undecided_before"] == 0


def test_field_codes_keep_the_broadcast_shape():
    b = np.linspace(0.1, 6.0, 5)
    assert brackets.field_codes("SS", b[:, None], b[None, :], 0.5, 0.0, 0.0).shape == (5, 5)


def test_bisect_shrinks_to_tol_and_keeps_different_ends():
    model = (0.5, 0.0, 0.0)
    # segments across the q = 0 neutral boundary at beta2 = 2.0 (closed form: beta1 ~ 0.2, 1.5)
    p = np.array([[0.1, 2.0], [1.2, 2.0]])
    q = np.array([[0.6, 2.0], [1.8, 2.0]])
    vp = brackets.field_codes("SS", p[:, 0], p[:, 1], *model)
    vq = brackets.field_codes("SS", q[:, 0], q[:, 1], *model)
    assert (vp != vq).all()
    p2, q2, a, b = brackets.bisect("SS", p, q, vp, vq, *model, tol=1e-10)
    assert np.hypot(*(q2 - p2).T).max() <= 1e-10
    assert (a != b).all()
    # the ends still carry their codes (re-checked by the exact tier)
    for (x, y), v in zip(p2, a):
        assert _exact_code("SS", x, y, *model) == v
    for (x, y), v in zip(q2, b):
        assert _exact_code("SS", x, y, *model) == v
    # and the boundary there is the closed-form q = 0 neutral boundary (paper Fig. 1): neutral
    # iff the eigenvalues mu of B diag(kappa, 1) are real and positive (disc, trace, det > 0)
    k = model[0]
    m = 0.5 * (p2 + q2)
    c1, s1, c2, s2 = np.cos(m[:, 0]), np.sin(m[:, 0]), np.cos(m[:, 1]), np.sin(m[:, 1])
    disc = (k * c1 - s2) ** 2 + 4 * k * s1 * c2
    trace, det = k * c1 + s2, c1 * s2 - s1 * c2
    assert np.min(np.abs([disc, trace, det]), axis=0).max() < 1e-9


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(field="XX"), "field: must be one of SS, II"),
        (dict(tol=0.0), "tol: must be positive"),
        (dict(vq=np.array([1])), "vp: the two ends"),
    ],
)
def test_bad_input(kwargs, match):
    args = dict(field="SS", p=[[0.3, 2.0]], q=[[1.2, 2.0]], vp=np.array([1]), vq=np.array([0]))
    args.update({k: v for k, v in kwargs.items() if k in args})
    tol = kwargs.get("tol", 1e-10)
    with pytest.raises(ValueError, match=match):
        brackets.bisect(args.pop("field"), *args.values(), 0.5, 0.0, 0.0, tol=tol)


def test_boundary_kind():
    assert brackets.boundary_kind("II", [0, 1], [2, 2]).tolist() == [
        "II_consistency",
        "II_stability",
    ]
    assert brackets.boundary_kind("SS", 0, 2)[()] == "SS_stability"


#: a bracket 1.4e-14 rad long across the II consistency boundary next to ``beta2 = beta1 + pi``
#: at kappa 2, q 0.1 (met by a slice's bisection): no fast tier decides its inner points
HARD_II = (
    np.array([1.1069434970966943, 4.24853613984915]),
    np.array([1.1069434970966843, 4.2485361398491595]),
    (2.0, 0.1, 0.1),
)


def _counting_exact(monkeypatch) -> list:
    """Patch the exact tier to record how many points each of its calls receives."""
    sizes, resolve = [], exact.resolve

    def counted(pts, names=None, **kw):
        sizes.append(len(pts["c1"]))
        return resolve(pts, names=names, **kw)

    monkeypatch.setattr(exact, "resolve", counted)
    return sizes


def test_bisect_settles_a_search_not_every_sample(monkeypatch):
    """A 64-section step of a bracket whose 63 samples all need the exact tier settles at most
    7 of them (a bisection over the sample positions), and lands on the first change of code
    that settling every sample finds (the codes change once along this bracket)."""
    p, q, model = HARD_II
    length = float(np.hypot(*(q - p)))
    sizes = _counting_exact(monkeypatch)
    pts = p + (np.arange(1, 64) / 64)[:, None] * (q - p)
    every = brackets.field_codes("II", pts[:, 0], pts[:, 1], *model)
    settled_all, sizes[:] = sum(sizes), []
    first = int(np.argmax(every != 0))
    assert (every[first:] != 0).all() and 0 < first  # one change: the reference is unique
    P, Q, vp, vq = brackets.bisect("II", p[None], q[None], [0], [2], *model, tol=length / 60)
    assert sum(sizes) <= 7 < settled_all
    np.testing.assert_array_equal(P[0], pts[first - 1])
    np.testing.assert_array_equal(Q[0], pts[first])
    assert vq[0] == every[first]
    assert _exact_code("II", *P[0], *model) == 0 and _exact_code("II", *Q[0], *model) == vq[0]


def test_first_change_codes_mark_the_unsettled_samples(monkeypatch):
    """``direction_codes`` with ``first_change`` settles a bisection's samples of a row and
    marks the rest ``NO_CODE``; the settled ones equal the exact tier's codes."""
    p, q, model = HARD_II
    pts = p + (np.arange(1, 16) / 16)[:, None] * (q - p)
    c1, s1 = contact_modes.direction(pts[:, 0])
    c2, s2 = contact_modes.direction(pts[:, 1])
    got = brackets.direction_codes("II", c1, s1, c2, s2, *model, first_change=np.array([0]))
    known = got != brackets.NO_CODE
    assert 2 <= known.sum() <= 5
    want = [_exact_code("II", x, y, *model) for x, y in pts[known]]
    assert got[known].tolist() == want


def test_bisect_leaves_a_bracket_once_within_tol():
    """A bracket already ``<= tol`` is returned as given (none of its samples, which only the
    exact tier decides, is evaluated), while a longer one sharing the calls is shrunk to
    ``tol``."""
    p, q, model = HARD_II
    u = (q - p) / np.hypot(*(q - p))
    far_p, far_q = p - 1e-6 * u, q + 1e-6 * u
    assert brackets.field_codes("II", *np.stack([far_p, far_q]).T, *model).tolist() == [0, 2]
    P, Q, vp, vq = brackets.bisect(
        "II", np.stack([p, far_p]), np.stack([q, far_q]), [0, 0], [2, 2], *model, tol=1e-9
    )
    np.testing.assert_array_equal(P[0], p)
    np.testing.assert_array_equal(Q[0], q)
    assert vq[0] == 2 and 1e-9 / 64 < np.hypot(*(Q[1] - P[1])) <= 1e-9


def test_padding_is_the_pad_point_in_the_kernel_dtype():
    """The padded columns of a kernel call are the points given, then :data:`PAD_POINT`'s
    direction vectors, as ``np.pad`` gives them."""
    for dtype in (np.float64, np.float32):
        pc, ps = contact_modes.direction(np.array(brackets.PAD_POINT), dtype)
        v = np.linspace(-1, 1, 5)
        got = brackets._padded(v, brackets._pad_direction(np.dtype(dtype))[0][1], 3)
        want = np.pad(v.astype(dtype), (0, 3), constant_values=pc[1])
        assert got.dtype == dtype
        np.testing.assert_array_equal(got, want)
