"""The main job: `occseg` without arguments runs the demo (the paper's cone scene, 320 x 320 x 128,
simulated, segmented, scored) and writes everything to ./occseg-out/. Checked: the files, their
shapes, the segment table against the labels, the scores against `occseg evaluate` run on the
written files, the picture (decoded here), and the --json summary of a smaller run."""
import glob
import json
import os
import subprocess
import sys

import numpy as np

from pngcheck import (FREE, OCCUPIED_HUES, SCENE_SIZE, SCENE_VIEW, UNKNOWN, colours, figure_layout, figure_size, read_png,
                      scene_shades)

occseg, work = sys.argv[1], sys.argv[2]


def run(*args):
    return subprocess.run([occseg, *args], capture_output=True, text=True, cwd=work, timeout=600)


r = run()
assert r.returncode == 0 and r.stderr == "", (r.returncode, r.stderr)
assert "occseg-out/segmentation.png" in r.stdout and "scores against the ground truth" in r.stdout, r.stdout
out = os.path.join(work, "occseg-out")
expected = ["evaluation.json", "evaluation.txt", "labels.npy", "labels.nrrd", "map.npy", "scene.json", "scene.png",
            "segmentation.png", "segments.json", "summary.json", "truth_objects.npy", "truth_state.npy"]
assert sorted(os.listdir(out)) == expected, sorted(os.listdir(out))

scene = json.load(open(os.path.join(out, "scene.json")))
assert scene["scene"] == "cone" and scene["seed"] == 1 and scene["dims"] == [320, 320, 128], scene
assert scene["construction"] == "planar" and scene["voxel_size"] == 0.04, scene
m, labels = np.load(os.path.join(out, "map.npy")), np.load(os.path.join(out, "labels.npy"))
assert m.dtype == np.float32 and m.shape == (128, 320, 320) and labels.dtype == np.uint32 and labels.shape == m.shape
assert ((m >= 0) & (m <= 1)).all() and (m == 0.5).any() and (m > 0.502).any() and (m < 0.498).any()
truth = np.load(os.path.join(out, "truth_state.npy"))
assert truth.shape == m.shape and set(np.unique(truth)) == {0, 1, 2}

# The segment table matches the labels: voxel counts and boxes, and each state is the state of
# the segment's mean probability.
doc = json.load(open(os.path.join(out, "segments.json")))
segs = doc["segments"]
assert doc["dims"] == [320, 320, 128] and doc["preset"] == "default" and len(segs) == labels.max() + 1
counts = np.bincount(labels.ravel(), minlength=len(segs))
assert all(counts[s["id"]] == s["voxels"] for s in segs)
for s in sorted(segs, key=lambda s: -s["voxels"])[:5]:
    z, y, x = np.nonzero(labels == s["id"])
    assert s["bbox"] == {"min": [int(x.min()), int(y.min()), int(z.min())], "max": [int(x.max()), int(y.max()), int(z.max())]}, s

# The scores the demo wrote are those `occseg evaluate` gives for its files.
ev = json.load(open(os.path.join(out, "evaluation.json")))
r = run("evaluate", "--truth", "occseg-out", "--labels", "occseg-out/labels.npy", "--segments",
        "occseg-out/segments.json", "--json")
assert r.returncode == 0, r.stderr
assert json.loads(r.stdout)["results"][0]["scores"] == ev["scores"]
# The paper's claims hold on the demo (docs/experiments.md): free and unknown space are labelled
# well; the default preset labels almost no object voxel free.
assert ev["scores"]["accuracy"] > 0.95 and ev["scores"]["iou"]["free"] > 0.9, ev["scores"]
assert ev["scores"]["object_free_share"] < 0.02 and ev["scores"]["spanning_segments"] == 0, ev["scores"]

summary = json.load(open(os.path.join(out, "summary.json")))
assert summary["segments"]["total"] == len(segs) and summary["evaluation"] == ev["scores"]
assert summary["largest_objects"][0]["voxels"] == max(s["voxels"] for s in segs if s["state"] == "occupied")

# The picture: map, segments and ideal state in three rows; the state colours are there.
w, h, px = read_png(os.path.join(out, "segmentation.png"))
title = "occseg demo: cone (planar, 320 x 320 x 128, seed 1, preset default)"
assert (w, h) == figure_size((320, 320, 128), rows=3, title=title) == (2288, 1064), (w, h)
layout = figure_layout((320, 320, 128), ["map", "segments", "ideal state"], title, ideal=True)
used = colours(px)
assert FREE in used and UNKNOWN in used and used & OCCUPIED_HUES, used
# Free space around the sensors: the segments row at voxel (160, 40) of the z = 16 slice is free,
# as its ideal state is.
assert truth[16, 40, 160] == 0 and labels[16, 40, 160] in [s["id"] for s in segs if s["state"] == "free"]
py = layout["rows"][1] + (320 - 1 - 40)
assert px[py][6 + 160] == FREE, px[py][6 + 160]
# The 3D picture: the cone (the largest occupied segment) in its colour, in the view.
w, h, px = read_png(os.path.join(out, "scene.png"))
assert (w, h) == SCENE_SIZE, (w, h)
cone = max((s for s in segs if s["state"] == "occupied"), key=lambda s: s["voxels"])
vx, vy, vw, vh = SCENE_VIEW
view = colours([row[vx:vx + vw] for row in px[vy:vy + vh]])
assert scene_shades(cone["id"]) <= view, (scene_shades(cone["id"]), len(view))

assert not glob.glob(os.path.join(out, "*.tmp-*"))

# `occseg demo` with options: another scene and size, JSON on stdout (with the scores), --out.
r = run("demo", "--scene", "close", "--dims", "96", "96", "32", "--out", "small", "--json")
assert r.returncode == 0 and r.stderr == "", r.stderr
j = json.loads(r.stdout)
assert j["dims"] == [96, 96, 32] and j["input"] == "simulated close scene" and "evaluation" in j, j.keys()
assert len(j["evaluation"]["objects"]) == 2 and j["files"][-1] == "small/summary.json", j["files"]
assert sorted(os.listdir(os.path.join(work, "small"))) == expected
# The building takes its own defaults for what is not given (rings, 25 m range), as `simulate` does.
r = run("demo", "--scene", "building", "--dims", "100", "75", "15", "--voxel-size", "0.2", "--out", "bldg", "--json")
assert r.returncode == 0 and r.stderr == "", r.stderr
with open(os.path.join(work, "bldg", "scene.json")) as f:
    scene = json.load(f)
assert scene["construction"] == "rings" and scene["sensor"]["max_range"] == 25.0, (scene["construction"], scene["sensor"])
assert scene["dims"] == [100, 75, 15] and scene["voxel_size"] == 0.2, (scene["dims"], scene["voxel_size"])
print("cli demo: all checks passed")
