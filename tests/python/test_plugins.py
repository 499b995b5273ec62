"""The plugin interface through Python: the registry, readers and writers by extension, stages
picked by parameter, broken plugins refused with the reason, and the example plugin
(plugins/example, built from a test install) used by segment() exactly as the tool uses it."""
import json
import os
import subprocess
import sys

import numpy as np
import pytest

import occseg
from occseg import OccsegError, Status

pytestmark = pytest.mark.skipif(not hasattr(occseg, "load_plugin"), reason="liboccseg predates plugins")

EXAMPLE = os.environ.get("OCCSEG_EXAMPLE_PLUGIN")
BROKEN = os.environ.get("OCCSEG_BROKEN_PLUGINS")


def cube_map():
    m = np.full((16, 16, 16), 0.1, dtype=np.float32)
    m[4:12, 4:12, 4:12] = 0.9
    return m


def test_builtin_registry():
    names = [p.name for p in occseg.plugins()]
    assert names[:2] == ["builtin", "builtin_io"]
    assert all(p.path == "" and p.abi[0] == 1 for p in occseg.plugins()[:2])
    assert {".npy", ".nrrd"} <= {s.name for s in occseg.stages("reader")}
    assert {".npy", ".nrrd"} <= {s.name for s in occseg.stages("writer")}
    assert {"lbp6", "lbp8"} <= {s.name for s in occseg.stages("texture")}
    assert {"g", "chi2"} <= {s.name for s in occseg.stages("similarity")}
    with pytest.raises(OccsegError) as e:
        occseg.stages("filters")
    assert e.value.status == Status.EINVAL and "filters" in e.value.message
    table = {p.name: p for p in occseg.param_table()}
    assert table["smax"].default == "64" and table["smax"].plugin == "builtin" and table["texture"].default == "auto"


def test_nrrd_round_trip_keeps_voxel_size_and_origin(tmp_path):
    v = np.random.default_rng(1).uniform(0, 1, size=(4, 5, 6))
    with occseg.Map.from_array(v, voxel_size=0.2, origin=(1.0, -2.5, 3.0)) as m:
        m.write(tmp_path / "m.nrrd")
    with occseg.read_map(tmp_path / "m.nrrd") as back:
        assert back.dims == (6, 5, 4) and back.voxel_size == 0.2 and back.origin == (1.0, -2.5, 3.0)
        assert np.array_equal(back.to_array(), v.astype(np.float32))


def test_reader_options(tmp_path):
    np.save(tmp_path / "m.npy", cube_map())
    with occseg.read_map(tmp_path / "m.npy", voxel_size=0.05) as m:
        assert m.voxel_size == 0.05
    with pytest.raises(OccsegError) as e:
        occseg.read_map(tmp_path / "m.npy", colour="red")
    assert e.value.status == Status.EINVAL and "colour=red" in e.value.message
    with pytest.raises(OccsegError) as e:
        occseg.read_map(tmp_path / "m.npy", voxel_size=None)
    assert e.value.status == Status.EINVAL and "'voxel_size': None" in e.value.message
    from occseg._text import option_array
    texts = option_array("t", {"a": "x", "b": 3, "c": 0.1, "bbox": (-8, 0.5, np.float32(0.25)), "e": np.array([1, 2])})
    assert [texts[i] for i in range(6)] == [b"a=x", b"b=3", b"c=0.1", b"bbox=-8,0.5,0.25", b"e=1,2", None]
    with pytest.raises(OccsegError) as e:
        occseg.read_map(tmp_path / "m.xyz")
    assert e.value.status == Status.EUNSUPPORTED and "'.xyz'" in e.value.message


def test_stages_by_parameter():
    flat = np.full((40, 50), 0.1, dtype=np.float32)
    flat[10:20, 5:25] = 0.95
    r = occseg.segment(flat, texture="lbp8")  # the 2D operator on a 2D map
    occ = [s for s in r.segments if s.state == occseg.State.OCCUPIED]
    assert len(occ) == 1 and occ[0].voxels == 200 and occ[0].bbox == ((5, 10, 0), (24, 19, 0))
    r = occseg.segment(cube_map(), similarity="chi2", smax=8, smin=2)
    assert sorted(s.voxels for s in r.segments) == [512, 16**3 - 512]
    with pytest.raises(OccsegError) as e:
        occseg.segment(cube_map(), texture="nosuch")
    assert e.value.status == Status.EINVAL and "nosuch" in e.value.message


@pytest.mark.parametrize("name,reason", [
    ("no_entry", "occseg_plugin_entry"),
    ("abi_major", "ABI mismatch"),
    ("not_a_library", "cannot be loaded"),
    ("/nonexistent/plugin", "cannot be loaded"),
])
def test_broken_plugins_are_refused_and_change_nothing(name, reason):
    if not name.startswith("/") and not BROKEN:
        pytest.skip("OCCSEG_BROKEN_PLUGINS is not set (tests/plugins absent)")
    path = name + ".so" if name.startswith("/") else os.path.join(BROKEN, name + ".so")
    assert name.startswith("/") or os.path.exists(path), path
    before = (occseg.plugins(), [occseg.stages(k) for k in ("texture", "similarity", "reader", "writer")],
              occseg.param_table())
    with pytest.raises(OccsegError) as e:
        occseg.load_plugin(path)
    assert e.value.status == Status.EPLUGIN
    assert path in e.value.message and reason in e.value.message, e.value.message
    after = (occseg.plugins(), [occseg.stages(k) for k in ("texture", "similarity", "reader", "writer")],
             occseg.param_table())
    assert after == before


@pytest.fixture(scope="module")
def example():
    if not EXAMPLE:
        pytest.skip("OCCSEG_EXAMPLE_PLUGIN is not set (tests/plugins absent)")
    assert os.path.exists(EXAMPLE), f"{EXAMPLE} was not built (fixture occseg_plugins_built)"
    occseg.load_plugin(EXAMPLE)
    return EXAMPLE


def test_example_plugin_registers_everything(example):
    mine = [p for p in occseg.plugins() if p.name == "example"]
    assert len(mine) == 1 and os.path.realpath(mine[0].path) == os.path.realpath(example)
    assert mine[0].version == "1.0.0" and mine[0].abi == (1, 0)
    assert ("lbp6ri", "example") in {(s.name, s.plugin) for s in occseg.stages("texture")}
    assert ("l1", "example") in {(s.name, s.plugin) for s in occseg.stages("similarity")}
    assert ".occtxt" in {s.name for s in occseg.stages("reader")}
    p = {p.name: p for p in occseg.param_table()}["ri_flat_below"]
    assert (p.kind, p.plugin, p.default, p.min, p.max) == ("double", "example", "0", 0.0, 1.0)
    with pytest.raises(OccsegError) as e:  # loading it twice: the name is taken
        occseg.load_plugin(example)
    assert e.value.status == Status.EPLUGIN and "example" in e.value.message


def test_example_plugin_segments_like_the_tool(example, cli, tmp_path):
    with occseg.Map.from_array(cube_map(), voxel_size=0.05) as m:
        m.write(tmp_path / "cube.occtxt")  # the plugin's writer
    params = {"texture": "lbp6ri", "similarity": "l1", "ri_flat_below": 0.05, "smax": 8, "smin": 2}
    with occseg.read_map(tmp_path / "cube.occtxt") as m:  # the plugin's reader
        assert m.voxel_size == 0.05 and np.array_equal(m.to_array(), cube_map())
        r = m.segment(**params)
    assert sorted(s.voxels for s in r.segments) == [512, 16**3 - 512]
    env = dict(os.environ, OCCSEG_PLUGIN_PATH=os.path.dirname(example))
    args = [a for k, v in params.items() for a in ("--param", f"{k}={v}")]
    out = subprocess.run([os.environ["OCCSEG_CLI"], "segment", str(tmp_path / "cube.occtxt"), "--out",
                          str(tmp_path / "cli"), "--outputs", "all", *args], env=env, capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert np.array_equal(np.load(tmp_path / "cli" / "labels.npy"), r.labels)
    r.write(tmp_path / "py")
    assert json.loads((tmp_path / "py" / "segments.json").read_text())["segments"] == \
        json.loads((tmp_path / "cli" / "segments.json").read_text())["segments"]


def test_default_plugins_from_the_search_path(tmp_path):
    if not EXAMPLE:
        pytest.skip("OCCSEG_EXAMPLE_PLUGIN is not set (tests/plugins absent)")
    code = ("import occseg; print(occseg.plugin_search_path()[0]); print(occseg.load_default_plugins()); "
            "print(occseg.load_default_plugins()); print([p.name for p in occseg.plugins()])")
    env = dict(os.environ, OCCSEG_PLUGIN_PATH=f"{tmp_path}/none:{os.path.dirname(EXAMPLE)}")
    r = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    lines = r.stdout.splitlines()
    assert lines[0] == f"{tmp_path}/none"
    assert lines[1:3] == ["1", "0"]  # found once; the second call skips the name already loaded
    assert lines[3] == str(["builtin", "builtin_io", "example"])
