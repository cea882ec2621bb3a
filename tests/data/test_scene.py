"""Scenes: range syntax, physical -> invariant parameters, built-ins, validation (SPEC §1-2)."""

import math

import numpy as np
import pytest

from atlas.data.outputs import default_outputs
from atlas.data.scene import Scene, builtin, invariants, parse_values


def test_linear_range_inclusive():
    vals, is_dim = parse_values("0:1:5", "q")
    assert is_dim
    np.testing.assert_array_equal(vals, [0, 0.25, 0.5, 0.75, 1.0])


def test_full_turn_excludes_endpoint():
    vals, _ = parse_values("0:2pi:4", "beta1")
    np.testing.assert_allclose(vals, [0, math.pi / 2, math.pi, 1.5 * math.pi])
    # an angle range that is not a full turn keeps both ends
    vals, _ = parse_values("0:pi:3", "beta1")
    np.testing.assert_allclose(vals, [0, math.pi / 2, math.pi])
    # a non-angle parameter over [0, 2 pi] keeps both ends
    vals, _ = parse_values("0:2pi:3", "q")
    assert vals[-1] == 2 * math.pi


def test_pi_suffix_and_lists():
    assert float(parse_values("0.2pi", "beta1")[0]) == 0.2 * math.pi
    assert float(parse_values("pi", "beta1")[0]) == math.pi
    assert float(parse_values("-1.5pi", "alpha")[0]) == -1.5 * math.pi
    vals, is_dim = parse_values("0, 0.5pi ,pi", "alpha")
    assert is_dim and vals.tolist() == [0, math.pi / 2, math.pi]
    vals, is_dim = parse_values("0.5,", "kappa")  # one-value range is a dimension
    assert is_dim and vals.shape == (1,)


def test_log_range():
    vals, _ = parse_values("log:0.01:100:5", "kappa")
    np.testing.assert_allclose(vals, [0.01, 0.1, 1, 10, 100])


def test_scalar_vs_dimension():
    s = Scene(beta1="0:2pi:8", beta2=0.3, kappa=[0.5, 2.0], q=0.1)
    assert s.dims == ("beta1", "kappa")
    assert s.output_dims("stable_SS") == ("beta1", "kappa")
    assert s.output_dims("class_code") == ("beta1",)
    assert s.output_dims("stable_FS") == ()
    assert s.fixed() == {"beta2": 0.3, "q": 0.1}


def test_output_dims_follow_dependencies():
    s = Scene(beta1="0:2pi:4", beta2="0:2pi:4", alpha="0:2pi:4", kappa="1,2", q1="0,1", q2="0.5")
    assert s.model_names == ("kappa", "q1", "q2")
    assert s.output_dims("stable_SF") == ("beta1",)
    assert s.output_dims("consistent_FI") == ("beta2",)
    assert s.output_dims("subclass_code") == ("beta1", "beta2", "alpha")
    assert s.output_dims("stable_II") == ("beta1", "beta2", "kappa", "q1")
    assert s.output_dims("model_dependent_SS") == ("beta1", "beta2")
    assert s.output_names == default_outputs()


def test_default_outputs_depend_on_scene():
    s = builtin("fig1")
    assert "subclass_code" not in s.output_names  # no alpha
    assert "model_dependent_SS" not in s.output_names  # kappa, q fixed
    m = builtin("fig1-model")
    assert {"model_dependent_SS", "model_dependent_II"} <= set(m.output_names)
    assert m.dims == ("beta1", "beta2", "kappa", "q")


def test_builtins():
    f = builtin("fig1")
    assert f.fixed() == {"kappa": 0.5, "q": 0.0}
    assert f.shape == {"beta1": 512, "beta2": 512}
    b = f.axes["beta1"].values
    assert b[0] == 0 and b[-1] < 2 * math.pi
    a = builtin("atlas4d", beta1="0:2pi:16")
    assert a.shape["beta1"] == 16 and a.axes["kappa"].values[0] == pytest.approx(0.01)
    q12 = builtin("fig1", q1="0.1", q2="0.2")
    assert q12.model_names == ("kappa", "q1", "q2")


def test_invariants_fig2():
    inv = invariants(k1=100, k2=200, q1=20, q2=20)
    assert inv["kappa"] == pytest.approx(0.5)
    assert inv["q1"] == pytest.approx(math.sqrt(2)) and inv["q2"] == pytest.approx(math.sqrt(2))
    inv = invariants(k1=1, k2=4, q1=1, q2=2, b1=2, b2=1)
    assert inv["kappa"] == pytest.approx(0.5)
    assert inv["q1"] == pytest.approx(1.0) and inv["q2"] == pytest.approx(1.0)
    s = Scene.from_physical(k1=100, k2=200, q1=20, q2=20, beta1="0:2pi:4", beta2="0:2pi:4")
    assert s.fixed()["q"] == pytest.approx(math.sqrt(2))


@pytest.mark.parametrize(
    "kwargs, name",
    [
        (dict(kappa="nan"), "kappa"),
        (dict(kappa=float("inf")), "kappa"),
        (dict(kappa=-1.0), "kappa"),
        (dict(kappa=0.0), "kappa"),
        (dict(q="-0.1"), "q"),
        (dict(beta1="1:0:5"), "beta1"),
        (dict(beta1="0:1:0"), "beta1"),
        (dict(beta1="0:0:3"), "beta1"),
        (dict(beta2="0,1,0.5"), "beta2"),
        (dict(beta2="a:b:3"), "beta2"),
        (dict(kappa="log:0:1:3"), "kappa"),
        (dict(alpha="0:1:x"), "alpha"),
        (dict(outputs="no_such_variable"), "outputs"),
        (dict(outputs="subclass_code"), "outputs"),  # needs alpha
        (dict(outputs="model_dependent_SS"), "outputs"),  # needs a varied model
        (dict(outputs=""), "outputs"),
        (dict(q1="0.1"), "q2"),
        (dict(q="0.1", q1="0.1", q2="0.2"), "q"),
    ],
)
def test_bad_input_names_parameter(kwargs, name):
    with pytest.raises(ValueError) as e:
        Scene(**kwargs)
    msg = str(e.value)
    assert msg.startswith(f"{name}:") and "\n" not in msg


@pytest.mark.parametrize(
    "kwargs, name",
    [
        (dict(k1=-1, k2=1), "k1"),
        (dict(k1=1, k2=0), "k2"),
        (dict(k1=1, k2=1, q1=-1), "q1"),
        (dict(k1=1, k2=1, b2=-1), "b2"),
        (dict(k1=float("nan"), k2=1), "k1"),
    ],
)
def test_bad_physical_names_parameter(kwargs, name):
    with pytest.raises(ValueError, match=f"^{name}:"):
        invariants(**kwargs)


def test_unknown_builtin():
    with pytest.raises(ValueError, match="^scene:"):
        builtin("fig9")


def test_builtin_overrides_none_keep_defaults():
    a = builtin("atlas4d", beta1=None, q=None, q1=None, q2=None, kappa=None)
    assert a.dims == ("beta1", "beta2", "kappa", "q")
    assert a.shape == {"beta1": 256, "beta2": 256, "kappa": 9, "q": 9}


@pytest.mark.parametrize(
    "kw, name",
    [
        ({"kappa": 1 + 2j}, "kappa"),
        ({"q": True}, "q"),
        ({"beta1": ["0", "1"]}, "beta1"),
        ({"beta2": "0:2PI:8"}, "beta2"),
        ({"kappa": "LOG:0.1:10:3"}, "kappa"),
    ],
)
def test_non_real_and_miscased_input_refused(kw, name):
    """Complex numbers, booleans and text arrays are not numbers; keywords are case-sensitive."""
    with pytest.raises(ValueError, match=f"^{name}: "):
        Scene(**kw)
