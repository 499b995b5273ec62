"""Runs `occseg simulate` and `occseg evaluate` as a user would and checks files, determinism,
exit codes and messages."""
import json
import os
import subprocess
import sys

import numpy as np

occseg, work = sys.argv[1], sys.argv[2]


def run(*args):
    return subprocess.run([occseg, *args], capture_output=True, text=True)


def sim(out, *extra):
    r = run("simulate", "--scene", "cone", "--dims", "64", "64", "16", "--out", out, *extra)
    assert r.returncode == 0, r.stderr
    return out


a = sim(os.path.join(work, "a"))
m = np.load(os.path.join(a, "map.npy"))
st = np.load(os.path.join(a, "truth_state.npy"))
ob = np.load(os.path.join(a, "truth_objects.npy"))
assert m.dtype == np.float32 and m.shape == (16, 64, 64), (m.dtype, m.shape)
assert st.dtype == np.uint8 and st.shape == m.shape and set(np.unique(st)) == {0, 1, 2}
assert ob.dtype == np.uint8 and set(np.unique(ob)) == {0, 1}
assert ((m >= 0.12 - 1e-6) & (m <= 0.97 + 1e-6)).all()
assert (m == 0.5).any() and (m > 0.5).any() and (m < 0.5).any()
# The cone stands on the floor and narrows upwards: fewer object voxels in higher layers.
per_layer = (ob == 1).sum(axis=(1, 2))
assert per_layer[0] > per_layer[8] > 0, per_layer
doc = json.load(open(os.path.join(a, "scene.json")))
assert doc["scene"] == "cone" and doc["dims"] == [64, 64, 16] and doc["seed"] == 1
assert doc["objects"] == [{"id": 1, "name": "cone", "voxels": int((ob == 1).sum())}]
assert doc["sensor"]["range_sigma"] == 0.04 and doc["sensor"]["angle_step_deg"] == 0.5
assert doc["truth_states"]["occupied"] == int((st == 2).sum())

# Deterministic from the seed, whatever the thread count.
b = sim(os.path.join(work, "b"), "--threads", "1")
for f in ("map.npy", "truth_state.npy", "truth_objects.npy"):
    assert open(os.path.join(a, f), "rb").read() == open(os.path.join(b, f), "rb").read(), f
c = sim(os.path.join(work, "c"), "--seed", "2")
assert not np.array_equal(np.load(os.path.join(c, "map.npy")), m)
assert np.array_equal(np.load(os.path.join(c, "truth_state.npy")), st), "the truth has no noise"

# evaluate: all methods side by side, JSON.
r = run("evaluate", "--truth", a, "--json")
assert r.returncode == 0, r.stderr
res = json.loads(r.stdout)
assert [x["method"] for x in res["results"]] == ["paper", "default", "baseline", "ideal"]
ideal = res["results"][3]["scores"]
assert ideal["accuracy"] == 1.0 and ideal["iou"]["occupied"] == 1.0 and ideal["unknown_free"] == 0
for x in res["results"]:
    s = x["scores"]
    assert s["voxels"] == 64 * 64 * 16 and 0.9 < s["accuracy"] <= 1.0, (x["method"], s["accuracy"])
    assert s["objects"][0]["name"] == "cone"

# evaluate an existing segmentation: the same numbers as --method default.
seg = os.path.join(work, "seg")
r = run("segment", os.path.join(a, "map.npy"), "--out", seg, "--outputs", "all")
assert r.returncode == 0, r.stderr
r = run("evaluate", "--truth", a, "--labels", os.path.join(seg, "labels.npy"), "--segments",
        os.path.join(seg, "segments.json"), "--json")
assert r.returncode == 0, r.stderr
mine = json.loads(r.stdout)["results"][0]["scores"]
assert mine == res["results"][1]["scores"], "labels + segments.json score like --method default"
r = run("evaluate", "--truth", a, "--method", "baseline")
assert r.returncode == 0 and "voxel accuracy" in r.stdout and "baseline" in r.stdout, r.stdout

# Bad input: a message naming the problem, exit code 1 (usage) or 2 (bad input), no output.
r = run("simulate", "--scene", "pyramid", "--out", os.path.join(work, "x"))
assert r.returncode == 1 and "pyramid" in r.stderr, r.stderr
assert not os.path.exists(os.path.join(work, "x"))
r = run("simulate", "--scene", "cone", "--dims", "8", "8", "8", "--out", os.path.join(work, "y"))
assert r.returncode == 2 and "16 x 16 x 8" in r.stderr, (r.returncode, r.stderr)
assert not os.path.exists(os.path.join(work, "y", "map.npy"))
r = run("evaluate", "--truth", os.path.join(work, "missing"))
assert r.returncode == 2 and "missing" in r.stderr, r.stderr
np.save(os.path.join(work, "small_labels.npy"), np.zeros((4, 4, 4), np.uint32))
r = run("evaluate", "--truth", a, "--labels", os.path.join(work, "small_labels.npy"), "--segments",
        os.path.join(seg, "segments.json"))
assert r.returncode == 2 and "small_labels.npy" in r.stderr and "expected 64 x 64 x 16" in r.stderr, r.stderr
np.save(os.path.join(work, "big_labels.npy"), np.full((16, 64, 64), 10 ** 6, np.uint32))
r = run("evaluate", "--truth", a, "--labels", os.path.join(work, "big_labels.npy"), "--segments",
        os.path.join(seg, "segments.json"))
assert r.returncode == 2 and "label 1000000" in r.stderr, r.stderr
r = run("evaluate", "--truth", a, "--labels", os.path.join(seg, "labels.npy"))
assert r.returncode == 1 and "--segments" in r.stderr, r.stderr
# The building takes its own defaults for what is not given: rings scans, 25 m range, 5 cm voxels
# (here --dims is given: a 3.2 x 2.4 x 0.6 m storey at scale 0.16, a quick map).
r = run("simulate", "--scene", "building", "--dims", "64", "48", "12", "--out", os.path.join(work, "bld"))
assert r.returncode == 0, r.stderr
doc = json.load(open(os.path.join(work, "bld", "scene.json")))
assert doc["construction"] == "rings" and doc["voxel_size"] == 0.05 and doc["dims"] == [64, 48, 12], doc
assert doc["sensor"]["max_range"] == 25 and doc["sensor"]["ring_step_deg"] == 3, doc["sensor"]
assert len(doc["viewpoints"]) == 7 and len(doc["objects"]) == 11
r = run("simulate", "--scene", "building", "--dims", "64", "48", "12", "--mode", "full3d", "--max-range", "8", "--angle-step", "3",
        "--out", os.path.join(work, "bld3"))
assert r.returncode == 0, r.stderr
doc = json.load(open(os.path.join(work, "bld3", "scene.json")))
assert doc["construction"] == "full3d" and doc["sensor"]["max_range"] == 8 and "ring_step_deg" not in doc["sensor"]

print("cli simulate/evaluate: all checks passed")

# figures: scores and a PNG picture for a small scene.
fig = os.path.join(work, "fig")
r = run("figures", "--out", fig, "--scene", "cone", "--dims", "64", "64", "16")
assert r.returncode == 0, r.stderr
png = open(os.path.join(fig, "cone.png"), "rb").read()
assert png[:8] == b"\x89PNG\r\n\x1a\n" and b"IHDR" in png[:16] and b"IEND" in png[-12:], png[:16]
width, height = int.from_bytes(png[16:20], "big"), int.from_bytes(png[20:24], "big")
assert width >= 3 * 64 and height >= 5 * 64, (width, height)  # 3 slices x 5 rows of 64-voxel panels
png = open(os.path.join(fig, "cone-scene.png"), "rb").read()  # the default preset's segments in 3D
assert png[:8] == b"\x89PNG\r\n\x1a\n" and (int.from_bytes(png[16:20], "big"), int.from_bytes(png[20:24], "big")) == (960, 720)
table = open(os.path.join(fig, "results-planar.md")).read()
assert "| cone | paper |" in table and "| cone | ideal | 100.00 |" in table, table
res = json.load(open(os.path.join(fig, "results-planar.json")))
assert [x["method"] for x in res["scenes"][0]["results"]] == ["paper", "default", "baseline", "ideal"]
r = run("figures", "--out", fig, "--scene", "cone", "--dims", "64", "64")
assert r.returncode == 1, r.returncode
print("cli figures: all checks passed")
