"""Contact-space data of any mechanism and its verdicts: ``B`` and ``a`` of eq. (1) from ``M`` and
the contact Jacobians, for any number of degrees of freedom.

**Derivation** (paper Sec. 2, eq. (1)).  A mechanism with generalised coordinates ``q`` (``n``
degrees of freedom) moves by ``M(q) q'' = Q + sum_j f_j W_j^T``: ``M`` the generalised mass matrix
(symmetric positive definite), ``Q`` the generalised force without contact forces (applied forces
minus the bias ``C(q, q') q' + G(q)``, i.e. MuJoCo's ``qfrc_smooth``), ``f_j >= 0`` the normal
force of contact ``j``.  The gap of contact ``j`` opens at ``d_j' = J_n,j q'`` (row ``j`` of the
normal Jacobian ``J_n``); its sliding velocity along a unit tangent ``t_j`` is ``J_t,j q'``, with
sign ``s_j`` (``+1``: sliding along ``t_j``).  The contact pushes with ``f_j`` along the normal and
Coulomb friction ``mu_j f_j`` against the sliding, the generalised force
``f_j W_j``, ``W_j = J_n,j - mu_j s_j J_t,j``.  Then ``d'' = J_n q'' + (J_n)' q'`` is eq. (1),
``d'' = B f - a``, with

    B = J_n M^-1 (J_n - diag(mu s) J_t)^T        a = -(J_n M^-1 Q + drift)

``b_ij`` the response of gap ``i`` to a unit normal force at contact ``j`` (SPEC §1: column ``j``
is ``b_j``), and ``drift = (J_n)' q'`` the velocity term of the gap accelerations [m/s^2] (for a
planar body: ``-omega^2 n_j . r_j``, and ``-2 omega u_j`` at a body side,
:mod:`atlas.core.rigid_body`).  With Kelvin-Voigt contacts ``f_j = -k_j d_j - c_j d_j'`` the
invariants are ``beta_j`` (direction of ``b_j``), ``alpha`` (direction of ``a``) and ``kappa``,
``q1, q2`` of :func:`atlas.core.contact_modes.invariants` (SPEC §1).

**One contact** is a first-class case: ``B = (b11)``, ``a = (a1)``, and the verdicts are those of
the two-contact theory with the second contact absent (paper Sec. 2-4, Table 1):
``consistent_F`` (lift-off) iff ``a1 < 0``, ``consistent_S`` (sliding) iff ``b11 a1 > 0``
(``f* = a1/b11 > 0``), ``stable_S`` iff ``b11 > 0``, ``consistent_I`` (impact without collision,
a jam) iff ``b11 < 0`` -- signs of floats, decided exactly.  More than two contacts: ``B`` and ``a``
are returned, the verdicts are refused (choose the two contacts of interest).

Layer 1: numpy only.  Every bad argument is a one-line ``ValueError`` naming the parameter.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from atlas.core import contact_modes as mech
from atlas.core import kernels

__all__ = [
    "ContactSpace",
    "contact_space",
    "single_contact_verdicts",
    "verdict_names",
    "verdicts_at",
    "SINGLE_CONTACT_VERDICTS",
]

_TWO_PI = 2.0 * math.pi
#: the verdicts of one sliding contact (module docstring)
SINGLE_CONTACT_VERDICTS = ("consistent_F", "consistent_S", "stable_S", "consistent_I")


def _matrix(name, x, shape=None):
    try:
        arr = np.array(x, dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError(f"{name}: cannot interpret {x!r} as a numeric array") from None
    if shape is not None:
        want = tuple(s if s is not None else arr.shape[i] for i, s in enumerate(shape))
        if arr.ndim != len(shape) or arr.shape != want:
            raise ValueError(f"{name}: expected shape {want}, got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name}: must be finite")
    return arr


def _per_contact(name, x, n):
    arr = np.broadcast_to(_matrix(name, x), (n,)) if np.ndim(x) == 0 else _matrix(name, x, (n,))
    return np.array(arr, dtype=np.float64)


def _mass_solve(M, rhs):
    """``M^-1 rhs`` through a Cholesky factor; ``M`` must be symmetric positive definite."""
    if not np.allclose(M, M.T, rtol=1e-12, atol=0.0):
        raise ValueError("M: the generalised mass matrix must be symmetric")
    try:
        L = np.linalg.cholesky(M)
    except np.linalg.LinAlgError:
        raise ValueError("M: the generalised mass matrix must be positive definite") from None
    return np.linalg.solve(L.T, np.linalg.solve(L, rhs))


def contact_space(
    M, Jn, Jt=None, mu=0.0, s=1, force=0.0, drift=0.0, *, k=1e5, c=0.0, names=None,
    approximate_model=False,
) -> ContactSpace:  # fmt: skip
    """``B`` [1/kg] and ``a`` [m/s^2] of eq. (1) from a mechanism's matrices (module docstring).

    ``M`` (n, n) generalised mass; ``Jn``, ``Jt`` (m, n) normal and tangent Jacobians (rows per
    contact; ``Jt`` along unit tangents ``t_j``, required where ``mu > 0``); ``mu`` (m,) friction
    coefficients ``>= 0``; ``s`` (m,) sliding signs along ``t_j`` (``+-1``); ``force`` (n,) the
    generalised force without contact forces (applied minus bias) [N or N m]; ``drift`` (m,)
    ``(J_n)' q'`` [m/s^2]; ``k`` [N/m] ``> 0`` and ``c`` [N s/m] ``>= 0`` the contacts' stiffness
    and damping (scalars or per contact); ``names`` contact labels; ``approximate_model`` flags
    ``k, c`` as an approximation (a regularised engine's constraint model).
    """
    M = _matrix("M", M)
    if M.ndim != 2 or M.shape[0] != M.shape[1] or M.shape[0] == 0:
        raise ValueError(f"M: must be a square matrix, got shape {M.shape}")
    n = M.shape[0]
    Jn = _matrix("Jn", np.atleast_2d(Jn), (None, n))
    m = Jn.shape[0]
    if m == 0:
        raise ValueError("Jn: no contacts (the normal Jacobian has no rows)")
    mu = _per_contact("mu", mu, m)
    if np.any(mu < 0):
        raise ValueError(f"mu: friction coefficients must be >= 0, got {mu.tolist()}")
    s = _per_contact("s", s, m)
    if np.any(np.abs(s) != 1):
        raise ValueError(f"s: sliding signs must be +1 or -1, got {s.tolist()}")
    if Jt is None:
        if np.any(mu > 0):
            raise ValueError("Jt: the tangent Jacobian is needed where mu > 0")
        Jt = np.zeros_like(Jn)
    Jt = _matrix("Jt", np.atleast_2d(Jt), (m, n))
    force = np.broadcast_to(_matrix("force", force), (n,)) if np.ndim(force) == 0 else force
    force = _matrix("force", force, (n,))
    drift = _per_contact("drift", drift, m)
    W = Jn - (mu * s)[:, None] * Jt
    B = Jn @ _mass_solve(M, W.T)
    a = -(Jn @ _mass_solve(M, force) + drift) + 0.0
    return ContactSpace(B, a, k=k, c=c, names=names, approximate_model=approximate_model)


@dataclasses.dataclass(frozen=True)
class ContactSpace:
    """``d'' = B f - a`` (eq. (1)) for ``m`` contacts, with their Kelvin-Voigt parameters.

    ``B`` (m, m) [1/kg], ``a`` (m,) [m/s^2]; ``k`` [N/m], ``c`` [N s/m] per contact (scalars are
    broadcast); ``names`` contact labels (default ``1 .. m``); ``approximate_model``: ``k, c`` only
    approximate the contact model (stability verdicts then hold for that approximation).
    """

    B: np.ndarray
    a: np.ndarray
    k: object = 1e5
    c: object = 0.0
    names: tuple = None
    approximate_model: bool = False

    def __post_init__(self):
        put = lambda key, v: object.__setattr__(self, key, v)  # noqa: E731
        B = _matrix("B", np.atleast_2d(self.B))
        m = B.shape[0]
        if B.shape != (m, m) or m == 0:
            raise ValueError(f"B: must be a square matrix, got shape {B.shape}")
        put("B", B)
        put("a", _matrix("a", np.atleast_1d(self.a), (m,)))
        put("k", _per_contact("k", self.k, m))
        put("c", _per_contact("c", self.c, m))
        if np.any(self.k <= 0):
            raise ValueError(f"k: contact stiffnesses must be > 0, got {self.k.tolist()}")
        if np.any(self.c < 0):
            raise ValueError(f"c: contact damping must be >= 0, got {self.c.tolist()}")
        names = tuple(str(i + 1) for i in range(m)) if self.names is None else tuple(self.names)
        if len(names) != m:
            raise ValueError(f"names: {m} contacts need {m} names, got {len(names)}")
        put("names", names)

    @property
    def n_contacts(self) -> int:
        return self.B.shape[0]

    def invariants(self) -> dict:
        """``beta1, beta2, alpha`` [rad, in [0, 2 pi)] and ``kappa, q1, q2`` [1] (SPEC §1; two
        contacts)."""
        self._need_two("invariants")
        B, a = self.B, self.a
        if not (a[0] or a[1]):
            raise ValueError("a: the free acceleration is zero, alpha is undefined")
        b1, b2 = math.hypot(B[0, 0], B[1, 0]), math.hypot(B[0, 1], B[1, 1])
        for j, b in ((1, b1), (2, b2)):
            if b == 0.0:
                raise ValueError(f"B: column b{j} is zero (contact {j} has no normal response)")
        out = {
            "beta1": _angle(B[0, 0], B[1, 0]),
            "beta2": _angle(B[0, 1], B[1, 1]),
            "alpha": _angle(a[0], a[1]),
        }
        k, c = self.k, self.c
        out.update(mech.invariants(k[0], k[1], c[0], c[1], b1, b2))
        return out

    def verdicts(self, dtype="float64", names=None) -> dict:
        """Every verdict at this contact space (or those ``names``): :func:`verdicts_at` at the
        invariants (two contacts) or :func:`single_contact_verdicts` (one)."""
        if self.n_contacts == 1:
            return single_contact_verdicts(self.B[0, 0], self.a[0])
        res = verdicts_at(**self.invariants(), dtype=dtype, names=names)
        return {key: v[()] for key, v in res.items()}

    def _need_two(self, what):
        if self.n_contacts != 2:
            raise ValueError(
                f"contacts: {what} are defined for one or two sliding contacts, got "
                f"{self.n_contacts} ({', '.join(self.names)}): choose the two of interest"
            )


def single_contact_verdicts(b11, a1) -> dict:
    """The verdicts of one sliding contact (module docstring), from exact signs of ``b11``
    [1/kg] and ``a1`` [m/s^2]: :data:`SINGLE_CONTACT_VERDICTS` as ``bool``."""
    sb, sa = np.sign(b11), np.sign(a1)
    return {
        "consistent_F": bool(sa < 0),
        "consistent_S": bool(sb * sa > 0),
        "stable_S": bool(sb > 0),
        "consistent_I": bool(sb < 0),
    }


def _angle(x, y) -> float:
    """Direction angle of ``(x, y)`` in ``[0, 2 pi)`` [rad]."""
    t = math.atan2(y, x) + 0.0  # no -0.0
    return t + _TWO_PI if t < 0 else t


# --- verdicts at invariants --------------------------------------------------------------------


def verdict_names() -> tuple[str, ...]:
    """The verdicts a single mechanism has: every result of the verdict kernels
    (:func:`atlas.core.kernels.verdict_kernels`; the reductions over model samples need several
    samples and are not among them)."""
    return tuple(r for k in kernels.verdict_kernels() for r in k.results)


def verdicts_at(beta1, beta2, alpha, kappa, q1, q2, *, dtype="float64", names=None) -> dict:
    """The verdicts ``names`` (default :func:`verdict_names`) at broadcastable invariants.

    The angles [rad] enter through :func:`atlas.core.contact_modes.direction` in ``dtype``, exactly as
    in :func:`atlas.generate`; each verdict comes from its kernel (:mod:`atlas.core.kernels`), and
    undecided codes are settled exactly.  Returns numpy arrays of the broadcast shape in the
    storage types of SPEC §2 (codes ``int8``/``int16``, flags with a ``true_code`` -- Table 1,
    SF/FS stability, IF/FI, CC -- as ``bool``, spectral verdict flags ``int8``, the abscissa float).
    """
    dtype = np.dtype(dtype)
    names = verdict_names() if names is None else tuple(names)
    unknown = set(names) - set(verdict_names())
    if unknown:
        raise ValueError(f"names: unknown verdict(s) {sorted(unknown)}")
    args = [np.asarray(x, np.float64) for x in (beta1, beta2, alpha, kappa, q1, q2)]
    shape = np.broadcast_shapes(*(x.shape for x in args))
    args = [np.broadcast_to(x, shape) for x in args]
    dirs = [c for ang in args[:3] for c in mech.direction(ang, dtype)]
    keys = [i for p in ("beta1", "beta2", "alpha", "model") for i in kernels.PARAM_INPUTS[p]]
    inputs = dict(zip(keys, dirs + args[3:]))
    out = {}
    for k in kernels.verdict_kernels():
        want = tuple(r for r in k.results if r in names)
        if not want:
            continue
        if k.driver is not None:
            res = k.driver(*(inputs[i] for i in k.inputs), names=want, dtype=dtype)
        else:
            res = {r: np.broadcast_to(v, shape).copy() for r, v in kernels.run(k, inputs).items()}
            kernels.settle(k, res, inputs)
        for r in want:
            v = np.asarray(res[r]).reshape(shape)
            out[r] = v == k.true_code[r] if r in k.true_code else v
    return {r: out[r] for r in names}
