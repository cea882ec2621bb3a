"""A MuJoCo model at a state -> the contact-space data of eq. (1) -> every verdict.

**What is read** (MuJoCo >= 3.1; the ``mujoco`` extra).  At the state ``(qpos, qvel)``:
``M`` from ``mj_fullM`` (armature included), the generalised force without contact forces
``Q = qfrc_smooth`` (applied, actuator and passive forces minus ``qfrc_bias``), and for each chosen
contact between geoms 1 and 2 (MuJoCo's contact frame: the normal ``n`` is the frame's first row and
points from geom 1 to geom 2; ``pos`` is the midpoint of the surfaces) the Jacobians
``J_n = n^T (J_2 - J_1)`` and ``J_t = t^T (J_2 - J_1)`` of the points of bodies 1 and 2 at ``pos``
(``mj_jac``).  ``t`` is the unit slip direction, the tangential part of the relative velocity
``(J_2 - J_1) qvel`` at ``pos`` (so ``s = +1``), and ``mu`` the contact's first friction
coefficient (MuJoCo's combination of the two geoms'; 0 where ``condim = 1``).  The velocity term
``drift = (J_n)' qvel`` is the derivative of ``J_n`` along ``qvel`` by central differences of the
collision geometry at
``qpos (+-) h qvel`` (``mj_integratePos``; ``h qvel`` moves about ``1e-5`` of the model's extent,
error about 1e-9 relative): it carries every geometric term -- the normal turning with a body side,
the rolling of rounded geoms -- that the planar closed forms of :mod:`atlas.core.rigid_body` write
by hand.  Then :func:`atlas.core.contact_space.contact_space` gives ``B`` and ``a``.

**Contacts.**  Touching means MuJoCo's signed distance ``dist <= tol`` (penetrating contacts are
touching).  ``contacts``: names of geoms (``"foot"``: the one touching contact of that geom) or pairs
(``"foot/floor"``); ``None`` takes the touching contacts (one or two); a choice orders them.
Every touching contact is analysed: three or more touching contacts, or a touching contact left
out of the choice, is refused in one line naming ``model`` and the contacts (its force would be
in neither ``Q`` nor ``B``).  Zero touching contacts, a geom that touches two things, or a
contact that does not slide (its slip direction is undefined; give ``slip``) is a one-line
``ValueError``.

**Supported models.**  Joints, actuators, passive and applied forces, and contacts.  A constraint
that acts at the state besides the contacts (an active equality constraint, a joint or tendon at
its limit, a joint's or tendon's friction loss) would add a force that neither ``Q`` nor ``B``
holds, so it is refused in one line naming ``model``.

**Contact model (approximate).**  MuJoCo's constraint is not a spring: with impedance ``d``, the
reference acceleration ``-b v - k r`` (``solref = (timeconst, dampratio)``: ``b = 2 / (dmax
timeconst)``, ``k = d / (dmax^2 timeconst^2 dampratio^2)``; ``solref < 0``: ``k = -solref[0] /
dmax^2``, ``b = -solref[1] / dmax``) is reached through ``f = -(d / A)(a0 + b v + k r)`` for a
single constraint with ``A = J_n M^-1 J_n^T``.  The nearest Kelvin-Voigt contact is
``k_j = d k / A_jj`` [N/m], ``c_j = d b / A_jj`` [N s/m] at ``d = solimp[0]`` (zero penetration),
``dmax = solimp[1]``: flagged ``approximate_model``.  Consistency, lift-off and jams (IF, FI, II
consistent) do not depend on it; SS stability and the II verdicts' model dependence do (docs).
"""

from __future__ import annotations

import dataclasses
import math
import os

import numpy as np

from atlas.core.contact_space import ContactSpace, contact_space

__all__ = [
    "INSTALL",
    "MissingExtra",
    "Contact",
    "MujocoContacts",
    "load",
    "touching",
    "contact_data",
    "require",
    "state",
    "collide",
    "relative_jacobian",
    "same_contact",
    "check_tol",
]

#: the one line a user without the extra gets
INSTALL = "pip install 'painleve-atlas[mujoco]'"
#: default touching tolerance [m] on MuJoCo's signed distance
TOUCH_TOL = 1e-6
_FD_STEP = 1e-5  # of the model's extent, per finite-difference step


class MissingExtra(ImportError, ValueError):
    """The ``mujoco`` extra is not installed (a ``ValueError`` too: the CLI prints one line)."""


def require():
    """The ``mujoco`` module, or :class:`MissingExtra` naming the install command."""
    try:
        import mujoco  # noqa: PLC0415  (optional extra)
    except ImportError:
        raise MissingExtra(f"mujoco: the MuJoCo bridge needs the mujoco extra: {INSTALL}") from None
    return mujoco


def load(path):
    """``(MjModel, MjData)`` of an MJCF (or MJB) file; a bad file is a one-line error."""
    mj = require()
    if not os.path.isfile(path):
        raise ValueError(f"model: cannot load {path}: no such file")
    binary = str(path).lower().endswith(".mjb")
    read = mj.MjModel.from_binary_path if binary else mj.MjModel.from_xml_path
    said, before = [], mj.get_mju_user_warning()
    mj.set_mju_user_warning(said.append)  # MuJoCo's own warning joins the one line
    try:
        model = read(str(path))
    except (ValueError, FileNotFoundError) as err:
        msg = " ".join(" ".join([*said, str(err)]).split())
        raise ValueError(f"model: cannot load {path}: {msg}") from None
    finally:
        mj.set_mju_user_warning(before)
    return model, mj.MjData(model)


@dataclasses.dataclass(frozen=True)
class Contact:
    """One MuJoCo contact: geom names and ids, bodies, ``pos`` [m], unit normal ``n`` (geom 1 to
    geom 2), signed distance ``dist`` [m], ``mu``, ``solref``, ``solimp``."""

    geom1: str
    geom2: str
    ids: tuple
    bodies: tuple
    pos: np.ndarray
    n: np.ndarray
    dist: float
    mu: float
    solref: tuple
    solimp: tuple

    @property
    def name(self) -> str:
        return f"{self.geom1}/{self.geom2}"


def _geom_name(mj, model, gid):
    return mj.mj_id2name(model, mj.mjtObj.mjOBJ_GEOM, gid) or f"geom{gid}"


def collide(model, data, qpos, margin):
    """Contacts of ``model`` at ``qpos`` (``data`` is scratch) with every geom margin raised to
    ``margin`` [m] while MuJoCo collides (restored after).  The midphase is off meanwhile: its
    bounding volumes are compiled with the model's margins, and a body's touching geoms lie on
    their boundary (found missing on a ladder at 0.6 rad)."""
    mj = require()
    saved, flags = model.geom_margin.copy(), model.opt.disableflags
    try:
        model.geom_margin[:] = np.maximum(saved, margin)
        model.opt.disableflags = flags | mj.mjtDisableBit.mjDSBL_MIDPHASE
        data.qpos[:] = qpos
        mj.mj_fwdPosition(model, data)
    finally:
        model.geom_margin[:] = saved
        model.opt.disableflags = flags
    out = []
    for c in data.contact[: data.ncon]:
        g1, g2 = int(c.geom1), int(c.geom2)
        out.append(
            Contact(
                _geom_name(mj, model, g1), _geom_name(mj, model, g2), (g1, g2),
                (int(model.geom_bodyid[g1]), int(model.geom_bodyid[g2])), c.pos.copy(),
                c.frame[:3].copy(), float(c.dist), 0.0 if c.dim == 1 else float(c.friction[0]),
                tuple(c.solref),
                tuple(c.solimp),
            )
        )  # fmt: skip
    return out


def touching(model, data, qpos, tol=TOUCH_TOL) -> list:
    """The contacts with MuJoCo's signed distance ``<= tol`` [m] at ``qpos``."""
    return [c for c in collide(model, data, qpos, tol) if c.dist <= tol]


def check_tol(tol) -> None:
    """The touching tolerance ``tol`` [m]: finite and ``>= 0``, else a one-line error."""
    if not (isinstance(tol, (int, float)) and math.isfinite(tol) and tol >= 0):
        raise ValueError(f"tol: must be a finite distance >= 0 m, got {tol!r}")


def _select(found, contacts):
    """The chosen contacts (module docstring), in the order asked; every touching contact must be
    among them (:func:`_refuse_left_out`)."""
    listing = ", ".join(c.name for c in found) or "none"
    if contacts is None:
        if not found:
            raise ValueError("contacts: no two geoms touch at this state (touching: none)")
        _refuse_left_out(found, found[:2])
        return found
    if isinstance(contacts, str):
        contacts = [x.strip() for x in contacts.split(",") if x.strip()]
    if not 1 <= len(contacts) <= 2:
        raise ValueError(f"contacts: give one or two contacts, got {len(contacts)}")
    out = []
    for want in contacts:
        parts = set(want.split("/"))
        hits = [c for c in found if parts <= {c.geom1, c.geom2}]
        if len(hits) != 1:
            what = "does not touch anything" if not hits else f"matches {len(hits)} contacts"
            raise ValueError(f"contacts: {want!r} {what} at this state (touching: {listing})")
        out.append(hits[0])
    if len(out) == 2 and out[0].name == out[1].name:
        raise ValueError(f"contacts: {contacts[0]!r} and {contacts[1]!r} are the same contact")
    _refuse_left_out(found, out)
    return out


def _refuse_left_out(found, chosen) -> None:
    """A one-line ``ValueError`` naming ``model`` where a touching contact is not among the
    ``chosen`` ones: its force would be in neither ``Q`` nor ``B`` (as an active constraint's),
    and the theory covers one or two touching contacts analysed together."""
    left = [c for c in found if all(c is not x for x in chosen)]
    if not left:
        return
    listing = ", ".join(c.name for c in found)
    if len(found) > 2:
        head = f"{len(found)} contacts touch at this state ({listing})"
    else:
        head = f"{', '.join(c.name for c in left)} touches at this state but is not chosen"
    raise ValueError(
        f"model: {head}; the theory covers one or two touching contacts, every touching contact "
        "analysed (a contact left out would add a force that neither Q nor B holds)"
    )


def relative_jacobian(mj, model, data, contact):
    """``J_2 - J_1`` (3, nv): relative velocity of bodies 2 and 1 at ``contact.pos``."""
    out = []
    for body in contact.bodies:
        jac = np.zeros((3, model.nv))
        mj.mj_jac(model, data, jac, None, contact.pos, body)
        out.append(jac)
    return out[1] - out[0]


def same_contact(found, contact):
    """The contact of the same geom pair nearest to ``contact.pos`` in ``found``."""
    same = [c for c in found if c.ids == contact.ids]
    if not same:
        raise ValueError(f"contacts: {contact.name} separates within the finite-difference step")
    return min(same, key=lambda c: float(np.sum((c.pos - contact.pos) ** 2)))


def _drift(mj, model, qpos, qvel, chosen, scratch):
    """``(J_n)' qvel`` per contact by central differences along ``qvel`` (module docstring)."""
    speed = float(np.max(np.abs(qvel))) if qvel.size else 0.0
    if speed == 0.0:
        return np.zeros(len(chosen))
    extent = float(model.stat.extent) or 1.0
    h = _FD_STEP * extent / speed
    margin = 1e-3 * extent
    rates = []
    for sign in (1.0, -1.0):
        q = qpos.copy()
        mj.mj_integratePos(model, q, qvel, sign * h)
        found = collide(model, scratch, q, margin)
        shifted = [same_contact(found, c) for c in chosen]
        rows = [c.n @ relative_jacobian(mj, model, scratch, c) for c in shifted]
        rates.append(np.array([row @ qvel for row in rows]))
    return (rates[0] - rates[1]) / (2 * h)


def _other_constraints(mj) -> dict:
    """MuJoCo's constraint kinds besides contacts: ``{type: (words, object kind of efc_id)}``."""
    C, O = mj.mjtConstraint, mj.mjtObj
    return {
        int(C.mjCNSTR_EQUALITY): ("equality constraint", O.mjOBJ_EQUALITY),
        int(C.mjCNSTR_FRICTION_DOF): ("friction loss of joint", O.mjOBJ_DOF),
        int(C.mjCNSTR_FRICTION_TENDON): ("friction loss of tendon", O.mjOBJ_TENDON),
        int(C.mjCNSTR_LIMIT_JOINT): ("limit of joint", O.mjOBJ_JOINT),
        int(C.mjCNSTR_LIMIT_TENDON): ("limit of tendon", O.mjOBJ_TENDON),
    }


def _refuse_other_constraints(mj, model, data) -> None:
    """A one-line ``ValueError`` naming ``model`` where a constraint other than a contact acts at
    the state (``data`` after ``mj_forward``): its force is in neither ``Q`` nor ``B``."""
    kinds = _other_constraints(mj)
    for kind, i in zip(data.efc_type[: data.nefc], data.efc_id[: data.nefc]):
        if int(kind) not in kinds:
            continue
        words, obj = kinds[int(kind)]
        i = int(model.dof_jntid[i]) if obj == mj.mjtObj.mjOBJ_DOF else int(i)
        obj = mj.mjtObj.mjOBJ_JOINT if obj == mj.mjtObj.mjOBJ_DOF else obj
        name = mj.mj_id2name(model, obj, i) or f"#{i}"
        raise ValueError(
            f"model: the {words} {name!r} acts at this state; the bridge reads the mass matrix, "
            "the smooth forces and the contacts only (not supported: active equality constraints, "
            "joint or tendon limits, friction loss)"
        )


def _full_mass(mj, model, data):
    """Dense ``M`` (nv, nv): ``mj_fullM`` (MuJoCo 4 takes ``data``, 3.x the packed ``qM``)."""
    M = np.zeros((model.nv, model.nv))
    try:
        mj.mj_fullM(model, data, M)
    except TypeError:
        mj.mj_fullM(model, M, data.qM)
    return M


def _contact_model(c, A):
    """Nearest ``(k, c)`` [N/m, N s/m] of MuJoCo's constraint (module docstring)."""
    d0, dmax = c.solimp[0], c.solimp[1]
    if c.solref[0] > 0:
        timeconst, dampratio = c.solref[0], c.solref[1]
        k = d0 / (dmax**2 * timeconst**2 * dampratio**2)
        b = 2.0 / (dmax * timeconst)
    else:
        k, b = -c.solref[0] / dmax**2, -c.solref[1] / dmax
    return d0 * k / A, d0 * b / A


@dataclasses.dataclass(frozen=True)
class MujocoContacts:
    """The bridge's answer: the contact space (``B``, ``a``, approximate ``k``, ``c``), the chosen
    contacts, their unit slip directions ``slip`` [world] and sliding speeds [m/s]."""

    space: ContactSpace
    contacts: tuple
    slip: np.ndarray
    speeds: np.ndarray

    def verdicts(self, dtype="float64", names=None) -> dict:
        return self.space.verdicts(dtype, names)


def contact_data(
    model, data=None, *, contacts=None, qpos=None, qvel=None, slip=None, tol=TOUCH_TOL
) -> MujocoContacts:
    """Contact-space data of a MuJoCo model at a state (module docstring).

    ``data``: a live ``MjData`` whose state is used (``qpos``, ``qvel``, controls, applied forces);
    ``None``: the model's ``qpos0`` and zero velocity.  ``qpos`` (nq,), ``qvel`` (nv,) override it.
    ``contacts``: ``None`` (the one or two touching contacts), or one or two geom names / pairs
    ``"g1/g2"`` (a list or a comma-separated string) naming every touching contact.  ``slip``:
    unit slip directions per contact (world 3-vectors), needed only where a frictional contact
    does not slide.  ``tol`` [m]: touching.
    """
    mj = require()
    check_tol(tol)
    work = state(model, data, qpos, qvel)
    qpos0, qvel0 = work.qpos.copy(), work.qvel.copy()
    chosen = _select(touching(model, work, qpos0, tol), contacts)
    work.qpos[:] = qpos0
    mj.mj_forward(model, work)
    _refuse_other_constraints(mj, model, work)
    M = _full_mass(mj, model, work)
    rel = [relative_jacobian(mj, model, work, c) for c in chosen]
    Jn = np.array([c.n @ J for c, J in zip(chosen, rel)])
    slip, speeds = _slip(chosen, rel, qvel0, slip)
    Jt = np.array([t @ J for t, J in zip(slip, rel)])
    drift = _drift(mj, model, qpos0, qvel0, chosen, mj.MjData(model))
    A = np.einsum("ij,ji->i", Jn, np.linalg.solve(M, Jn.T))
    kc = [_contact_model(c, Aj) for c, Aj in zip(chosen, A)]
    space = contact_space(
        M, Jn, Jt, [c.mu for c in chosen], 1, work.qfrc_smooth.copy(), drift,
        k=[x[0] for x in kc], c=[x[1] for x in kc], names=[c.name for c in chosen],
        approximate_model=True,
    )  # fmt: skip
    return MujocoContacts(space, tuple(chosen), slip, speeds)


def state(model, data=None, qpos=None, qvel=None):
    """A fresh ``MjData`` with the state of ``data`` (positions, velocities, controls, applied
    forces, mocap, time; ``None``: ``qpos0`` at rest) and ``qpos`` / ``qvel`` overriding it."""
    mj = require()
    work = mj.MjData(model)
    if data is not None:
        for key in ("qpos", "qvel", "act", "ctrl", "qfrc_applied", "xfrc_applied", "mocap_pos"):
            getattr(work, key)[:] = getattr(data, key)
        work.mocap_quat[:] = data.mocap_quat
        work.time = data.time
    for key, value, size in (("qpos", qpos, model.nq), ("qvel", qvel, model.nv)):
        if value is not None:
            arr = np.asarray(value, dtype=np.float64).ravel()
            if arr.shape != (size,) or not np.all(np.isfinite(arr)):
                raise ValueError(f"{key}: expected {size} finite numbers, got {arr.size}")
            getattr(work, key)[:] = arr
    return work


def _slip(chosen, rel, qvel, given):
    """Unit slip directions: the tangential relative velocity at each contact, or ``given``."""
    out, speeds = [], []
    for j, (c, J) in enumerate(zip(chosen, rel)):
        v = J @ qvel
        vt = v - (c.n @ v) * c.n
        speed = float(np.linalg.norm(vt))
        speeds.append(speed)
        if c.mu == 0.0 and not speed > 0:
            out.append(np.zeros(3))  # frictionless: the slip direction does not enter B
        elif given is not None and given[j] is not None:
            t = np.asarray(given[j], dtype=np.float64)
            t = t - (c.n @ t) * c.n
            norm = float(np.linalg.norm(t))
            if not norm > 0 or not math.isfinite(norm):
                raise ValueError(f"slip: direction {j + 1} has no component tangent to {c.name}")
            out.append(t / norm)
        elif speed > 1e-12 * max(1.0, float(np.linalg.norm(v))):
            out.append(vt / speed)
        else:
            raise ValueError(
                f"qvel: contact {c.name} does not slide (tangential speed {speed:.3g} m/s): "
                "give a sliding velocity or its slip direction"
            )
    return np.array(out), np.array(speeds)
