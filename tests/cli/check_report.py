"""`occseg segment` reports: segmentation.png (decoded here: size by the documented layout, state
colours at voxels whose state is known), the text summary and --json (largest objects with boxes in
metres, time per stage), --quiet, --preset, every --param, --threads, and all-or-none outputs."""
import gzip
import json
import os
import re
import subprocess
import sys

import numpy as np

from pngcheck import (FREE, INK, OCCUPIED_HUES, SEGMENT_PALETTE as OCCUPIED_PALETTE, UNKNOWN, colours, figure_layout,
                      figure_size, read_png, segment_colour, shade)

occseg, work = sys.argv[1], sys.argv[2]


def run(*args):
    return subprocess.run([occseg, *args], capture_output=True, text=True, cwd=work, timeout=300)


# 56 x 48 x 40 voxels of 0.5 m: free space (0.12), two occupied boxes (0.97), an unobserved slab.
m = np.full((40, 48, 56), 0.12, dtype=np.float32)
m[5:15, 5:15, 5:15] = 0.97      # x, y, z 5..14: 1000 voxels
m[20:35, 25:40, 30:50] = 0.97   # x 30..49, y 25..39, z 20..34: 4500 voxels
m[:, 42:, :8] = 0.5             # x 0..7, y 42..47, all z: never observed
np.save(os.path.join(work, "map.npy"), m)

r = run("segment", "map.npy", "--voxel-size", "0.5", "--out", "out")
assert r.returncode == 0 and r.stderr == "", (r.returncode, r.stderr)
files = sorted(os.listdir(os.path.join(work, "out")))
assert files == ["labels.nrrd", "scene.png", "segmentation.png", "segments.json"], files  # the default set
doc = json.load(open(os.path.join(work, "out", "segments.json")))
states = [s["state"] for s in doc["segments"]]
assert states.count("occupied") == 2 and states.count("unknown") == 1, states

# Text summary: segments per state, the two boxes in metres (voxel 0.5 m, origin 0), time per stage.
out = r.stdout
assert "map.npy: NumPy .npy, float32, C order, 56 x 48 x 40 voxels of 0.5 m, origin (0.0, 0.0, 0.0) m" in out, out
n_free = states.count("free")
assert f"preset default: {len(states)} segments: {n_free} free, 1 unknown, 2 occupied" in out, out
rows = [l.split() for l in out.splitlines() if re.match(r"^\s+\d+\s+object\s+\d+\s+0\.970\s", l)]
assert [row[2] for row in rows] == ["4500", "1000"], rows  # objects first, largest first
assert re.search(r"\(15\.0, 12\.5, 10\.0\)\s+\(25\.0, 20\.0, 17\.5\)\s+10\.0 x 7\.5 x 7\.5$", out, re.M), out
assert re.search(r"\(2\.5, 2\.5, 2\.5\)\s+\(7\.5, 7\.5, 7\.5\)\s+5\.0 x 5\.0 x 5\.0$", out, re.M), out
assert re.search(r"^time: read [\d.]+ s, texture [\d.]+ s, division [\d.]+ s, creation [\d.]+ s, "
                 r"refinement [\d.]+ s, labelling [\d.]+ s, write [\d.]+ s; total [\d.]+ s$", out, re.M), out
assert "written: out/labels.nrrd out/segments.json out/segmentation.png out/scene.png" in out, out

# The picture: two rows (map, segments), four z slices, a y and an x slice and the top view; the
# size and the places follow the layout of docs/cli.md; voxels of known state show their state's
# colour.
w, h, px = read_png(os.path.join(work, "out", "segmentation.png"))
title = "occseg segment map.npy  (56 x 48 x 40, preset default)"
layout = figure_layout((56, 48, 40), ["map", "segments"], title, yx=(32, 40))  # the big box's centroid
assert (w, h) == (layout["width"], layout["height"]) == figure_size((56, 48, 40), rows=2, title=title) == (1584, 472), (w, h)
used = colours(px)
assert FREE in used and UNKNOWN in used and used & OCCUPIED_HUES, used
scale = 4  # 256 // 56 pixels per voxel


def pixel(row, column_x0, x, y):
    """Colour at the centre of voxel (x, y) of a z-slice panel (y up) in figure row `row`."""
    py = layout["rows"][row] + (48 - 1 - y) * scale + scale // 2
    return px[py][column_x0 + x * scale + scale // 2]


small = next(s["id"] for s in doc["segments"] if s["state"] == "occupied" and s["voxels"] == 1000)
big = next(s["id"] for s in doc["segments"] if s["state"] == "occupied" and s["voxels"] == 4500)
z5 = layout["columns"][0]  # the first column: z = (2 * 0 + 1) * 40 // 8 = 5, through the small box
assert [c[0] for c in layout["captions"]] == ["z = 5", "z = 15", "z = 25", "z = 35", "y = 32", "x = 40", "top view"]
assert pixel(1, z5, 6, 6) == segment_colour(small), (pixel(1, z5, 6, 6), segment_colour(small))
# The larger segments carry their id: dark text on a white box inside the small box's square.
square = [px[layout["rows"][1] + (48 - 1 - y) * scale + j][z5 + x * scale + i]
          for y in range(5, 15) for x in range(5, 15) for i in range(scale) for j in range(scale)]
assert INK in square and (255, 255, 255) in square, set(square)
# The top view: each box's colour where it lies, shaded by the height of its top (z 14 of 40:
# level 14 * 6 // 40 = 2, factor 0.5 + 0.5 * 2 / 5 = 0.7; z 34: level 5, factor 1), the rest the
# grey of columns without an occupied voxel.
top = layout["columns"][6]
assert pixel(1, top, 6, 6) == shade(segment_colour(small), 0.7), pixel(1, top, 6, 6)
assert pixel(1, top, 32, 27) == segment_colour(big), pixel(1, top, 32, 27)
assert pixel(1, top, 20, 20) == (225, 225, 225), pixel(1, top, 20, 20)
assert pixel(0, top, 32, 27) == (5, 5, 5) and pixel(0, top, 20, 20) == (220, 220, 220)  # largest p of the column
# The legend shows the palette, not a single occupied colour (no row here without segments).
legend = {k: (x, y) for k, x, y in layout["legend"]}
assert "occupied" not in legend, legend
lx, ly = legend["segments"]
assert [px[ly + 5][lx + 3 * i + 1] for i in range(16)] == list(OCCUPIED_PALETTE), px[ly + 5][lx:lx + 48]
assert pixel(1, z5, 30, 10) == FREE and pixel(1, z5, 3, 45) == UNKNOWN, (pixel(1, z5, 30, 10), pixel(1, z5, 3, 45))
# The map row is grey: level round(50 (1 - p)) of 51, times 5; float32 0.97 is 0.97000003, level
# 1 (1.4999985 rounds down); 0.12 gives level 44, 0.5 level 25.
assert pixel(0, z5, 10, 10) == (5, 5, 5) and pixel(0, z5, 30, 10) == (220, 220, 220), pixel(0, z5, 10, 10)
assert pixel(0, z5, 3, 45) == (125, 125, 125), pixel(0, z5, 3, 45)
# Segment boundaries are drawn darker: the free voxel left of the box (x = 4) borders it.
b = pixel(1, z5, 4, 10)
assert b != FREE and b == tuple(int(c * 0.55) for c in FREE), b

# --json: the same summary for programs.
r = run("segment", "map.npy", "--voxel-size", "0.5", "--out", "out_json", "--json", "--top", "1")
assert r.returncode == 0 and r.stderr == "", r.stderr
j = json.loads(r.stdout)
assert j["dims"] == [56, 48, 40] and j["voxel_size"] == 0.5 and j["preset"] == "default", j
assert j["segments"] == {"total": len(states), "free": n_free, "unknown": 1, "occupied": 2}, j["segments"]
assert j["voxels"]["occupied"] == 5500 and j["voxels"]["unknown"] == 40 * 6 * 8, j["voxels"]
(big,) = j["largest_objects"]
assert big["voxels"] == 4500 and big["bbox_voxels"] == {"min": [30, 25, 20], "max": [49, 39, 34]}, big
assert big["bbox_m"] == {"min": [15.0, 12.5, 10.0], "max": [25.0, 20.0, 17.5]} and big["size_m"] == [10.0, 7.5, 7.5], big
assert set(j["seconds"]) == {"read", "texture", "division", "creation", "refinement", "labelling", "write", "total"}
assert abs(sum(v for k, v in j["seconds"].items() if k != "total") - j["seconds"]["total"]) < 1e-9, j["seconds"]
assert j["files"] == [f"out_json/{f}" for f in ("labels.nrrd", "segments.json", "segmentation.png", "scene.png")]

# --quiet: nothing on stdout or stderr, the same files.
r = run("segment", "map.npy", "--out", "out_quiet", "--quiet", "--threads", "1")
assert r.returncode == 0 and r.stdout == "" and r.stderr == "", (r.stdout, r.stderr)
assert sorted(os.listdir(os.path.join(work, "out_quiet"))) == files
# --threads never changes the result.
def nrrd_samples(d):  # the samples of a gzip-encoded labels.nrrd (the header holds the spacing)
    b = open(os.path.join(work, d, "labels.nrrd"), "rb").read()
    return gzip.decompress(b[b.index(b"\n\n") + 2:])
assert nrrd_samples("out_quiet") == nrrd_samples("out")

# --preset and every parameter --help lists: accepted at its default, refused (exit 1, named)
# beyond its bounds.
r = run("segment", "map.npy", "--out", "out_paper", "--preset", "paper", "--json")
assert r.returncode == 0 and json.loads(r.stdout)["preset"] == "paper"
assert json.load(open(os.path.join(work, "out_paper", "segments.json")))["preset"] == "paper"
helptext = run("segment", "--help").stdout
params = re.findall(r"^  (\w+) \((int|double|string), default (\S+?)(?:, ([-\d.e+]+)\.\.([-\d.e+]+))?[,)]", helptext, re.M)
names = [p[0] for p in params]
for expected in ("smax", "smin", "split_ratio", "contrast_bins", "free_below", "occupied_above", "lookahead",
                 "refine_passes", "gap_radius", "occupied_connectivity", "support_plane", "threads", "texture",
                 "similarity", "preset"):
    assert expected in names, (expected, names)
small = m[:16, :16, :16].copy()
np.save(os.path.join(work, "small.npy"), small)
for name, kind, default, lo, hi in params:
    r = run("segment", "small.npy", "--out", "p_ok", "--quiet", "--param", f"{name}={default}")
    assert r.returncode == 0, (name, default, r.stderr)
    if kind != "string":
        bad = str(float(hi) * 2 + 1) if kind == "double" else str(int(float(hi)) + 1)
        r = run("segment", "small.npy", "--out", "p_bad", "--param", f"{name}={bad}")
        assert r.returncode == 1 and name in r.stderr and r.stderr.count("\n") == 1, (name, bad, r.stderr)
assert not os.path.exists(os.path.join(work, "p_bad"))
r = run("segment", "small.npy", "--out", "p_tex", "--param", "texture=nosuch")
assert r.returncode == 1 and "nosuch" in r.stderr, r.stderr

# All or none: when the picture cannot be written (a directory is in its place), the files
# written before it are removed, and what was there before stays.
os.makedirs(os.path.join(work, "blocked", "segmentation.png"))
r = run("segment", "map.npy", "--out", "blocked")
assert r.returncode == 2 and "segmentation.png" in r.stderr and r.stderr.count("\n") == 1, (r.returncode, r.stderr)
assert os.listdir(os.path.join(work, "blocked")) == ["segmentation.png"], os.listdir(os.path.join(work, "blocked"))

# A 2D map (nz = 1): only the z slice.
np.save(os.path.join(work, "flat.npy"), m[10:11])
r = run("segment", "flat.npy", "--out", "flat", "--quiet")
assert r.returncode == 0, r.stderr
w, h, _ = read_png(os.path.join(work, "flat", "segmentation.png"))
# Narrower than the title: the title is wrapped onto two lines, the legend onto four.
assert (w, h) == figure_size((56, 48, 1), rows=2, title="occseg segment flat.npy  (56 x 48 x 1, preset default)") == (
    256, 510), (w, h)
print("cli report: all checks passed")
