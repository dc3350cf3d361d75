"""drake_mh._support.borrow: a borrowed array is the same array (type, data, shape, strides), so the
kernels that receive it compile once for both, and writes go to the owner's memory."""

import numba
import numpy as np
import pytest

from drake_mh._support.borrow import borrow


@numba.njit
def _row_sums(a):
    return a.sum(axis=1)


@numba.njit
def _write_through_borrowed(owner, value):
    """Borrow an argument (held by the caller), write through a view of it, read it back."""
    b = borrow(owner)
    b[1, 2] = value
    row = b[1]
    return _row_sums(b), row[2], b.shape, b.strides, b.ctypes.data == owner.ctypes.data


def test_a_borrowed_array_is_the_same_array():
    owner = np.arange(12.0).reshape(3, 4)
    sums, seen, shape, strides, same_data = _write_through_borrowed(owner, 100.0)
    assert owner[1, 2] == 100.0 and seen == 100.0 and same_data
    np.testing.assert_array_equal(sums, owner.sum(axis=1))
    assert shape == owner.shape and strides == owner.strides


def test_a_borrowed_array_has_the_owners_type():
    owner = np.arange(6.0).reshape(2, 3)
    _row_sums(owner)
    _write_through_borrowed(owner, 1.0)  # calls _row_sums with the borrowed array
    assert len(_row_sums.signatures) == 1


def test_only_arrays_are_borrowed():
    @numba.njit
    def borrow_a_number(x):
        return borrow(x)

    with pytest.raises(numba.core.errors.TypingError):
        borrow_a_number(1.0)


@numba.njit
def _borrow_nested(a, b, c):
    (x, (y, z)) = borrow((a, (b, c)))
    y[0] = 7
    return x.sum() + z.sum(), y.ctypes.data == b.ctypes.data


def test_a_tuple_of_arrays_is_borrowed_element_by_element():
    a, b, c = np.ones(3), np.zeros(2, np.int64), np.full((2, 2), 2.0)
    total, same_data = _borrow_nested(a, b, c)
    assert total == 11.0 and same_data and b[0] == 7
