"""Layer 1, the mathematics: numpy/JAX only, no I/O, no xarray.

* :mod:`~atlas.core.verdicts`  the verdict and class codes (SPEC §2) and their CF flag attributes;
* :mod:`~atlas.core.signs`     certified signs of polynomials in float arithmetic (error models);
* :mod:`~atlas.core.contact_modes` B, its invariants, the class code and the consistency of FF, SF, FS;
* :mod:`~atlas.core.rigid_body` a rigid body with two sliding contacts -> B, a, invariants, verdicts;
* :mod:`~atlas.core.invariants` the typed point ``Invariants(c1, s1, c2, s2, kappa, q1, q2)``;
* :mod:`~atlas.core.expressions` every polynomial and exact scaling of the spectral problem, once;
* :mod:`~atlas.core.hurwitz`   the certified SS verdict (Hurwitz signs);
* :mod:`~atlas.core.undamped`  the closed-form II verdicts at ``Q = 0``;
* :mod:`~atlas.core.enclosures` the II verdicts from certified root enclosures;
* :mod:`~atlas.core.baseline`  the uncertified ``eig`` baseline (comparisons only);
* :mod:`~atlas.core.spectral`  all spectral verdicts of M, assembled from these parts;
* :mod:`~atlas.core.rootfree`  the root-free damped II verdicts (tiers 1 and 2);
* :mod:`~atlas.core.exact`     the exact integer/rational tier that settles every remaining point;
* :mod:`~atlas.core.points`    the tier driver: verdicts of arbitrary point sets, certified;
* :mod:`~atlas.core.hardcases` the hard-case suites (near-boundary points with 50-digit references);
* :mod:`~atlas.core.checks`    the one validator of the Python API's arguments;
* :mod:`~atlas.core.interrupts` whether a stop signal arrived (writers check it before committing).
"""
