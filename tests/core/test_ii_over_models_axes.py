"""II over a box of contact models where a direction lies on an axis (``gamma = c2 s1 = 0``) or
a component is tiny, against the independent sympy/mpmath reference (``tests/reference_sympy.py``:
the characteristic polynomial from its definition, exact root isolation)."""

import numpy as np
from reference_sympy import point_spectral

from atlas.core import ii_over_models as iim
from atlas.core import model_box as mb
from atlas.core.verdicts import OverModels, Verdict

NO, YES, DEP, UND = (int(v) for v in OverModels)
CONS, STAB = iim.SIDES
BOX = mb.model_box(kappa=(0.01, 100.0), q1=(0.0, 1.0), q2=(0.0, 1.0))


def _reference(g, m) -> tuple[int, int]:
    """``(consistent_II, stable_II is STABLE)`` of model ``m`` at geometry ``g`` (reference)."""
    v = point_spectral(*g, *m)
    return int(v["consistent_II"]), int(v["stable_II"] == int(Verdict.STABLE))


def _grid(box: mb.ModelBox, n: int = 5) -> list:
    """``n^3`` models spread over a bounded box (geometric in ``kappa``, linear in ``q``)."""
    k = np.geomspace(*box.kappa, n)
    q1, q2 = (np.linspace(*r, n) for r in (box.q1, box.q2))
    return [(float(a), float(b), float(c)) for a in k for b in q1 for c in q2]


def _witnesses(r, name, i) -> tuple:
    w = [float(r[x][i]) for x in iim.witness_names(name)]
    return tuple(w[:3]), tuple(w[3:])


# b1 = (-1, 0) with b2 in QIV, and b2 = (0, -1) with b1 in QII: gamma = 0, c1 < 0, s2 < 0, and
# the II root, where there is one, lies below a larger root (never stable)
NEVER_STABLE = [
    (-1.0, 0.0, 0.6, -0.8),
    (-1.0, 0.0, 0.28, -0.96),
    (-0.6, 0.8, 0.0, -1.0),
    (-0.96, 0.28, 0.0, -1.0),
]


def test_consistency_is_sampled_where_the_signs_decide_only_the_stability():
    """The signs say "never stable" but leave the consistency open: it depends on the model (the
    reference sees both sides on a grid of the box), with both witnesses on their sides; the
    stability is unstable for every model (the reference never sees a stable II)."""
    r = iim.ii_over_models(*np.array(NEVER_STABLE).T, BOX, settle=False)
    assert r[CONS].tolist() == [DEP] * 4 and r[STAB].tolist() == [NO] * 4
    for i, g in enumerate(NEVER_STABLE):
        got = {_reference(g, m) for m in _grid(BOX)}
        assert got == {(0, 0), (1, 0)}, (g, got)
        yes, no = _witnesses(r, CONS, i)
        assert _reference(g, yes)[0] == 1 and _reference(g, no)[0] == 0, (g, yes, no)
