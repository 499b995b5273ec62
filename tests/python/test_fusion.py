"""Clouds as arrays (issue 26): occseg.fuse / occseg.Fusion give the map of the .pcd path bit for
bit, and Result.point_labels puts the segmentation back on the input points.

The real clouds are read here by a small independent .pcd reader (binary_compressed: LZF, fields
stored one after the other), so the arrays do not come from occseg itself."""
import os
import struct

import numpy as np
import pytest

import occseg
from occseg import OccsegError, Status

DATA = os.environ.get("OCCSEG_SHARED_DATA", os.path.join(os.path.dirname(__file__), "..", "..", "..", "shared", "data"))

TABLE = "table_scene_mug_stereo_textured.pcd"
OFFICE = "office1.pcd"


def lzf_decompress(src, size):
    """liblzf's lzf_decompress: literal runs (ctrl < 32) and back references."""
    out = bytearray(size)
    i = o = 0
    while i < len(src):
        ctrl = src[i]
        i += 1
        if ctrl < 32:
            n = ctrl + 1
            out[o:o + n] = src[i:i + n]
            i += n
            o += n
            continue
        n = ctrl >> 5
        ref = o - ((ctrl & 0x1F) << 8) - 1
        if n == 7:
            n += src[i]
            i += 1
        ref -= src[i]
        i += 1
        n += 2
        period = o - ref
        if n <= period:
            out[o:o + n] = out[ref:ref + n]
        else:  # overlapping: the last `period` bytes repeat
            chunk = bytes(out[ref:o])
            out[o:o + n] = (chunk * (n // period + 1))[:n]
        o += n
    assert o == size
    return bytes(out)


def read_pcd(path):
    """(points float32 (H, W, 3) in the file's frame, VIEWPOINT origin (3,), orientation (w, x, y, z)),
    for the binary_compressed and binary files with float x y z fields used here."""
    with open(path, "rb") as f:
        data = f.read()
    header, at = {}, 0
    while True:
        end = data.index(b"\n", at)
        line = data[at:end].decode().strip()
        at = end + 1
        if not line or line.startswith("#"):
            continue
        key, *vals = line.split()
        header[key] = vals
        if key == "DATA":
            break
    fields, sizes, counts = header["FIELDS"], [int(s) for s in header["SIZE"]], [int(c) for c in header.get("COUNT", ["1"] * len(header["FIELDS"]))]
    w, h = int(header["WIDTH"][0]), int(header["HEIGHT"][0])
    n = w * h
    kind = header["DATA"][0]
    cols = {}
    if kind == "binary_compressed":
        csize, usize = struct.unpack_from("<II", data, at)
        raw = lzf_decompress(data[at + 8:at + 8 + csize], usize)
        off = 0
        for name, size, count in zip(fields, sizes, counts):
            cols[name] = raw[off:off + n * size * count]
            off += n * size * count
        xyz = np.stack([np.frombuffer(cols[c], dtype="<f4") for c in "xyz"], axis=-1)
    else:
        assert kind == "binary"
        dt = np.dtype([(name if name != "_" else f"_{k}", f"V{size * count}") for k, (name, size, count)
                       in enumerate(zip(fields, sizes, counts))])
        rec = np.frombuffer(data, dtype=dt, count=n, offset=at)
        xyz = np.stack([np.frombuffer(rec[c].tobytes(), dtype="<f4") for c in "xyz"], axis=-1)
    vp = [float(v) for v in header.get("VIEWPOINT", "0 0 0 1 0 0 0".split())]
    # PCL keeps the VIEWPOINT in float: the pose the .pcd path uses is the float one.
    vp = [float(np.float32(v)) for v in vp]
    return xyz.reshape(h, w, 3).astype(np.float32), tuple(vp[:3]), tuple(vp[3:])


@pytest.fixture(scope="module")
def pcd_reader():
    plugin_dir = os.environ.get("OCCSEG_READER_PLUGINS")
    if not plugin_dir or not os.path.exists(os.path.join(plugin_dir, "occseg_pcl_reader.so")):
        pytest.skip("no PCL reader plugin in this build")
    os.environ["OCCSEG_PLUGIN_PATH"] = plugin_dir
    occseg.load_default_plugins()
    return plugin_dir


@pytest.fixture(scope="module")
def clouds():
    return {name: read_pcd(os.path.join(DATA, name)) for name in (TABLE, OFFICE)}


def same_map(a, b):
    assert a.dims == b.dims
    assert a.voxel_size == b.voxel_size
    assert a.origin == b.origin  # exactly
    x, y = a.to_array(), b.to_array()
    assert np.array_equal(x.view(np.uint32), y.view(np.uint32))  # every value, bit for bit


@pytest.mark.parametrize("name,voxel_size,layout", [(TABLE, 0.02, "organized"), (TABLE, 0.05, "float64"),
                                                    (OFFICE, 0.05, "list"), (OFFICE, 0.03, "strided")])
def test_fuse_equals_the_pcd_reader(pcd_reader, clouds, name, voxel_size, layout):
    """Points and VIEWPOINT of the file as arrays: the map of occseg.read_map on the file, bit for
    bit (dims, origin, every value), whatever the array's layout; NaN points skipped alike."""
    xyz, origin, orientation = clouds[name]
    assert np.isnan(xyz).any()  # organized clouds carry NaN holes
    pts = {"organized": xyz, "float64": xyz.astype(np.float64), "list": xyz.reshape(-1, 3),
           "strided": np.concatenate([xyz.reshape(-1, 3), np.ones((xyz.size // 3, 1), np.float32)], axis=1)[:, :3]}[layout]
    with occseg.read_map(os.path.join(DATA, name), voxel_size=voxel_size) as ref, \
            occseg.fuse(pts, origin=origin, orientation=orientation, voxel_size=voxel_size) as m:
        same_map(m, ref)


def test_fuse_with_a_box_equals_the_pcd_reader_with_the_box(pcd_reader, clouds):
    xyz, origin, orientation = clouds[TABLE]
    box = (-0.5, -0.6, -2.7, 0.7, 0.4, 0.1)
    with occseg.read_map(os.path.join(DATA, TABLE), voxel_size=0.04, bbox=",".join(map(str, box))) as ref, \
            occseg.fuse(xyz, origin, orientation, voxel_size=0.04, bbox=box) as m:
        same_map(m, ref)
        assert m.origin == box[:3]


def test_several_scans_fitted_box_equals_fixed_box(clouds):
    """Scans from several poses in turn: fitting the box at the end (buffered scans) gives the map
    of ray-casting each scan at once into that same box given up front."""
    xyz, origin, orientation = clouds[TABLE]
    half = np.sqrt(0.5)
    poses = [(origin, orientation), ((0.3, 0.0, 0.1), (0.0, 1.0, 0.0, 0.0)),
             ((0.0, 0.2, 0.0), (0.0, half, half, 0.0))]  # another turn about the x/y diagonal
    with occseg.Fusion(voxel_size=0.04) as f:
        for o, q in poses:
            f.add(xyz, origin=o, orientation=q)
        assert f.scans == 3 and f.points == 3 * int(np.isfinite(xyz).all(axis=-1).sum())
        fitted = f.map()
    with fitted:
        lo = np.array(fitted.origin)
        hi = lo + np.array(fitted.dims) * fitted.voxel_size
        with occseg.Fusion(voxel_size=0.04, bbox=(*lo, *hi)) as g:
            for o, q in poses:
                g.add(xyz, o, q)
            with g.map() as fixed:
                same_map(fixed, fitted)
            # a later map() still holds every scan, and more can come
            g.add(xyz[:100], poses[0][0], poses[0][1])
            with g.map() as more:
                assert more.dims == fitted.dims
        with occseg.fuse(xyz, *poses[0], voxel_size=0.04) as one:
            assert one.dims != fitted.dims  # the other scans did widen the box


def test_the_quaternion_is_normalised_as_for_the_pcd_path(clouds):
    xyz = clouds[TABLE][0][::4, ::4]
    with occseg.fuse(xyz, (0, 0, 0), (0, 1, 0, 0), voxel_size=0.05) as a, \
            occseg.fuse(xyz, (0, 0, 0), (0, 3.5, 0, 0), voxel_size=0.05) as b:
        same_map(a, b)


def refused(status, fn, *args, **kw):
    with pytest.raises(OccsegError) as e:
        fn(*args, **kw)
    assert e.value.status == status, str(e.value)
    return str(e.value)


def test_bad_input_is_refused_with_a_message():
    p = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], np.float32)
    assert "voxel_size" in refused(Status.EVALUE, occseg.fuse, p, voxel_size=0.0)
    assert "voxel_size" in refused(Status.EVALUE, occseg.fuse, p, voxel_size=-1.0)
    assert "sensor origin" in refused(Status.EVALUE, occseg.fuse, p, origin=(np.nan, 0, 0))
    assert "orientation" in refused(Status.EVALUE, occseg.fuse, p, orientation=(1, np.nan, 0, 0))
    assert "zero" in refused(Status.EVALUE, occseg.fuse, p, orientation=(0, 0, 0, 0))
    assert "no point" in refused(Status.EINVAL, occseg.fuse, np.zeros((0, 3), np.float32))
    assert "no finite point" in refused(Status.EVALUE, occseg.fuse, np.full((4, 3), np.nan, np.float32))
    assert "dtype" in refused(Status.EINVAL, occseg.fuse, p.astype(np.int32))
    assert "shape" in refused(Status.EINVAL, occseg.fuse, p[:, :2])
    assert "(w, x, y, z)" in refused(Status.EINVAL, occseg.fuse, p, orientation=(1, 0, 0))
    assert "voxels" in refused(Status.EDIMS, occseg.fuse, np.array([[0, 0, 0], [1e5, 1e5, 0]], np.float64),
                               voxel_size=1e-3)
    assert "bounding box" in refused(Status.EVALUE, occseg.fuse, p, bbox=(0, 0, 0, 0, 1, 1))
    assert "out of range" in refused(Status.EVALUE, occseg.fuse, np.array([[1e300, 0, 0]]), voxel_size=1.0)
    # a refused scan leaves the fusion as it was
    with occseg.Fusion(voxel_size=0.1) as f:
        f.add(p)
        refused(Status.EDIMS, f.add, np.array([[6e7, 6e7, 0]]))
        assert f.scans == 1
        with f.map() as m:
            assert m.dims[0] < 100


def test_point_labels_organized_cloud(clouds):
    """A label image (H, W) for an organized cloud: NaN pixels NO_LABEL, every other pixel the label
    of the voxel its return went into (computed here as the fusion computes it)."""
    xyz, origin, orientation = clouds[TABLE]
    with occseg.fuse(xyz, origin, orientation, voxel_size=0.02) as m, m.segment() as r:
        img = r.point_labels(xyz, origin=origin, orientation=orientation)
        assert img.shape == xyz.shape[:2] and img.dtype == np.uint32
        finite = np.isfinite(xyz).all(axis=-1)
        assert np.all(img[~finite] == occseg.NO_LABEL)
        assert np.all(img[finite] != occseg.NO_LABEL)  # the fitted box holds every point
        # the voxel of each point, as the fusion computes it: relative to the grid corner, in float
        q = np.array(orientation)
        rot = {(0.0, 1.0, 0.0, 0.0): np.diag([1.0, -1.0, -1.0])}[tuple(q)]
        o = np.array(m.origin)
        p = xyz[finite].astype(np.float64)
        rel = (p @ rot.T + (np.array(origin) - o)).astype(np.float32).astype(np.float64)
        a = (np.array(origin) - o) / m.voxel_size
        b = rel / m.voxel_size
        idx = np.clip(np.floor(a + (b - a)).astype(np.int64), 0, np.array(m.dims) - 1)
        labels = r.labels.reshape(-1)
        nx, ny, _ = m.dims
        expect = labels[idx[:, 0] + nx * (idx[:, 1] + ny * idx[:, 2])]
        assert np.array_equal(img[finite], expect)
        # most returns lie in occupied segments
        occupied = np.array([s.state == occseg.State.OCCUPIED for s in r.segments])
        assert occupied[img[finite]].mean() > 0.99
        # the same as a flat (N, 3) cloud in float64
        flat = r.point_labels(xyz.reshape(-1, 3).astype(np.float64), origin, orientation)
        assert np.array_equal(flat, img.reshape(-1))


def test_point_labels_outside_the_grid_and_bad_input(clouds):
    p = np.array([[0.05, 0.05, 0.05], [0.95, 0.95, 0.95], [5.0, 0.0, 0.0], [np.inf, 0, 0], [-0.01, 0.5, 0.5]])
    m = occseg.Map.from_array(np.full((10, 10, 10), 0.9, np.float32), voxel_size=0.1)
    with m, m.segment() as r:
        lab = r.point_labels(p)
        assert lab.tolist() == [0, 0, occseg.NO_LABEL, occseg.NO_LABEL, occseg.NO_LABEL]
        # the pose moves the points: shifted by -0.5, the first two fall outside too
        assert r.point_labels(p, origin=(-0.5, 0, 0)).tolist()[:2] == [occseg.NO_LABEL, 0]
        assert "orientation" in refused(Status.EVALUE, r.point_labels, p, orientation=(0, 0, 0, 0))
        assert "no point" in refused(Status.EINVAL, r.point_labels, p[:0])
    with pytest.raises(ValueError):
        r.point_labels(p)  # closed
