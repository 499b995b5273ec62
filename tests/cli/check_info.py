"""`occseg info FILE` for every input format: format, dims, voxel size, origin, value range,
voxels per state, never-observed voxels; text and --json; checked against values computed here
or recorded from the data's own tools (tests/adapters), never against occseg's own output."""
import json
import os
import struct
import subprocess
import sys

import numpy as np

occseg, work, data = sys.argv[1], sys.argv[2], sys.argv[3]


def run(*args):
    return subprocess.run([occseg, *args], capture_output=True, text=True, cwd=work, timeout=300)


def info(*args):
    r = run("info", *args, "--json")
    assert r.returncode == 0 and r.stderr == "", (args, r.returncode, r.stderr)  # OctoMap's chatter too
    return json.loads(r.stdout)


# .npy: every statistic computed with numpy. [z, y, x] = (6, 5, 4).
m = np.full((6, 5, 4), 0.2, dtype=np.float32)
m[0, 0, 0] = 0.05
m[1:3, 1:3, 1:3] = 0.9
m[5] = 0.5
m[4, 4, 3] = 0.499  # unknown by the thresholds, but observed
np.save(os.path.join(work, "small.npy"), m)
j = info("small.npy", "--voxel-size", "0.25")
assert j["file"] == "small.npy" and j["format"] == "NumPy .npy, float32, C order", j
assert j["dims"] == [4, 5, 6] and j["voxels"] == 120 and j["voxel_size"] == 0.25, j
assert j["origin"] == [0, 0, 0] and j["extent_m"]["max"] == [1.0, 1.25, 1.5], j
assert abs(j["values"]["min"] - 0.05) < 1e-7 and abs(j["values"]["max"] - 0.9) < 1e-7, j["values"]
assert abs(j["values"]["mean"] - float(m.astype(np.float64).mean())) < 1e-9, j["values"]
free, occ = int((m < 0.498).sum()), int((m > 0.502).sum())
assert j["states"] == {"free": free, "unknown": 120 - free - occ, "occupied": occ} == \
    {"free": 91, "unknown": 21, "occupied": 8}, j["states"]
assert j["unobserved"] == 20, j
# The thresholds follow the preset and --param.
j = info("small.npy", "--param", "free_below=0.1", "--param", "occupied_above=0.95")
assert j["states"] == {"free": 1, "unknown": 119, "occupied": 0} and j["thresholds"]["free_below"] == 0.1, j
np.save(os.path.join(work, "small_f.npy"), np.asfortranarray(m.astype(np.float64)))
assert info("small_f.npy")["format"] == "NumPy .npy, float64, Fortran order"

# Text: one line per property.
r = run("info", "small.npy", "--voxel-size", "0.25")
assert r.returncode == 0 and r.stderr == "", r.stderr
lines = dict(l.split(":", 1) for l in r.stdout.splitlines())
assert lines["dims"].strip() == "4 x 5 x 6 voxels (x, y, z), 120 in all", lines
assert lines["voxel size"].strip() == "0.25 m", lines
assert lines["states"].strip().startswith("free 91 (75.83 %), unknown 21 (17.50 %), occupied 8 (6.67 %)"), lines
assert lines["unobserved"].strip() == "20 (16.67 %) exactly 0.5", lines
assert run("info", "small.npy", "--quiet").stdout == ""

# .nrrd written by hand: the space origin is the centre of the first voxel, so the grid's corner
# origin is half a voxel lower.
header = ("NRRD0004\ntype: float\ndimension: 3\nsizes: 4 5 6\nspace: right-anterior-superior\n"
          "space directions: (0.25,0,0) (0,0.25,0) (0,0,0.25)\nspace origin: (1.125,-2.125,3.125)\n"
          "encoding: raw\nendian: little\n\n")
with open(os.path.join(work, "small.nrrd"), "wb") as f:
    f.write(header.encode() + m.astype("<f4").tobytes())
j = info("small.nrrd")
assert j["format"] == "NRRD, float" and j["dims"] == [4, 5, 6] and j["voxel_size"] == 0.25, j
assert np.allclose(j["origin"], [1.0, -2.25, 3.0]), j["origin"]
assert j["states"] == {"free": 91, "unknown": 21, "occupied": 8} and j["unobserved"] == 20, j

# OctoMap .bt: the tree's box and leaf counts, as OctoMap itself reports them (docs/adapters.md).
j = info(os.path.join(data, "geb079.bt"))
assert j["format"].startswith("OctoMap tree (.bt"), j["format"]
assert j["dims"] == [487, 187, 39] and abs(j["voxel_size"] - 0.08) < 1e-9, j
assert np.allclose(j["origin"], [-8.0, -7.52, -0.32]), j["origin"]
assert j["states"]["occupied"] == 185673 and j["states"]["free"] == 950759, j["states"]
assert j["unobserved"] == j["states"]["unknown"] == 487 * 187 * 39 - 185673 - 950759, j
assert abs(j["values"]["min"] - 0.1192) < 1e-3 and abs(j["values"]["max"] - 0.971) < 1e-3, j["values"]
# At a coarser voxel size the box covers the same space with 2x2x2 blocks.
j = info(os.path.join(data, "geb079.bt"), "--voxel-size", "0.16")
assert j["dims"] == [244, 94, 20] and abs(j["voxel_size"] - 0.16) < 1e-9, j

# OctoMap .ot written by hand (octomap's AbstractOcTree::write layout: header lines, then per node
# its float log-odds and a byte of child flags, depth first). Root child 7, then child 0 down to
# depth 14, whose eight children are leaves of 2 x 2 x 2 voxels of 0.1 m: keys 32768..32771, so
# the known box is 0..0.4 m on each axis. Leaf i has log-odds l[i]: inner nodes hold the maximum.
l = [2.0, -1.0, 0.0, 2.0, -2.0, 1.0, -1.0, 0.25]
nodes = [(max(l), 1 << 7)] + [(max(l), 1)] * 13 + [(max(l), 0xFF)] + [(v, 0) for v in l]
with open(os.path.join(work, "tiny.ot"), "wb") as f:
    f.write(f"# Octomap OcTree file\nid OcTree\nsize {len(nodes)}\nres 0.1\ndata\n".encode())
    for value, children in nodes:
        f.write(struct.pack("<fB", value, children))
j = info("tiny.ot")
assert j["format"] == "OctoMap tree (.ot, log-odds)" and j["dims"] == [4, 4, 4], j
assert abs(j["voxel_size"] - 0.1) < 1e-9 and np.allclose(j["origin"], [0, 0, 0]), j
p = 1 / (1 + np.exp(-np.array(l)))  # each leaf: 8 voxels at its probability
assert j["states"] == {"free": 8 * int((p < 0.498).sum()), "unknown": 8 * int(((p >= 0.498) & (p <= 0.502)).sum()),
                       "occupied": 8 * int((p > 0.502).sum())} == {"free": 24, "unknown": 8, "occupied": 32}, j
assert abs(j["values"]["min"] - p.min()) < 1e-6 and abs(j["values"]["max"] - p.max()) < 1e-6, j["values"]
assert j["unobserved"] == 8, j  # log-odds 0 is exactly 0.5

# Clouds are fused first (the grid segment would use): sizes follow --voxel-size.
pcd = os.path.join(data, "table_scene_mug_stereo_textured.pcd")
a, b = info(pcd), info(pcd, "--voxel-size", "0.025")
assert a["format"].startswith("PCL point cloud (.pcd)") and a["voxel_size"] == 0.05, a
for k in range(3):  # the same box: twice the voxels per axis, give or take the rounding at the faces
    assert abs(b["dims"][k] - 2 * a["dims"][k]) <= 2, (a["dims"], b["dims"])
for j in (a, b):
    s = j["states"]
    assert s["free"] + s["unknown"] + s["occupied"] == j["voxels"] and s["occupied"] > 0 and s["free"] > 0, j
    # OctoMap's sensor model: a voxel holds 0.5 (never touched), or was hit or missed at least once.
    assert 0.119 < j["values"]["min"] <= 0.4 + 1e-6 and 0.7 - 1e-6 <= j["values"]["max"] < 0.971, j["values"]
j = info(os.path.join(data, "spherical_scan.graph"), "--voxel-size", "0.1")
assert j["format"].startswith("OctoMap scan graph (.graph)") and j["voxel_size"] == 0.1, j
assert j["states"]["occupied"] > 0 and j["unobserved"] == j["states"]["unknown"], j
# Box given: the dims follow from it exactly.
j = info(os.path.join(data, "spherical_scan.graph"), "--bbox", "0", "-2", "-2", "4", "2", "1", "--voxel-size", "0.1")
assert j["dims"] == [40, 40, 30] and np.allclose(j["origin"], [0, -2, -2]), j
print("cli info: all checks passed")
