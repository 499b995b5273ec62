"""Arguments that ctypes would hand to C altered are refused before any C call: texts and paths
holding a NUL character (C would see only the text before it), integers beyond their C type (ctypes
cuts them), and values of the wrong type (a float segment id, a bool or str where a number is
meant). The errors are OccsegTypeError / OccsegValueError: OccsegErrors that are also TypeError /
ValueError, naming the function, the argument and the value."""
import pathlib

import numpy as np
import pytest

import occseg
from occseg import OccsegError, OccsegTypeError, OccsegValueError, Status


def good():
    m = np.full((6, 7, 8), 0.2, dtype=np.float32)
    m[1:4, 2:5, 3:6] = 0.9
    return m


def refused(kind, status, fn, *args, **kwargs):
    with pytest.raises(kind) as e:
        fn(*args, **kwargs)
    err = e.value
    assert isinstance(err, OccsegError) and err.status == status, err
    assert isinstance(err, ValueError if kind is OccsegValueError else TypeError)
    return err.message


# ---- NUL characters ---------------------------------------------------------------------------

@pytest.mark.parametrize("form", [str, bytes, pathlib.Path])
def test_map_write_refuses_a_nul_in_the_path_and_writes_nothing(tmp_path, form):
    target = str(tmp_path / "a.npy") + "\0.nrrd"
    path = form(target.encode()) if form is bytes else form(target)
    with occseg.Map.from_array(good()) as m:
        msg = refused(OccsegValueError, Status.EINVAL, m.write, path)
    assert "occseg.Map.write: path" in msg and "NUL character" in msg
    assert list(tmp_path.iterdir()) == []  # before the fix: a.npy, in NPY


def test_read_map_refuses_a_nul_in_the_path(tmp_path):
    np.save(tmp_path / "m.npy", good())
    msg = refused(OccsegValueError, Status.EINVAL, occseg.read_map, str(tmp_path / "m.npy") + "\0.nrrd")
    assert "occseg.read_map: path" in msg and "NUL" in msg


def test_result_write_refuses_a_nul_in_the_directory(tmp_path):
    r = occseg.segment(good())
    msg = refused(OccsegValueError, Status.EINVAL, r.write, str(tmp_path / "out") + "\0more")
    assert "occseg.Result.write: directory" in msg
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("kwargs,words", [
    ({"preset": "paper\0junk"}, ["preset", "'paper\\x00junk'"]),
    ({"smax\0junk": 16}, ["parameter name", "'smax\\x00junk'"]),
    ({"split_ratio": "1.2\0junk"}, ["parameter 'split_ratio'"]),
])
def test_segment_refuses_a_nul_in_a_preset_name_or_text(kwargs, words):
    msg = refused(OccsegValueError, Status.EINVAL, occseg.segment, good(), **kwargs)
    for w in words:
        assert w in msg, (w, msg)
    assert "NUL character" in msg


@pytest.mark.skipif(not occseg._lib.has("occseg_map_read_options"), reason="a library without reader options")
@pytest.mark.parametrize("options", [{"voxel_size": "0.5\0junk"}, {"voxel_size\0junk": 0.5}])
def test_reader_and_writer_options_refuse_a_nul(tmp_path, options):
    np.save(tmp_path / "m.npy", good())
    msg = refused(OccsegValueError, Status.EINVAL, occseg.read_map, tmp_path / "m.npy", **options)
    assert "occseg_map_read: option" in msg and "NUL" in msg
    with occseg.Map.from_array(good()) as m:
        refused(OccsegValueError, Status.EINVAL, m.write, tmp_path / "w.npy", **options)
    assert not (tmp_path / "w.npy").exists()


@pytest.mark.skipif(not hasattr(occseg, "load_plugin"), reason="a library without plugins")
def test_load_plugin_refuses_a_nul_in_the_path(tmp_path):
    before = occseg.plugins()
    msg = refused(OccsegValueError, Status.EINVAL, occseg.load_plugin, str(tmp_path / "p.so") + "\0x")
    assert "occseg.load_plugin: path" in msg
    assert occseg.plugins() == before


def test_paths_of_the_wrong_type_are_type_errors(tmp_path):
    with occseg.Map.from_array(good()) as m:
        assert "not NoneType" in refused(OccsegTypeError, Status.EINVAL, m.write, None)
    assert "not int" in refused(OccsegTypeError, Status.EINVAL, occseg.read_map, 3)
    assert "preset must be a str" in refused(OccsegTypeError, Status.EINVAL, occseg.segment, good(), preset=b"paper")


# ---- integers and numbers -----------------------------------------------------------------------

@pytest.mark.parametrize("threads", [2**32 + 3, -2**31 - 1, 2**64])
def test_context_threads_beyond_a_c_int_are_refused_not_cut(threads):
    msg = refused(OccsegValueError, Status.EINVAL, occseg.Context, threads)
    assert f"occseg.Context: threads = {threads} does not fit the C int" in msg


@pytest.mark.parametrize("threads", [1.5, 2.0, True, "2", None])
def test_context_threads_of_the_wrong_type(threads):
    assert "threads must be an int" in refused(OccsegTypeError, Status.EINVAL, occseg.Context, threads)


def test_context_takes_numpy_integers():
    with occseg.Context(np.int64(2)) as a, occseg.Context(np.uint8(1)) as b:
        assert 1 <= a.threads <= 2 and b.threads == 1


@pytest.mark.parametrize("value", ["0.5", True, None, b"1"])
def test_voxel_size_must_be_a_number(value):
    msg = refused(OccsegTypeError, Status.EINVAL, occseg.Map.from_array, good(), voxel_size=value)
    assert "voxel_size must be a number" in msg
    with occseg.Map.from_array(good(), voxel_size=0.25) as m:
        refused(OccsegTypeError, Status.EINVAL, setattr, m, "voxel_size", value)
        assert m.voxel_size == 0.25


def test_origin_must_be_three_numbers():
    assert "origin has 2 values" in refused(OccsegValueError, Status.EINVAL, occseg.segment, good(), origin=(0, 0))
    assert "origin must be a sequence" in refused(OccsegTypeError, Status.EINVAL, occseg.segment, good(), origin=1.0)
    assert "origin[2] must be a number" in refused(OccsegTypeError, Status.EINVAL, occseg.Map.from_array, good(),
                                                   origin=(0, 0, "1"))
    assert "too large for a double" in refused(OccsegValueError, Status.EVALUE, occseg.Map.from_array, good(),
                                               voxel_size=10**400)


# ---- segment ids ----------------------------------------------------------------------------------

@pytest.mark.parametrize("method", ["mask", "voxels", "points"])
@pytest.mark.parametrize("segment_id", [1.5, 1.0, np.float64(1), True, np.bool_(True), "1", None])
def test_segment_ids_must_be_integers(method, segment_id):
    r = occseg.segment(good())
    assert len(r.segments) == 2 and r.segments[1].voxels == 27
    fn = getattr(r, method)
    for i in (np.int64(1), np.uint32(1), np.int8(1), np.array(1)):  # NumPy integers are ids
        assert np.array_equal(fn(i), fn(1))
    assert r.mask(1).sum() == 27
    msg = refused(OccsegTypeError, Status.EINVAL, fn, segment_id)  # before the fix, mask(1.5) was all False
    assert f"occseg.Result.{method}: segment id must be an int" in msg


@pytest.mark.parametrize("method", ["mask", "voxels", "points"])
@pytest.mark.parametrize("segment_id", [-1, 2, 2**64, np.int64(-3)])
def test_segment_ids_out_of_range(method, segment_id):
    r = occseg.segment(good())
    msg = refused_range(getattr(r, method), segment_id)
    assert f"occseg.Result.{method}: segment id {int(segment_id)} is out of range (the result has 2 segments)" in msg


def refused_range(fn, segment_id):
    with pytest.raises(OccsegError) as e:
        fn(segment_id)
    assert e.value.status == Status.ERANGE
    return e.value.message


@pytest.mark.skipif(not hasattr(occseg, "stages"), reason="a library without plugins")
def test_stage_kind_must_be_text():
    assert "kind must be a str" in refused(OccsegTypeError, Status.EINVAL, occseg.stages, ["texture"])
