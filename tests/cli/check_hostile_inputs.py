"""Hostile input files through `occseg segment` / `occseg info` (issue 24): the command reads what
the reference library reads (liboctomap, NumPy, teem) or refuses with exit code 2 and a message,
never crashes, never writes outputs for a refused input, keeps an NRRD input's space, and never
prints a file's raw control bytes."""
import gzip
import json
import os
import struct
import subprocess
import sys

import numpy as np

occseg, work, data = sys.argv[1], sys.argv[2], sys.argv[3]


def run(*args):
    return subprocess.run([occseg, *args], capture_output=True)


def put(name, b):
    p = os.path.join(work, name)
    with open(p, "wb") as f:
        f.write(b)
    return p


def refused(args, phrase, name):
    out = os.path.join(work, "out_" + name)
    r = run("segment", *args, "--out", out)
    err = r.stderr.decode("ascii")  # the message is plain ASCII (escaped file bytes)
    assert r.returncode == 2, (name, r.returncode, err)
    assert phrase in err, (name, err)
    assert not os.path.exists(os.path.join(out, "labels.npy")), name


# 1. OctoMap: "data" in the middle of line 2, a '#' line of 0xff bytes, a harmless second header.
#    liboctomap reads the 0xff line as the tree and overflows the stack (SIGSEGV, exit -11).
for ext, first, leaf in ((".bt", b"# Octomap OcTree binary file\n", b"\x00\x00"),
                         (".ot", b"# Octomap OcTree file\n", b"\x00" * 5)):
    f = put("hostile" + ext, first + b"id OcTree size 5 res 0.1 data\n#" + b"\xff" * 200000 +
            b"\nid OcTree\nsize 1\nres 0.1\ndata\n" + leaf)
    refused([f], "is not a valid OctoMap file", "hostile" + ext)
# The same words on one line before a valid tree are a header liboctomap reads: so does occseg.
tree = put("one_line.ot", b"# Octomap OcTree file\nid OcTree size 1 res 0.1 data\n" + struct.pack("<f", 2.0) + b"\x00")
r = run("segment", tree, "--bbox", "-0.2", "-0.2", "-0.2", "0.2", "0.2", "0.2", "--out", os.path.join(work, "out_ol"))
assert r.returncode == 0, r.stderr

# 2. A huge --bbox on a tree: refused like the .pcd path refuses it (no 1-voxel map at -7e17 m).
huge = ["--bbox", "-1e300", "-1e300", "-1e300", "1e300", "1e300", "1e300"]
refused([os.path.join(data, "geb079.bt")] + huge, "bounding box needs too many voxels", "huge_bt")
refused([tree] + huge, "bounding box needs too many voxels", "huge_ot")
refused([os.path.join(data, "table_scene_mug_stereo_textured.pcd")] + huge, "bounding box needs too many voxels",
        "huge_pcd")

# 3. NRRD in LPS (3D Slicer's default): labels.nrrd in the same space, origin and directions.
m = np.full((6, 7, 8), 0.1, dtype="<f4")
m[2:4, 2:5, 3:6] = 0.95
geometry = "sizes: 8 7 6\nspace directions: (0.5,0,0) (0,0.5,0) (0,0,0.5)\n"
for space, written in (("left-posterior-superior", "left-posterior-superior"), ("LPS", "left-posterior-superior"),
                       ("right-anterior-superior", "right-anterior-superior")):
    hdr = ("NRRD0004\ntype: float\ndimension: 3\nspace: " + space + "\n" + geometry +
           "kinds: domain domain domain\nendian: little\nencoding: raw\nspace origin: (10.25,-20.5,3)\n\n")
    f = put("vol.nrrd", hdr.encode() + m.tobytes())
    out = os.path.join(work, "out_" + space)
    r = run("segment", f, "--out", out, "--outputs", "all")
    assert r.returncode == 0, r.stderr
    b = open(os.path.join(out, "labels.nrrd"), "rb").read()
    head = b[:b.index(b"\n\n") + 1].decode()
    assert ("\nspace: %s\n" % written) in head, head
    assert "\n" + geometry.split("\n")[1] + "\n" in head and "\nspace origin: (10.25,-20.5,3)\n" in head, head
    assert "\nencoding: gzip\n" in head, head
    labels = np.frombuffer(gzip.decompress(b[b.index(b"\n\n") + 2:]), dtype="<u4").reshape(6, 7, 8)
    assert np.array_equal(labels, np.load(os.path.join(out, "labels.npy"))), space

# 4. .npy headers: whatever occseg reads, NumPy reads with the same shape; the rest is refused.
def npy(header):
    h = header.encode("latin1")
    h += b" " * ((64 - (10 + len(h) + 1) % 64) % 64) + b"\n"
    return b"\x93NUMPY\x01\x00" + struct.pack("<H", len(h)) + h + np.full(64, 0.25, "<f4").tobytes()


headers = [
    "{'descr': '<f4', 'fortran_order': False, 'shape': (4, 4, 4), }",
    "{'descr': '<f4', 'fortran_order': False, 'shape': (2,2,2), 'shape': (4,4,4)}",
    "{'descr': '<f4', 'fortran_order': False, 'shape': (4,4,4), 'shape': (2,2,2)}",
    "{'descr': '<f4', 'fortran_order': False, 'note': \"'shape': (2,2,2)\", 'shape': (4,4,4)}",
    "{'descr': \"<f4', 'shape': (2,2,2), 'x': '\", 'fortran_order': False, 'shape': (4,4,4)}",
    "{'descr': '<f4', 'fortran_order': False, 'shape': (64)}",
    "{'descr': '<f4', 'fortran_order': 0, 'shape': (4,4,4)}",
    "{'descr': '<f4', 'fortran_order': False, 'shape': (4,4,4)} 'shape': (2,2,2)",
    "{\"descr\": \"<f4\", \"fortran_order\": False, \"shape\": (4, 4, 4)}",
    "{'descr': '<f4', # comment\n 'fortran_order': False, 'shape': (4,\n 4, 4,)}",
    "{'shape': (8, 8), 'descr': '<f4', 'fortran_order': True}",
    "{'descr': '<f4', 'fortran_order': False, 'shape': (4L, 4L, 4L)}",
]
for i, h in enumerate(headers):
    f = put("h%d.npy" % i, npy(h))
    try:
        theirs = np.load(f).shape
    except Exception:
        theirs = None
    r = run("info", f, "--json")
    if r.returncode == 0:
        dims = json.loads(r.stdout)["dims"]  # x, y, z
        assert theirs is not None and list(reversed(theirs)) == [d for d in dims if len(theirs) == 3 or d != 1], (h, theirs, dims)
    else:
        assert r.returncode == 2 and b"is not a valid .npy file" in r.stderr, (h, r.stderr)

# 5. NRRD field names in any case, as teem reads them: "Data File:" is a detached data file.
base = "NRRD0004\ntype: float\ndimension: 3\nsizes: 2 2 2\nendian: little\nencoding: raw\n"
refused([put("detached.nrrd", (base + "Data File: elsewhere.raw\n\n").encode() + bytes(32))],
        "detached data files are not supported", "detached")
refused([put("twice.nrrd", (base + "Sizes: 4 4 4\n\n").encode() + bytes(32))], "appears twice", "twice")

# 6. A garbage header's control bytes are escaped in the message (no raw ESC, BEL or 0xff).
evil = b"\x1b]0;owned\x07\x1b[31mRED\xff\xfe"
for name, b in (("evil.pcd", b"# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\n" + evil + b"\nDATA ascii\n"),
                ("evil.nrrd", b"NRRD0004\n" + evil + b"\n\n"),
                ("evil.npy", npy("{'descr': '" + evil.decode("latin1") + "', 'fortran_order': False, 'shape': (4,4,4)}")),
                ("evil.bt", b"# Octomap OcTree binary file\nid " + evil + b"\nsize 0\nres 0.1\ndata\n")):
    r = run("info", put(name, b))
    assert r.returncode == 2, (name, r.stderr)
    assert all(0x20 <= c < 0x7f or c == 0x0a for c in r.stderr), (name, r.stderr)
    assert b"\\x1b" in r.stderr, (name, r.stderr)
print("cli hostile inputs: all checks passed")
