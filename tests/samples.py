"""Reference samples shared by several test modules (independent of the code under test)."""

import functools

import numpy as np

from atlas.core import contact_modes, exact
from atlas.core.contact_modes import ALL_CLASSES, class_code, direction


@functools.cache
def per_class(k: int, seed: int):
    """``k`` random geometries of every class (direction components and the class codes)."""
    rng = np.random.default_rng(seed)
    b1, b2 = rng.uniform(0, 2 * np.pi, (2, 6000))
    c1, s1 = direction(b1)
    c2, s2 = direction(b2)
    cc = np.asarray(class_code(c1, s1, c2, s2))
    idx = np.concatenate([np.flatnonzero(cc == c)[:k] for c in ALL_CLASSES])
    return c1[idx], s1[idx], c2[idx], s2[idx], cc[idx]


def exact_code(field, b1, b2, model):
    """The exact tier's boundary code of ``field`` at ``(b1, b2)`` [rad] for ``model`` =
    ``(kappa, q1, q2)``: SS its ``stable_SS``; II 0 inconsistent, else ``1 + stable_II``."""
    c1, s1 = (float(x) for x in contact_modes.direction(b1))
    c2, s2 = (float(x) for x in contact_modes.direction(b2))
    v = exact.point_verdicts(c1, s1, c2, s2, *model)
    if field == "SS":
        return v["stable_SS"]
    return 0 if v["consistent_II"] == 0 else 1 + v["stable_II"]


def limit_bracket_inputs(n: int = 2000, seed: int = 7):
    """Random inputs ``(d, v, M, scale, H)`` of the stop rule's limit brackets spanning the limits:
    gaps (n, 2) up to 1e7 scale, velocities up to 1e5, curvature bounds (n, 4) 1e-2..1e6, scales
    0.1..10, windows 0.1..3."""
    rng = np.random.default_rng(seed)
    d = rng.normal(size=(n, 2)) * 10 ** rng.uniform(0, 7, (n, 2))
    v = rng.normal(size=(n, 2)) * 10 ** rng.uniform(0, 5, (n, 2))
    M, scale = 10 ** rng.uniform(-2, 6, (n, 4)), 10 ** rng.uniform(-1, 1, n)
    H = rng.uniform(0.1, 3, n)
    return d, v, M, scale, H


def count_eig(monkeypatch) -> list:
    """Count the matrices ``np.linalg.eig`` (LAPACK ``geev``) decomposes from now on: a one-item
    list whose value grows by the batch size of each call (``monkeypatch.undo()`` stops it)."""
    seen = [0]
    real = np.linalg.eig

    def counted(a):
        seen[0] += int(np.prod(np.shape(a)[:-2], dtype=int))
        return real(a)

    monkeypatch.setattr(np.linalg, "eig", counted)
    return seen


def eq9_roots(b1, b2, model, dps=60):
    """The roots of ``p`` (paper eq. 9, ``k2 = 1``) at ``(b1, b2)`` [rad] for ``model = (kappa,
    q1, q2)``, by mpmath at ``dps`` digits (an independent reference)."""
    import mpmath

    with mpmath.workdps(dps):
        kappa, q1, q2 = (mpmath.mpf(v) for v in model)
        b1, b2 = mpmath.mpf(b1), mpmath.mpf(b2)
        c1, s1, c2, s2 = mpmath.cos(b1), mpmath.sin(b1), mpmath.cos(b2), mpmath.sin(b2)
        D = c1 * s2 - s1 * c2
        coeffs = [1, q1 * c1 + q2 * s2, kappa * c1 + s2 + q1 * q2 * D, D * (q1 + kappa * q2),
                  kappa * D]  # fmt: skip
        return mpmath.polyroots(coeffs, maxsteps=200, extraprec=200)
