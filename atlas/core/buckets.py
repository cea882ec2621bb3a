"""Shape buckets of the elementwise kernels: every caller's points as flat columns of a few lengths.

A jitted kernel compiles one program per distinct shape of its inputs.  The elementwise kernels
(the class codes, Table 1, SF/FS/IF/FI, CC: :mod:`atlas.core.contact_modes`, and the point
kernels without a driver, :mod:`atlas.core.kernels`) are called by the engine on tiles of any
size, by the plane on ``(n, 1) x (1, n)`` grids, by single points and by point lists.  Here every
such call runs on flat columns of a few lengths (:func:`batches`): :data:`LARGE`, :data:`BATCH`
and :data:`SMALL` points, as many of each as fit, the rest padded to :data:`SMALL` (the two short
lengths are those of the spectral driver's flat first pass, :mod:`atlas.core.points`); a large
grid runs whole (:func:`call`).  Each input is broadcast to the call's shape and cut into
batches one at a time (a broadcast grid is never materialized whole), an input of one value
stays a scalar (a Python number as it is: weakly typed, it meets the other inputs as in the
unpadded call), the last batch is padded with its own last point, and the results are sliced
back and reshaped: the same values as the unpadded call, bit for bit, since every output point
depends on its own input point only.  The padding is under :data:`SMALL` points whatever the
call.  One program per kernel, length, dtype and set of scalar inputs, whoever calls.
"""

from __future__ import annotations

import functools
import math

import jax
import numpy as np

from atlas.core import warm

__all__ = [
    "SMALL",
    "BATCH",
    "LARGE",
    "LENGTHS",
    "batches",
    "call",
    "Pending",
    "submit",
    "elementwise",
]

#: the shortest batch [points]: the rest of a call below :data:`BATCH` points
SMALL = 1 << 9
#: the middle batch [points]
BATCH = 1 << 12
#: the longest batch [points] (the engine's default tile)
LARGE = 1 << 16
#: the batch lengths, longest first
LENGTHS = (LARGE, BATCH, SMALL)


def batches(n: int) -> list[tuple[int, int]]:
    """``(start, length)`` of the batches of a call of ``n`` points: as many of each length of
    :data:`LENGTHS` as fit, longest first, the rest in one padded batch of :data:`SMALL`
    (padding < :data:`SMALL` points, whatever ``n``)."""
    out, start = [], 0
    for length in LENGTHS:
        while n - start >= length:
            out.append((start, length))
            start += length
    if start < n:
        out.append((start, SMALL))
    return out


def _python(a) -> bool:
    """A Python number (weakly typed in JAX: it takes the dtype of what it meets)."""
    return isinstance(a, (int, float, complex)) and not isinstance(a, np.generic)


def _host(a):
    """An argument as a numpy array; a Python number stays one, passed to the kernel as it is
    (so it meets the other inputs in the kernel exactly as in the unpadded call)."""
    return a if _python(a) else np.asarray(a)


def _flat_range(v, start: int, stop: int) -> np.ndarray:
    """``v.reshape(-1)[start:stop]`` of a (broadcast) array, copying only those points."""
    if v.ndim <= 1:
        return v.reshape(-1)[start:stop]
    inner = math.prod(v.shape[1:])
    r0, r1 = start // inner, (stop - 1) // inner
    if r0 == r1:
        return _flat_range(v[r0], start - r0 * inner, stop - r0 * inner)
    head = _flat_range(v[r0], start - r0 * inner, inner)
    tail = _flat_range(v[r1], 0, stop - r1 * inner)
    return np.concatenate([head, v[r0 + 1 : r1].reshape(-1), tail])


class Pending:
    """The results of :func:`submit`: the batches dispatched so far; :meth:`result` dispatches
    the rest (one batch ahead of the one it reads) and returns numpy arrays of the call's shape."""

    def __init__(self, fn, args, ahead: int | None):
        self.fn = fn
        self.shape = np.broadcast_shapes(*(np.shape(a) for a in args))
        self.n = math.prod(self.shape)
        # an input of one value stays a scalar (the kernel computes what depends on it once)
        # unless every input is one: a point of arrays runs as a column, like any other call
        scalar = [np.size(a) == 1 for a in args]
        if all(scalar) and not any(map(_python, args)):
            scalar = [False] * len(args)
        self.scalar = scalar
        self.args = [
            (a if _python(a) else a.reshape(())) if sc else np.broadcast_to(a, self.shape)
            for a, sc in zip(args, self.scalar, strict=True)
        ]
        self.batches = batches(self.n)
        ahead = len(self.batches) if ahead is None else ahead
        self.out = [self._dispatch(*b) for b in self.batches[:ahead]]

    def _dispatch(self, start: int, length: int):
        """One batch of columns (cut, padded with the batch's last point), sent."""
        stop = min(start + length, self.n)
        cols = []
        for a, sc in zip(self.args, self.scalar, strict=True):
            if sc:
                cols.append(a)
                continue
            col = np.empty(length, a.dtype)
            col[: stop - start] = _flat_range(a, start, stop)
            col[stop - start :] = col[stop - start - 1]
            cols.append(col)
        return self.fn(*cols)

    def result(self):
        """The outputs (the kernel's pytree of numpy arrays, each shaped like the call)."""
        if self.n == 0:
            specs = [
                a if _python(a) else jax.ShapeDtypeStruct(() if sc else (SMALL,), a.dtype)
                for a, sc in zip(self.args, self.scalar, strict=True)
            ]
            return jax.tree.map(
                lambda s: np.empty(self.shape, s.dtype), jax.eval_shape(self.fn, *specs)
            )
        parts = []
        for k, (start, length) in enumerate(self.batches):
            if k + 1 < len(self.batches) and k + 1 >= len(self.out):
                self.out.append(self._dispatch(*self.batches[k + 1]))
            m = min(length, self.n - start)
            parts.append(jax.tree.map(lambda v, m=m: _points(v, m), self.out[k]))
            self.out[k] = None
        flat = jax.tree.map(lambda *p: np.concatenate(p), *parts)  # writable, fresh arrays
        return jax.tree.map(lambda v: v.reshape(self.shape), flat)


def _points(v, m: int) -> np.ndarray:
    """The first ``m`` points of a batch's output (of one value if it depends on scalars only)."""
    v = np.asarray(v)
    return v[:m] if v.shape else np.full(m, v)


def submit(fn, *args, ahead: int | None = 1) -> Pending:
    """``fn`` (a jitted elementwise kernel) on broadcastable ``args`` in the batches of
    :func:`batches`; ``ahead`` batches (``None``: all) are dispatched at once (asynchronously),
    the rest by :meth:`Pending.result`.  An input is a flat column of the batch's length, or a
    scalar if it has one value (a Python number stays one): one program per batch length, dtype
    and set of scalar inputs."""
    args = [_host(a) for a in args]
    if not args:
        raise ValueError("args: an elementwise kernel needs at least one input")
    return Pending(fn, args, ahead)


def call(fn, *args):
    """The outputs of ``fn`` on broadcastable ``args`` as numpy arrays of their broadcast shape,
    bit for bit those of ``fn(*args)``: ``submit(fn, *args).result()``, except for a grid (an
    input varying along some axes only) of at least :data:`LARGE` points, which runs whole in its
    own shape: its kernel computes what depends on one axis once per value of that axis (half
    the time of flat columns on a 513 x 513 plane), a saving that repeats at every call."""
    args = [_host(a) for a in args]
    shape = np.broadcast_shapes(*(np.shape(a) for a in args))
    n = math.prod(shape)
    if n >= LARGE and any(1 < np.size(a) < n for a in args):
        return jax.tree.map(lambda v: np.array(np.broadcast_to(v, shape)), fn(*args))
    return submit(fn, *args).result()


class Elementwise:
    """A kept elementwise kernel (:class:`atlas.core.warm.Kernel`) whose calls on host arrays
    run in shape buckets (:func:`call`: numpy results); traced calls (inside another kernel)
    are the kernel itself."""

    def __init__(self, fn):
        self.kernel = warm.Kernel(fn)
        functools.update_wrapper(self, fn)

    def __call__(self, *args):
        if any(isinstance(a, jax.core.Tracer) for a in args):
            return self.kernel(*args)
        return call(self.kernel, *args)

    def __getattr__(self, name):  # the jitted kernel's API: lower, trace, ...
        kernel = self.__dict__.get("kernel")
        if kernel is None:
            raise AttributeError(name)
        return getattr(kernel, name)


def elementwise(fn) -> Elementwise:
    """:class:`Elementwise` as a decorator."""
    return Elementwise(fn)
