"""The paper's claims (Sec. 3-6, Appendix B-C), checked against the computation.

Every claim gets a status -- ``confirmed``, ``refuted`` (with counterexamples) or ``imprecise`` (with
the corrected statement) -- and the evidence behind it.  The verdicts come from the certified fast
kernels (:func:`atlas.paper.figures.evaluate_points`; undecided points settled exactly); every
counterexample is re-verified point by point by the high-precision reference
:func:`atlas.core.exact.point_spectral` (its eigenvalues are printed), see :func:`verify_counterexample`.

Layout: :mod:`.records` (Claim, Counterexample), :mod:`.verify` (exact re-verification),
:mod:`.samples` and :mod:`.context` (the shared samples, each computed once, on first use),
:mod:`.registry` (:data:`CLAIMS`, :func:`run_audit`), the claims by section (:mod:`.classes`,
:mod:`.stability`, :mod:`.appendix_c`, :mod:`.table2_shading`, :mod:`.consistency`,
:mod:`.examples`, :mod:`.coverage`; imported in report order) and :mod:`.report` (Markdown).
"""

from atlas.paper.audit.context import Context as Context
from atlas.paper.audit.context import Sizes as Sizes
from atlas.paper.audit.printed import PAPER_TABLE2 as PAPER_TABLE2
from atlas.paper.audit.records import Claim as Claim
from atlas.paper.audit.records import Counterexample as Counterexample
from atlas.paper.audit.records import Finding as Finding
from atlas.paper.audit.registry import CLAIMS as CLAIMS
from atlas.paper.audit.registry import claim as claim
from atlas.paper.audit.registry import run_audit as run_audit
from atlas.paper.audit.report import to_markdown as to_markdown
from atlas.paper.audit.report import write_audit as write_audit
from atlas.paper.audit.verify import mode_2x2_exact as mode_2x2_exact
from atlas.paper.audit.verify import verify_counterexample as verify_counterexample

# the claims register themselves on import, in this (report) order
# isort: off
from atlas.paper.audit import classes as classes
from atlas.paper.audit import stability as stability
from atlas.paper.audit import appendix_c as appendix_c
from atlas.paper.audit import table2_shading as table2_shading
from atlas.paper.audit import consistency as consistency
from atlas.paper.audit import examples as examples
from atlas.paper.audit import coverage as coverage
# isort: on

__all__ = [
    "CLAIMS",
    "Claim",
    "Context",
    "Counterexample",
    "Finding",
    "PAPER_TABLE2",
    "Sizes",
    "claim",
    "mode_2x2_exact",
    "run_audit",
    "to_markdown",
    "verify_counterexample",
    "write_audit",
]
