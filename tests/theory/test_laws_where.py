"""``laws.where`` must give ``np.where``'s answer bit for bit (it selects through bit masks on
arrays large enough to pay, and by a plain conditional on scalars)."""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from planar_impact import laws

SIZES = st.sampled_from([1, 7, laws._MASKED_SELECT_MIN_SIZE - 1, laws._MASKED_SELECT_MIN_SIZE,
                         1000])
ANY_FLOAT = st.floats(allow_nan=True, allow_infinity=True, allow_subnormal=True)


@settings(max_examples=200, deadline=None)
@given(data=st.data(), size=SIZES)
def test_float_arrays_and_scalars_select_like_np_where(data, size):
    condition = data.draw(hnp.arrays(np.bool_, size))
    if_true = data.draw(hnp.arrays(np.float64, size, elements=ANY_FLOAT))
    if_false = data.draw(st.one_of(hnp.arrays(np.float64, size, elements=ANY_FLOAT), ANY_FLOAT))
    expected = np.where(condition, if_true, if_false)
    got = laws.where(condition, if_true, if_false)
    assert got.dtype == expected.dtype and got.shape == expected.shape
    assert got.tobytes() == expected.tobytes()  # NaN payloads and signed zeros included


@settings(max_examples=100, deadline=None)
@given(data=st.data(), size=SIZES)
def test_small_integer_codes_select_like_np_where(data, size):
    condition = data.draw(hnp.arrays(np.bool_, size))
    codes = data.draw(hnp.arrays(np.int8, size, elements=st.integers(0, 5)))
    for if_true, if_false in ((3, codes), (codes, 1), (codes, codes[::-1].copy())):
        expected = np.where(condition, if_true, if_false)
        got = laws.where(condition, if_true, if_false)
        assert got.dtype == expected.dtype and np.array_equal(got, expected)


def test_negative_zero_and_nan_payload_survive_the_mask():
    size = 2 * laws._MASKED_SELECT_MIN_SIZE
    condition = np.arange(size) % 2 == 0
    payload_nan = np.frombuffer(np.uint64(0x7FF8_0000_DEAD_BEEF).tobytes(), dtype=np.float64)[0]
    got = laws.where(condition, np.full(size, -0.0), np.full(size, payload_nan))
    assert np.signbit(got[0]) and got[0] == 0.0
    assert got[1:2].tobytes() == np.float64(payload_nan).tobytes()


def test_scalar_condition_is_a_plain_conditional():
    assert laws.where(np.float64(1.0) > 0, "yes", "no") == "yes"
    assert laws.where(False, 1.0, 2.0) == 2.0
