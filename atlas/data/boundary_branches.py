"""A multiple or shared root on a class line decided from the branches of the boundaries through it.

Near a root ``r`` (``t_r = tan(r / 2)``) of line ``m`` where some boundary polynomials' germs
``G_i(t, e)`` vanish (:mod:`atlas.data.boundary_germs`: ``t`` along the line, ``e = tan(delta /
2)`` off it) take the box ``T x E``, ``T = [tan((r - h) / 2), tan((r + h) / 2)]`` (no other
break of the line in it) and ``E = [-e_max, e_max]``.  If in ball arithmetic (256 bits)

* every germ that does not vanish at ``r`` is dominated by its ``e^0`` row over the box
  (:func:`atlas.data.boundary_germs.clear`: no zero in the box), and
* every germ ``G_i`` that vanishes at ``r`` has ``dG_i / de`` bounded away from 0 over the box
  (its ``e^1`` row dominates the rest of the derivative),

then for each ``t`` in ``T`` each ``G_i(t, .)`` is strictly monotone on ``E``: its zero set in the
box is one graph ``e = phi_i(t)``, through ``(t_r, 0)`` (implicit function theorem), on the side
``-sign(g_0(t)) sign(dG_i / de)`` left and right of ``t_r``, and the vertical ``t = t_r, e != 0``
meets no zero.  When no two graphs enter the same quadrant (left or right of ``t_r``, ``e < 0``
or ``> 0``), the codes arbitrarily close to ``r`` on one side of the line are exactly: the codes
next to the line left and right of ``r`` (the two neighbouring intervals,
:func:`atlas.data.boundary_germs.near_side_codes`) and, where a graph enters that side, the code
on the vertical, sampled exactly at ``(t_q, +-e_max)`` with ``t_q`` the 256-bit middle of ``t_r``
(no zero between it and the vertical: the germs' balls over the segment exclude 0).  One code per
side: no boundary point (``not_boundary``); two: a boundary point at ``r`` (``point``), a
tangency (``touches_class_line``) where the codes next to the line agree on both sides.
Otherwise (a germ with ``dG / de = 0`` at ``r``, two graphs in a quadrant) the root is not
decided here.
"""

from __future__ import annotations

import math
from fractions import Fraction

import flint

from atlas.data import boundary_germs, root_frames

__all__ = ["REASONS", "decide"]

#: why a root is left undecided (the key is stored with its ``undecided_line_root`` point)
REASONS = {
    "no_box": "no box around the root where the other boundary polynomials are proven zero-free"
    " and each vanishing one a graph over the line (roots too close to separate at the box sizes"
    " tried, or dG/de = 0 at the root)",
    "vertical": "the codes on the vertical through the root are not proven",
    "unequal_multiplicities": "two graphs enter one quarter and meet the line with different"
    " multiplicities: the chart e = lam f^k needs them equal",
    "chart_factor": "no irreducible factor of g_0 proven to vanish at the root",
    "chart_unseparated": "two graphs enter one quarter with limits lam not proven apart",
    "chart_curve": "a curve e = lam f^k of the chart is not proven clear of the graphs",
}

#: the exponents ``k`` of ``e_max = 2^-k`` tried (largest box first)
E_EXPONENTS = (8, 12, 16, 20, 26, 32, 43, 60, 80, 110, 140)
#: the fractions of the root's half-interval ``h`` tried for the box along the line
H_FRACTIONS = (1.0, 1 / 8, 1 / 64, 1 / 512)


def _rows(germ):
    return [flint.arb_poly(list(r.coeffs())) for r in germ]


#: bits of the balls in which :func:`_clear_curve` Taylor-shifts its polynomials first (ten
#: times faster than in exact rationals; where that leaves the range's ball around 0, exactly)
SHIFT_PREC = 512


def _shifted(germ, t_mid):
    """The rows of ``germ`` as polynomials in ``x = t - t_mid`` (exact Taylor shift, then
    balls): over a small ``x`` ball Horner's scheme then bounds the true range closely."""
    shift = flint.fmpq_poly([t_mid, 1])
    return [flint.arb_poly(list(r(shift).coeffs())) if not r.is_zero() else flint.arb_poly([])
            for r in germ]  # fmt: skip


def _monotone(rows, x, e_max) -> int:
    """The sign of ``dG / de`` over ``x x [-e_max, e_max]`` (``rows``: ``G``'s rows
    :func:`_shifted`, ``x`` the ball of ``t - t_mid``), or 0 where its ball is not proven away
    from 0."""
    if len(rows) < 2:
        return 0
    lead = rows[1](x)
    rest = sum(
        (b * abs(p(x)) * e_max ** (b - 1) for b, p in enumerate(rows) if b >= 2),
        flint.arb(0),
    )
    if abs(lead).lower() > rest.upper():
        return 1 if lead > 0 else -1
    return 0


def _quiet(rows, x, e_max) -> bool:
    """Whether ``G`` has no zero over ``x x [-e_max, e_max]`` (rows :func:`_shifted`; its
    ``e^0`` row dominates)."""
    rest = sum((abs(p(x)) * e_max**b for b, p in enumerate(rows) if b), flint.arb(0))
    return abs(rows[0](x)).lower() > rest.upper()


def _sign(p, t: flint.fmpq) -> int:
    """The sign of the rational polynomial ``p`` at the rational ``t``, exactly."""
    return _sgn(p(t))


def _graphs(germs, t_root, t_ends, e_max):
    """Per germ vanishing at ``t_root``, its rows and the quadrants ``(j, side)`` its zero set
    enters (``j``: 0 left of ``t_root``, 1 right; ``side``: the sign of ``e``), for the box
    ``t_ends`` (rationals) x ``[-e_max, e_max]`` (module docstring; a germ even in ``e`` as a
    polynomial in ``e^2``: a graph ``e^2 = psi(t)`` enters both sides where ``psi > 0``, none
    where ``< 0``); ``None`` where a condition is not proven."""
    t_mid = (t_ends[0] + t_ends[1]) / 2
    x = flint.arb(0).union(flint.arb(t_ends[1] - t_mid)).union(flint.arb(t_ends[0] - t_mid))
    out = []
    for germ in germs:
        rows = _shifted(germ, t_mid)
        if not flint.arb_poly(list(germ[0].coeffs()))(t_root).contains(0):
            if not _quiet(rows, x, e_max):
                return None
            continue
        even = len(rows) > 2 and all(germ[b].is_zero() for b in range(1, len(rows), 2))
        var, box = (rows[::2], e_max * e_max) if even else (rows, e_max)
        slope = _monotone(var, x, box)
        signs = [-_sign(germ[0], t) * slope for t in t_ends]
        if 0 in signs:
            return None
        sides = [((-1, 1) if s > 0 else ()) if even else (s,) for s in signs]
        out.append((_rows(germ), [(j, s) for j in (0, 1) for s in sides[j]], germ))
    return out


def _vertical_codes(fld, model, m, rows_list, t_root, e_max, k) -> dict | None:
    """The exact codes on the vertical ``t = t_root`` on both sides (``{-1: code, 1: code}``),
    sampled at ``(t_q, +-2^-k)``, ``t_q`` the middle of ``t_root``: ``None`` where a germ's ball
    over the segment from the vertical to the sample is not proven away from 0."""
    q = _q(t_root)
    t_q = Fraction(int(q.p), int(q.q))  # exactly the ball's middle
    seg = t_root.union(flint.arb(q))
    for rows in rows_list:
        for s in (-1, 1):
            g = sum((p(seg) * (s * e_max) ** b for b, p in enumerate(rows)), flint.arb(0))
            if g.contains(0):
                return None
    codes = boundary_germs.exact_codes(fld, model, m, t_q, k)
    return {-1: codes[0], 1: codes[1]}


def decide(fld, model, m, fr, near) -> tuple[str | None, str | None]:
    """The verdict at the root of line ``m`` in the frame ``fr``
    (:class:`atlas.data.root_frames.Frame`), from the branches through it (module docstring):
    ``"not_boundary"``, ``"point"`` (a code changes next to it on a side),
    ``"touches_class_line"`` (a point where the codes next to the line agree left and right),
    or ``None`` (not decided); and, for ``None``, the reason (a key of :data:`REASONS`).  The
    box reaches ``beta +- h frac`` along the line (rational ends,
    :func:`atlas.data.root_frames.sample`); ``near``: the codes next to the line at ``beta -+
    h`` (each ``(code at -e, code at +e, ...)``,
    :func:`atlas.data.boundary_germs.near_side_codes`)."""
    model = tuple(float(v) for v in model)
    germs = boundary_germs.germs(fld, m, model)
    h = fr.h
    with flint.ctx.workprec(256):
        t_root = (fr.beta / 2).tan()
        t_root = t_root if fr.exact else _refined(germs, t_root)
        for frac in H_FRACTIONS:
            ends = [_fmpq(root_frames.sample(fr, s * h * frac)) for s in (-1, 1)]
            for k in E_EXPONENTS:
                if 2 * math.atan(2.0**-k) > h * frac:  # no other class line in the box
                    continue
                e_max = flint.arb(2) ** -k
                graphs = _graphs(germs, t_root, ends, e_max)
                if graphs is None:
                    continue
                return _verdict(fld, model, m, graphs, t_root, e_max, k, near, ends)
    return None, "no_box"


def _refined(germs, t_ball, steps: int = 160) -> flint.arb:
    """``t_ball`` shrunk by bisection on the squarefree part of the first germ's ``g_0`` whose
    exact signs at the ball's ends differ (a root there: its only one, isolated by
    :func:`atlas.data.boundary_points.real_roots`; a ``g_0`` whose ball merely contains 0 at
    ``t_ball`` may have its root just outside): 2^-160 of its width."""
    lo, hi = _q(t_ball.lower()), _q(t_ball.upper())
    parts = (g[0] / g[0].gcd(g[0].derivative()) for g in germs if not g[0].is_zero())
    p = next((p for p in parts if _sgn(p(lo)) * _sgn(p(hi)) < 0), None)
    if p is None:
        return t_ball
    s_lo = _sgn(p(lo))
    for _ in range(steps):
        mid = (lo + hi) / 2
        s_mid = _sgn(p(mid))
        if s_mid == 0:
            return flint.arb(mid)
        lo, hi, s_lo = (mid, hi, s_lo) if s_mid == s_lo else (lo, mid, s_lo)
    return flint.arb(lo).union(flint.arb(hi))


def _sgn(x: flint.fmpq) -> int:
    return (x > 0) - (x < 0)


def _q(a: flint.arb) -> flint.fmpq:
    """The exact middle of the ball ``a``."""
    man, exp = (int(v) for v in a.mid().man_exp())
    return flint.fmpq(man * 2**exp) if exp >= 0 else flint.fmpq(man, 2**-exp)


def _fmpq(x) -> flint.fmpq:
    """The float or ``Fraction`` ``x`` exactly."""
    return flint.fmpq(*Fraction(x).as_integer_ratio())


def _verdict(fld, model, m, graphs, t_root, e_max, k, near, ends):
    """:func:`decide` once the box is proven (:func:`_graphs`)."""
    quadrants = [q for _, entered, _ in graphs for q in entered]
    entered = {s for _, s in quadrants}
    sampled = {-1: set(), 1: set()}
    if len(set(quadrants)) < len(quadrants):  # a sector between two graphs: the chart
        sampled = _chart_codes(fld, model, m, [g for _, _, g in graphs], t_root, ends, e_max)
        if isinstance(sampled, str):
            return None, sampled
    elif entered:
        vertical = _vertical_codes(fld, model, m, [r for r, _, _ in graphs], t_root, e_max, k)
        if vertical is None:
            return None, "vertical"
        sampled = {s: {vertical[s]} if s in entered else set() for s in (-1, 1)}
    sides = {s: {near[0][i], near[1][i]} | sampled[s] for s, i in ((-1, 0), (1, 1))}
    if all(len(c) == 1 for c in sides.values()):
        return "not_boundary", None
    if all(near[0][i] == near[1][i] for i in (0, 1)):
        return "touches_class_line", None
    return "point", None


def _chart(germs, t_root):
    """The minimal polynomial ``f`` of ``t_root`` (an irreducible factor of the first germ's
    ``g_0``), the common multiplicity ``k`` of ``t_root`` in every ``g_0``, and per germ the rows
    of ``H(t, lam) = G(t, lam f^k) / f^k`` (exact: ``h_0 = g_0 / f^k``, ``h_b = g_b f^(k (b -
    1))``); else why not (``"chart_factor"``: no factor proven to vanish there,
    ``"unequal_multiplicities"``)."""
    with flint.ctx.workprec(256):
        f = next((p for p, _ in germs[0][0].factor()[1]
                  if flint.arb_poly(list(p.coeffs()))(t_root).contains(0)), None)  # fmt: skip
    if f is None:
        return "chart_factor"
    charts, ks = [], set()
    for germ in germs:
        k = 0
        while (germ[0] % f ** (k + 1)).is_zero():
            k += 1
        ks.add(k)
        rows = [germ[0] / f**k] + [g * f ** (k * (b - 1)) for b, g in enumerate(germ) if b]
        charts.append(rows)
    return (f, ks.pop(), charts) if len(ks) == 1 else "unequal_multiplicities"


def _chart_codes(fld, model, m, germs, t_root, ends, e_max) -> dict | str:
    """The exact codes of the sectors around ``t_root`` where two graphs enter one quadrant
    (module docstring), per side of the line (``{-1: codes, 1: codes}``), or why not (a key of
    :data:`REASONS`).

    In the chart ``e = lam f(t)^k`` (:func:`_chart`) each graph ``phi_i`` tends to ``lam_i =
    -h_0 / h_1`` at ``t_root``.  For ``lam`` in each gap between ``0`` and the ``lam_i`` (and
    beyond the outermost), the curve ``e = lam f(t)^k`` from ``t_s`` to ``t_root`` meets no
    graph (every ``H_i(., lam)`` proven away from 0 over it) and stays in the box (``|e| <=
    e_max``): it lies in one sector, the one between those ``lam_i`` next to ``t_root``; the
    code at ``(t_s, lam f(t_s)^k)`` is that sector's, on each half of the box."""
    got = _chart(germs, t_root)
    if isinstance(got, str):
        return got
    f, k, charts = got
    with flint.ctx.workprec(256):
        lams = []
        for rows in charts:
            h0, h1 = (flint.arb_poly(list(r.coeffs()))(t_root) for r in rows[:2])
            if h1.contains(0):
                return "chart_unseparated"
            lams.append(-h0 / h1)
        if any(a.overlaps(b) for i, a in enumerate(lams) for b in lams[i + 1 :]):
            return "chart_unseparated"
        marks = sorted([0.0] + [float(v.mid()) for v in lams])
        big = 2 * max(abs(v) for v in marks)
        gaps = [0.5 * (a + b) for a, b in zip(marks, marks[1:])] + [-big, big]
        t_q = _q(t_root)
        codes = {-1: set(), 1: set()}
        for end in ends:
            for lam in (_fmpq(g) for g in gaps if g != 0):
                t_s = _inside(f, k, lam, t_q, end, e_max)
                if t_s is None or not _clear_curve(charts, t_q, t_s, t_root, lam):
                    return "chart_curve"
                e_s = lam * f(t_s) ** k
                side = 1 if e_s > 0 else -1
                t, e = (Fraction(int(v.p), int(v.q)) for v in (t_s, e_s))
                codes[side].add(boundary_germs.exact_codes_at(fld, model, m, t, e))
    return codes


def _inside(f, k, lam, t_q, end, e_max):
    """A rational ``t_s`` between ``t_q`` and ``end`` where ``|lam f^k| <= e_max`` over
    ``[t_s, t_q]`` (halving the way towards ``t_q``), or ``None``."""
    t_s = end
    for _ in range(200):
        box = flint.arb(t_s).union(flint.arb(t_q))
        if (abs(flint.arb(lam) * flint.arb_poly(list(f.coeffs()))(box) ** k)).upper() <= e_max:
            return t_s
        t_s = (t_s + t_q) / 2
    return None


def _clear_curve(charts, t_q, t_s, t_root, lam) -> bool:
    """Whether every ``H_i(t, lam)`` is proven away from 0 for ``t`` between ``t_s`` and the
    root (Taylor-shifted about the middle in :data:`SHIFT_PREC`-bit balls, or exactly,
    :func:`_shifted`, where those leave 0 in the range; ``t_q`` the root's exact middle)."""
    mid = (t_s + t_q) / 2
    x = flint.arb(t_s).union(t_root) - flint.arb(mid)
    for rows in charts:
        h = flint.fmpq_poly([0])
        for b, r in enumerate(rows):
            h += r * lam**b
        with flint.ctx.workprec(SHIFT_PREC):
            shifted = flint.arb_poly(list(h.coeffs()))(flint.arb_poly([flint.arb(mid), 1]))
        if shifted(x).contains(0) and _shifted([h], mid)[0](x).contains(0):
            return False
    return True
