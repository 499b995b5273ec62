"""In place both ways: occseg.segment(array) reads the array where it lies (Map.view, no copy for
any accepted dtype or strides) and returns labels and states() as read-only arrays over the C
result's memory, which they keep alive; the labels equal those of the copying path bit for bit."""
import ctypes
import gc

import numpy as np
import pytest

import occseg
from conftest import noisy_scene
from occseg._lib import lib


def live(kind):
    return occseg.live_handles().get(kind, 0)


def as_dtype(m, dtype):
    if dtype == np.int8:  # an OccupancyGrid: percent, -1 for the unknown slab
        g = np.round(m * 100).astype(np.int8)
        g[m == 0.5] = -1
        return g
    if np.issubdtype(dtype, np.integer):
        return np.round(m * np.iinfo(dtype).max).astype(dtype)
    return m.astype(dtype)


def layouts(a):
    """The same logical [z, y, x] map in C order, Fortran order, as a slice of a larger array and
    flipped (negative strides): every one a view NumPy makes without copying."""
    big = np.zeros((a.shape[0] * 2, a.shape[1], a.shape[2] * 3), a.dtype)
    big[::2, :, ::3] = a
    flipped = np.ascontiguousarray(a[::-1, ::-1, ::-1])[::-1, ::-1, ::-1]
    return {"C": a, "F": np.asfortranarray(a), "sliced": big[::2, :, ::3], "flipped": flipped}


DTYPES = [np.float32, np.float64, np.uint8, np.uint16, np.int8]


def copied(arr, **kw):
    """The copying path of before: Map.from_array, then segment the map."""
    with occseg.Map.from_array(arr) as m:
        return occseg.segment(m, **kw)


@pytest.mark.parametrize("dtype", DTYPES)
def test_same_labels_as_the_copying_path_for_every_dtype_and_layout(dtype):
    base = as_dtype(noisy_scene(seed=11), dtype)
    ref = copied(base)
    for name, arr in layouts(base).items():
        assert np.array_equal(arr, base)
        r = occseg.segment(arr)
        assert r.labels.dtype == np.uint32 and r.labels.shape == base.shape
        assert np.array_equal(r.labels, ref.labels), name
        assert r.segments == ref.segments, name
        assert np.array_equal(r.states(), ref.states()), name


def test_the_map_views_the_array_and_keeps_it_alive():
    arr = noisy_scene(seed=12).astype(np.float32)
    address = arr.ctypes.data
    m = occseg.Map.view(arr, voxel_size=0.05)
    assert m._h.keep is arr  # the very array, not a copy
    del arr
    gc.collect()
    kept = m._h.keep
    assert kept.ctypes.data == address  # still alive, at the same address, while the map views it
    a = m.to_array()
    assert np.array_equal(a, kept)
    kept[3, 4, 5] = 0.75  # the view reads the buffer at each call: no copy was taken
    assert m.to_array()[3, 4, 5] == np.float32(0.75)
    m.close()
    assert m._h.keep is None


def test_segment_reads_the_array_where_it_lies():
    """A NaN put in the caller's array after the view was made is what the call reports: the map
    read the caller's memory, not a snapshot (a copy would have been taken before)."""
    arr = noisy_scene(seed=13).astype(np.float32)
    with occseg.Map.view(arr) as m:
        r = occseg.segment(m)
        arr[7, 8, 9] = np.nan
        with pytest.raises(occseg.OccsegError) as e:
            occseg.segment(m)
    assert e.value.status == occseg.Status.EVALUE
    assert "probability at voxel (9, 8, 7) = nan is NaN" in e.value.message
    assert len(r.segments) > 2


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_bad_values_raise_what_the_copying_path_raises(dtype):
    for name, arr in layouts(noisy_scene(seed=14).astype(dtype)).items():
        arr = arr.copy(order="K") if name == "flipped" else arr
        arr[2, 3, 4] = 1.5 if name != "C" else np.nan
        with pytest.raises(occseg.OccsegError) as copy_error:
            occseg.Map.from_array(arr)
        with pytest.raises(occseg.OccsegError) as view_error:
            occseg.segment(arr)
        assert view_error.value.status == copy_error.value.status == occseg.Status.EVALUE
        detail = copy_error.value.message.split(": ", 1)[1]
        assert view_error.value.message.split(": ", 1)[1] == detail, name
        assert "voxel (4, 3, 2)" in detail


def test_clamp_and_nan_unknown_apply_to_a_viewed_array():
    arr = noisy_scene(seed=15).astype(np.float32)
    arr[1, 1, 1], arr[2, 2, 2] = 3.0, np.nan
    ref = copied(np.nan_to_num(np.clip(arr, 0, 1), nan=0.5))
    r = occseg.segment(arr, clamp=True, nan_unknown=True)
    assert np.array_equal(r.labels, ref.labels)
    assert np.isnan(arr[2, 2, 2]) and arr[1, 1, 1] == 3.0  # the caller's array is never written


def test_labels_and_states_view_the_result_memory():
    r = occseg.segment(noisy_scene(seed=16).astype(np.float32))
    address, count = ctypes.c_void_p(), ctypes.c_size_t()
    with r._used() as h:
        assert lib.occseg_result_labels_view(h, ctypes.byref(address), ctypes.byref(count)) == 0
    assert r.labels.ctypes.data == address.value  # the C result's array itself
    assert count.value == r.labels.size
    states = r.states()
    with r._used() as h:
        assert lib.occseg_result_states_view(h, ctypes.byref(address), ctypes.byref(count)) == 0
    assert states.ctypes.data == address.value and r.states().ctypes.data == address.value
    assert not r.labels.flags.writeable and not states.flags.writeable and not r.labels.flags.owndata
    with pytest.raises(ValueError):
        r.labels[0, 0, 0] = 5
    base = r.labels.base
    assert isinstance(base, occseg._handles.Borrow)


def test_labels_keep_the_result_alive_after_it_is_dropped():
    gc.collect()
    before = live("result")
    r = occseg.segment(noisy_scene(seed=17).astype(np.float32))
    expected = r.labels.copy()
    expected_states = r.states().copy()
    labels, states = r.labels, r.states()
    del r
    gc.collect()
    assert live("result") == before + 1  # held by the arrays, not freed under them
    np.ones(labels.size, np.uint32)  # fresh allocations that would reuse freed memory
    assert np.array_equal(labels, expected) and np.array_equal(states, expected_states)
    del labels
    gc.collect()
    assert live("result") == before + 1  # the states array still refers to it
    assert np.array_equal(states, expected_states)
    del states
    gc.collect()
    assert live("result") == before  # the last array gone: the result is freed


def test_close_keeps_labels_usable_and_frees_with_them():
    gc.collect()
    before = live("result")
    with occseg.segment(noisy_scene(seed=18).astype(np.float32)) as r:
        labels = r.labels
        expected = labels.copy()
    assert r.closed
    with pytest.raises(ValueError):
        r.states()
    assert np.array_equal(r.labels, expected) and r.labels is labels
    assert live("result") == before + 1
    del r, labels
    gc.collect()
    assert live("result") == before


def test_slices_of_labels_keep_the_result_alive_too():
    gc.collect()
    before = live("result")
    r = occseg.segment(noisy_scene(seed=19).astype(np.float32))
    part = r.labels[3:5, ::2]
    expected = part.copy()
    del r
    gc.collect()
    assert live("result") == before + 1 and np.array_equal(part, expected)
    del part
    gc.collect()
    assert live("result") == before


def test_recycle_takes_the_labels_only_when_nobody_holds_them():
    m = noisy_scene(seed=20).astype(np.float32)
    flat = np.full(m.shape, 0.1, np.float32)
    plain = occseg.segment(m)
    gc.collect()
    before = live("result")
    with occseg.Context(2) as ctx:
        r = occseg.segment(m, context=ctx)
        held = r.labels
        ctx.recycle(r)  # the caller holds the labels: closed, not recycled, freed with them
        assert r.closed and live("result") == before + 1
        f = occseg.segment(flat, context=ctx)
        assert not np.shares_memory(f.labels, held)
        assert np.array_equal(held, plain.labels) and r.labels is held  # never overwritten
        del held
        gc.collect()
        assert live("result") == before + 1  # f only
        address = f.labels.ctypes.data
        ctx.recycle(f)  # nobody holds its labels: handed back
        assert live("result") == before
        with pytest.raises(ValueError, match="recycle"):
            f.labels
        again = occseg.segment(m, context=ctx)
        assert again.labels.ctypes.data == address  # written into the recycled array
        assert np.array_equal(again.labels, plain.labels)


@pytest.mark.parametrize("dtype", [">f4", ">f8", ">u2"])
def test_a_foreign_byte_order_is_read_in_place(dtype):
    """A big-endian array is viewed as it is (the C ABI swaps each item as it reads it), in every
    layout, with the labels of the native array."""
    native = as_dtype(noisy_scene(seed=21), np.dtype(dtype).newbyteorder("="))
    ref = copied(native)
    for name, arr in layouts(native.astype(dtype)).items():
        with occseg.Map.view(arr) as m:
            assert m._h.keep is arr, name  # the very array: no native copy was made
            assert np.array_equal(m.to_array(), native.astype(np.float32) if native.dtype.kind == "f"
                                  else (native / 65535.0).astype(np.float32)), name
        r = occseg.segment(arr)
        assert np.array_equal(r.labels, ref.labels), name
        assert r.segments == ref.segments, name


def test_a_foreign_byte_order_is_converted_and_other_dtypes_refused():
    m = noisy_scene(seed=21)
    swapped = m.astype(">f8")
    assert np.array_equal(occseg.segment(swapped).labels, occseg.segment(m).labels)
    with occseg.Map.from_array(swapped) as copy:
        assert np.array_equal(copy.to_array(), m.astype(np.float32))
    with pytest.raises(occseg.OccsegError) as e:
        occseg.segment(m.astype(np.float16))
    assert e.value.status == occseg.Status.EINVAL and "float16" in e.value.message


def test_segments_read_from_the_c_table_equal_the_per_segment_calls():
    r = occseg.segment(noisy_scene(seed=22).astype(np.float32))
    assert isinstance(r.segments, occseg._result.Segments)
    with r._used() as h:
        one_by_one = [occseg.Result._segment(h, i) for i in range(lib.occseg_result_segment_count(h))]
    assert len(r.segments) == len(one_by_one) > 3
    assert list(r.segments) == one_by_one and r.segments == one_by_one and one_by_one == r.segments
    assert r.segments[-1] == one_by_one[-1] and r.segments[1:3] == one_by_one[1:3]
    assert r.segments != one_by_one[:-1]
    table = r.segments._table
    assert not table.flags.writeable and np.shares_memory(table, table.base)
    held = r.segments
    del r
    gc.collect()
    assert list(held) == one_by_one  # the table keeps the C result alive too


def test_the_segment_table_is_read_on_first_access_and_survives_close():
    m = noisy_scene(seed=23).astype(np.float32)
    ref = copied(m)
    r = occseg.segment(m)
    assert r._segments is None  # a call that only needs labels never makes the table
    assert r.segments == ref.segments and r._segments is not None
    with occseg.segment(m) as s:
        pass
    assert s.closed and s.segments == ref.segments  # made by close(), usable after it
