"""The C API gives exactly what the C++ pipeline gives: the same map segmented by `occseg segment`
(C++) and by tests/c/compare_tool.c (C, through the installed liboccseg) must yield identical
labels.npy and segments.json. Usage: compare_cli.py OCCSEG_CLI COMPARE_TOOL WORKDIR"""
import json
import os
import subprocess
import sys

import numpy as np

cli, tool, work = sys.argv[1:4]
os.makedirs(work, exist_ok=True)

# A noisy scene: graded free space, two occupied boxes, an unknown (0.5) slab, sensor-like noise.
rng = np.random.default_rng(20240611)
nz, ny, nx = 36, 44, 52
m = rng.uniform(0.05, 0.3, size=(nz, ny, nx))
m[4:14, 6:18, 5:15] = rng.uniform(0.8, 0.99, size=(10, 12, 10))
m[20:31, 25:40, 28:47] = rng.uniform(0.7, 0.95, size=(11, 15, 19))
m[:, 30:36, 0:20] = 0.5
m = m.astype(np.float64)
np.save(os.path.join(work, "map.npy"), m.astype(np.float32))
# Raw float64 in Fortran order of [z, y, x]: the tool passes it with strides (x slowest).
np.asfortranarray(m.astype(np.float32).astype(np.float64)).ravel(order="K").tofile(os.path.join(work, "map.f64"))

cpp_out, c_npy, c_raw = (os.path.join(work, d) for d in ("cpp", "c_npy", "c_raw"))
subprocess.run([cli, "segment", os.path.join(work, "map.npy"), "--out", cpp_out, "--outputs", "all"], check=True)
subprocess.run([tool, os.path.join(work, "map.npy"), c_npy, os.path.join(work, "map.f64"),
                str(nx), str(ny), str(nz), c_raw], check=True)

ref_labels = np.load(os.path.join(cpp_out, "labels.npy"))
ref_json = json.load(open(os.path.join(cpp_out, "segments.json")))
assert len(ref_json["segments"]) >= 3, ref_json["segments"]
for out in (c_npy, c_raw):
    labels = np.load(os.path.join(out, "labels.npy"))
    assert labels.dtype == np.uint32 and labels.shape == (nz, ny, nx), (labels.dtype, labels.shape)
    assert (labels == ref_labels).all(), f"{out}: {(labels != ref_labels).sum()} labels differ"
    doc = json.load(open(os.path.join(out, "segments.json")))
    assert doc == ref_json, f"{out}/segments.json differs from the C++ tool's"
print(f"C API matches the C++ pipeline: {len(ref_json['segments'])} segments, {ref_labels.size} voxels")
