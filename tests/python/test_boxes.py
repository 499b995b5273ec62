"""Oriented boxes (Result.boxes / Result.box, occseg_result_segment_box), the segment palette, the
collision-box example (bindings/examples/collision_boxes.py) and Result.to_open3d."""
import json
import math
import os
import re
import subprocess
import sys

import numpy as np
import pytest

import occseg

ROOT = os.path.join(os.path.dirname(__file__), "..", "..")
EXAMPLE = os.path.join(ROOT, "bindings", "examples", "collision_boxes.py")


def test_axis_aligned_box_is_its_voxel_box_in_metres():
    m = np.full((16, 20, 24), 0.12, np.float32)
    m[2:6, 5:11, 3:13] = 0.97  # z, y, x: 4 x 6 x 10 voxels
    with occseg.segment(m, voxel_size=0.05, origin=(1.0, -2.0, 0.5)) as r:
        (obj,) = [s for s in r.segments if s.state == occseg.State.OCCUPIED]
        b = r.box(obj.id)
        assert len(r.boxes()) == len(r.segments)
    assert b.quaternion == (1.0, 0.0, 0.0, 0.0)
    assert b.extents == pytest.approx((0.5, 0.3, 0.2), abs=1e-12)
    assert b.center == pytest.approx((1.0 + 0.4, -2.0 + 0.4, 0.5 + 0.2), abs=1e-12)
    assert np.allclose(b.rotation(), np.eye(3))
    assert r.box(obj.id) == b  # kept after close()


def test_box_turned_about_z_holds_every_voxel():
    nz, ny, nx = 16, 40, 40
    z, y, x = np.meshgrid(*(np.arange(n) + 0.5 for n in (nz, ny, nx)), indexing="ij")
    a = math.radians(25)
    u = math.cos(a) * (x - 20.2) + math.sin(a) * (y - 19.7)
    v = -math.sin(a) * (x - 20.2) + math.cos(a) * (y - 19.7)
    m = np.where((abs(u) <= 11) & (abs(v) <= 4.5) & (abs(z - 8) <= 3), 0.97, 0.12).astype(np.float32)
    with occseg.segment(m, voxel_size=0.1) as r:
        (obj,) = [s for s in r.segments if s.state == occseg.State.OCCUPIED]
        b = r.box(obj.id)
        pts = r.points(obj.id)
    rot = b.rotation()
    longest = int(np.argmax(b.extents))
    axis = rot[:, longest]
    err = (math.atan2(axis[1], axis[0]) - a + math.pi / 2) % math.pi - math.pi / 2
    assert abs(err) <= math.atan(0.5 / 11)  # half a voxel at the ends of the long side
    assert sorted(b.extents)[2] == pytest.approx(2.2, abs=0.05 + 0.137)  # 22 voxels, + up to a voxel's diagonal
    local = (pts - np.asarray(b.center)) @ rot  # voxel centres in the box's frame
    assert np.all(np.abs(local) <= np.asarray(b.extents) / 2 + 1e-9)


def test_box_errors_and_closed_result():
    m = np.full((8, 8, 8), 0.1, np.float32)
    m[2:4, 2:4, 2:4] = 0.9
    r = occseg.segment(m)
    with pytest.raises(occseg.OccsegError) as e:
        r.box(len(r.segments))
    assert e.value.status == occseg.Status.ERANGE
    with pytest.raises(occseg.OccsegTypeError):
        r.box(1.0)
    r.close()
    with pytest.raises(ValueError):
        r.boxes()  # never computed before close(): the C result is gone


def test_palette_is_the_one_of_every_output():
    header = open(os.path.join(ROOT, "adapters", "include", "occseg", "segment_colour.hpp")).read()
    body = header.split("hues[kSegmentPaletteSize] = {", 1)[1].split("};", 1)[0]
    hues = tuple(tuple(int(v) for v in t) for t in re.findall(r"\{(\d+), (\d+), (\d+)\}", body))
    assert len(hues) == 16 and hues == occseg._result.SEGMENT_HUES
    assert occseg.segment_colour(0) == hues[0] and occseg.segment_colour(1) == hues[(2654435761 >> 16) % 16]


def test_collision_box_example():
    r = subprocess.run([sys.executable, EXAMPLE, "--json"], capture_output=True, text=True, env=os.environ)
    assert r.returncode == 0, r.stderr
    boxes = json.loads(r.stdout)
    assert len(boxes) == 2
    table, shelf = sorted(boxes, key=lambda b: b["position"][1])
    # The shelf, axis-aligned: exactly its voxels, 60 x 8 x 36 of 2.5 cm.
    assert shelf["orientation"] == [0, 0, 0, 1]
    assert shelf["size"] == pytest.approx([1.5, 0.2, 0.9])
    assert shelf["position"] == pytest.approx([1.0, 1.85, 0.45])
    # The table, turned by 30 degrees about z: 0.8 x 0.4 m (+ at most a voxel's diagonal), 0.75 m high.
    x, y, z, w = table["orientation"]
    assert abs(x) < 1e-9 and abs(y) < 1e-9
    yaw = math.degrees(2 * math.atan2(z, w)) % 90
    assert min(abs(yaw - 30), abs(yaw - 30 + 90), abs(yaw - 30 - 90)) < math.degrees(math.atan(0.5 / 16))
    long_side, short_side = sorted(table["size"][:2], reverse=True)
    assert 0.8 - 0.0125 <= long_side <= 0.8 + 0.035 + 0.0125
    assert 0.4 - 0.0125 <= short_side <= 0.4 + 0.035 + 0.0125
    assert table["size"][2] == pytest.approx(0.75)


def test_to_open3d_without_open3d_says_what_to_install():
    code = ("import sys; sys.modules['open3d'] = None\nimport numpy as np, occseg\n"
            "m = np.full((4, 4, 4), 0.1, np.float32); m[1:3, 1:3, 1:3] = 0.9\n"
            "r = occseg.segment(m)\ntry:\n    r.to_open3d()\nexcept ImportError as e:\n    print('ImportError:', e)\n")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=os.environ)
    assert r.returncode == 0, r.stderr
    assert r.stdout.startswith("ImportError: occseg.Result.to_open3d needs Open3D")
    assert "apt-get install python3-open3d" in r.stdout


def test_to_open3d_with_open3d():
    o3d = pytest.importorskip("open3d")
    m = np.full((4, 4, 4), 0.1, np.float32)
    m[1:3, 1:3, 1:3] = 0.9
    with occseg.segment(m, voxel_size=0.5) as r:
        pcd = r.to_open3d()
        grid = r.to_open3d("voxels")
    assert len(pcd.points) == 8
    assert np.allclose(np.asarray(pcd.colors), np.asarray(occseg.segment_colour(1)) / 255)
    assert isinstance(grid, o3d.geometry.VoxelGrid) and len(grid.get_voxels()) == 8
