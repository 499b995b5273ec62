"""2D robot maps from Python (issue 26): an int8 array is a ROS nav_msgs/OccupancyGrid (-1 unknown,
0..100 percent), and map_server .yaml maps are read by occseg.read_map; 2D maps get lbp8."""
import os

import numpy as np
import pytest

import occseg

DATA = os.path.join(os.path.dirname(__file__), "..", "..", "..", "shared", "data")


def room_grid():
    """An OccupancyGrid of a room with a box, as msg.data reshaped to (height, width): unknown
    outside, a wall of 100, free inside (0, with some cells at 10 %), a box of 95 near the top."""
    g = np.full((30, 40), -1, dtype=np.int8)
    g[2:28, 3:37] = 100
    g[3:27, 4:36] = 0
    g[3:27:4, 4:36:3] = 10
    g[20:24, 10:16] = 95
    return g


def states_of(result):
    return np.vectorize(lambda i: result.segments[i].state.name.lower())(result.labels)


def test_int8_is_an_occupancy_grid():
    g = room_grid()
    with occseg.Map.from_array(g, voxel_size=0.05, origin=(-2.0, -1.5, 0.0)) as m:
        p = m.to_array()
        assert m.dims == (40, 30, 1) and m.voxel_size == 0.05 and m.origin == (-2.0, -1.5, 0.0)
    assert p.shape == (1, 30, 40) and p.dtype == np.float32
    expect = np.where(g == -1, 0.5, g / 100.0).astype(np.float32)
    assert np.array_equal(p[0], expect)


def test_occupancy_grid_room_segments():
    g = room_grid()
    r = occseg.segment(g, voxel_size=0.05)
    assert r.labels.shape == g.shape  # [y, x] in, [y, x] out
    by_state = {}
    for s in r.segments:
        by_state.setdefault(s.state.name.lower(), []).append(s)
    assert {k: len(v) for k, v in by_state.items()} == {"free": 1, "unknown": 1, "occupied": 2}, by_state
    box = [s for s in by_state["occupied"] if s.voxels == 24]
    assert len(box) == 1
    assert (r.labels[20:24, 10:16] == box[0].id).all()
    st = states_of(r)
    assert (st[g == -1] == "unknown").all() and (st[g == 100] == "occupied").all() and (st[g == 0] == "free").all()
    # The same grid in floats gives the same segmentation: int8 is only a way in.
    f = np.where(g == -1, 0.5, g / 100.0)
    assert np.array_equal(occseg.segment(f).labels, r.labels)


def test_flipped_and_strided_views_are_read_in_place():
    g = room_grid()
    image = np.ascontiguousarray(g[::-1])  # stored top row first, as an image
    a = occseg.segment(image[::-1])  # a view with a negative stride, not copied
    b = occseg.segment(g)
    assert np.array_equal(a.labels, b.labels)


@pytest.mark.parametrize("bad", [101, -2, -128, 127])
def test_values_outside_the_occupancy_grid_range_name_the_first_cell(bad):
    g = room_grid()
    g[12, 7] = bad
    g[29, 39] = -5
    with pytest.raises(occseg.OccsegError) as e:
        occseg.segment(g, clamp=True, nan_unknown=True)  # no flag accepts them
    assert e.value.status == occseg.Status.EVALUE
    assert f"OccupancyGrid cell (7, 12, 0) = {bad} is neither -1 (unknown) nor an occupancy in 0..100" in e.value.message


def test_2d_maps_get_lbp8_unless_the_texture_is_set():
    assert {p.name: p.default for p in occseg.param_table()}["texture"] == "auto"
    rng = np.random.default_rng(5)
    g = rng.integers(0, 101, size=(64, 64)).astype(np.int8)
    g[40:55, 30:50] = np.where(rng.random((15, 20)) < 0.5, 30, 70)
    auto = occseg.segment(g, preset="paper")
    assert np.array_equal(auto.labels, occseg.segment(g, preset="paper", texture="lbp8").labels)
    lbp6 = occseg.segment(g, preset="paper", texture="lbp6")  # set: kept
    assert not np.array_equal(auto.labels, lbp6.labels)


def test_map_server_yaml_is_read_with_its_resolution_and_origin():
    path = os.path.join(DATA, "tb3_sandbox.yaml")
    with occseg.read_map(path) as m:
        assert m.dims == (384, 384, 1) and m.voxel_size == 0.05 and m.origin == (-10.0, -10.0, 0.0)
        r = occseg.segment(m)
    assert sum(s.state == occseg.State.OCCUPIED for s in r.segments) == 10  # the wall and the nine pillars


def test_bad_map_server_yaml_is_an_occseg_error(tmp_path):
    (tmp_path / "m.yaml").write_text("image: m.pgm\nresolution: 0.05\norigin: [0, 0, 0.3]\nnegate: 0\n"
                                     "occupied_thresh: 0.65\nfree_thresh: 0.196\n")
    with pytest.raises(occseg.OccsegError) as e:
        occseg.read_map(str(tmp_path / "m.yaml"))
    assert e.value.status == occseg.Status.EUNSUPPORTED and "origin yaw 0.3 is not 0" in e.value.message
