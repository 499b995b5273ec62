"""Every format the occseg command reads, from Python without a load call: the first read of an
extension no loaded reader serves loads the default plugin search path (issue 26), unless
OCCSEG_NO_DEFAULT_PLUGINS is set; an extension nothing serves names the fix. Each case runs in a
fresh interpreter, since plugins stay loaded. The search path is the build's plugin folder on
OCCSEG_PLUGIN_PATH (an installed liboccseg finds <libdir>/occseg/plugins by itself)."""
import json
import os
import subprocess
import sys

import pytest

import occseg

READERS = os.environ.get("OCCSEG_READER_PLUGINS")
DATA = os.environ.get("OCCSEG_SHARED_DATA", "")
pytestmark = [pytest.mark.skipif(not hasattr(occseg, "load_plugin"), reason="liboccseg predates plugins"),
              pytest.mark.skipif(not READERS, reason="this build has no reader plugins")]


def fresh(code, **env):
    """Runs `code` in a new interpreter with the suite's environment, the build's plugin folder on
    the search path and `env` on top (None removes a variable); returns the CompletedProcess."""
    e = dict(os.environ, OCCSEG_PLUGIN_PATH=READERS)
    e.pop("OCCSEG_NO_DEFAULT_PLUGINS", None)
    for k, v in env.items():
        if v is None:
            e.pop(k, None)
        else:
            e[k] = v
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=e, timeout=600)


def test_read_map_of_a_tree_needs_no_load_call():
    r = fresh(f"""
import json, occseg
before = [p.name for p in occseg.plugins()]
with occseg.read_map({os.path.join(DATA, 'geb079.bt')!r}) as m:
    out = dict(dims=m.dims, voxel_size=m.voxel_size, before=before, after=[p.name for p in occseg.plugins()])
print(json.dumps(out))
""")
    assert r.returncode == 0, r.stderr
    out = json.loads(r.stdout)
    assert "octomap_reader" not in out["before"]
    assert out["dims"] == [487, 187, 39] and abs(out["voxel_size"] - 0.08) < 1e-9
    assert out["after"].count("octomap_reader") == 1 and "pcl_reader" in out["after"]


def test_cloud_and_scan_graph_need_no_load_call():
    r = fresh(f"""
import occseg
for f, kw in (("table_scene_mug_stereo_textured.pcd", dict(voxel_size=0.05)), ("spherical_scan.graph", {{}})):
    with occseg.read_map({DATA!r} + "/" + f, **kw) as m:
        assert min(m.dims) > 1, m.dims
""")
    assert r.returncode == 0, r.stderr


def test_liboctomap_prints_nothing_on_the_host_streams():
    # liboctomap's readers print progress ("Reading 10201 points from binary file...done." for a
    # scan graph) on stderr; a library must not write into its host's streams.
    r = fresh(f"""
import occseg
for f in ("geb079.bt", "spherical_scan.graph"):
    occseg.read_map({DATA!r} + "/" + f).close()
""")
    assert r.returncode == 0, r.stderr
    assert r.stdout == "" and r.stderr == ""


def test_opt_out_loads_nothing_and_says_how_to_load():
    r = fresh(f"""
import occseg
try:
    occseg.read_map({os.path.join(DATA, 'geb079.bt')!r})
except occseg.OccsegError as e:
    assert e.status == occseg.Status.EUNSUPPORTED, e
    assert "octomap_reader" not in [p.name for p in occseg.plugins()]
    print(e.message)
    assert occseg.load_default_plugins() >= 1
    occseg.read_map({os.path.join(DATA, 'geb079.bt')!r}).close()
else:
    raise SystemExit("read without plugins")
""", OCCSEG_NO_DEFAULT_PLUGINS="1")
    assert r.returncode == 0, r.stderr
    for part in ("'.bt'", "OCCSEG_NO_DEFAULT_PLUGINS is set", "occseg_plugins_load_default()",
                 "occseg.load_default_plugins()", "occseg.load_plugin(path)"):
        assert part in r.stdout, (part, r.stdout)


def test_an_extension_nothing_reads_names_the_search_path_and_the_fix(tmp_path):
    r = fresh(f"""
import occseg
try:
    occseg.read_map({str(tmp_path / 'map.nosuchformat')!r})
except occseg.OccsegError as e:
    assert e.status == occseg.Status.EUNSUPPORTED, e
    print(":".join(occseg.plugin_search_path()))
    print(e.message)
""")
    assert r.returncode == 0, r.stderr
    search, message = r.stdout.splitlines()
    for part in ("'.nosuchformat'", search, "occseg_plugins_load(", "OCCSEG_PLUGIN_PATH", "occseg.load_plugin(path)"):
        assert part in message, (part, message)


def test_pcd_pose_options_replace_one_half_each():
    # read_map takes the pose as the command's --sensor-origin / --sensor-orientation do: each
    # replaces its half of the VIEWPOINT (the table scene: the origin, turned 180 degrees about x).
    r = fresh(f"""
import numpy as np, occseg
f = {os.path.join(DATA, 'table_scene_mug_stereo_textured.pcd')!r}
def values(**kw):
    with occseg.read_map(f, voxel_size=0.1, **kw) as m:
        return m.dims, m.origin, m.to_array()
stored = values()
for kw in (dict(sensor_origin=(0, 0, 0)), dict(sensor_orientation=(0, 1, 0, 0))):
    got = values(**kw)
    assert got[:2] == stored[:2] and np.array_equal(got[2], stored[2]), kw
none = values(sensor_orientation=(1, 0, 0, 0))
assert none[:2] != stored[:2]
try:
    values(sensor_orientation=(0, 0, 0, 0))
except occseg.OccsegError as e:
    assert e.status == occseg.Status.EINVAL and "sensor_orientation" in e.message, e
else:
    raise SystemExit("a zero quaternion was accepted")
""")
    assert r.returncode == 0, r.stderr
