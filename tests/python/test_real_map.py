"""A real map: the OctoMap corridor geb079.bt (../shared/data, 487 x 187 x 39 voxels of 8 cm),
turned into a grid by `occseg segment` (which writes it as map.nrrd next to its labels). The
bindings, fed that grid straight from the file's bytes, must reproduce the tool's segmentation.
Needs a build with OctoMap (and, for the .bt read by occseg.read_map, its reader plugin);
skipped with the reason otherwise."""
import gzip
import json
import os
import re
import subprocess

import numpy as np
import pytest

import occseg
from test_matches_cli import as_json_rows, voxel_fields

DATA = os.environ.get("OCCSEG_SHARED_DATA", os.path.join(os.path.dirname(__file__), "..", "..", "..", "shared", "data"))


def read_nrrd(path):
    """(float32 [z, y, x] array, voxel size, origin corner) of the little-endian, axis-aligned NRRD
    the tool writes (gzip-encoded; raw ones are read too)."""
    raw = open(path, "rb").read()
    head, _, _ = raw.partition(b"\n\n")
    fields = dict(line.split(": ", 1) for line in head.decode().splitlines()[1:] if ": " in line)
    assert fields["type"] == "float" and fields["encoding"] in ("raw", "gzip") and fields["endian"] == "little"
    nx, ny, nz = map(int, fields["sizes"].split())
    steps = [float(v) for v in re.findall(r"[-0-9.e]+", fields["space directions"])]
    assert steps[0] == steps[4] == steps[8]
    # NRRD's space origin is the centre of the first voxel; occseg's origin is its outer corner
    origin = tuple(float(v) - steps[0] / 2 for v in re.findall(r"[-0-9.e]+", fields["space origin"]))
    body = raw[len(head) + 2:]
    if fields["encoding"] == "gzip":  # map.nrrd is gzip-encoded since issue 27
        body = gzip.decompress(body)
    data = np.frombuffer(body, dtype="<f4", count=nx * ny * nz).reshape(nz, ny, nx)
    return data, steps[0], origin


@pytest.fixture(scope="module")
def corridor(tmp_path_factory):
    bt = os.path.join(DATA, "geb079.bt")
    if not os.path.exists(bt):
        pytest.fail(f"{bt} is missing (see ../shared/data/README.md)")
    out = tmp_path_factory.mktemp("geb079") / "out"
    r = subprocess.run([os.environ["OCCSEG_CLI"], "segment", bt, "--out", str(out), "--outputs", "all"], capture_output=True, text=True)
    if r.returncode != 0 and "needs OctoMap" in r.stderr:
        pytest.skip(r.stderr.strip())
    assert r.returncode == 0, r.stderr
    return out


def test_corridor_matches_the_tool(corridor):
    grid, voxel_size, origin = read_nrrd(corridor / "map.nrrd")
    assert grid.shape == (39, 187, 487) and voxel_size == 0.08
    assert not grid.flags.writeable  # the file's bytes, read in place (possibly misaligned)
    ref = json.loads((corridor / "segments.json").read_text())
    ref_labels = np.load(corridor / "labels.npy")
    if hasattr(occseg, "stages") and ".nrrd" in {s.name for s in occseg.stages("reader")}:
        with occseg.read_map(corridor / "map.nrrd") as m:  # the library's own NRRD reader agrees
            assert m.voxel_size == voxel_size and np.allclose(m.origin, origin, rtol=0, atol=1e-12)
            assert np.array_equal(m.to_array(), grid)
    with occseg.segment(grid, voxel_size=voxel_size, origin=origin) as r:
        assert np.array_equal(r.labels, ref_labels)
        assert as_json_rows(r.segments, r.boxes()) == voxel_fields(ref["segments"])
        states = {s.state for s in r.segments}
        assert states == set(occseg.State) and len(r.segments) > 20  # a real, busy map (about 100 segments)
        # the points of an occupied segment lie inside the map's metric box
        occ = max((s for s in r.segments if s.state == occseg.State.OCCUPIED), key=lambda s: s.voxels)
        p = r.points(occ.id)
        lo = np.array(origin)
        hi = lo + np.array([487, 187, 39]) * voxel_size
        assert np.all(p > lo) and np.all(p < hi)


def test_corridor_through_the_octomap_reader_plugin(corridor, monkeypatch):
    """The .bt file itself, read by the OctoMap reader plugin (built with OctoMap): the same grid
    as the tool's, the same segmentation; reader options pass through (a coarser voxel size)."""
    plugin_dir = os.environ.get("OCCSEG_READER_PLUGINS")
    if not plugin_dir:
        pytest.skip("no OctoMap reader plugin in this build")
    monkeypatch.setenv("OCCSEG_PLUGIN_PATH", plugin_dir)  # read by the library at the call
    assert occseg.load_default_plugins() >= 1
    assert ".bt" in {s.name for s in occseg.stages("reader")}
    grid, voxel_size, origin = read_nrrd(corridor / "map.nrrd")
    bt = os.path.join(DATA, "geb079.bt")
    with occseg.read_map(bt) as m:
        assert m.voxel_size == voxel_size and np.allclose(m.origin, origin, rtol=0, atol=1e-12)
        assert np.array_equal(m.to_array(), grid)
        with m.segment() as r:
            assert np.array_equal(r.labels, np.load(corridor / "labels.npy"))
    with occseg.read_map(bt, voxel_size=0.16, coarsen="max") as m:
        assert m.voxel_size == 0.16 and m.dims[0] in (243, 244)
