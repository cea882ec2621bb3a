"""The samples the claims share, each computed once, on first use (:class:`Context`).

A claim asks the context for what it needs (``ctx.q0``, ``ctx.rows``, ...); running one claim alone
computes only those samples.  The sizes come from :class:`Sizes` (full, ``quick``, ``ci``).
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from functools import cached_property

from atlas.core import contact_modes
from atlas.paper import figure_models, realisability
from atlas.paper.audit import samples
from atlas.paper.audit.samples import Points
from atlas.paper.tables import KAPPA_Q_SAMPLE, class_samples, table2

#: the ``kappa`` ladder of the class samples at ``Q = 0``
KAPPAS_Q0 = (1e-3, 0.1, 0.5, 1.0, 2.0, 10.0, 1e3)
#: damped ``(kappa, q1, q2)`` added to :data:`KAPPA_Q_SAMPLE` (unequal damping, Fig. 2's q)
EXTRA_DAMPED = [
    (0.5, 2**0.5, 2**0.5),
    (0.5, 1e-3, 1.0),
    (0.5, 1.0, 1e-3),
    (1e3, 1e-2, 10.0),
    (1e-3, 10.0, 1e-2),
]


@dataclass(frozen=True)
class Sizes:
    """Sample sizes: class-sample points per class, random points, exact matrix-(7) points, blocks of
    720 alphas and exact re-checks for Sec. 6.2, stride over the damped ``(kappa, q1, q2)``."""

    per_class: int
    n_random: int
    n_matrix7: int
    alpha_blocks: int
    n_exact62: int
    damped_stride: int

    @classmethod
    def of(cls, quick: bool = False, ci: bool = False) -> Sizes:
        """Full audit; ``quick``; ``ci`` (the smallest size that still runs every check)."""
        if ci:
            return cls(4, 1 << 12, 500, 1, 100, 4)
        if quick:
            return cls(8, 1 << 14, 2000, 2, 300, 1)
        return cls(24, 1 << 16, 8000, 8, 1000, 1)


class Context:
    """The shared, lazily computed samples of one audit run.

    ``rows``: Table 2 rows already computed (:func:`atlas.paper.tables.table2`), else computed here;
    ``progress``: a callable taking a message; ``sizes`` overrides the sizes of ``quick``/``ci``.
    """

    def __init__(self, quick=False, ci=False, progress=None, rows=None, sizes: Sizes | None = None):
        self.quick = quick or ci
        self.ci = ci
        self.sizes = sizes or Sizes.of(self.quick, ci)
        self.say = progress or (lambda msg: None)
        self._rows = rows
        self.t0 = time.perf_counter()

    def elapsed(self) -> float:
        """Seconds since the context was made."""
        return time.perf_counter() - self.t0

    def computed(self) -> set:
        """Names of the samples computed so far."""
        lazy = {k for k, v in vars(type(self)).items() if isinstance(v, cached_property)}
        return lazy & set(vars(self))

    # ---- evaluated points ---------------------------------------------------------------------

    @cached_property
    def realisations(self) -> realisability.Search:
        """:func:`atlas.paper.realisability.search` (2^19 random bodies, mu <= 2) and its stats."""
        self.say("searching single rigid bodies for the 144 subclasses")
        return realisability.search(1 << 19)

    @cached_property
    def models_map(self):
        """SS over the whole model space on the Fig. 1 plane at this run's size
        (:func:`atlas.paper.figure_models.model_dependence_map`): the map of ``fig1_models.png``,
        which ``atlas paper`` draws from here."""
        return figure_models.model_dependence_map(figure_models.N_MODELS[self.ci + self.quick])

    @cached_property
    def class_points(self) -> dict:
        """Class-interior ``(beta1, beta2)`` samples, ``{class: (n, 2)}`` [rad]."""
        return class_samples(96, self.sizes.per_class)

    @cached_property
    def q0(self) -> Points:
        """Class samples x :data:`KAPPAS_Q0` at ``Q = 0``."""
        self.say("evaluating class samples at Q = 0")
        return samples.class_grid(self.class_points, [(k, 0.0, 0.0) for k in KAPPAS_Q0])

    @cached_property
    def damped(self) -> Points:
        """Class samples x the damped ``(kappa, q1, q2)`` of Table 2 (every ``damped_stride``-th)
        and :data:`EXTRA_DAMPED`."""
        self.say("evaluating class samples over the damped kappa-q sample")
        kq = [t for t in KAPPA_Q_SAMPLE if t[1] or t[2]][:: self.sizes.damped_stride]
        return samples.class_grid(self.class_points, kq + EXTRA_DAMPED)

    @cached_property
    def q0_half(self) -> Points:
        """Four times denser class samples at ``kappa = 0.5``, ``Q = 0`` (Fig. 1's parameters)."""
        return samples.class_grid(class_samples(96, 4 * self.sizes.per_class), [(0.5, 0.0, 0.0)])

    @cached_property
    def random(self) -> Points:
        """Seeded random points (:func:`samples.random_points`)."""
        self.say(f"random search, {self.sizes.n_random} points")
        return samples.random_points(self.sizes.n_random)

    @cached_property
    def random_damped(self):
        """Mask of the damped random points (``q1 > 0`` or ``q2 > 0``)."""
        return (self.random.q1 > 0) | (self.random.q2 > 0)

    @cached_property
    def rows(self) -> dict:
        """Table 2 rows by class (never below 8 points per class: at 4 the II model-dependence of
        15/32 is missed)."""
        if self._rows is None:
            self.say("Table 2")
            self._rows = table2(n=96, per_class=max(self.sizes.per_class, 8))
        return {r.cls: r for r in self._rows}

    # ---- exact and closed-form sets -------------------------------------------------------------

    @cached_property
    def table1_points(self) -> samples.Table1Points:
        return samples.table1_points()

    @cached_property
    def matrix7(self) -> samples.Matrix7Sample:
        self.say("Appendix B: matrix (7), exact")
        return samples.matrix7_sample(self.sizes.n_matrix7)

    @cached_property
    def neg_bk(self) -> samples.NegBK:
        return samples.neg_bk(self.random, ~self.random_damped)

    # ---- verdicts per class: {class: set of verdict codes} --------------------------------------

    @cached_property
    def ss_q0(self) -> dict:
        return self.q0.by_class(self.q0.v["stable_SS"])

    @cached_property
    def ss_damped(self) -> dict:
        return self.damped.by_class(self.damped.v["stable_SS"])

    @cached_property
    def ss_random(self) -> dict:
        return self.random.by_class(self.random.v["stable_SS"], where=self.random_damped)

    @cached_property
    def ss_word_q0(self) -> dict:
        """SS stability word per class at ``Q = 0``."""
        return {c: samples.ss_word(v) for c, v in self.ss_q0.items()}

    @cached_property
    def ss_word_all(self) -> dict:
        """SS stability word per class over every search (``Q = 0``, damped, random damped)."""
        return {
            c: samples.ss_word(self.ss_q0[c] | self.ss_damped[c] | self.ss_random[c])
            for c in contact_modes.ALL_CLASSES
        }

    @cached_property
    def ii_consistent_q0(self) -> dict:
        return self.q0.by_class(self.q0.v["consistent_II"])

    @cached_property
    def ii_stable_q0(self) -> dict:
        return self.q0.by_class(self.q0.v["stable_II"])

    @cached_property
    def ii_stable_q0_consistent(self) -> dict:
        """II stability where II is consistent, class samples at ``Q = 0``."""
        v = self.q0.v
        return self.q0.by_class(v["stable_II"], where=v["consistent_II"] == 1)

    @cached_property
    def ii_consistent_damped(self) -> dict:
        return self.damped.by_class(self.damped.v["consistent_II"])

    @cached_property
    def ii_consistent_random(self) -> dict:
        return self.random.by_class(self.random.v["consistent_II"], where=self.random_damped)

    @cached_property
    def ii_stable_damped(self) -> dict:
        """II stability where II is consistent, damped class samples."""
        v = self.damped.v
        return self.damped.by_class(v["stable_II"], where=v["consistent_II"] == 1)

    @cached_property
    def ii_stable_random(self) -> dict:
        """II stability where II is consistent, damped random points."""
        v = self.random.v
        return self.random.by_class(
            v["stable_II"], where=self.random_damped & (v["consistent_II"] == 1)
        )

    def ii_consistent_any(self, c) -> set:
        """II consistency values of class ``c`` over every search."""
        return (
            self.ii_consistent_q0[c] | self.ii_consistent_damped[c] | self.ii_consistent_random[c]
        )
