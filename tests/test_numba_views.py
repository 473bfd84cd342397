"""The kernels' views (``robots._numba_views.view``) against numpy's reshape."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from sensorless.robots.recursion import numba_available

pytestmark = pytest.mark.skipif(not numba_available(), reason="numba is not installed")


@pytest.fixture(scope="module")
def kernels():
    from numba import njit

    from sensorless.robots._numba_views import view

    @njit
    def two(flat, start, rows, columns):
        return view(flat[start : start + rows * columns], (rows, columns))

    @njit
    def three(flat, blocks, rows, columns):
        return view(flat, (blocks, rows, columns))

    @njit
    def write(flat, value):
        out = view(flat[2:8], (2, 3))
        out[1, 2] = value

    return two, three, write


def test_a_view_is_numpys_reshape(kernels) -> None:
    two, three, _ = kernels
    flat = np.random.default_rng(0).normal(size=60)
    for start, rows, columns in ((0, 3, 7), (5, 7, 1), (11, 1, 49), (60, 0, 4)):
        got = two(flat, start, rows, columns)
        expected = flat[start : start + rows * columns].reshape(rows, columns)
        np.testing.assert_array_equal(got, expected)
        assert (got.shape, got.strides) == (expected.shape, expected.strides)
        assert got.flags.c_contiguous
        assert np.shares_memory(got, flat) or got.size == 0
    grid = flat.reshape(3, 20)  # a 2-D source: its items in C order
    np.testing.assert_array_equal(three(grid, 5, 3, 4), flat.reshape(5, 3, 4))


def test_a_view_writes_through_and_keeps_read_only(kernels) -> None:
    two, _, write = kernels
    flat = np.zeros(10)
    write(flat, 7.5)
    assert flat[7] == 7.5 and np.count_nonzero(flat) == 1
    flat.setflags(write=False)
    assert not two(flat, 0, 2, 5).flags.writeable
    from numba.core.errors import TypingError

    with pytest.raises(TypingError):  # numba refuses to type a write into a read-only view
        write(flat, 1.0)
    assert flat[7] == 7.5


def test_a_view_of_the_wrong_size_raises(kernels) -> None:
    two, three, _ = kernels
    with pytest.raises(ValueError, match="size differs"):
        three(np.zeros(10), 2, 2, 3)
    flat = np.zeros(10)
    with pytest.raises(ValueError, match="size differs"):
        two(flat, 8, 2, 2)  # the slice holds 2 items, not 4


@pytest.fixture(scope="module")
def any_view():
    """A compiled view of ``flat[start:start + size]`` with shape (a, b, c)."""
    from numba import njit

    from sensorless.robots._numba_views import view

    @njit
    def three(flat, start, shape):
        a, b, c = shape
        return view(flat[start : start + a * b * c], (a, b, c))

    return three


@settings(max_examples=60, deadline=None)
@given(
    shape=st.tuples(*[st.integers(0, 6)] * 3),
    start=st.integers(0, 10),
    read_only=st.booleans(),
)
def test_any_view_is_numpys_reshape(any_view, shape, start, read_only) -> None:
    flat = np.arange(start + int(np.prod(shape)) + 3, dtype=np.float64)
    flat.setflags(write=not read_only)
    got = any_view(flat, start, shape)
    expected = flat[start : start + int(np.prod(shape))].reshape(shape)
    np.testing.assert_array_equal(got, expected)
    assert got.shape == expected.shape and got.flags.writeable == (not read_only)
    if got.size:
        assert got.strides == expected.strides and np.shares_memory(got, flat)
