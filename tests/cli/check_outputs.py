"""The output set of `occseg segment` (issue 27): the compact default set and --outputs LIST;
labels.nrrd gzip-encoded (read back with Python's gzip, equal to labels.npy); gzip-encoded NRRD
inputs (hand-made here with Python's gzip module, as 3D Slicer saves them) and corrupt ones
(truncated, flipped bytes, more or fewer bytes than the sizes say: exit 2, one line naming the file
and the problem, nothing written); a reused output folder keeps only the new run's files (an earlier
run's outputs removed, a foreign file and the input kept, the summary says so); a map too large for
the memory fails before it is allocated, naming voxels, bytes and the voxel size that would fit."""
import gzip
import json
import os
import shutil
import subprocess
import sys

import numpy as np

occseg, work, data = sys.argv[1], sys.argv[2], sys.argv[3]
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)


def run(*args):
    return subprocess.run([occseg, *args], capture_output=True, text=True, cwd=work)


def nrrd(path):
    """(header text, samples bytes) of a NRRD with an attached header, gzip or raw."""
    b = open(path, "rb").read()
    i = b.index(b"\n\n")
    head = b[:i + 1].decode()
    body = b[i + 2:]
    return head, gzip.decompress(body) if "\nencoding: gzip\n" in head else body


z, y, x = np.mgrid[0:24, 0:20, 0:16]
m = np.full((24, 20, 16), 0.1, dtype="<f4")
m[4:12, 5:15, 3:9] = 0.95
m[16:20, 2:6, 10:14] = 0.9
m[0:3] = 0.5
np.save(os.path.join(work, "map.npy"), m)

# --- the default set, and --outputs -----------------------------------------------------------
r = run("segment", "map.npy", "--out", "dflt", "--json")
assert r.returncode == 0, r.stderr
assert sorted(os.listdir(os.path.join(work, "dflt"))) == ["labels.nrrd", "scene.png", "segmentation.png", "segments.json"]
head, samples = nrrd(os.path.join(work, "dflt", "labels.nrrd"))
assert "\nencoding: gzip\n" in head and "\ntype: uint32\n" in head and "\nsizes: 16 20 24\n" in head, head

r = run("segment", "map.npy", "--out", "all", "--outputs", "all")
assert r.returncode == 0, r.stderr
assert sorted(os.listdir(os.path.join(work, "all"))) == ["labels.npy", "labels.nrrd", "scene.png", "segmentation.png",
                                                         "segments.json", "segments.ot", "segments.ply"]  # a grid: no map.nrrd, no cloud
labels = np.load(os.path.join(work, "all", "labels.npy"))
assert np.frombuffer(samples, "<u4").reshape(labels.shape).tolist() == labels.tolist()

r = run("segment", "map.npy", "--out", "two", "--outputs", "labels.npy, segments.json")
assert r.returncode == 0 and sorted(os.listdir(os.path.join(work, "two"))) == ["labels.npy", "segments.json"], r.stderr
r = run("segment", "map.npy", "--out", "plus", "--outputs", "default,labels.npy")
assert r.returncode == 0 and len(os.listdir(os.path.join(work, "plus"))) == 5, r.stderr

for bad, what in (("labels.vtk", "'labels.vtk'"), ("labels.npy,,segments.json", "an empty name"), ("ALL", "'ALL'")):
    r = run("segment", "map.npy", "--out", "bad_list", "--outputs", bad)
    assert r.returncode == 1 and r.stdout == "" and r.stderr.count("\n") == 1, (bad, r.returncode, r.stderr)
    assert what in r.stderr and "labels.nrrd, segments.json, segmentation.png" in r.stderr and "default or all" in r.stderr, r.stderr
    assert not os.path.exists(os.path.join(work, "bad_list")), bad
r = run("segment", "map.npy", "--out", "bad_kind", "--outputs", "segments.pcd")
assert r.returncode == 1 and "segments.pcd does not apply to this input" in r.stderr, r.stderr
assert not os.path.exists(os.path.join(work, "bad_kind"))

# --- a gzip-encoded NRRD input, made with Python's gzip (3D Slicer's default encoding) --------
def nrrd_file(name, body, sizes="16 20 24", encoding="gzip"):
    hdr = ("NRRD0004\ntype: float\ndimension: 3\nspace: left-posterior-superior\nsizes: " + sizes + "\n"
           "space directions: (1,0,0) (0,1,0) (0,0,1)\nkinds: domain domain domain\nendian: little\n"
           "encoding: " + encoding + "\nspace origin: (0.5,0.5,0.5)\n\n")
    with open(os.path.join(work, name), "wb") as f:
        f.write(hdr.encode() + body)
    return name

nrrd_file("slicer.nrrd", gzip.compress(m.tobytes()))
r = run("segment", "slicer.nrrd", "--out", "slicer", "--json")
assert r.returncode == 0, r.stderr
assert json.loads(r.stdout)["format"] == "NRRD, float, left-posterior-superior coordinates"
_, s2 = nrrd(os.path.join(work, "slicer", "labels.nrrd"))
assert s2 == samples, "the gzip NRRD input segments as the .npy of the same map"
nrrd_file("gz.nrrd", gzip.compress(m.tobytes()), encoding="gz")  # teem's other spelling
assert run("segment", "gz.nrrd", "--out", "gz").returncode == 0

# Corrupt gzip data: one line naming the file and the problem, exit 2, nothing written.
good = gzip.compress(m.tobytes())
flipped = bytearray(good)
flipped[len(good) // 2] ^= 0xff
bomb = gzip.compress(np.zeros(16 * 20 * 24 * 4, "<f4").tobytes())  # 4 x the bytes the sizes say
cases = [("cut.nrrd", good[:len(good) // 2], "is truncated"),
         ("flip.nrrd", bytes(flipped), "is corrupt"),
         ("noise.nrrd", b"\x1f\x8b\x08\x00" + bytes(range(256)) * 4, "is corrupt"),
         ("bomb.nrrd", bomb, "decompresses to more than the 30720 bytes the header promises"),
         ("short.nrrd", gzip.compress(m.tobytes()[:1000]), "ends after 1000 of the 30720 bytes"),
         ("empty.nrrd", b"", "is truncated"),
         ("huge.nrrd", gzip.compress(b"\0" * 100), "cannot hold")]
for name, body, why in cases:
    nrrd_file(name, body, sizes="16 20 24" if name != "huge.nrrd" else "4000 4000 4000")
    out = "out_" + name
    r = run("segment", name, "--out", out)
    assert r.returncode == 2 and r.stdout == "" and r.stderr.count("\n") == 1, (name, r.returncode, r.stderr)
    assert r.stderr.startswith("occseg: error: '" + name + "' is not a valid NRRD file: ") and why in r.stderr, (name, r.stderr)
    assert not os.path.exists(os.path.join(work, out)), name
# The bomb's output stopped at the expected size (the message says "more than", not how much).

# --- a reused folder holds this run's files only ------------------------------------------------
reuse = os.path.join(work, "reuse")
assert run("segment", "map.npy", "--out", "reuse", "--outputs", "all").returncode == 0
open(os.path.join(reuse, "notes.txt"), "w").write("mine")
os.makedirs(os.path.join(reuse, "map.nrrd"))  # a directory under an output's name is not a file of a run
shutil.copy(os.path.join(work, "map.npy"), os.path.join(reuse, "segments.pcd"))  # a stand-in for an old cloud
r = run("segment", "map.npy", "--out", "reuse")
assert r.returncode == 0, r.stderr
assert sorted(os.listdir(reuse)) == ["labels.nrrd", "map.nrrd", "notes.txt", "scene.png", "segmentation.png", "segments.json"], \
    os.listdir(reuse)
assert "removed (an earlier run's, not written now): reuse/labels.npy reuse/segments.pcd reuse/segments.ot reuse/segments.ply" in r.stdout, r.stdout
assert open(os.path.join(reuse, "notes.txt")).read() == "mine"
r = run("segment", "map.npy", "--out", "reuse", "--json")
assert json.loads(r.stdout)["removed"] == [], r.stdout
# The input itself, in the folder under an output's name, is never removed.
shutil.copy(os.path.join(work, "map.npy"), os.path.join(reuse, "labels.npy"))
r = run("segment", "reuse/labels.npy", "--out", "reuse", "--json")
assert r.returncode == 0 and os.path.exists(os.path.join(reuse, "labels.npy")), r.stderr
assert json.loads(r.stdout)["removed"] == []
# A run that fails removes nothing.
shutil.copy(os.path.join(work, "map.npy"), os.path.join(reuse, "labels.npy"))
open(os.path.join(work, "bad.npy"), "wb").write(b"\x93NUMPY garbage")
r = run("segment", "bad.npy", "--out", "reuse")
assert r.returncode == 2 and os.path.exists(os.path.join(reuse, "labels.npy")), r.stderr

# --- a map too large for the memory: refused before it is allocated ---------------------------
office = os.path.join(data, "office1.pcd")
r = run("segment", office, "--voxel-size", "0.001", "--out", "huge")
assert r.returncode == 3 and r.stderr.count("\n") == 1, (r.returncode, r.stderr)
for part in ("out of memory while reading office1.pcd: the map has ", " voxels, which need ", " GB (10 bytes per voxel)",
             " are available: a voxel size of ", " m or more would fit (--voxel-size)"):
    assert part in r.stderr, (part, r.stderr)
suggested = float(r.stderr.split("a voxel size of ")[1].split(" m")[0])
assert 0.001 < suggested < 0.05, suggested
assert not os.path.exists(os.path.join(work, "huge"))
print("ok")
