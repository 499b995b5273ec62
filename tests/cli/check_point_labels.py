"""Labels back on the input points (issue 26): `occseg segment cloud.pcd` writes points.labels.npy
(uint32, one label per input point in file order; a label image [height, width] for an organized
cloud) and points.pcd (the input cloud in its own frame with a `label` field). On the real table
scene every point's label is the label segments.pcd gives its voxel on the same run; NaN points
and points outside the grid (--bbox) get UINT32_MAX."""
import json
import os
import subprocess
import sys

import numpy as np

occseg, work, data = sys.argv[1], sys.argv[2], sys.argv[3]
NO_LABEL = 2**32 - 1
TABLE = os.path.join(data, "table_scene_mug_stereo_textured.pcd")


def run(*args):
    r = subprocess.run([occseg, *args], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    return r


def read_binary_pcd(path):
    """(header dict, structured array) of a DATA binary .pcd (as occseg writes them)."""
    raw = open(path, "rb").read()
    header, at = {}, 0
    while True:
        end = raw.index(b"\n", at)
        line = raw[at:end].decode()
        at = end + 1
        if line.startswith("#"):
            continue
        key, *vals = line.split()
        header[key] = vals
        if key == "DATA":
            assert vals == ["binary"], vals
            break
    kinds = {"F": "f", "U": "u", "I": "i"}
    dt = np.dtype([(name if name != "_" else f"pad{k}", f"<{kinds[t]}{s}", (int(c),) if int(c) > 1 else ())
                   for k, (name, s, t, c) in enumerate(zip(header["FIELDS"], header["SIZE"], header["TYPE"],
                                                           header["COUNT"]))])
    n = int(header["POINTS"][0])
    assert len(raw) - at == n * dt.itemsize, (len(raw) - at, n, dt.itemsize)
    return header, np.frombuffer(raw, dtype=dt, count=n, offset=at)


def nrrd_frame(path):
    """(corner of voxel (0, 0, 0), voxel size) of a map.nrrd written by occseg (origin = first centre)."""
    head = open(path, "rb").read(2000).split(b"\n\n")[0].decode()
    fields = dict(line.split(": ", 1) for line in head.splitlines()[1:] if ": " in line)
    centre = np.array([float(v) for v in fields["space origin"].strip("()").split(",")])
    vs = float(fields["space directions"].split(")")[0].strip("(").split(",")[0])
    return centre - vs / 2, vs


# The table scene: an organized 640 x 480 cloud, VIEWPOINT 0 0 0 0 1 0 0 (x, -y, -z).
out = os.path.join(work, "table")
run("segment", TABLE, "--voxel-size", "0.02", "--out", out, "--outputs", "default,points.pcd,segments.pcd,map.nrrd", "--quiet")
labels = np.load(os.path.join(out, "points.labels.npy"))
assert labels.dtype == np.uint32 and labels.shape == (480, 640), (labels.dtype, labels.shape)
doc = json.load(open(os.path.join(out, "segments.json")))
state = {s["id"]: s["state"] for s in doc["segments"]}

# The input points, from points.pcd: the cloud in its own frame, every field kept, labels added.
header, cloud = read_binary_pcd(os.path.join(out, "points.pcd"))
assert header["FIELDS"] == ["x", "y", "z", "rgba", "label"], header["FIELDS"]
assert header["WIDTH"] == ["640"] and header["HEIGHT"] == ["480"] and header["VIEWPOINT"] == "0 0 0 0 1 0 0".split()
assert np.array_equal(cloud["label"], labels.reshape(-1))
xyz = np.stack([cloud["x"], cloud["y"], cloud["z"]], axis=1).astype(np.float64)
finite = np.isfinite(xyz).all(axis=1)
assert finite.sum() == 209280, finite.sum()  # the file's finite points (../shared/data/README.md)
flat = labels.reshape(-1)
assert np.all(flat[~finite] == NO_LABEL) and np.all(flat[finite] != NO_LABEL)

# Every point's voxel (world = the VIEWPOINT's turn about x) against segments.pcd of the same run.
corner, vs = nrrd_frame(os.path.join(out, "map.nrrd"))
_, seg = read_binary_pcd(os.path.join(out, "segments.pcd"))
centres = np.stack([seg["x"], seg["y"], seg["z"]], axis=1).astype(np.float64)
dims = np.array(doc["dims"])
vid = np.rint((centres - corner) / vs - 0.5).astype(np.int64)
key = lambda v: v[:, 0] + dims[0] * (v[:, 1] + dims[1] * v[:, 2])  # noqa: E731
voxel_label = dict(zip(key(vid).tolist(), seg["label"].tolist()))
world = xyz[finite] * np.array([1.0, -1.0, -1.0])
frac = (world - corner) / vs
clear = np.all(np.abs(frac - np.rint(frac)) > 1e-4, axis=1)  # not on a voxel face (rounding)
pv = key(np.floor(frac).astype(np.int64))
mine = flat[finite]
in_pcd = np.array([v in voxel_label for v in pv.tolist()])
agree = np.array([voxel_label.get(v, -1) == l for v, l in zip(pv.tolist(), mine.tolist())])
assert np.all(agree[in_pcd & clear]), int((~agree[in_pcd & clear]).sum())
# the points whose voxel is not in segments.pcd (occupied voxels only) are in other segments
assert all(state[l] != "occupied" for l in mine[~in_pcd & clear].tolist())
assert in_pcd.mean() > 0.99, in_pcd.mean()  # returns lie in occupied voxels
print(f"table: {finite.sum()} points, {in_pcd.mean():.4%} in occupied segments, all agree with segments.pcd")

# points.pcd is a cloud occseg reads again: the same map and the same labels.
again = os.path.join(work, "again")
run("segment", os.path.join(out, "points.pcd"), "--voxel-size", "0.02", "--out", again, "--outputs", "default,map.nrrd", "--quiet")
assert open(os.path.join(again, "map.nrrd"), "rb").read() == open(os.path.join(out, "map.nrrd"), "rb").read()
assert np.array_equal(np.load(os.path.join(again, "points.labels.npy")), labels)

# An unorganized cloud: (N,) labels; NaN and points outside the --bbox get NO_LABEL.
small = os.path.join(work, "small.pcd")
pts = ["0.1 0.1 0.1", "0.3 0.1 0.1", "nan nan nan", "5 5 5", "0.15 0.35 0.25"]
with open(small, "w") as f:
    f.write("VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 5\nHEIGHT 1\n"
            "VIEWPOINT 0 0 0 1 0 0 0\nPOINTS 5\nDATA ascii\n" + "\n".join(pts) + "\n")
sout = os.path.join(work, "small")
run("segment", small, "--voxel-size", "0.1", "--bbox", "0", "0", "0", "0.5", "0.5", "0.5", "--out", sout,
    "--outputs", "default,points.pcd", "--quiet")
sl = np.load(os.path.join(sout, "points.labels.npy"))
assert sl.shape == (5,) and sl.dtype == np.uint32, (sl.shape, sl.dtype)
assert sl[2] == NO_LABEL and sl[3] == NO_LABEL, sl
assert all(v != NO_LABEL for v in sl[[0, 1, 4]]), sl
_, sc = read_binary_pcd(os.path.join(sout, "points.pcd"))
assert np.array_equal(sc["label"], sl) and np.isnan(sc["x"][2])
# a grid input has none of these files
grid = os.path.join(work, "grid.npy")
np.save(grid, np.full((4, 5, 6), 0.2, np.float32))
gout = os.path.join(work, "grid")
run("segment", grid, "--out", gout, "--quiet")
assert not {"points.labels.npy", "points.pcd"} & set(os.listdir(gout)), os.listdir(gout)
print("point labels: ok")
