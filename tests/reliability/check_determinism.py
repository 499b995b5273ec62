"""`occseg segment` output is byte-identical across runs and thread counts (1, 2, 5): a noisy
synthetic map with odd sizes (so work chunks split unevenly), and real data (the OctoMap
corridor .bt, the table-scene .pcd, whose fusion is threaded too)."""
import hashlib
import os
import subprocess
import sys

import numpy as np

occseg, work, data = sys.argv[1], sys.argv[2], sys.argv[3]

rng = np.random.default_rng(11)
m = np.clip(rng.normal(0.15, 0.08, (37, 53, 71)), 0, 1).astype(np.float32)
m[5:20, 10:40, 20:60] = np.clip(rng.normal(0.85, 0.1, (15, 30, 40)), 0, 1)
m[25:37, :, 50:] = 0.5
np.save(os.path.join(work, "noisy.npy"), m)

inputs = [(os.path.join(work, "noisy.npy"), [])]
if os.path.exists(os.path.join(data, "geb079.bt")):
    inputs.append((os.path.join(data, "geb079.bt"), []))
if os.path.exists(os.path.join(data, "table_scene_mug_stereo_textured.pcd")):
    inputs.append((os.path.join(data, "table_scene_mug_stereo_textured.pcd"), ["--voxel-size", "0.02"]))

failed = 0
for path, extra in inputs:
    name = os.path.basename(path)
    digests = {}
    for run, threads in enumerate([1, 2, 5, 2]):  # 2 twice: across runs too
        out = os.path.join(work, "%s_%d_t%d" % (name, run, threads))
        r = subprocess.run([occseg, "segment", path, "--out", out, "--threads", str(threads), "--outputs", "all"] + extra,
                           capture_output=True, text=True)
        if r.returncode == 2 and "which this build of occseg lacks" in r.stderr:
            break  # e.g. the ThreadSanitizer build, made without the PCL and OctoMap adapters
        assert r.returncode == 0, (name, threads, r.stderr)
        files = sorted(os.listdir(out))
        assert "labels.npy" in files and "segments.json" in files, files
        digests[(run, threads)] = {f: hashlib.sha256(open(os.path.join(out, f), "rb").read()).hexdigest()
                                   for f in files}
    if not digests:
        print("%s: skipped, this build cannot read it" % name)
        continue
    first = next(iter(digests.values()))
    for key, d in digests.items():
        if d != first:
            failed += 1
            print("%s: run %d with --threads %d differs: %s" % (
                name, key[0], key[1], [f for f in d if d[f] != first.get(f)]))
    labels = np.load(os.path.join(work, "%s_0_t1" % name, "labels.npy"))
    assert labels.max() > 0, name  # more than one segment, so the comparison means something
    print("%s: %d files identical over 4 runs (threads 1, 2, 5, 2), %d segments" % (
        name, len(first), labels.max() + 1))
sys.exit(1 if failed else 0)
