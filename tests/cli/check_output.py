"""What `occseg` leaves when output fails (docs/cli.md, "Output files: all or none"): stdout that
cannot be written (a full disk) is exit 2 with a message, never a silent exit 0; out of memory at
any point of `occseg segment` is exit 3 with "out of memory while ..."; and a re-run into the
folder of an earlier run that fails in any of these ways, or at a later file, leaves every file
of the earlier run exactly as it was, with no temporary beside it."""
import glob
import os
import resource
import shutil
import subprocess
import sys

import numpy as np

occseg, work, data = sys.argv[1], sys.argv[2], sys.argv[3]


def run(args, stdout=subprocess.PIPE, address_space=None):
    """Runs occseg in `work`; `address_space`: RLIMIT_AS in bytes (as `ulimit -v`)."""
    def limit():
        if address_space:
            resource.setrlimit(resource.RLIMIT_AS, (address_space, address_space))
    return subprocess.run([occseg, *args], cwd=work, stdout=stdout, stderr=subprocess.PIPE, text=True,
                          preexec_fn=limit)


def snapshot(d):
    """Every entry of folder `d` (work-relative) with its bytes; folders as None."""
    p = os.path.join(work, d)
    out = {}
    for f in sorted(os.listdir(p)):
        full = os.path.join(p, f)
        out[f] = None if os.path.isdir(full) else open(full, "rb").read()
    return out


def restore(d, snap):
    p = os.path.join(work, d)
    shutil.rmtree(p, ignore_errors=True)
    os.makedirs(p)
    for f, b in snap.items():
        if b is None:
            os.makedirs(os.path.join(p, f))
        else:
            with open(os.path.join(p, f), "wb") as o:
                o.write(b)


def no_temporaries():
    left = glob.glob(os.path.join(work, "**", "*.tmp-*"), recursive=True)
    assert not left, left


# A small map, and one with many segments (2^3-voxel cells of alternating state: 65536 segments),
# whose segment table is the largest thing the command builds after the segmentation.
z, y, x = np.indices((40, 48, 56))
small = np.where((x >= 10) & (x < 30) & (y >= 10) & (y < 30) & (z >= 10) & (z < 30), 0.9, 0.1).astype(np.float32)
np.save(os.path.join(work, "small.npy"), small)
z, y, x = np.indices((64, 64, 128))
cells = np.where(((x // 2) + (y // 2) + (z // 2)) % 2 == 1, 240, 10).astype(np.uint8)
np.save(os.path.join(work, "cells.npy"), cells)

# --- stdout on a full disk: exit 2 and a message, for the data outputs and for --help ---------
with open("/dev/full", "w") as full:
    for args in (["segment", "small.npy", "--out", "full_json", "--json"], ["segment", "small.npy", "--out", "full_text"],
                 ["info", "small.npy"], ["info", "small.npy", "--json"], ["plugins"], ["--help"],
                 ["segment", "--help"], ["--version"]):
        r = run(args, stdout=full)
        assert r.returncode == 2, (args, r.returncode, r.stderr)
        assert r.stderr == "occseg: error: cannot write to standard output: No space left on device\n", (args, r.stderr)
        assert run(args).returncode == 0, args  # and the same to a pipe works
# The files were complete before the summary was printed; they stay.
assert sorted(os.listdir(os.path.join(work, "full_json"))) == ["labels.nrrd", "scene.png", "segmentation.png", "segments.json"]
no_temporaries()

# --- out of memory anywhere in `occseg segment`: exit 3, "out of memory while ...", old set kept ---
# Not under sanitizers (OCCSEG_TEST_NO_OOM, set by CMake there): see tests/cli/CMakeLists.txt.
if os.environ.get("OCCSEG_TEST_NO_OOM"):
    print("out of memory: skipped (sanitizer build)")
else:
    # The earlier run (preset paper) and what the new one (preset default) writes without a limit.
    assert run(["segment", "cells.npy", "--out", "oom", "--preset", "paper", "--threads", "2"]).returncode == 0
    assert run(["segment", "cells.npy", "--out", "oom_ref", "--threads", "2"]).returncode == 0
    old, new = snapshot("oom"), snapshot("oom_ref")
    assert old != new
    # The smallest limit at which the program starts at all, then limits in steps of 8 MiB from there
    # until three runs in a row succeed: each run either succeeds with the complete new set or fails
    # with exit 3 and leaves the old one.
    start = 16 << 20
    while run(["--version"], address_space=start).returncode != 0:
        start = int(start * 1.25)
        assert start < 8 << 30, "occseg does not start under any address-space limit"
    results, limit = [], start
    while len(results) < 3 or any(c != 0 for _, c, _ in results[-3:]):
        assert limit < start + (4 << 30), results
        restore("oom", old)
        r = run(["segment", "cells.npy", "--out", "oom", "--threads", "2"], address_space=limit)
        mb = limit >> 20
        assert r.returncode in (0, 3), (mb, r.returncode, r.stderr)
        if r.returncode == 3:
            assert r.stderr.startswith("occseg: error: out of memory while ") and r.stderr.count("\n") == 1, (mb, r.stderr)
            assert r.stdout == "", (mb, r.stdout)
            assert snapshot("oom") == old, f"{mb} MiB: the earlier run's files changed: {sorted(snapshot('oom'))}"
        else:
            assert snapshot("oom") == new, f"{mb} MiB: exit 0 but not the complete new set: {sorted(snapshot('oom'))}"
        no_temporaries()
        results.append((mb, r.returncode, r.stderr.strip()))
        limit += 8 << 20
    codes = [c for _, c, _ in results]
    assert 3 in codes and 0 in codes, results  # the limits did bite, and enough memory works
    print("out of memory:", "; ".join(f"{mb} MiB: {e or 'ok'}" for mb, _, e in results))

# --- a re-run that fails at a later file: the earlier run's files stay as they were -----------------
# (a folder where segments.json, summary.json, truth_state.npy would go: only found when that file
# is reached, after the ones before it are written)
for name, first, second, blocker in (
        ("segment", ["segment", "cells.npy", "--out", "later", "--preset", "paper"],
         ["segment", "small.npy", "--out", "later"], "segments.json"),
        ("demo", ["demo", "--dims", "48", "48", "24", "--out", "later_demo", "--quiet"],
         ["demo", "--dims", "48", "48", "24", "--seed", "2", "--out", "later_demo", "--quiet"], "summary.json"),
        ("simulate", ["simulate", "--scene", "cone", "--dims", "48", "48", "24", "--out", "later_sim"],
         ["simulate", "--scene", "cone", "--dims", "48", "48", "24", "--seed", "2", "--out", "later_sim"],
         "truth_state.npy")):
    r = run(first)
    assert r.returncode == 0, (name, r.stderr)
    d = first[first.index("--out") + 1]
    os.remove(os.path.join(work, d, blocker))
    os.makedirs(os.path.join(work, d, blocker))
    before = snapshot(d)
    r = run(second)
    assert r.returncode == 2 and f"{blocker}': it is a directory" in r.stderr, (name, r.returncode, r.stderr)
    assert snapshot(d) == before, f"{name}: the earlier run's files changed: {sorted(snapshot(d))}"
    no_temporaries()

print("cli output: all checks passed")
