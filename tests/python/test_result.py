"""The result's helpers agree with its segment table, and the rest of the package surface."""
import re

import numpy as np
import pytest

import occseg
from conftest import noisy_scene


@pytest.fixture(scope="module")
def result():
    r = occseg.segment(noisy_scene().astype(np.float32), voxel_size=0.05, origin=(1.0, -2.0, 0.5))
    yield r
    r.close()


def test_segment_table_matches_labels(result):
    labels = result.labels
    assert [s.id for s in result.segments] == list(range(len(result.segments)))
    assert {s.state for s in result.segments} == set(occseg.State)
    counts = np.bincount(labels.ravel(), minlength=len(result.segments))
    assert counts.tolist() == [s.voxels for s in result.segments]
    assert int(labels.max()) == len(result.segments) - 1
    assert not labels.flags.writeable


def test_voxels_mask_and_points(result):
    for s in result.segments:
        v = result.voxels(s.id)
        assert v.shape == (s.voxels, 3) and v.dtype == np.int64
        assert tuple(v.min(axis=0)) == s.bbox[0] and tuple(v.max(axis=0)) == s.bbox[1]
        assert np.allclose(v.mean(axis=0), s.centroid, rtol=0, atol=1e-9)
        assert np.all(result.labels[v[:, 2], v[:, 1], v[:, 0]] == s.id)
        mask = result.mask(s.id)
        assert mask.dtype == bool and mask.sum() == s.voxels
        assert np.array_equal(np.argwhere(mask)[:, ::-1], v)  # same voxels, same order (x fastest)
        assert (result.labels[s.slices] == s.id).sum() == s.voxels  # the box holds the whole segment
        p = result.points(s.id)
        assert np.allclose(p, np.array([1.0, -2.0, 0.5]) + (v + 0.5) * 0.05)


def test_states_match_segment_states(result):
    table = np.array([s.state for s in result.segments], dtype=np.uint8)
    st = result.states()
    assert st.dtype == np.uint8 and st.shape == result.labels.shape
    assert np.array_equal(st, table[result.labels])


def test_timings_and_metadata(result):
    assert list(result.timings) == ["texture", "division", "creation", "refinement", "labelling"]
    assert all(t >= 0 for t in result.timings.values())
    assert result.voxel_size == 0.05 and result.origin == (1.0, -2.0, 0.5)
    assert result.dims == (52, 44, 36) and result.shape == (36, 44, 52)
    assert re.fullmatch(r"<occseg.Result dims=\(52, 44, 36\) segments=\d+ \(free \d+, unknown \d+, occupied \d+\)>",
                        repr(result))


def test_progress_reports_every_stage_in_order():
    seen = []
    occseg.segment(noisy_scene(), progress=lambda stage, f: seen.append((stage, f)))
    stages = ["texture", "division", "creation", "refinement", "labelling"]
    assert seen == [(s, f) for s in stages for f in (0.0, 1.0)]


def test_threads_do_not_change_results():
    m = noisy_scene(seed=9)
    a, b = occseg.segment(m, threads=1), occseg.segment(m, threads=3)
    assert np.array_equal(a.labels, b.labels) and a.segments == b.segments


def test_map_properties(tmp_path):
    m = np.random.default_rng(2).uniform(0, 1, size=(5, 6, 7))
    with occseg.Map.from_array(m, voxel_size=0.1, origin=(1, 2, 3)) as mm:
        assert mm.dims == (7, 6, 5) and mm.shape == (5, 6, 7)
        assert mm.voxel_size == 0.1 and mm.origin == (1.0, 2.0, 3.0)
        mm.voxel_size, mm.origin = 0.25, (-1, 0, 4.5)
        assert mm.voxel_size == 0.25 and mm.origin == (-1.0, 0.0, 4.5)
        mm.write(tmp_path / "w.npy")
        assert "dims=(7, 6, 5)" in repr(mm)
        r = mm.segment()
        assert r.voxel_size == 0.25 and r.origin == (-1.0, 0.0, 4.5)
    back = np.load(tmp_path / "w.npy")
    assert back.dtype == np.float32 and np.array_equal(back, m.astype(np.float32))
    assert repr(mm) == "<occseg.Map closed>"


def test_param_table_and_version():
    table = {p.name: p for p in occseg.param_table()}
    assert {"preset", "smax", "smin", "split_ratio", "threads"} <= set(table)
    assert table["smax"].kind == "int" and table["split_ratio"].kind == "double" and table["preset"].kind == "string"
    assert table["smax"].min <= 64 <= table["smax"].max and table["smax"].description
    assert re.fullmatch(r"\d+\.\d+\.\d+", occseg.version())
    major, minor, patch = map(int, occseg.version().split("."))
    assert occseg.version_number() == major * 10000 + minor * 100 + patch and major == 0


def test_library_path_is_the_one_loaded():
    import os
    lib = os.environ.get("OCCSEG_LIBRARY")
    assert lib and occseg.library_path() == os.path.realpath(lib)


def test_plugin_functions_only_with_a_library_that_has_them():
    from occseg import _lib
    assert hasattr(occseg, "load_plugin") == _lib.has("occseg_plugins_load")
    assert hasattr(occseg, "plugins") == hasattr(occseg, "load_plugin")


def test_concurrent_calls_from_python_threads():
    """ctypes releases the GIL during occseg_segment: threads run at once, each with its own
    error text, and get what sequential calls get."""
    import threading
    maps = [noisy_scene(seed=s, shape=(36, 44, 52)) for s in range(4)]
    expected = [occseg.segment(m, threads=1).labels for m in maps]
    got, errors = [None] * 4, [None] * 4

    def work(i):
        for _ in range(3):
            got[i] = occseg.segment(maps[i], threads=1).labels
            try:
                occseg.segment(maps[i], smax=3 + i * 2)  # odd: never a power of two
            except occseg.OccsegError as e:
                errors[i] = e.message

    threads = [threading.Thread(target=work, args=(i,)) for i in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for i in range(4):
        assert np.array_equal(got[i], expected[i])
        assert f"smax': {3 + i * 2} is not a power of two" in errors[i], errors[i]
