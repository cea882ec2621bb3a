"""The one validator of the Python API: every kind of bad argument refused naming the parameter."""

import numpy as np
import pytest

from atlas.core import checks


@pytest.mark.parametrize("value", [True, np.True_, 1 + 2j, "1", b"1", None, [1, "a"], {"a": 1}])
def test_real_refuses_what_is_not_a_real_number(value):
    with pytest.raises(ValueError, match="^kappa: expected real numbers?"):
        checks.real("kappa", value)


def test_real_accepts_integers_and_floats():
    assert checks.real("q", 2).dtype == np.float64
    np.testing.assert_array_equal(checks.real("q", [0, 0.5]), [0.0, 0.5])
    with pytest.raises(ValueError, match="^q: must be finite"):
        checks.real("q", [0, np.nan])
    assert np.isnan(checks.real("q", np.nan, finite=False))


def test_pair_is_one_number_or_two():
    np.testing.assert_array_equal(checks.pair("k", 3), [3.0, 3.0])
    np.testing.assert_array_equal(checks.pair("k", (1, 2)), [1.0, 2.0])
    for bad in ((1,), (1, 2, 3), [[1, 2]]):
        with pytest.raises(ValueError, match="^k: expected one number or two"):
            checks.pair("k", bad)


@pytest.mark.parametrize("value", ["no", "yes", 1, 0, None, "True"])
def test_boolean_only_true_or_false(value):
    with pytest.raises(ValueError, match="^resolve: expected True or False"):
        checks.boolean("resolve", value)
    assert checks.boolean("resolve", np.False_) is False


@pytest.mark.parametrize("value", ["float16", np.float16, "int8", None, True, "Float64", "f8"])
def test_float_dtype_only_float32_float64(value):
    with pytest.raises(ValueError, match="^dtype: must be float32 or float64"):
        checks.float_dtype(value)
    assert (
        checks.float_dtype(np.float32) == "float32" and checks.float_dtype("float64") == "float64"
    )


def test_integer_range_and_type():
    assert checks.integer("n", np.int64(3), 1) == 3 and checks.integer("n", 4.0, 1, 4) == 4
    for bad in (True, "3", 1.5, 0, 5, None, 1 + 0j, float("inf")):
        with pytest.raises(ValueError, match="^n: must be an integer >= 1 and <= 4"):
            checks.integer("n", bad, 1, 4)


def test_choice_and_axis_size():
    assert checks.choice("engine", "fast", ("fast", "numpy")) == "fast"
    with pytest.raises(ValueError, match="^engine: must be one of fast, numpy, got 'gpu'"):
        checks.choice("engine", "gpu", ("fast", "numpy"))
    assert checks.axis_size("beta1", 1000, 1 << 20) == 1000
    with pytest.raises(MemoryError, match=r"^size: beta1 has 1e\+14 values: ~728 TiB"):
        checks.axis_size("beta1", 10**14, 1 << 30)


def test_plain_numpy_scalars_and_model_values():
    """numpy scalars become the Python numbers they hold (booleans and arrays stay); kappa must be
    > 0 and q >= 0, with the command line's messages."""
    assert type(checks.plain(np.float32(0.5))) is float and type(checks.plain(np.int64(2))) is int
    assert checks.plain(np.True_) is np.True_ and checks.plain("2") == "2"
    with pytest.raises(ValueError, match=r"^kappa: must be > 0 \(k1\|b1\|/\(k2\|b2\|\)\), got 0.0"):
        checks.model_values("kappa", [1.0, 0.0])
    with pytest.raises(ValueError, match="^q2: must be >= 0, got -0.1"):
        checks.model_values("q2", -0.1)
    with pytest.raises(ValueError, match="^q: must be finite"):
        checks.model_values("q", np.nan)
