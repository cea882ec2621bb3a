"""Uncertified baseline: the batched general eigen-solver a user would write (``eig`` of ``M`` with
a tolerance).  For comparisons (``atlas bench``, ``method="eig"``) and display only; no verdict of
the atlas comes from here.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from atlas.core.verdicts import Verdict

__all__ = ["build_M", "eig_verdicts", "eig_verdicts_jit"]


def build_M(c1, s1, c2, s2, kappa, q1, q2):
    """The 4x4 matrix ``M`` of eq. (9) in invariant parameters (``K = diag(kappa, 1)``)."""
    shape = jnp.broadcast_shapes(
        c1.shape, s1.shape, c2.shape, s2.shape, kappa.shape, q1.shape, q2.shape
    )
    bc = lambda a: jnp.broadcast_to(a, shape)  # noqa: E731
    c1, s1, c2, s2, kappa, q1, q2 = (bc(a) for a in (c1, s1, c2, s2, kappa, q1, q2))
    zero, one = jnp.zeros_like(c1), jnp.ones_like(c1)
    rows = [
        [zero, zero, one, zero],
        [zero, zero, zero, one],
        [-c1 * kappa, -c2, -c1 * q1, -c2 * q2],
        [-s1 * kappa, -s2, -s1 * q1, -s2 * q2],
    ]
    return jnp.stack([jnp.stack(r, -1) for r in rows], -2)


def eig_verdicts(c1, s1, c2, s2, kappa, q1, q2, *, tol=None):
    """Baseline a user would write: ``eig`` of ``M`` with a tolerance. NOT certified.

    stable (all Re < -tol), neutral (max |Re| <= tol), unstable otherwise; II from eigenvalues with
    ``|Im| <= tol`` and ``Re > tol`` whose eigenvector gap part has ``x1 x2 > 0``.
    """
    dtype = c1.dtype
    tol = float(jnp.finfo(dtype).eps) ** 0.5 if tol is None else tol
    M = build_M(c1, s1, c2, s2, kappa, q1, q2)
    w, v = jnp.linalg.eig(M)
    re, im = jnp.real(w), jnp.imag(w)
    smax = jnp.max(re, -1)
    ss = jnp.where(
        smax < -tol, Verdict.STABLE, jnp.where(smax <= tol, Verdict.NEUTRAL, Verdict.UNSTABLE)
    ).astype(jnp.int8)
    x1, x2 = jnp.real(v[..., 0, :]), jnp.real(v[..., 1, :])
    iitype = (jnp.abs(im) <= tol) & (re > tol) & (x1 * x2 > 0)
    cons = jnp.any(iitype, -1).astype(jnp.int8)
    idx = jnp.argmax(re, -1)
    dom_ii = jnp.take_along_axis(iitype, idx[..., None], -1)[..., 0]
    second = jnp.sort(re, -1)[..., -2]
    stab = (dom_ii & (second < smax - tol)).astype(jnp.int8)
    return {"stable_SS": ss, "consistent_II": cons, "stable_II": stab, "spectral_abscissa": smax}


eig_verdicts_jit = jax.jit(eig_verdicts)
