"""Views with any strides are read in place, and segment exactly like their contiguous copies."""
import numpy as np
import pytest

import occseg
from occseg import _map
from conftest import noisy_scene

BIG = noisy_scene(seed=11, shape=(40, 50, 60))


def views():
    """(name, view) pairs: every kind of non-contiguous array NumPy makes, all [z, y, x]."""
    f32 = BIG.astype(np.float32)
    yield "c", f32
    yield "fortran", np.asfortranarray(f32)
    yield "step slices", f32[::2, 1::3, ::2]
    yield "offset box", f32[3:35, 5:44, 7:50]
    yield "transpose", f32.transpose(2, 1, 0)
    yield "axes swapped", np.swapaxes(f32, 0, 1)
    yield "negative x", f32[:, :, ::-1]
    yield "all negative", f32[::-1, ::-2, ::-3]
    yield "transposed negative steps", BIG.transpose(1, 0, 2)[::-3, 2:, ::2]
    yield "float64 column of records", np.stack([BIG, 1 - BIG], axis=-1)[..., 0]
    u16 = np.round(BIG * 65535).astype(np.uint16)
    yield "uint16 fortran, flipped", np.asfortranarray(u16)[::-1]
    # misaligned: float32 starting one byte into a buffer
    raw = np.zeros(f32.nbytes + 1, dtype=np.uint8)
    mis = np.frombuffer(raw.data, dtype=np.float32, count=f32.size, offset=1).reshape(f32.shape)
    mis[...] = f32
    yield "misaligned", mis
    yield "2d slice of 3d", f32[:, 7, :]


@pytest.mark.parametrize("name,view", list(views()), ids=[n for n, _ in views()])
def test_view_equals_contiguous_copy(name, view):
    assert _map.as_voxel_array(view, "t") is view  # no copy on the Python side
    data, _, dims, strides, swapped = _map.buffer_args(view)
    assert swapped == 0
    assert data == view.__array_interface__["data"][0]  # the C ABI reads the caller's memory
    assert tuple(dims) == tuple(reversed(view.shape)) + (() if view.ndim == 3 else (1,))
    copy = np.ascontiguousarray(view)
    a, b = occseg.segment(view, smax=16), occseg.segment(copy, smax=16)
    assert a.labels.shape == view.shape
    assert np.array_equal(a.labels, b.labels)
    assert a.segments == b.segments
    assert len(a.segments) >= 2
    with occseg.Map.from_array(view) as m:
        expect = copy.astype(np.float32) if copy.dtype.kind == "f" else (copy / np.iinfo(copy.dtype).max).astype(np.float32)
        assert np.array_equal(m.to_array().reshape(view.shape), expect)


def test_big_endian_is_converted():
    le = BIG.astype("<f8")
    be = BIG.astype(">f8")
    assert np.array_equal(occseg.segment(be).labels, occseg.segment(le).labels)


@pytest.mark.parametrize("make,bbox,voxels", [
    (lambda m: m, ((10, 4, 1), (19, 7, 2)), 80),
    (lambda m: m.transpose(2, 1, 0), ((1, 4, 10), (2, 7, 19)), 80),
    (lambda m: m[:, :, ::-1], ((12, 4, 1), (21, 7, 2)), 80),
    (lambda m: m[::-1, ::2], ((10, 2, 5), (19, 3, 6)), 40),
])
def test_strides_map_axes_as_numpy_does(make, bbox, voxels):
    """Hand-computed boxes: x is the last axis, y the middle one, z the first, and flips and
    steps move the box where NumPy's indexing puts it."""
    m = np.full((8, 16, 32), 0.1, dtype=np.float32)
    m[1:3, 4:8, 10:20] = 0.9
    r = occseg.segment(make(m))
    occupied = [s for s in r.segments if s.state == occseg.State.OCCUPIED]
    assert len(occupied) == 1
    assert occupied[0].bbox == bbox and occupied[0].voxels == voxels
