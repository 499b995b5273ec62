"""Numeric options of every subcommand: NaN, infinities, overflow, negative or octal-looking whole
numbers are usage errors naming the option (CLI11's own range checks let NaN through, so
`--voxel-size nan` used to be ignored with exit 0); options of another input format are usage
errors; values that put a map out of range are bad input saying so; a quaternion whose norm
overflows is still the rotation it names; and a cloud seen from UTM-like coordinates gives the
same map as at the world origin (in float it lost half to two thirds of its occupied voxels)."""
import json
import os
import subprocess
import sys

import numpy as np

occseg, work, data = sys.argv[1], sys.argv[2], sys.argv[3]
table = os.path.join(data, "table_scene_mug_stereo_textured.pcd")
graph = os.path.join(data, "spherical_scan.graph")


def run(*args):
    return subprocess.run([occseg, *args], capture_output=True, text=True, cwd=work, timeout=300)


def one_line_error(r, code, *words):
    assert r.returncode == code, (r.args, r.returncode, r.stdout[-300:], r.stderr)
    assert r.stdout == "", (r.args, r.stdout[-300:])
    assert r.stderr.count("\n") == 1 and r.stderr.startswith("occseg: "), (r.args, r.stderr)
    for w in words:
        assert w in r.stderr, (r.args, w, r.stderr)


def info(*args):
    r = run("info", *args, "--json")
    assert r.returncode == 0, (args, r.returncode, r.stderr)
    return json.loads(r.stdout)


m = np.full((8, 8, 8), 0.2, np.float32)
m[3:5, 3:5, 3:5] = 0.9
np.save(os.path.join(work, "m.npy"), m)
BAD_REAL = ["nan", "-nan", "NaN", "inf", "-inf", "1e400", "-1e400"]

# --- segment and info: every numeric option, every bad value: exit 1, nothing created.
for sub, base in (("segment", ["m.npy", "--out", "o"]), ("info", ["m.npy"])):
    for opt, n, extra_bad in (("--voxel-size", 1, ["0", "-1", "1e-400"]), ("--max-range", 1, ["0", "-2"]),
                              ("--bbox", 6, []), ("--sensor-origin", 3, []), ("--sensor-orientation", 4, []),
                              ("--threads", 1, ["-1", "1.5", "1e3", "2000", "99999999999999999999", "0x2"])):
        for v in BAD_REAL + extra_bad:
            one_line_error(run(sub, *base, opt, *([v] + ["1"] * (n - 1))), 1, opt, "usage error")
    for v in BAD_REAL + ["-1", "2.5", "1000001"]:
        if sub == "segment":
            one_line_error(run(sub, *base, "--top", v), 1, "--top")
    one_line_error(run(sub, *base, "--param", "free_below=nan"), 1, "free_below")
# The same values on a cloud (where --max-range and the pose apply) are usage errors too.
for opt, vals in (("--max-range", ["nan"]), ("--sensor-origin", ["nan", "0", "0"]),
                  ("--sensor-orientation", ["1", "inf", "0", "0"]), ("--bbox", ["0", "0", "0", "1", "1", "nan"])):
    one_line_error(run("info", table, opt, *vals), 1, opt)
one_line_error(run("info", table, "--sensor-orientation", "0", "0", "0", "0"), 1, "--sensor-orientation")

# --- demo, simulate, figures, evaluate.
sim = ["simulate", "--scene", "cube", "--dims", "40", "40", "20", "--out", "s"]
for opt, bad in (("--voxel-size", BAD_REAL + ["0"]), ("--sigma", BAD_REAL + ["-1"]),
                 ("--angle-step", BAD_REAL + ["0", "91"]), ("--max-range", BAD_REAL + ["0"]),
                 ("--seed", BAD_REAL + ["-1", "1.5", "18446744073709551616", "99999999999999999999"]),
                 ("--threads", ["nan", "-1"])):
    for v in bad:
        one_line_error(run(*sim, opt, v), 1, opt)
for v in ["nan", "-1", "0", "1.5", "1e3", "99999999999999999999"]:
    one_line_error(run("simulate", "--scene", "cube", "--out", "s", "--dims", v, "40", "20"), 1, "--dims")
    one_line_error(run("demo", "--out", "d", "--dims", "40", v, "20"), 1, "--dims")
    one_line_error(run("figures", "--out", "f", "--scene", "cube", "--dims", "40", "40", v), 1, "--dims")
for v in BAD_REAL + ["0"]:
    one_line_error(run("demo", "--out", "d", "--voxel-size", v), 1, "--voxel-size")
    one_line_error(run("figures", "--out", "f", "--voxel-size", v), 1, "--voxel-size")
for v in ["nan", "-1", "99999999999999999999"]:
    one_line_error(run("demo", "--out", "d", "--seed", v), 1, "--seed")
    one_line_error(run("figures", "--out", "f", "--seed", v), 1, "--seed")
for opt in ("--reach", "--threads"):
    for v in ["nan", "-1", "1.5"]:
        one_line_error(run("evaluate", "--truth", "t", opt, v), 1, opt)
for d in ("o", "s", "d", "f"):
    assert not os.path.exists(os.path.join(work, d)), d

# A leading zero is decimal, not octal: seed 010 is ten (CLI11 alone read it as eight).
r = run(*sim[:-2], "--out", "s10", "--seed", "010")
assert r.returncode == 0 and "seed 10)" in r.stdout, (r.returncode, r.stdout, r.stderr)

# --- Options of another input format are usage errors, whatever their value.
one_line_error(run("info", "m.npy", "--max-range", "5"), 1, "--max-range", ".npy")
one_line_error(run("info", "m.npy", "--coarsen", "mean"), 1, "--coarsen", ".npy")
one_line_error(run("info", table, "--coarsen", "max"), 1, "--coarsen", ".pcd")
one_line_error(run("info", "m.npy", "--bbox", "0", "0", "0", "1", "1", "1"), 1, "--bbox")

# --- Values that put the map out of range: bad input (exit 2) saying so, nothing written.
one_line_error(run("segment", "m.npy", "--out", "o", "--voxel-size", "1e308"), 2, "m.npy", "out of range")
r = run("info", table, "--sensor-origin", "1e30", "0", "0")
one_line_error(r, 2, "out of range", "x = 1e+30")
assert "have a zero" not in r.stderr, r.stderr
one_line_error(run("info", table, "--bbox", "1e15", "0", "0", "1.0000000001e15", "1", "1"), 2, "out of range")
assert not os.path.exists(os.path.join(work, "o"))

# --- A quaternion is normalised without overflow: (1e200, 1e200, 0, 0) is (1, 1, 0, 0), a turn
# of 90 degrees about x, not the identity it became when its squared norm overflowed.
turn = info(table, "--sensor-orientation", "1", "1", "0", "0")
for q in (["1e200", "1e200", "0", "0"], ["1e-200", "1e-200", "0", "0"]):
    j = info(table, "--sensor-orientation", *q)
    for key in ("dims", "origin", "states", "values", "unobserved"):
        assert j[key] == turn[key], (q, key, j[key], turn[key])
identity = info(table, "--sensor-orientation", "1", "0", "0", "0")
assert identity["dims"] != turn["dims"] or identity["states"] != turn["states"], "the turn must change the map"

# --- UTM-like sensor positions: the same map, shifted (fitted boxes; whole metres, so the voxel
# grid lies the same way relative to the sensor).
for path, vs in ((table, "0.05"), (table, "0.02"), (graph, "0.1")):
    a = info(path, "--voxel-size", vs, "--sensor-origin", "0", "0", "0")
    b = info(path, "--voxel-size", vs, "--sensor-origin", "500000", "5000000", "0")
    assert a["states"]["occupied"] > 100, a
    assert b["dims"] == a["dims"] and b["states"] == a["states"], (path, vs, a["states"], b["states"])
    for k, s in enumerate((500000, 5000000, 0)):
        assert abs(b["origin"][k] - a["origin"][k] - s) < 1e-6, (path, a["origin"], b["origin"])
print("cli options: all checks passed")
