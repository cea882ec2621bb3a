"""Shape buckets of the elementwise kernels: the same bits as the unpadded call, few programs.

The reference of every comparison is the kernel's own jitted program called on the caller's
shapes as they are (no buckets): padding with a point of the batch must not change one bit, on
edge inputs (signed zeros, subnormals, infinities, NaN) in float64 and float32.
"""

import jax
import numpy as np
import pytest

from atlas.core import buckets, contact_space, kernels, warm
from atlas.core import contact_modes as mech
from atlas.data.engine import generate
from atlas.data.plane import plane_outputs
from atlas.data.scene import Scene
from atlas.explore.maps import compute_map
from atlas.paper.tables import class_kernel

ELEMENTWISE = ("b1", "b2", "b1b2", "b1b2a")


def edge_values(dtype) -> np.ndarray:
    """Signed zeros, the smallest subnormal, tiny and huge normals, +-inf, NaN, directions."""
    t = np.finfo(dtype)
    v = [0.0, -0.0, t.smallest_subnormal, -t.smallest_subnormal, t.tiny, -t.tiny, t.max, -t.max]
    v += [np.inf, -np.inf, np.nan, 1.0, -1.0, 0.6, -0.8, 1e-8, -3e-20]
    return np.array(v, dtype)


def edge_inputs(n_in, shapes, dtype, seed):
    """``n_in`` arrays of the given broadcastable ``shapes`` drawn from :func:`edge_values`."""
    rng = np.random.default_rng(seed)
    pool = edge_values(dtype)
    return [pool[rng.integers(0, pool.size, shapes[i % len(shapes)])] for i in range(n_in)]


def same_bits(a, b) -> bool:
    a, b = np.asarray(a), np.asarray(b)
    return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()


#: broadcast shapes of the calls: a point; a grid (n, 1) x (1, n) of 5,000 points (batches of
#: 4,096, 512 and one padded from 392) with scalars among the inputs
CASES = ([()], [(50, 1), (), (1, 100)])


def check_bits(fn, reference, args):
    """Every output of ``fn(*args)`` has the bits of ``reference(*args)`` (broadcast)."""
    shape = np.broadcast_shapes(*(a.shape for a in args))
    got, ref = jax.tree.leaves(fn(*args)), jax.tree.leaves(reference(*args))
    for g, r in zip(got, ref, strict=True):
        assert same_bits(g, np.broadcast_to(np.asarray(r), shape)), (fn, shape)
        assert g.flags.writeable  # callers settle undecided codes in place


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
@pytest.mark.parametrize("name", ELEMENTWISE)
def test_kernels_run_is_bit_identical_to_the_unpadded_call(name, dtype):
    k = kernels.KERNELS[name]
    run = lambda *a: kernels.run(k, dict(zip(k.inputs, a)))  # noqa: E731
    for i, shapes in enumerate(CASES):
        args = edge_inputs(len(k.inputs), shapes, dtype, seed=i)
        check_bits(run, kernels.jitted(k).jitted, args)  # the program on the call's own shapes
    empty = run(*edge_inputs(len(k.inputs), [(0,), (3, 0)], dtype, seed=0))
    full = run(*args)
    assert all(empty[r].shape == (3, 0) and empty[r].dtype == full[r].dtype for r in k.results)


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_contact_modes_and_class_kernel_are_bit_identical_to_the_unpadded_call(dtype):
    for fn, n_in in ((mech.class_code, 4), (class_kernel, 6)):
        args = edge_inputs(n_in, CASES[1], dtype, seed=7)
        check_bits(fn, fn.kernel.jitted, args)


def test_python_numbers_take_the_arrays_dtype():
    """A Python float beside float32 arrays is rounded to float32, as JAX's weak type does."""
    c = np.array([0.6, -0.8, 0.0], np.float32)
    got = mech.class_code(c, c[::-1], 0.1, 0.3)
    ref = mech.class_code.kernel.jitted(c, c[::-1], 0.1, 0.3)
    assert same_bits(got, ref)


@pytest.mark.parametrize("n", [0, 1, 511, 512, 513, 4095, 4096, 5000, 65535, 65536, 200_001])
def test_batches_cover_the_call_with_less_than_a_small_batch_of_padding(n):
    got = buckets.batches(n)
    starts = [s for s, _ in got]
    assert starts == [sum(length for _, length in got[:i]) for i in range(len(got))]
    assert {length for _, length in got} <= set(buckets.LENGTHS)
    total = sum(length for _, length in got)
    assert n <= total < n + buckets.SMALL
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

    def per_kernel(self) -> dict:
        """Programs per kernel, dtype and set of scalar inputs."""
        out: dict = {}
        for name, sig in self.seen:
            key = (name, sig[0][1], tuple(len(shape) == 0 for shape, _ in sig))
            out[key] = out.get(key, 0) + 1
        return out


def test_every_entry_point_shares_the_programs_of_each_kernel(monkeypatch):
    """The engine at several grid sizes and ``tile_points``, the plane, the contact-space
    verdicts and the explorer's map run each elementwise kernel in at most two lengths per dtype
    and set of scalar inputs (12 programs here; before shape buckets one per grid size, tile and
    broadcast shape: 26, 8 of one kernel)."""
    shapes = Shapes(monkeypatch)
    outs = "class_code,cc_possible,stable_SF,consistent_IF,stable_FS,consistent_FI"
    for n, tile, dtype in ((5, 1 << 16, "float64"), (24, 64, "float64"), (70, 1000, "float32")):
        for extra in ("", ",subclass_code,consistent_SS"):
            scene = Scene(
                name="b", beta1=f"0:2pi:{n}", beta2=f"0:2pi:{n + 3}", alpha="0:2pi:3",
                outputs=outs + extra,
            )  # fmt: skip
            generate(scene, tile_points=tile, dtype=dtype, resolve=False)
    names = ("class_code", "subclass_code", "consistent_SS", "stable_SF", "consistent_FI")
    for n in (9, 33, 100):
        beta = np.linspace(0, 2 * np.pi, n, endpoint=False)
        plane_outputs(names, beta, (0.5, 0.1, 0.1), alpha=0.3, resolve=False)
        compute_map(n=n, layers=("class_code", "stable_SF"), resolve=False)
    for shape in ((), (4,), (3, 5)):
        b = np.full(shape, 0.7)
        contact_space.verdicts_at(b, b + 2, b + 1, 0.5, 0.1, 0.1, names=("subclass_code",))
    counts = shapes.per_kernel()
    assert {k[0] for k in counts} == {"_b1", "_b2", "_b1b2", "_b1b2a"}, counts
    assert max(counts.values()) <= 2, counts
    assert sum(counts.values()) <= 12, counts
