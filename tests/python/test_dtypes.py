"""Every accepted dtype, 2D maps, and the dtypes that are refused."""
import numpy as np
import pytest

import occseg
from conftest import noisy_scene


@pytest.mark.parametrize("dtype", [np.uint8, np.uint16])
def test_integer_maps_mean_value_over_max(dtype):
    top = np.iinfo(dtype).max
    q = np.round(noisy_scene(seed=3) * top).astype(dtype)
    as_float = (q / float(top)).astype(np.float32)  # 0..max onto 0..1, as the C ABI documents
    with occseg.Map.from_array(q) as m:
        assert np.array_equal(m.to_array(), as_float)
    a, b = occseg.segment(q), occseg.segment(as_float)
    assert np.array_equal(a.labels, b.labels) and a.segments == b.segments


def test_float64_is_rounded_to_float32():
    m = noisy_scene(seed=4)
    with occseg.Map.from_array(m) as mm:
        assert np.array_equal(mm.to_array(), m.astype(np.float32))
    assert np.array_equal(occseg.segment(m).labels, occseg.segment(m.astype(np.float32)).labels)


def test_extreme_integer_values():
    m = np.zeros((4, 5, 6), dtype=np.uint16)
    m[1, 2, 3] = 65535
    with occseg.Map.from_array(m) as mm:
        v = mm.to_array()
    assert v[1, 2, 3] == 1.0 and v.sum() == 1.0


@pytest.mark.parametrize("dtype", [np.int64, np.int32, np.int16, np.float16, np.bool_, np.complex64, np.uint32])
def test_unsupported_dtypes_are_refused(dtype):
    with pytest.raises(occseg.OccsegError) as e:
        occseg.segment(np.zeros((4, 4, 4), dtype=dtype))
    assert e.value.status == occseg.Status.EINVAL
    assert str(np.dtype(dtype)) in e.value.message and "float32, float64, uint8 or uint16" in e.value.message


def test_two_dimensional_map_gives_two_dimensional_labels():
    m = np.full((40, 50), 0.1, dtype=np.float32)
    m[10:20, 5:25] = 0.95
    r = occseg.segment(m)
    assert r.labels.shape == (40, 50) and r.dims == (50, 40, 1)
    occ = [s for s in r.segments if s.state == occseg.State.OCCUPIED]
    assert len(occ) == 1 and occ[0].voxels == 200 and occ[0].bbox == ((5, 10, 0), (24, 19, 0))
    assert r.mask(occ[0].id).shape == (40, 50) and r.mask(occ[0].id)[10:20, 5:25].all()
    assert r.states().shape == (40, 50)


def test_nested_lists_are_accepted():
    m = np.full((3, 4, 5), 0.2)
    r = occseg.segment(m.tolist())
    assert r.labels.shape == (3, 4, 5) and len(r.segments) == 1 and r.segments[0].voxels == 60
