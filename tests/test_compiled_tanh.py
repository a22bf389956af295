"""The compiled replay's tanh and logistic (plain arithmetic, not the C library's) against
NumPy's in float64: within a float32 ulp everywhere, NaN and infinity kept."""

import numpy as np
from numba import njit

from models.compiled import fast_logistic, fast_tanh

FLOAT32_ULP_AT_ONE = float(np.spacing(np.float32(1.0)))


@njit(cache=False)
def _over(values: np.ndarray, logistic: bool) -> np.ndarray:
    out = np.empty_like(values)
    for i in range(values.size):
        out[i] = fast_logistic(values[i]) if logistic else fast_tanh(values[i])
    return out


def _grid() -> np.ndarray:
    tiny = np.geomspace(1e-38, 1.0, 20_001)
    return np.concatenate([np.linspace(-30.0, 30.0, 2_000_001), tiny, -tiny]).astype(np.float32)


def test_tanh_is_within_one_float32_ulp_of_the_exact_value_everywhere():
    x = _grid()
    exact = np.tanh(x.astype(np.float64))
    error = np.abs(_over(x, False).astype(np.float64) - exact)
    ulp = np.spacing(np.abs(exact).astype(np.float32)).astype(np.float64)
    assert np.max(error / ulp) <= 1.0
    assert _over(np.float32([0.0]), False)[0] == 0.0


def test_logistic_is_within_one_float32_ulp_of_one_of_the_exact_value():
    x = _grid()
    exact = 1.0 / (1.0 + np.exp(-x.astype(np.float64)))
    error = np.abs(_over(x, True).astype(np.float64) - exact)
    # 0.5 + 0.5·tanh(x/2), as in the NumPy path: the error is absolute, not relative to
    # a value near 0.
    assert error.max() <= FLOAT32_ULP_AT_ONE


def test_nan_stays_nan_and_infinity_saturates():
    values = np.float32([np.nan, np.inf, -np.inf, 1e30, -1e30])
    tanh = _over(values, False)
    assert np.isnan(tanh[0])
    np.testing.assert_array_equal(tanh[1:], [1.0, -1.0, 1.0, -1.0])
    logistic = _over(values, True)
    assert np.isnan(logistic[0])
    np.testing.assert_array_equal(logistic[1:], [1.0, 0.0, 1.0, 0.0])
