"""Runs `occseg segment` as a user would and checks files, exit codes and messages."""
import json
import os
import subprocess
import sys

import numpy as np

occseg, work = sys.argv[1], sys.argv[2]


def run(*args):
    return subprocess.run([occseg, *args], capture_output=True, text=True)


# Two boxes in free space, with a Fortran-ordered copy that must give the same labels.
m = np.full((40, 48, 56), 0.12, dtype=np.float32)
m[5:15, 5:15, 5:15] = 0.97
m[20:35, 25:40, 30:50] = 0.97
np.save(os.path.join(work, "map.npy"), m)
np.save(os.path.join(work, "map_f.npy"), np.asfortranarray(m.astype(np.float64)))

out = os.path.join(work, "out")
r = run("segment", os.path.join(work, "map.npy"), "--out", out, "--outputs", "all")
assert r.returncode == 0, r.stderr
labels = np.load(os.path.join(out, "labels.npy"))
assert labels.dtype == np.uint32 and labels.shape == m.shape, (labels.dtype, labels.shape)
doc = json.load(open(os.path.join(out, "segments.json")))
assert doc["dims"] == [56, 48, 40] and doc["preset"] == "default"
occ = [s for s in doc["segments"] if s["state"] == "occupied"]
assert len(occ) == 2, occ
assert occ[0]["voxels"] == 1000 and occ[0]["bbox"] == {"min": [5, 5, 5], "max": [14, 14, 14]}, occ[0]
assert occ[1]["voxels"] == 15 * 15 * 20
assert all(s["id"] == i for i, s in enumerate(doc["segments"]))
assert (labels == labels[7, 7, 7]).sum() == 1000

r = run("segment", os.path.join(work, "map_f.npy"), "--out", out + "_f", "--threads", "1", "--outputs", "all")
assert r.returncode == 0, r.stderr
assert (np.load(os.path.join(out + "_f", "labels.npy")) == labels).all()

# Bad input: one line on stderr naming the problem, exit code 2, no output files.
bad = m.copy()
bad[3, 2, 1] = np.nan
np.save(os.path.join(work, "bad.npy"), bad)
r = run("segment", os.path.join(work, "bad.npy"), "--out", os.path.join(work, "bad_out"))
assert r.returncode == 2, (r.returncode, r.stderr)
assert "(1, 2, 3)" in r.stderr and "NaN" in r.stderr and r.stderr.count("\n") == 1, r.stderr
assert not os.path.exists(os.path.join(work, "bad_out", "labels.npy"))

with open(os.path.join(work, "trunc.npy"), "wb") as f:
    f.write(open(os.path.join(work, "map.npy"), "rb").read()[:500])
r = run("segment", os.path.join(work, "trunc.npy"), "--out", os.path.join(work, "t_out"))
assert r.returncode == 2 and "truncated" in r.stderr, r.stderr
r = run("segment", os.path.join(work, "missing.npy"), "--out", os.path.join(work, "m_out"))
assert r.returncode == 2 and "missing.npy" in r.stderr, r.stderr
r = run("segment", os.path.join(work, "map.npy"))
assert r.returncode == 1, r.returncode  # usage: --out missing
r = run("segment", os.path.join(work, "map.npy"), "--out", out, "--param", "smax=48", "--outputs", "all")
assert r.returncode == 1 and "smax" in r.stderr, r.stderr
print("cli segment: all checks passed")
