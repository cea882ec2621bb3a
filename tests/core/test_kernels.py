"""The point-kernel table: declarations are checked when made; every kernel's ``fn`` agrees with
the verdict functions it names (closed forms at axis-free points)."""

import numpy as np
import pytest

from atlas.core import contact_modes, kernels
from atlas.core.verdicts import Verdict


def _fn(c1, s1):
    return {"x": c1 > 0}


@pytest.mark.parametrize(
    "kw, match",
    [
        (dict(params=("beta2", "beta1")), "params: .* out of order"),
        (dict(params=("gamma",)), "params: "),
        (dict(results=()), "results: "),
        (dict(fn=None), "fn: "),
        (dict(true_code={"y": 1}), "true_code: .* unknown results"),
        (dict(undecided={"x": 3}), "settle: .* cannot settle"),
        (dict(batches=(("x",), ("x",))), "batches: "),
        (dict(kind="other"), "kind: "),
    ],
)
def test_a_bad_kernel_fails_when_declared(kw, match):
    args = dict(name="k", params=("beta1",), results=("x",), fn=_fn)
    with pytest.raises(ValueError, match=match):
        kernels.PointKernel(**{**args, **kw})


def test_register_refuses_a_taken_name_or_result():
    with pytest.raises(ValueError, match="name: kernel 'b1' is already registered"):
        kernels.register(kernels.KERNELS["b1"])
    clash = kernels.PointKernel("other", ("beta1",), ("stable_SF",), _fn)
    with pytest.raises(ValueError, match="results: 'stable_SF' is already computed by kernel 'b1'"):
        kernels.register(clash)
    assert "other" not in kernels.KERNELS


def test_kernel_inputs_follow_the_parameters():
    assert kernels.KERNELS["b1b2a"].inputs == ("c1", "s1", "c2", "s2", "ca", "sa")
    assert kernels.KERNELS["spectral"].inputs == ("c1", "s1", "c2", "s2", "kappa", "q1", "q2")


def test_b1_kernel_matches_the_sign_of_b11():
    # beta1 in (pi/2, 3 pi/2) <=> b11 = cos(beta1) < 0: SF unstable (paper Sec. 4.2)
    beta = np.array([0.3, 2.0, 4.0, 5.5])
    c, s = contact_modes.direction(beta)
    res = kernels.run(kernels.KERNELS["b1"], {"c1": c, "s1": s})
    want = np.where(np.cos(beta) > 0, int(Verdict.STABLE), int(Verdict.UNSTABLE))
    np.testing.assert_array_equal(res["stable_SF"], want)
    np.testing.assert_array_equal(res["consistent_IF"], (np.cos(beta) < 0) & (np.sin(beta) > 0))
