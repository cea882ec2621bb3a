"""Shape buckets of the elementwise kernels: the same bits as the unpadded call, few programs.

Every comparison is against the kernel's own jitted program called on the points as they are
(no buckets): padding with a point of the batch must not change one bit, on edge inputs (signed
zeros, subnormals, extremes, infinities, NaN) in float64 and float32.  The batching rule is one
piece of code (:mod:`atlas.core.buckets`): it is checked on every kind of call (a point, grids,
scalars, every batch length, a whole large grid, no points) with the cheapest kernel, whose
reference programs in the call's own shapes cost little.  The other kernels are checked against
their unpadded calls of :data:`~atlas.core.buckets.SMALL` points (a program every caller uses),
at another place of a padded batch and, in float64, inside a :data:`~atlas.core.buckets.BATCH`
batch (a program of another length; the tables' kernel, made of the ops of the others, in the
short one only).
"""

import jax
import numpy as np
import pytest

from atlas.core import buckets, contact_space, kernels, model_box, warm
from atlas.core import contact_modes as mech
from atlas.data.engine import generate
from atlas.data.plane import plane_outputs
from atlas.data.scene import Scene
from atlas.explore.maps import compute_map
from atlas.paper.tables import class_kernel

SMALL, BATCH, LARGE = buckets.SMALL, buckets.BATCH, buckets.LARGE


def edge_values(dtype) -> np.ndarray:
    """Signed zeros, the smallest subnormal, tiny and huge normals, +-inf, NaN, directions."""
    t = np.finfo(dtype)
    v = [0.0, -0.0, t.smallest_subnormal, -t.smallest_subnormal, t.tiny, -t.tiny, t.max, -t.max]
    v += [np.inf, -np.inf, np.nan, 1.0, -1.0, 0.6, -0.8, 1e-8, -3e-20]
    return np.array(v, dtype)


def edge_inputs(shapes, dtype, seed) -> list:
    """One array per shape of ``shapes``, drawn from :func:`edge_values`."""
    rng = np.random.default_rng(seed)
    pool = edge_values(dtype)
    return [pool[rng.integers(0, pool.size, shape)] for shape in shapes]


def same_bits(a, b) -> bool:
    a, b = np.asarray(a), np.asarray(b)
    return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()


def run(name):
    """The host call of kernel ``name`` of :data:`atlas.core.kernels.KERNELS` (in buckets)."""
    k = kernels.KERNELS[name]
    return lambda *a: kernels.run(k, dict(zip(k.inputs, a)))


#: shapes of the two inputs of ``b1``: a point (one padded small batch); a grid of 5,000 points
#: (4,096 + 512 + 392 padded); a column and a scalar (one batch of each length, 188 padded); a
#: grid of at least LARGE points (run whole, one result broadcast along the other axis)
CALLS = ([(), ()], [(50, 1), (1, 100)], [(LARGE + BATCH + SMALL + 188,), ()], [(256, 1), (1, 257)])


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_calls_of_every_shape_have_the_bits_of_the_unpadded_call(dtype):
    reference = kernels.jitted(kernels.KERNELS["b1"]).jitted  # the program on the call's shapes
    for i, shapes in enumerate(CALLS):
        args = edge_inputs(shapes, dtype, seed=i)
        shape = np.broadcast_shapes(*shapes)
        got, ref = run("b1")(*args), reference(*args)
        for name, r in ref.items():
            assert same_bits(got[name], np.broadcast_to(np.asarray(r), shape)), (name, shape)
            assert got[name].flags.writeable  # callers settle undecided codes in place
    empty = run("b1")(*edge_inputs([(0,), (3, 0)], dtype, seed=0))
    assert all(v.shape == (3, 0) and v.dtype == got[k].dtype for k, v in empty.items())


def _kernels(dtype):
    """(bucketed call, its unpadded program, input shapes: ``None`` a column, ``()`` a scalar,
    points of the call) of every entry point's kernel; scalars where a caller has them (the
    plane's fixed alpha); in float64 a BATCH-point batch first, except for the tables' kernel
    (float64 only, its ops are those of ``b1b2`` and ``b1b2a``)."""
    col, n = None, (BATCH if dtype == np.float64 else 0) + SMALL + 188
    out = [(run(k), kernels.jitted(kernels.KERNELS[k]).jitted, [col] * m, n)
           for k, m in (("b1", 2), ("b2", 2), ("b1b2", 4))]  # fmt: skip
    alpha = [(), ()] if dtype == np.float64 else [col] * 2
    b1b2a = kernels.jitted(kernels.KERNELS["b1b2a"]).jitted
    out.append((run("b1b2a"), b1b2a, [col] * 4 + alpha, n))
    out.append((mech.class_code, mech.class_code.kernel.jitted, [col] * 4, n))
    if dtype == np.float64:
        out.append((class_kernel, class_kernel.kernel.jitted, [col] * 6, SMALL + 188))
    return out


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_every_kernel_has_the_bits_of_its_unpadded_calls(dtype):
    """The first and the last SMALL points of a call (the last ones shifted in a padded batch;
    in float64 the first ones computed in a BATCH-point program) against the kernel's
    unpadded calls on those points."""
    for fn, reference, kinds, n in _kernels(dtype):
        args = edge_inputs([(n,) if k is None else k for k in kinds], dtype, seed=len(kinds))
        got = jax.tree.leaves(fn(*args))
        for part in (slice(0, SMALL), slice(n - SMALL, n)):
            ref = jax.tree.leaves(reference(*(a if a.ndim == 0 else a[part] for a in args)))
            for g, r in zip(got, ref, strict=True):
                assert same_bits(g[part], np.broadcast_to(np.asarray(r), (SMALL,))), (fn, part)


def test_python_numbers_meet_the_arrays_as_in_the_unpadded_call():
    """A Python number is weakly typed: beside float32 arrays, ``1e-46`` (zero in float32) keeps
    its sign where the kernel takes it alone, so these IF modes are consistent, as unpadded."""
    reference = kernels.jitted(kernels.KERNELS["b1"]).jitted
    for c1 in (np.array([-0.6, -1.0, 0.5], np.float32), np.float32(-0.6), -0.6):
        got, ref = run("b1")(c1, 1e-46), reference(c1, 1e-46)
        assert all(same_bits(got[k], ref[k]) for k in ref), c1
        assert got["consistent_IF"].any()


@pytest.mark.parametrize("n", [0, 1, 511, 512, 513, 4095, 4096, 5000, 65535, 65536, 200_001])
def test_batches_cover_the_call_with_less_than_a_small_batch_of_padding(n):
    got = buckets.batches(n)
    starts = [s for s, _ in got]
    assert starts == [sum(length for _, length in got[:i]) for i in range(len(got))]
    assert {length for _, length in got} <= set(buckets.LENGTHS)
    total = sum(length for _, length in got)
    assert n <= total < n + SMALL
    assert not got or n > total - got[-1][1]  # the last batch holds a point of the call


class Shapes:
    """The distinct (kernel, argument shapes and dtypes) that host calls of kept kernels see:
    one compiled program each."""

    def __init__(self, monkeypatch):
        self.seen = set()
        call = warm.Kernel.__call__

        def spy(kernel, *args, **static):
            if not any(isinstance(a, jax.core.Tracer) for a in args):
                sig = tuple((np.shape(a), np.result_type(a).name) for a in args)
                self.seen.add((kernel.name.rsplit(".", 1)[-1], sig))
            return call(kernel, *args, **static)

        monkeypatch.setattr(warm.Kernel, "__call__", spy)

    def lengths(self) -> dict:
        """The lengths of the columns, per kernel, dtype and set of scalar inputs."""
        out: dict = {}
        for name, sig in self.seen:
            key = (name, sig[0][1], tuple(shape == () for shape, _ in sig))
            out.setdefault(key, set()).update(shape for shape, _ in sig if shape != ())
        return out


def _entry_points():
    """Every host caller of the elementwise kernels, at sizes and tiles that gave each its own
    programs before shape buckets (one per grid size, tile and broadcast shape)."""
    outs = "class_code,cc_possible,stable_SF,consistent_IF,stable_FS,consistent_FI,"
    for n, tile, dtype in ((5, LARGE, "float64"), (24, 64, "float64"), (9, LARGE, "float32")):
        scene = Scene(
            name="b", beta1=f"0:2pi:{n}", beta2=f"0:2pi:{n + 3}", alpha="0:2pi:3",
            outputs=outs + "subclass_code,consistent_SS",
        )  # fmt: skip
        generate(scene, tile_points=tile, dtype=dtype, resolve=False)
    names = ("class_code", "subclass_code", "consistent_SS", "stable_SF", "consistent_FI")
    for n in (9, 33, 100):  # 100 x 100: batches of both lengths
        beta = np.linspace(0, 2 * np.pi, n, endpoint=False)
        plane_outputs(names, beta, (0.5, 0.1, 0.1), alpha=0.3, resolve=False)
    compute_map(n=20, layers=("class_code", "stable_SF"), resolve=False)
    for shape in ((), (3, 5)):
        b = np.full(shape, 0.7)
        contact_space.verdicts_at(b, b + 2, b + 1, 0.5, 0.1, 0.1, names=("subclass_code",))
        mech.class_code(*mech.direction(b), *mech.direction(b + 2))
    c, s = mech.direction(np.linspace(0.1, 6, 24)[:, None])
    ca, sa = mech.direction(np.linspace(0.05, 6.2, 100)[None, :])
    class_kernel(c, s, s, c, ca, sa)  # the tables' (sample x alpha) grid
    geo = np.array([[0.6, 0.8, -0.8, 0.6]] * 5)
    model_box._verify(geo, np.full((5, 3), 0.5))  # the witness checks


def test_every_entry_point_shares_the_programs_of_each_kernel(monkeypatch):
    """The engine at several grid sizes, tiles and dtypes, the plane, the explorer's map, the
    contact-space verdicts, the public verdicts, the tables and the witness checks run every
    elementwise kernel on columns of the bucket lengths only: at most two programs per kernel,
    dtype and set of scalar inputs (before shape buckets the engine alone compiled ``_b1b2a``
    at 8 shapes)."""
    shapes = Shapes(monkeypatch)
    _entry_points()
    lengths = shapes.lengths()
    names = {k[0] for k in lengths}
    assert names == {"_b1", "_b2", "_b1b2", "_b1b2a", "class_code", "class_kernel", "ss_verdict"}
    assert all(s <= {(SMALL,), (BATCH,)} for s in lengths.values()), lengths
