"""Body inputs (:mod:`atlas.core.body_checks`): a contact normal is normalised as accurately when
its components are subnormal as when they are not (mpmath reference on the exact float values)."""

from fractions import Fraction

import mpmath
import numpy as np
import pytest

from atlas.core import body_checks
from atlas.core.rigid_body import Mechanism

TINY = [(1e-320, 1e-320), (5e-324, 1.5e-323), (3e-323, -1e-323), (-1e-310, 2e-310), (0.0, -1e-318)]


def _reference(x, y):
    """``(x, y) / |(x, y)|`` at 50 digits from the exact float values."""
    with mpmath.workdps(50):
        fx, fy = (Fraction(v) for v in (x, y))
        mx, my = (mpmath.mpf(f.numerator) / f.denominator for f in (fx, fy))
        norm = mpmath.sqrt(mx * mx + my * my)
        return mx / norm, my / norm


@pytest.mark.parametrize("v", TINY + [(0.6, -0.8), (3.0, 4.0), (1e300, 1e300)])
def test_a_normal_is_normalised_to_the_last_bit(v):
    """Each component within one float step of the reference (before: ``(1e-320, 1e-320)``
    came out of length 1.00013)."""
    got = body_checks.unit("n1", v)
    for g, r in zip(got, _reference(*v)):
        assert abs(mpmath.mpf(g) - r) <= np.spacing(abs(float(r)))
    arr = body_checks.unit("n1", tuple(np.array([c, 0.5]) for c in v))  # element by element
    assert (arr[0][0], arr[1][0]) == got


def test_a_subnormal_normal_gives_the_body_of_its_direction():
    """A body with the normal ``(1e-320, 1e-320)`` has the ``B`` of the normal ``(1, 1)`` (to a
    few float steps; before: 1e-4 off)."""
    base = dict(m=1.0, I=0.1, r1=(-0.5, 0.0), r2=(0.5, 0.0), n1=(1.0, 1.0), n2=(0.0, 1.0))
    want = Mechanism(**base).B
    got = Mechanism(**base | dict(n1=(1e-320, 1e-320))).B
    np.testing.assert_allclose(got, want, rtol=1e-14, atol=0)


def test_a_zero_normal_is_refused():
    with pytest.raises(ValueError, match=r"^n2: normal has zero length$"):
        body_checks.unit("n2", (0.0, -0.0))
