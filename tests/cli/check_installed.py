"""The installed `occseg` (<prefix>/bin/occseg) runs without ldconfig or LD_LIBRARY_PATH: its
adapter libraries resolve to <prefix>/<libdir>, and it reads the formats they serve."""
import json
import os
import subprocess
import sys

prefix, libdir, data = sys.argv[1], sys.argv[2], sys.argv[3]
tool = os.path.join(prefix, "bin", "occseg")
assert os.access(tool, os.X_OK), tool
assert "LD_LIBRARY_PATH" not in os.environ

# Every occseg library the tool needs comes from the prefix.
ldd = subprocess.run(["ldd", tool], capture_output=True, text=True, check=True).stdout
ours = [l.split() for l in ldd.splitlines() if "liboccseg" in l]
assert ours, ldd
for parts in ours:
    assert "not found" not in " ".join(parts), ldd
    assert os.path.realpath(parts[2]).startswith(os.path.realpath(os.path.join(prefix, libdir))), (parts, ldd)

r = subprocess.run([tool, "--version"], capture_output=True, text=True)
assert r.returncode == 0 and r.stdout.startswith("occseg "), (r.returncode, r.stderr)
for name, fmt in (("geb079.bt", "OctoMap tree"), ("table_scene_mug_stereo_textured.pcd", "PCL point cloud")):
    r = subprocess.run([tool, "info", os.path.join(data, name), "--json"], capture_output=True, text=True)
    assert r.returncode == 0, (name, r.stderr)
    assert json.loads(r.stdout)["format"].startswith(fmt), r.stdout
# The documentation is installed, and --help names the installed folder (found beside the program).
docs = os.path.realpath(os.path.join(prefix, "share", "doc", "occseg"))
for f in ("README.md", "docs/cli.md", "docs/c-api.md", "docs/python.md"):
    assert os.path.isfile(os.path.join(docs, f)), f
r = subprocess.run([tool, "--help"], capture_output=True, text=True)
assert r.returncode == 0 and f"Documentation: {docs}/README.md and {docs}/docs/" in r.stdout, r.stdout[-400:]
print(f"cli installed ({prefix}): all checks passed")
