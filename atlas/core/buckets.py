"""Shape buckets of the elementwise kernels: every caller's points as flat columns of a few lengths.

A jitted kernel compiles one program per distinct shape of its inputs.  The elementwise kernels
(the class codes, Table 1, SF/FS/IF/FI, CC: :mod:`atlas.core.contact_modes`, and the point
kernels without a driver, :mod:`atlas.core.kernels`) are called by the engine on tiles of any
size, by the plane on ``(n, 1) x (1, n)`` grids, by single points and by point lists.  Here every
such call runs on flat columns of one of two lengths (:func:`batch_length`): :data:`SMALL` points
for at most :data:`BATCH` points, :data:`BATCH` points above (the lengths of the spectral
driver's flat first pass, :mod:`atlas.core.points`).  Each input is broadcast to the call's shape
and cut into batches one at a time (a broadcast grid is never materialized whole), the last
batch is padded with its own last point, and the results are sliced back and reshaped: the same
values as the unpadded call, bit for bit, since every output point depends on its own input point
only.  The padding is below one batch: under 2x the points from :data:`BATCH` points on, and at
most :data:`SMALL` points below.  One program per kernel, length and dtype, whoever calls.
"""

from __future__ import annotations

import functools
import math

import jax
import numpy as np

from atlas.core import warm

__all__ = ["SMALL", "BATCH", "batch_length", "call", "Pending", "submit", "elementwise"]

#: the batch length of calls of fewer than :data:`BATCH` points [points]
SMALL = 1 << 9
#: the batch length of larger calls [points]
BATCH = 1 << 12


def batch_length(n: int) -> int:
    """The column length a call of ``n`` points runs in: :data:`SMALL` below :data:`BATCH`
    points (padding < :data:`SMALL`), :data:`BATCH` from there on (padding < ``n``)."""
    return SMALL if n < BATCH else BATCH


def _host(a):
    """An argument as a numpy array (a Python number stays one, typed by :func:`_typed`)."""
    if isinstance(a, (int, float, complex, bool)) and not isinstance(a, np.generic):
        return a
    return np.asarray(a)


def _typed(args):
    """Python numbers as arrays of the dtype JAX gives them beside the array arguments (a weak
    type takes the arrays' dtype; alone, JAX's default)."""
    arrays = [a for a in args if isinstance(a, np.ndarray)]
    dt = jax.dtypes.result_type(*arrays, *(a for a in args if not isinstance(a, np.ndarray)))
    return [a if isinstance(a, np.ndarray) else np.asarray(a, dt) for a in args]


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

    def __init__(self, fn, args, ahead: int):
        self.fn, self.args = fn, args
        self.shape = np.broadcast_shapes(*(a.shape for a in args))
        self.n = math.prod(self.shape)
        self.length = batch_length(self.n)
        self.starts = list(range(0, self.n, self.length))
        ahead = len(self.starts) if ahead is None else ahead
        self.out = [self._dispatch(i) for i in self.starts[:ahead]]

    def _dispatch(self, start: int):
        """One batch of columns (broadcast, cut, padded with the batch's last point), sent."""
        stop = min(start + self.length, self.n)
        cols = []
        for a in self.args:
            col = np.empty(self.length, a.dtype)
            col[: stop - start] = _flat_range(np.broadcast_to(a, self.shape), start, stop)
            col[stop - start :] = col[stop - start - 1]
            cols.append(col)
        return self.fn(*cols)

    def result(self):
        """The outputs (the kernel's pytree of numpy arrays, each shaped like the call)."""
        if self.n == 0:
            specs = [jax.ShapeDtypeStruct((self.length,), a.dtype) for a in self.args]
            return jax.tree.map(
                lambda s: np.empty(self.shape, s.dtype), jax.eval_shape(self.fn, *specs)
            )
        parts = []
        for k in range(len(self.starts)):
            if k + 1 < len(self.starts) and k + 1 >= len(self.out):
                self.out.append(self._dispatch(self.starts[k + 1]))
            parts.append(jax.tree.map(np.asarray, self.out[k]))
            self.out[k] = None
        flat = jax.tree.map(lambda *p: np.concatenate(p)[: self.n], *parts)
        return jax.tree.map(lambda v: v.reshape(self.shape), flat)


def submit(fn, *args, ahead: int | None = 1) -> Pending:
    """``fn`` (a jitted elementwise kernel) on broadcastable ``args`` in batches of
    :func:`batch_length`; ``ahead`` batches (``None``: all) are dispatched at once
    (asynchronously), the rest by :meth:`Pending.result`.  Every input is a flat column of the batch length (a scalar too):
    one program per batch length and dtype."""
    args = _typed([_host(a) for a in args])
    if not args:
        raise ValueError("args: an elementwise kernel needs at least one input")
    return Pending(fn, args, ahead)


def call(fn, *args):
    """``submit(fn, *args).result()``: the outputs of ``fn`` on broadcastable ``args`` as numpy
    arrays of their broadcast shape, bit for bit those of ``fn(*args)``."""
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
