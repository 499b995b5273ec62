"""Every error path raises OccsegError with the C status, its name and a message naming the problem."""
import os
import subprocess
import sys

import numpy as np
import pytest

import occseg
from occseg import OccsegError, Status


def raises(status, fn, *args, **kwargs):
    with pytest.raises(OccsegError) as e:
        fn(*args, **kwargs)
    err = e.value
    assert err.status == status and err.code == int(status) and err.name == "OCCSEG_" + status.name
    assert err.message and err.message in str(err) and err.name in str(err)
    return err.message


def good():
    return np.full((6, 7, 8), 0.2, dtype=np.float32)


@pytest.mark.parametrize("bad,word", [(np.nan, "NaN"), (np.inf, "infinite"), (-np.inf, "infinite"),
                                      (1.5, "outside [0, 1]"), (-0.25, "outside [0, 1]")])
def test_bad_probability_names_the_voxel(bad, word):
    m = good()
    m[3, 2, 1] = bad  # z=3, y=2, x=1
    msg = raises(Status.EVALUE, occseg.segment, m)
    assert "voxel (1, 2, 3)" in msg and word in msg


def test_bad_probability_in_a_view_names_the_views_voxel():
    m = good().astype(np.float64)
    m[4, 3, 5] = np.nan
    view = m[::-1, :, ::-2]  # z 4 -> 1; x takes 7, 5, 3, 1, so 5 -> 1
    assert "voxel (1, 3, 1)" in raises(Status.EVALUE, occseg.segment, view)


def test_clamp_and_nan_unknown_accept_bad_values():
    m = good()
    m[0, 0, 0], m[1, 1, 1], m[2, 2, 2] = np.nan, 3.0, -1.0
    with occseg.Map.from_array(m, clamp=True, nan_unknown=True) as mm:
        v = mm.to_array()
    assert (v[0, 0, 0], v[1, 1, 1], v[2, 2, 2]) == (0.5, 1.0, 0.0)
    assert "voxel (0, 0, 0)" in raises(Status.EVALUE, occseg.segment, m, clamp=True)
    assert "voxel (1, 1, 1)" in raises(Status.EVALUE, occseg.segment, m, nan_unknown=True)


@pytest.mark.parametrize("shape", [(0, 4, 4), (4, 0, 4), (4, 4, 0), (0, 0)])
def test_empty_dims(shape):
    raises(Status.EDIMS, occseg.segment, np.zeros(shape, dtype=np.float32))


@pytest.mark.parametrize("shape", [(8,), (2, 2, 2, 2), ()])
def test_wrong_number_of_dimensions(shape):
    msg = raises(Status.EDIMS, occseg.segment, np.zeros(shape, dtype=np.float32))
    assert str(np.zeros(shape).shape) in msg


def test_unknown_parameter_name():
    msg = raises(Status.EINVAL, occseg.segment, good(), smaxx=16)
    assert "'smaxx'" in msg and "no such parameter" in msg


@pytest.mark.parametrize("params,words", [
    ({"smax": 48}, ["smax", "power of two"]),
    ({"smax": -1}, ["smax", "-1"]),
    ({"smax": 2**70}, ["smax", str(2**70)]),
    ({"split_ratio": "abc"}, ["split_ratio", "abc"]),
    ({"split_ratio": float("nan")}, ["split_ratio", "nan"]),
    ({"smin": 8, "smax": 4}, ["smin"]),
    ({"threads": -2}, ["threads", "-2"]),
])
def test_bad_parameter_values(params, words):
    msg = raises(Status.EINVAL, occseg.segment, good(), **params)
    for w in words:
        assert w in msg, (w, msg)


@pytest.mark.parametrize("value", [True, None, b"16", [16], 2j])
def test_parameter_values_of_the_wrong_type(value):
    msg = raises(Status.EINVAL, occseg.segment, good(), smax=value)
    assert "'smax'" in msg and repr(value) in msg


def test_bad_preset():
    assert "fancy" in raises(Status.EINVAL, occseg.segment, good(), preset="fancy")


def test_missing_file(tmp_path):
    path = tmp_path / "no_such_map.npy"
    msg = raises(Status.EIO, occseg.read_map, path)
    assert str(path) in msg


def test_truncated_file(tmp_path):
    path = tmp_path / "map.npy"
    np.save(path, good())
    path.write_bytes(path.read_bytes()[:150])
    msg = raises(Status.EFORMAT, occseg.read_map, path)
    assert str(path) in msg and "truncated" in msg


def test_bad_voxel_size_and_origin(tmp_path):
    assert "voxel_size" in raises(Status.EVALUE, occseg.segment, good(), voxel_size=0)
    assert "voxel_size" in raises(Status.EVALUE, occseg.segment, good(), voxel_size=float("inf"))
    assert "origin[1]" in raises(Status.EVALUE, occseg.segment, good(), origin=(0, float("nan"), 0))
    np.save(tmp_path / "m.npy", good())
    # a reader option (an argument of the reader) with the plugin interface, else set afterwards
    reader_option = occseg._lib.has("occseg_map_read_options")
    assert "voxel_size" in raises(Status.EINVAL if reader_option else Status.EVALUE, occseg.read_map,
                                  tmp_path / "m.npy", voxel_size=-1)
    with occseg.read_map(tmp_path / "m.npy") as m:
        with pytest.raises(OccsegError):
            m.voxel_size = -0.5
        assert m.voxel_size == 1.0  # unchanged by the failed call
        assert "Map carries" in raises(Status.EINVAL, occseg.segment, m, voxel_size=0.1)


def test_write_into_a_missing_folder(tmp_path):
    r = occseg.segment(good())
    target = tmp_path / "not" / "there"
    assert str(target) in raises(Status.EIO, r.write, target)
    assert not (tmp_path / "not").exists()


def test_segment_id_out_of_range():
    r = occseg.segment(good())
    assert "7" in raises(Status.ERANGE, r.voxels, 7)
    raises(Status.ERANGE, r.mask, -1)


def test_closed_objects_refuse_use():
    m = occseg.Map.from_array(good())
    m.close()
    m.close()  # twice is fine
    with pytest.raises(ValueError, match="closed"):
        m.dims
    with pytest.raises(ValueError, match="closed"):
        occseg.segment(m)
    r = occseg.segment(good())
    r.close()
    with pytest.raises(ValueError, match="closed"):
        r.states()
    assert r.labels.shape == (6, 7, 8) and len(r.segments) == 1  # copied data stays


def test_cancel_from_the_progress_callback():
    seen = []

    def progress(stage, fraction):
        seen.append((stage, fraction))
        return stage == "division"  # true: stop

    before = occseg.live_handles()
    msg = raises(Status.ECANCELLED, occseg.segment, good(), progress=progress)
    assert "division" in msg
    assert seen == [("texture", 0.0), ("texture", 1.0), ("division", 0.0)]
    assert occseg.live_handles() == before  # the temporary map and the parameters are freed


def test_exception_in_the_callback_cancels_and_is_reraised():
    class Boom(Exception):
        pass

    calls = []

    def progress(stage, fraction):
        calls.append(stage)
        if stage == "creation":
            raise Boom("from the callback")

    before = occseg.live_handles()
    with pytest.raises(Boom, match="from the callback"):
        occseg.segment(good(), progress=progress)
    assert calls == ["texture", "texture", "division", "division", "creation"]  # stopped there
    assert occseg.live_handles() == before
    # KeyboardInterrupt too: it must not be swallowed by ctypes
    with pytest.raises(KeyboardInterrupt):
        occseg.segment(good(), progress=lambda s, f: (_ for _ in ()).throw(KeyboardInterrupt()))


def test_error_pickles():
    import pickle
    try:
        occseg.segment(good(), smax=48)
    except OccsegError as e:
        back = pickle.loads(pickle.dumps(e))
        assert (back.status, back.message, str(back)) == (e.status, e.message, str(e))


def test_library_not_found_lists_every_place(tmp_path):
    import ctypes.util
    if ctypes.util.find_library("occseg"):
        pytest.skip("a system-wide liboccseg is installed: the lookup cannot fail here")
    env = dict(os.environ, OCCSEG_LIBRARY=str(tmp_path / "nowhere" / "liboccseg.so.0"))
    env.pop("LD_LIBRARY_PATH", None)
    r = subprocess.run([sys.executable, "-c", "import occseg"], env=env, capture_output=True, text=True,
                       cwd=tmp_path)
    assert r.returncode != 0
    err = r.stderr
    assert "ImportError" in err and "cannot load liboccseg.so.0" in err
    assert "OCCSEG_LIBRARY: " + str(tmp_path / "nowhere" / "liboccseg.so.0") + ": no such file" in err
    assert "the package's install location" in err and "the system library path: liboccseg.so.0" in err
    # a file that is not a library: the dlopen text is reported
    (tmp_path / "fake.so").write_bytes(b"not a library, " * 100)
    env["OCCSEG_LIBRARY"] = str(tmp_path / "fake.so")
    r = subprocess.run([sys.executable, "-c", "import occseg"], env=env, capture_output=True, text=True)
    assert str(tmp_path / "fake.so") + ": " in r.stderr and "invalid ELF header" in r.stderr, r.stderr
