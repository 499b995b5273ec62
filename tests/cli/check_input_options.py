"""Input options as their help states them (issue 26): --sensor-origin and --sensor-orientation
each replace their half of the stored pose ("default: stored pose"), so one alone keeps the
other half (--sensor-origin alone flipped the table scene); an option of another format is a usage
error naming the option and the formats it applies to, for every format and option (--coarsen
on a .yaml map was accepted and ignored); big-endian .npy files, as NumPy writes and reads them,
are read (they were refused although np.load reads them)."""
import json
import os
import subprocess
import sys

import numpy as np

occseg, work, data = sys.argv[1], sys.argv[2], sys.argv[3]
table = os.path.join(data, "table_scene_mug_stereo_textured.pcd")
graph = os.path.join(data, "spherical_scan.graph")
tree = os.path.join(data, "geb079.bt")
yaml_map = os.path.join(data, "tb3_sandbox.yaml")


def run(*args):
    return subprocess.run([occseg, *args], capture_output=True, text=True, cwd=work, timeout=600)


def info(*args):
    r = run("info", *args, "--json")
    assert r.returncode == 0, (args, r.returncode, r.stderr)
    return json.loads(r.stdout)


def same_map(a, b):
    return all(a[k] == b[k] for k in ("dims", "origin", "states", "values", "unobserved"))


# --- The pose: each half defaults to the stored one. The table scene's VIEWPOINT is the origin
# turned 180 degrees about x (0 0 0 0 1 0 0): the grid is 59 x 35 x 131 at (-0.46, -0.18, -2.6).
stored = info(table, "--voxel-size", "0.02")
assert stored["dims"] == [59, 35, 131], stored["dims"]
assert [round(v, 2) for v in stored["origin"]] == [-0.46, -0.18, -2.6], stored["origin"]
assert same_map(info(table, "--voxel-size", "0.02", "--sensor-origin", "0", "0", "0"), stored)
assert same_map(info(table, "--voxel-size", "0.02", "--sensor-orientation", "0", "1", "0", "0"), stored)
unturned = info(table, "--voxel-size", "0.02", "--sensor-orientation", "1", "0", "0", "0")
assert unturned["dims"] == [59, 35, 130] and round(unturned["origin"][2], 2) == 0.0, unturned
assert same_map(info(table, "--voxel-size", "0.02", "--sensor-origin", "0", "0", "0", "--sensor-orientation", "1", "0",
                     "0", "0"), unturned)
# A moved sensor alone keeps the turn: the map of the stored pose, shifted by the move.
moved = info(table, "--voxel-size", "0.02", "--sensor-origin", "3", "-2", "1")
assert moved["dims"] == stored["dims"] and moved["states"] == stored["states"], (moved, stored)
for k, s in enumerate((3, -2, 1)):
    assert abs(moved["origin"][k] - stored["origin"][k] - s) < 1e-9, (moved["origin"], stored["origin"])

# A hand-written cloud whose VIEWPOINT has a position and no turn: --sensor-orientation alone
# keeps that position (it used to put the sensor at the world origin).
pts = [(x * 0.1, y * 0.1, 2.0) for x in range(-5, 6) for y in range(-5, 6)]
with open(os.path.join(work, "wall.pcd"), "w") as f:
    f.write("# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n"
            f"WIDTH {len(pts)}\nHEIGHT 1\nVIEWPOINT 1 2 -1 1 0 0 0\nPOINTS {len(pts)}\nDATA ascii\n")
    f.writelines(f"{x} {y} {z}\n" for x, y, z in pts)
wall = info("wall.pcd", "--voxel-size", "0.1")
assert wall["extent_m"]["min"][2] <= -1 + 1e-9, wall  # the sensor at z = -1 is inside the fitted grid
assert same_map(info("wall.pcd", "--voxel-size", "0.1", "--sensor-orientation", "1", "0", "0", "0"), wall)
assert same_map(info("wall.pcd", "--voxel-size", "0.1", "--sensor-origin", "1", "2", "-1"), wall)
assert not same_map(info("wall.pcd", "--voxel-size", "0.1", "--sensor-origin", "0", "0", "0"), wall)

# --- Options of another format: exit 1, one line naming the option and the formats it applies to.
np.save(os.path.join(work, "m.npy"), np.full((4, 5, 6), 0.2, np.float32))
APPLIES = {
    "--voxel-size": (["0.1"], ".npy, .nrrd, .pcd, .graph, .bt, .ot and plugin formats"),
    "--bbox": (["-1", "-1", "-1", "1", "1", "1"], ".pcd, .graph, .bt and .ot"),
    "--sensor-origin": (["0", "0", "0"], ".pcd and .graph"),
    "--sensor-orientation": (["1", "0", "0", "0"], ".pcd and .graph"),
    "--max-range": (["5"], ".pcd and .graph"),
    "--coarsen": (["max"], ".bt and .ot"),
}
for path, ext in (("m.npy", ".npy"), (yaml_map, ".yaml"), (table, ".pcd"), (graph, ".graph"), (tree, ".bt")):
    for opt, (vals, formats) in APPLIES.items():
        if ext in formats.replace(",", " ").split():
            continue
        for sub, extra in (("info", []), ("segment", ["--out", "o"])):
            r = run(sub, path, opt, *vals, *extra)
            assert r.returncode == 1, (sub, path, opt, r.returncode, r.stderr)
            assert r.stdout == "" and r.stderr.count("\n") == 1, (sub, path, opt, r.stdout, r.stderr)
            assert f"{opt} does not apply to {ext} input" in r.stderr and f"it applies to {formats} only" in r.stderr, \
                (sub, path, opt, r.stderr)
assert not os.path.exists(os.path.join(work, "o"))
# ... and the options of the format itself are accepted.
assert info(tree, "--coarsen", "mean", "--voxel-size", "0.16")["dims"][0] in (243, 244)

# --- Big-endian .npy, written by NumPy: the same map as the native-order file, for every dtype.
rng = np.random.default_rng(5)
p = rng.uniform(0, 1, size=(6, 7, 8))
for native, big in (("<f4", ">f4"), ("<f8", ">f8"), ("<u2", ">u2")):
    v = p if native[1] == "f" else np.round(p * 65535)
    np.save(os.path.join(work, "le.npy"), v.astype(native))
    np.save(os.path.join(work, "be.npy"), v.astype(big))
    assert np.load(os.path.join(work, "be.npy")).dtype.str == big  # really big-endian on disk
    a, b = info("le.npy"), info("be.npy")
    assert "big-endian" in b["format"] and "big-endian" not in a["format"], (a["format"], b["format"])
    assert same_map(a, b), (big, a, b)
    for d in ("le", "be"):
        r = run("segment", f"{d}.npy", "--out", f"seg_{d}", "--outputs", "labels.npy", "--quiet")
        assert r.returncode == 0, r.stderr
    assert np.array_equal(np.load(os.path.join(work, "seg_le", "labels.npy")),
                          np.load(os.path.join(work, "seg_be", "labels.npy"))), big
print("cli input options: all checks passed")
