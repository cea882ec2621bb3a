"""MJCF versions of planar Mechanism bodies (tests only; written from the body's geometry, not by
the code under test).

The body moves in MuJoCo's x-z plane (planar ``(x, y)`` -> ``(x, 0, y)``, gravity ``-z``), its
centre of mass at the origin, turning about ``-y`` (so a positive angle turns ``x`` towards ``z``,
as in the plane).  Contact ``j`` has its contact point exactly at ``r_j``: a ``body_vertex`` is a
body sphere of radius ``rho`` centred at ``r_j + rho n_j`` on a world plane through ``r_j`` with
normal ``n_j``; a ``body_side`` is a world sphere (the rounded edge, radius ``rho``) centred at
``r_j - rho n_j`` under a body capsule (radius ``rod``) whose axis runs along ``t_j`` through
``r_j + rod n_j``.  The geoms of contact ``j`` collide only with each other (contype bit ``j``).
A rounded vertex rolls: the gap's second derivative gains ``-rho omega^2``, so MuJoCo's
``a_j = a_j(point vertex) + rho omega^2`` (``d = n.c - rho`` against ``n.q - rho cos(phi)``).
"""

from __future__ import annotations


def _v(p):
    return f"{p[0]!r} 0 {p[1]!r}"


def mjcf(body, *, rho=0.01, rod=0.02, free=False):
    """The MJCF text of ``body`` (an :class:`atlas.Mechanism`) and its ``qvel`` at the state."""
    world, parts = [], []
    for j, (r, n, mu, kind) in enumerate(
        ((body.r1, body.n1, body.mu1, body.kind1), (body.r2, body.n2, body.mu2, body.kind2))
    ):
        bits = f'contype="{1 << j}" conaffinity="{1 << j}" friction="{mu!r} 0 0"'
        name = f"c{j + 1}"
        if kind == "body_vertex":
            world.append(
                f'<geom name="surf{j + 1}" type="plane" pos="{_v(r)}" '
                f'zaxis="{_v(n)}" size="0 0 1" {bits}/>'
            )
            centre = (r[0] + rho * n[0], r[1] + rho * n[1])
            parts.append(
                f'<geom name="{name}" type="sphere" size="{rho!r}" pos="{_v(centre)}" {bits}/>'
            )
        else:
            centre = (r[0] - rho * n[0], r[1] - rho * n[1])
            world.append(
                f'<geom name="edge{j + 1}" type="sphere" size="{rho!r}" pos="{_v(centre)}" {bits}/>'
            )
            t = (n[1], -n[0])
            axis = (r[0] + rod * n[0], r[1] + rod * n[1])
            a = (axis[0] - 0.3 * t[0], axis[1] - 0.3 * t[1])
            b = (axis[0] + 0.3 * t[0], axis[1] + 0.3 * t[1])
            parts.append(
                f'<geom name="{name}" type="capsule" size="{rod!r}" '
                f'fromto="{_v(a)} {_v(b)}" {bits}/>'
            )
    vx, vy, w = body.twist
    if free:
        joints = '<freejoint name="free"/>'
        qvel = [vx, 0.0, vy, 0.0, -w, 0.0]
    else:
        joints = (
            '<joint name="x" type="slide" axis="1 0 0"/>'
            '<joint name="z" type="slide" axis="0 0 1"/>'
            '<joint name="phi" type="hinge" axis="0 -1 0"/>'
        )
        qvel = [vx, vy, w]
    g = body.g
    text = f"""<mujoco>
  <option gravity="{g[0]!r} 0 {g[1]!r}"/>
  <worldbody>
    {" ".join(world)}
    <body name="body" pos="0 0 0">
      {joints}
      <inertial pos="0 0 0" mass="{body.m!r}" diaginertia="{body.I!r} {body.I!r} {body.I!r}"/>
      {" ".join(parts)}
    </body>
  </worldbody>
</mujoco>"""
    return text, qvel
