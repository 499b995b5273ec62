"""Runs `occseg segment` on every input kind (.npy .nrrd .pcd .graph .bt .ot) as a user would and
checks the outputs: labels.npy, labels.nrrd (same labels, grid geometry), segments.json,
map.nrrd for non-grid inputs and segments.pcd (occupied voxels, label = segment id) for clouds."""
import gzip
import json
import os
import re
import subprocess
import sys

import numpy as np

occseg, work = sys.argv[1], sys.argv[2]
data = os.path.normpath(os.path.join(os.path.dirname(__file__), "..", "..", "..", "shared", "data"))


def run(*args):
    r = subprocess.run([occseg, *args], capture_output=True, text=True)
    return r


def read_nrrd(path):
    b = open(path, "rb").read()
    i = b.index(b"\n\n")
    head = b[:i].decode()
    fields = dict(line.split(": ", 1) for line in head.splitlines()[1:] if ": " in line)
    dt = {"float": "<f4", "uint32": "<u4"}[fields["type"]]
    nx, ny, nz = map(int, fields["sizes"].split())
    vs = float(re.match(r"\(([^,]+),", fields["space directions"]).group(1))
    origin = [float(v) for v in fields["space origin"].strip("()").split(",")]
    data = gzip.decompress(b[i + 2:]) if fields["encoding"] == "gzip" else b[i + 2:]
    return np.frombuffer(data, dtype=dt).reshape(nz, ny, nx), vs, origin


def read_pcd_xyzl(path):
    b = open(path, "rb").read()
    i = b.index(b"DATA binary\n") + len(b"DATA binary\n")
    head = b[:i].decode()
    assert "FIELDS x y z label" in head, head
    n = int(re.search(r"POINTS (\d+)", head).group(1))
    rec = np.frombuffer(b[i:], dtype=[("x", "<f4"), ("y", "<f4"), ("z", "<f4"), ("label", "<u4")])
    assert len(rec) == n
    return rec


def check(name, args, cloud=False, grid=False, octomap=False):
    out = os.path.join(work, name)
    r = run("segment", *args, "--out", out, "--outputs", "all")
    assert r.returncode == 0, (name, r.stderr)
    files = sorted(os.listdir(out))
    want = ["labels.npy", "labels.nrrd", "scene.png", "segmentation.png", "segments.json"] + ([] if grid else ["map.nrrd"]) + (
        ["segments.pcd"] if cloud else []) + (["points.labels.npy", "points.pcd"] if name.startswith("pcd") else []) + (
        ["segments.ot", "segments.ply"])  # --outputs all: segments.ot applies to any input
    assert files == sorted(want), (name, files)
    if octomap:  # a ColorOcTree at the map's voxel size (its leaves: tests/adapters/test_segments_octree.cpp)
        head = open(os.path.join(out, "segments.ot"), "rb").read(200).split(b"\ndata\n")[0].decode()
        assert head.startswith("# Octomap OcTree file") and "\nid ColorOcTree\n" in head, head
        res = float(re.search(r"\nres (\S+)", head).group(1))
        vs_json = json.load(open(os.path.join(out, "segments.json")))["voxel_size"]
        assert res == vs_json, (res, vs_json)
    check.stderr = r.stderr
    labels = np.load(os.path.join(out, "labels.npy"))
    lab_nrrd, vs, origin = read_nrrd(os.path.join(out, "labels.nrrd"))
    assert np.array_equal(labels, lab_nrrd), name
    doc = json.load(open(os.path.join(out, "segments.json")))
    assert doc["dims"] == [labels.shape[2], labels.shape[1], labels.shape[0]], name
    states = np.array([s["state"] for s in doc["segments"]])
    if not grid:
        m, vs2, origin2 = read_nrrd(os.path.join(out, "map.nrrd"))
        assert m.shape == labels.shape and vs2 == vs and origin2 == origin, name
        assert ((m >= 0) & (m <= 1)).all()
    if cloud:
        pts = read_pcd_xyzl(os.path.join(out, "segments.pcd"))
        occupied = states[labels] == "occupied"
        assert len(pts) == occupied.sum(), (name, len(pts), occupied.sum())
        corner = np.array(origin) - vs / 2
        ijk = np.floor((np.stack([pts["x"], pts["y"], pts["z"]], 1) - corner) / vs).astype(int)
        assert np.array_equal(labels[ijk[:, 2], ijk[:, 1], ijk[:, 0]], pts["label"]), name
    return labels, doc, vs, origin


# A grid as .npy, then the same map through .nrrd (written by the tool itself as map.nrrd of a
# cloud run below would be; here: by hand, with an origin).
m = np.full((20, 24, 28), 0.12, dtype=np.float32)
m[4:10, 4:10, 4:10] = 0.97
np.save(os.path.join(work, "map.npy"), m)
lab_npy, _, _, _ = check("npy", [os.path.join(work, "map.npy"), "--voxel-size", "0.1"], grid=True)
hdr = ("NRRD0004\ntype: float\ndimension: 3\nspace: right-anterior-superior\nsizes: 28 24 20\nspace directions: (0.1,0,0) (0,0.1,0) "
       "(0,0,0.1)\nendian: little\nencoding: raw\nspace origin: (1.05,2.05,3.05)\n\n")
with open(os.path.join(work, "map.nrrd"), "wb") as f:
    f.write(hdr.encode() + m.tobytes())
lab_nrrd, _, vs, origin = check("nrrd", [os.path.join(work, "map.nrrd")], grid=True)
assert np.array_equal(lab_npy, lab_nrrd) and vs == 0.1 and origin == [1.05, 2.05, 3.05], origin

check("pcd", [os.path.join(data, "table_scene_mug_stereo_textured.pcd"), "--voxel-size", "0.03"], cloud=True)
check("graph", [os.path.join(data, "spherical_scan.graph"), "--voxel-size", "0.1"], cloud=True, octomap=True)
labels, doc, vs, origin = check("bt", [os.path.join(data, "geb079.bt"), "--voxel-size", "0.16",
                                       "--bbox", "-8", "-7.52", "-0.32", "8", "7.44", "2.8"], octomap=True)
assert abs(vs - 0.16) < 1e-12 and labels.shape == (20, 94, 100), labels.shape
assert "note:" not in check.stderr, check.stderr  # the box is on the 0.16 m lattice
# A box starting at y = -7.44 m: 46.5 voxels of 0.16 m, off OctoMap's lattice: segments.ot moves.
check("bt_off_lattice", [os.path.join(data, "geb079.bt"), "--voxel-size", "0.16",
                         "--bbox", "-8", "-7.44", "-0.32", "8", "7.44", "2.8"], octomap=True)
assert "segments.ot: the map's origin is not a whole number of 0.16 m voxels" in check.stderr, check.stderr
assert "moved by (0, -0.08, 0) m" in check.stderr, check.stderr

# Options a format cannot use, unknown extensions, missing files: exit codes and messages.
r = run("segment", os.path.join(work, "map.npy"), "--sensor-origin", "0", "0", "0", "--out", os.path.join(work, "x"))
assert r.returncode == 1 and "does not apply" in r.stderr, r.stderr
r = run("segment", os.path.join(work, "map.xyz"), "--out", os.path.join(work, "x"))
assert r.returncode == 1 and "unknown input type" in r.stderr, r.stderr
r = run("segment", os.path.join(work, "nothere.pcd"), "--out", os.path.join(work, "x"))
assert r.returncode == 2 and "nothere.pcd" in r.stderr, r.stderr
r = run("segment", os.path.join(data, "geb079.bt"), "--voxel-size", "0.1", "--out", os.path.join(work, "x"))
assert r.returncode == 1 and "multiple" in r.stderr, r.stderr
assert not os.path.exists(os.path.join(work, "x", "labels.npy"))
print("cli inputs: 6 input kinds checked")
