"""2D robot maps through the command (issue 26): the real Nav2 map tb3_sandbox.yaml, a hand-made
map_server room with a box, a 2D .npy; segmentation.pgm + segmentation.yaml written back for
nz = 1 (and only then), map_server conventions; bad map files refused with exit code 2."""
import json
import os
import subprocess
import sys

import numpy as np

occseg, work, data = sys.argv[1], sys.argv[2], sys.argv[3]
FREE, UNKNOWN, OCCUPIED = 0, 1, 2
PIXEL = {OCCUPIED: 0, FREE: 254, UNKNOWN: 205}


def run(*args):
    return subprocess.run([occseg, *args], capture_output=True, text=True)


def read_pgm(path):
    """An 8-bit P5 PGM as written by map_saver and by occseg: (rows from the top, header lines)."""
    raw = open(path, "rb").read()
    assert raw[:3] == b"P5\n", raw[:20]
    fields, pos = [], 3
    while len(fields) < 3:
        if raw[pos:pos + 1] == b"#":
            pos = raw.index(b"\n", pos) + 1
            continue
        end = min(i for i in (raw.find(b" ", pos), raw.find(b"\n", pos)) if i >= 0)
        fields.append(int(raw[pos:end]))
        pos = end + 1
    w, h, maxval = fields
    assert maxval == 255 and len(raw) - pos == w * h, (w, h, maxval, len(raw) - pos)
    return np.frombuffer(raw[pos:], dtype=np.uint8).reshape(h, w)


def segment(path, out, *extra):
    r = run("segment", path, "--out", out, "--outputs", "default,labels.npy", *extra)
    assert r.returncode == 0, r.stderr
    doc = json.load(open(os.path.join(out, "segments.json")))
    labels = np.load(os.path.join(out, "labels.npy"))
    states = np.array([{"free": FREE, "unknown": UNKNOWN, "occupied": OCCUPIED}[s["state"]]
                       for s in doc["segments"]], dtype=np.uint8)[labels[0]]  # [y, x], y up
    return r, doc, labels[0], states


def counts(doc):
    c = {"free": 0, "unknown": 0, "occupied": 0}
    for s in doc["segments"]:
        c[s["state"]] += 1
    return c


def check_pair(out, states, resolution, origin):
    """segmentation.pgm is the states, top row = largest y; segmentation.yaml loads it."""
    img = read_pgm(os.path.join(out, "segmentation.pgm"))
    expect = np.vectorize(PIXEL.get)(states[::-1]).astype(np.uint8)
    assert (img == expect).all(), int((img != expect).sum())
    y = open(os.path.join(out, "segmentation.yaml")).read().splitlines()
    assert y[0] == "image: segmentation.pgm" and "mode: trinary" in y and "negate: 0" in y, y
    assert f"resolution: {resolution}" in y, y
    assert f"origin: [{origin[0]}, {origin[1]}, 0]" in y, y
    assert "occupied_thresh: 0.65" in y and "free_thresh: 0.196" in y, y


# --- the real Nav2 map: a hexagonal arena (a wall) with nine pillars --------------------------
tb3 = os.path.join(data, "tb3_sandbox.yaml")
out = os.path.join(work, "tb3")
r, doc, labels, states = segment(tb3, out, "--json")
summary = json.loads(r.stdout)
assert doc["dims"] == [384, 384, 1], doc["dims"]
c = counts(doc)
print("tb3_sandbox segments per state:", c)
occ = sorted((s for s in doc["segments"] if s["state"] == "occupied"), key=lambda s: -s["voxels"])
assert len(occ) == 10, [s["voxels"] for s in occ]  # the wall and the nine pillars
wall, pillars = occ[0], occ[1:]
# The pillars lie inside the wall's box, each of about 0.35 m (7 cells) across.
for p in pillars:
    for k in (0, 1):
        assert wall["bbox"]["min"][k] < p["bbox"]["min"][k] and p["bbox"]["max"][k] < wall["bbox"]["max"][k], p
        assert 5 <= p["bbox"]["max"][k] - p["bbox"]["min"][k] + 1 <= 9, p
# Free inside: the largest free segment fills the arena, inside the wall's box, around the centre.
free = max((s for s in doc["segments"] if s["state"] == "free"), key=lambda s: s["voxels"])
for k in (0, 1):
    assert wall["bbox"]["min"][k] <= free["bbox"]["min"][k] and free["bbox"]["max"][k] <= wall["bbox"]["max"][k]
centre = [(wall["bbox"]["min"][k] + wall["bbox"]["max"][k]) / 2 for k in (0, 1)]
assert free["voxels"] > 7000 and all(abs(free["centroid"][k] - centre[k]) < 10 for k in (0, 1)), free
# Unknown outside: one unknown segment holds all four corners of the image.
corners = {int(labels[0, 0]), int(labels[0, -1]), int(labels[-1, 0]), int(labels[-1, -1])}
assert len(corners) == 1 and doc["segments"][corners.pop()]["state"] == "unknown"
# Every other segment is one of the map's own regions: the segmentation keeps each cell's state
# (it may close a handful of one-cell gaps), so segmentation.pgm is the map it was given, except
# for the pockets rule (docs/algorithm.md, default preset rule 8): free regions of fewer than 16
# cells become unknown, unknown ones that small beside a wall or pillar join it; both only ever
# move a cell towards occupied.
src = np.fromfile(os.path.join(data, "tb3_sandbox.pgm"), dtype=np.uint8)[-384 * 384:].reshape(384, 384)
given = np.select([src == 0, src == 254], [OCCUPIED, FREE], UNKNOWN)[::-1]
pockets = ((given == FREE) & (states == UNKNOWN)) | ((given == UNKNOWN) & (states == OCCUPIED))
print("tb3_sandbox cells moved by the pockets rule:", int(pockets.sum()))
assert ((states != given) & ~pockets).sum() <= 10, int(((states != given) & ~pockets).sum())
assert pockets.sum() <= 400, int(pockets.sum())
check_pair(out, states, "0.05", ("-10", "-10"))
assert {"segmentation.pgm", "segmentation.yaml"} <= set(os.listdir(out))  # map.nrrd: on request
assert summary["format"].startswith("map_server map"), summary["format"]
# The pair written back is itself a map_server map the command reads: the same segments.
_, doc2, _, states2 = segment(os.path.join(out, "segmentation.yaml"), os.path.join(work, "tb3_again"))
# (Up to a handful of cells may move: unknown cells the pockets rule left in a thin channel are
# gaps between rays to the next run's rule 2, and a gap beside a wall that closes off is a pocket.)
assert (states2 != states).sum() <= 10, int((states2 != states).sum())

# --- a hand-made map_server map: a room with a box, origin and resolution of its own ----------
h, w = 40, 60
img = np.full((h, w), 205, dtype=np.uint8)                    # unknown outside
img[5:35, 8:52] = 0                                          # the wall ...
img[6:34, 9:51] = 254                                        # ... around free space
img[10:16, 12:20] = 0                                        # a box near the image top-left
room = os.path.join(work, "room")
os.makedirs(room)
with open(os.path.join(room, "room.pgm"), "wb") as f:
    f.write(b"P5\n# a room with a box\n%d %d\n255\n" % (w, h) + img.tobytes())
yaml = "image: room.pgm\nresolution: 0.1\norigin: [2.5, -4.0, 0.0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n"
open(os.path.join(room, "room.yaml"), "w").write(yaml)
out = os.path.join(work, "room_out")
_, doc, labels, states = segment(os.path.join(room, "room.yaml"), out)
assert counts(doc) == {"free": 1, "unknown": 1, "occupied": 2}, counts(doc)
box = [s for s in doc["segments"] if s["state"] == "occupied" and s["voxels"] == 48]
assert len(box) == 1, [s["voxels"] for s in doc["segments"]]
# Image rows 10..15 from the top are y = 24..29 (y up): the box is near the map's largest y.
assert box[0]["bbox"] == {"min": [12, h - 16, 0], "max": [19, h - 11, 0]}, box[0]["bbox"]
wall = [s for s in doc["segments"] if s["state"] == "occupied" and s["voxels"] != 48][0]
assert wall["voxels"] == 30 * 44 - 28 * 42, wall
free = [s for s in doc["segments"] if s["state"] == "free"][0]
assert free["voxels"] == 28 * 42 - 48, free
check_pair(out, states, "0.1", ("2.5", "-4"))
# The same room negated (white occupied) reads the same.
open(os.path.join(room, "neg.yaml"), "w").write(yaml.replace("negate: 0", "negate: 1").replace("room.pgm", "neg.pgm"))
with open(os.path.join(room, "neg.pgm"), "wb") as f:
    f.write(b"P5\n%d %d\n255\n" % (w, h) + (255 - img).tobytes())
_, _, labels_neg, _ = segment(os.path.join(room, "neg.yaml"), os.path.join(work, "neg_out"))
assert (labels_neg == labels).all()

# --- 2D .npy maps get the pair too; 3D maps do not -------------------------------------------
flat = np.where(img[::-1] == 0, 0.95, np.where(img[::-1] == 254, 0.05, 0.5)).astype(np.float32)
np.save(os.path.join(work, "flat.npy"), flat)
out = os.path.join(work, "flat_out")
_, doc, _, states = segment(os.path.join(work, "flat.npy"), out, "--voxel-size", "0.1")
assert counts(doc) == {"free": 1, "unknown": 1, "occupied": 2}, counts(doc)
check_pair(out, states, "0.1", ("0", "0"))
np.save(os.path.join(work, "cube.npy"), np.stack([flat, flat]))
out = os.path.join(work, "cube_out")
assert run("segment", os.path.join(work, "cube.npy"), "--out", out).returncode == 0
assert "segmentation.pgm" not in os.listdir(out) and "segmentation.yaml" not in os.listdir(out)

# --- bad map files: exit 2, one line naming the file and the problem, nothing written ---------
bad = [
    ("image: nowhere.pgm\nresolution: 0.1\norigin: [0, 0, 0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n",
     "image 'nowhere.pgm': cannot open"),
    (yaml.replace("origin: [2.5, -4.0, 0.0]", "origin: [2.5, -4.0, 1.57]"), "origin yaw 1.57 is not 0"),
    (yaml.replace("resolution: 0.1", "resolution: -0.1"), "line 2: resolution: -0.1 is not positive"),
    (yaml.replace("negate: 0\n", ""), "no 'negate' key"),
    (yaml + "extra:\n  nested: 1\n", "line 8: nested mappings are not supported"),
]
for k, (text, message) in enumerate(bad):
    path = os.path.join(room, f"bad{k}.yaml")
    open(path, "w").write(text)
    out = os.path.join(work, f"bad{k}_out")
    r = run("segment", path, "--out", out)
    assert r.returncode == 2, (r.returncode, r.stderr)
    assert message in r.stderr and f"bad{k}.yaml" in r.stderr and r.stderr.count("\n") == 1, r.stderr
    assert not os.path.exists(out), os.listdir(out)
with open(os.path.join(room, "short.pgm"), "wb") as f:
    f.write(b"P5\n%d %d\n255\n" % (w, h) + img.tobytes()[:100])
open(os.path.join(room, "short.yaml"), "w").write(yaml.replace("room.pgm", "short.pgm"))
r = run("segment", os.path.join(room, "short.yaml"), "--out", os.path.join(work, "short_out"))
assert r.returncode == 2 and "short.pgm' is not a valid PGM image: truncated raster" in r.stderr, r.stderr
r = run("segment", os.path.join(room, "room.yaml"), "--out", os.path.join(work, "vs_out"), "--voxel-size", "0.2")
assert r.returncode == 1 and "--voxel-size" in r.stderr, r.stderr
print("cli map2d: all checks passed")
