"""The pictures of `occseg segment` (issue 25): scene.png decoded (its size; each hand-built box in
its segment's colour where the documented projection puts it, the legend's colours, nothing of a
segment on an empty map, one voxel and a coarsened huge map drawn) and segmentation.png on a narrow
map (the table scene at 2 cm: the title and the captions inside the picture, apart from each other;
the top view shows the objects)."""
import json
import os
import subprocess
import sys

import numpy as np

from pngcheck import (INK, SCENE_SIZE, SCENE_VIEW, SEGMENT_PALETTE, colours, figure_layout, read_png, scene_projection,
                      scene_shades, segment_colour)

occseg, work, data = sys.argv[1], sys.argv[2], sys.argv[3]
all_shades = set()
for c in SEGMENT_PALETTE:
    for f in (1.0, 0.80, 0.62):
        all_shades.add(tuple(int(v * f) for v in c))


def run(*args):
    return subprocess.run([occseg, *args], capture_output=True, text=True, cwd=work, timeout=600)


def segment(name, m, *args):
    np.save(os.path.join(work, name + ".npy"), m)
    r = run("segment", name + ".npy", "--out", name, "--quiet", *args)
    assert r.returncode == 0 and r.stderr == "", (name, r.returncode, r.stderr)
    doc = json.load(open(os.path.join(work, name, "segments.json")))
    w, h, px = read_png(os.path.join(work, name, "scene.png"))
    assert (w, h) == SCENE_SIZE, (name, w, h)
    return doc, px


def region(px, u, v, r):
    return colours([row[max(0, int(u) - r):int(u) + r + 1] for row in px[max(0, int(v) - r):int(v) + r + 1]])


# --- scene.png: three boxes at known places in a 64 x 48 x 32 map of 0.1 m voxels ---
m = np.full((32, 48, 64), 0.1, dtype=np.float32)
boxes = {"low left": (slice(0, 6), slice(4, 14), slice(4, 14)),     # z, y, x
         "low right": (slice(0, 6), slice(4, 14), slice(48, 60)),
         "high back": (slice(20, 30), slice(34, 44), slice(26, 36))}
for z, y, x in boxes.values():
    m[z, y, x] = 0.95
doc, px = segment("boxes", m, "--voxel-size", "0.1")
occ = [s for s in doc["segments"] if s["state"] == "occupied"]
assert len(occ) == 3, occ
lo = [min(s["bbox"]["min"][k] for s in occ) for k in range(3)]
hi = [max(s["bbox"]["max"][k] for s in occ) + 1 for k in range(3)]
scale, u0, v0, project = scene_projection(lo, hi)
vx, vy, vw, vh = SCENE_VIEW
centres = {}
for name, (z, y, x) in boxes.items():
    s = next(s for s in occ if s["bbox"]["min"] == [x.start, y.start, z.start])
    # The centre of the box's top face: its colour at full brightness, or a face shade of it.
    u, v = project((x.start + x.stop) / 2, (y.start + y.stop) / 2, z.stop)
    assert vx <= u < vx + vw and vy <= v < vy + vh, (name, u, v)
    assert region(px, u, v, 2) <= scene_shades(s["id"]), (name, region(px, u, v, 2), scene_shades(s["id"]))
    assert px[int(v)][int(u)] == segment_colour(s["id"]), (name, px[int(v)][int(u)])
    # The box's front face (-y), the 0.80 shade.
    u, v = project((x.start + x.stop) / 2, y.start, (z.start + z.stop) / 2)
    assert px[int(v)][int(u)] == tuple(int(c * 0.8) for c in segment_colour(s["id"])), (name, px[int(v)][int(u)])
    centres[name] = s["id"]
# Free space is not drawn: halfway between the two low boxes there is no segment colour.
u, v = project(31, 9, 3)
assert not region(px, u, v, 4) & all_shades, region(px, u, v, 4)
# The legend lists the three segments, largest first, each with its colour.
legend = colours([row[vx + vw:] for row in px])
for s in occ:
    assert segment_colour(s["id"]) in legend, s
assert INK in legend
# The scale bar under the view: a dark bar 3 pixels high starting at x = 16.
bar_y = vy + vh + 14
bar = [px[bar_y][x] for x in range(16, 16 + 40)]
assert all(c == INK for c in bar), bar

# --- an empty map (free space only): no segment colour anywhere ---
doc, px = segment("empty", np.full((16, 16, 16), 0.1, dtype=np.float32))
assert not [s for s in doc["segments"] if s["state"] == "occupied"]
assert not colours(px) & all_shades, colours(px) & all_shades

# --- one voxel, occupied: drawn, bounded in size ---
doc, px = segment("one", np.full((1, 1, 1), 0.9, dtype=np.float32))
(s,) = [s for s in doc["segments"] if s["state"] == "occupied"]
assert segment_colour(s["id"]) in colours(px)
scale, u0, v0, project = scene_projection([0, 0, 0], [1, 1, 1])
assert scale == 96
u, v = project(0.5, 0.5, 1)
assert px[int(v)][int(u)] == segment_colour(s["id"])

# --- maps of millions of occupied voxels. The legend's last line (after the segments, their
# count and "free, unknown: not drawn") says when k x k x k voxels were drawn as one cell.
def coarsening_note(doc, px):
    n = len([s for s in doc["segments"] if s["state"] == "occupied"])
    y = SCENE_VIEW[1] + 16 + 28 * min(8, n) + 10 + 10
    return any(c == INK for row in px[y:y + 7] for c in row[vx + vw:])


# A solid block of 2 million voxels: more than the budget if every voxel were visible, but only
# its surface is: drawn voxel by voxel (no note), its top face in its colour where it projects.
solid = np.full((100, 200, 200), 0.1, dtype=np.float32)
solid[:50] = 0.9
doc, px = segment("solid", solid)
(s,) = [s for s in doc["segments"] if s["state"] == "occupied"]
assert not coarsening_note(doc, px)
scale, u0, v0, project = scene_projection([0, 0, 0], [200, 200, 50])
u, v = project(100, 100, 50)
assert region(px, u, v, 3) == {segment_colour(s["id"])}, region(px, u, v, 3)
u, v = project(100, 0, 25)
assert px[int(v)][int(u)] == tuple(int(c * 0.8) for c in segment_colour(s["id"]))
# Random noise, half of 7.4 million voxels occupied: its visible voxels pass the budget, so it is
# drawn again in cells (the note), still in the segments' colours.
rng = np.random.default_rng(3)
doc, px = segment("noise", np.where(rng.random((200, 192, 192)) < 0.5, 0.9, 0.1).astype(np.float32))
assert coarsening_note(doc, px)
big = max((s for s in doc["segments"] if s["state"] == "occupied"), key=lambda s: s["voxels"])
assert scene_shades(big["id"]) & colours(px), scene_shades(big["id"])

# --- scene.png cannot be written (a directory in its place): exit 2 naming it, nothing of the set ---
os.makedirs(os.path.join(work, "blocked", "scene.png"))
r = run("segment", "boxes.npy", "--out", "blocked")
assert r.returncode == 2 and "scene.png" in r.stderr and r.stderr.count("\n") == 1, (r.returncode, r.stderr)
assert os.listdir(os.path.join(work, "blocked")) == ["scene.png"], os.listdir(os.path.join(work, "blocked"))

# --- segmentation.png on a narrow map: the table scene at 2 cm (59 x 35 x 131 voxels) ---
if not os.path.exists(os.path.join(data, "table_scene_mug_stereo_textured.pcd")):
    print("cli pictures: no shared data, table scene skipped")
else:
    r = run("segment", os.path.join(data, "table_scene_mug_stereo_textured.pcd"), "--voxel-size", "0.02",
            "--out", "table", "--json")
    assert r.returncode == 0, r.stderr
    j = json.loads(r.stdout)
    assert j["dims"] == [59, 35, 131], j["dims"]
    w, h, px = read_png(os.path.join(work, "table", "segmentation.png"))
    title = "occseg segment table_scene_mug_stereo_textured.pcd  (59 x 35 x 131, preset default)"
    big = j["largest_objects"][0]
    doc = json.load(open(os.path.join(work, "table", "segments.json")))
    c = next(s for s in doc["segments"] if s["id"] == big["id"])["centroid"]
    yx = (min(34, int(c[1] + 0.5)), min(58, int(c[0] + 0.5)))
    L = figure_layout((59, 35, 131), ["map", "segments"], title, yx=yx)
    assert (w, h) == (L["width"], L["height"]), ((w, h), (L["width"], L["height"]))
    ink = lambda x0, y0, x1, y1: any(px[y][x] == INK for y in range(y0, y1) for x in range(x0, x1))
    # The title: wrapped, every line inside the picture, nothing printed in the right margin.
    assert len(L["title"]) >= 2 and all(x + 6 * len(t) <= w - 6 for t, x, y in L["title"]), L["title"]
    assert not ink(w - 6, 0, w, h), "ink in the right margin"
    assert ink(6, 6, 12, 13), "no title"
    # Captions: each inside its column, with blank pixels between neighbours.
    for (t, x, y), nxt in zip(L["captions"], L["captions"][1:] + [None]):
        end = x + 6 * len(t)
        assert ink(x, y, end, y + 7), t
        stop = nxt[1] if nxt else w
        assert end <= stop - 6 and not ink(end, y, stop, y + 7), (t, end, stop)
    # The top view of the segments row shows the largest object in its colour (shaded by height).
    tx, ty = L["columns"][6], L["rows"][1]
    tw, th = L["panels"][6]
    top = colours([row[tx:tx + tw] for row in px[ty:ty + th]])
    colour = segment_colour(big["id"])
    assert any(all(abs(a - b * f) < 1 for a, b in zip(t, colour)) for t in top for f in (0.5, 0.6, 0.7, 0.8, 0.9, 1.0)), top
    w, h, _ = read_png(os.path.join(work, "table", "scene.png"))
    assert (w, h) == SCENE_SIZE
print("cli pictures: all checks passed")
