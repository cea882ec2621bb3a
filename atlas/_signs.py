"""Certified signs of floating-point polynomial expressions (pure JAX).

A polynomial quantity ``P`` is evaluated twice by the same code: once as written (``sub`` is
subtraction) and once with every input replaced by its absolute value and every subtraction by an
addition (``P_abs``).  For an expression of depth at most ``n`` evaluated in IEEE arithmetic with unit
roundoff ``u`` and exact inputs,

    |fl(P) - P| <= gamma_n * P_abs + floor,     gamma_n = n u / (1 - n u)

(Higham, *Accuracy and Stability of Numerical Algorithms*, 2nd ed., §3.1), where ``floor`` covers
results flushed to zero below the smallest normal number (XLA on CPU flushes subnormals): each of the
at most ``n_ops`` operations can lose ``tiny`` absolutely, amplified by at most ``amplification`` by
the downstream factors (all inputs are scaled to magnitude <= 2 before evaluation).  The computed
``fl(P_abs)`` is itself rounded, so the bound used is ``gamma_n (1 + gamma_n) fl(P_abs) + floor``.
A sign is *certified* when ``|fl(P)|`` exceeds that bound; otherwise it is ``UNKNOWN``.  Non-finite
values are never certified.  An exact zero is certified only where the caller knows it structurally.
"""

from __future__ import annotations

import jax.numpy as jnp

#: sign code for "floating point could not certify the sign"
UNKNOWN = 2

N_DEPTH = 24  # generous bound on expression depth (the deepest expression here has depth < 12)
AMPLIFICATION = 4096.0


def gamma(n: int, dtype) -> float:
    u = float(jnp.finfo(dtype).eps) / 2.0
    return n * u / (1.0 - n * u)


def certified_sign(value, abs_value, exact_zero=None, n: int = N_DEPTH):
    """Sign code in {-1, 0, +1, UNKNOWN} (int8) of the exact quantity behind ``value``.

    Parameters
    ----------
    value : array
        Floating-point evaluation of the quantity.
    abs_value : array
        Evaluation of the same expression on absolute values with additions only.
    exact_zero : bool array, optional
        Where the caller knows the exact quantity is zero (structural zero).
    """
    dtype = value.dtype
    g = gamma(n, dtype)
    tiny = float(jnp.finfo(dtype).tiny)
    bound = g * (1.0 + g) * abs_value + n * AMPLIFICATION * tiny
    ok = jnp.isfinite(value) & jnp.isfinite(bound)
    s = jnp.where(value > bound, 1, jnp.where(value < -bound, -1, UNKNOWN))
    s = jnp.where(ok, s, UNKNOWN)
    if exact_zero is not None:
        s = jnp.where(exact_zero, 0, s)
    return s.astype(jnp.int8)


def evaluate_certified(fn, *args, exact_zero=None):
    """Evaluate ``fn(*args, sub)`` with its certified sign; returns ``(value, abs_value, sign)``."""
    value = fn(*args, sub=jnp.subtract)
    abs_value = fn(*(jnp.abs(a) for a in args), sub=jnp.add)
    return value, abs_value, certified_sign(value, abs_value, exact_zero)


def det2(ux, uy, vx, vy, *, sub=jnp.subtract):
    """``ux vy - uy vx`` (the cross product of two plane vectors)."""
    return sub(ux * vy, uy * vx)


def det2_sign(ux, uy, vx, vy):
    """Certified sign of ``ux vy - uy vx`` for direction vectors (components of magnitude <= 1).

    Identical or opposite vectors give an exact zero.  In float32 the products are formed exactly in
    float64 (24 + 24 bits < 53), so the sign is always certified.  Products of direction components
    never underflow (``|cos|, |sin| >= 1e-17`` off the axes), so ``abs == 0`` is an exact zero.
    """
    if ux.dtype == jnp.float32 and jnp.zeros((), jnp.float64).dtype == jnp.float64:
        wide = [a.astype(jnp.float64) for a in (ux, uy, vx, vy)]
        d = det2(*wide)
        return jnp.sign(d).astype(jnp.int8)
    same = ((ux == vx) & (uy == vy)) | ((ux == -vx) & (uy == -vy))
    value = det2(ux, uy, vx, vy)
    abs_value = det2(jnp.abs(ux), jnp.abs(uy), jnp.abs(vx), jnp.abs(vy), sub=jnp.add)
    return certified_sign(value, abs_value, exact_zero=same | (abs_value == 0), n=4)


def sign_of(x):
    """Exact sign code of a floating-point number (int8)."""
    return jnp.sign(x).astype(jnp.int8)


def known(s):
    return s != UNKNOWN
