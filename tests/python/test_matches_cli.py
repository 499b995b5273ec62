"""occseg.segment() gives exactly what `occseg segment` (the C++ tool) gives on the same map."""
import json

import numpy as np
import pytest

import occseg
from conftest import noisy_scene


def cli_segment(cli, tmp_path, array, *args):
    np.save(tmp_path / "map.npy", array)
    cli("segment", tmp_path / "map.npy", "--out", tmp_path / "cli", "--outputs", "all", *args)
    labels = np.load(tmp_path / "cli" / "labels.npy")
    doc = json.loads((tmp_path / "cli" / "segments.json").read_text())
    return labels, doc


def as_json_rows(segments, boxes):
    names = {occseg.State.FREE: "free", occseg.State.UNKNOWN: "unknown", occseg.State.OCCUPIED: "occupied"}
    return [{"id": s.id, "state": names[s.state], "kind": s.kind.name.lower(), "voxels": s.voxels, "mop": s.mop,
             "bbox": {"min": list(s.bbox[0]), "max": list(s.bbox[1])}, "centroid": list(s.centroid),
             "obb": {"center": list(b.center), "extents": list(b.extents), "quaternion": list(b.quaternion)}}
            for s, b in zip(segments, boxes)]


def voxel_fields(rows):
    """segments.json rows without the fields in metres (the map's frame, not the result's)."""
    return [{k: v for k, v in row.items() if not k.endswith("_m")} for row in rows]


@pytest.mark.parametrize("preset,params,args", [
    ("default", {}, []),
    ("paper", {}, ["--preset", "paper"]),
    ("default", {"smax": 16, "split_ratio": 1.3}, ["--param", "smax=16", "--param", "split_ratio=1.3"]),
])
def test_labels_and_segments_identical(cli, tmp_path, scene, preset, params, args):
    ref_labels, ref = cli_segment(cli, tmp_path, scene, *args)
    # a scene with structure (the paper preset may fold the unknown slab into its neighbours)
    assert {"free", "occupied"} <= {s["state"] for s in ref["segments"]} and len(ref["segments"]) >= 3
    with occseg.segment(scene, preset, **params) as r:
        assert r.labels.dtype == np.uint32 and r.labels.shape == scene.shape
        assert np.array_equal(r.labels, ref_labels)
        assert as_json_rows(r.segments, r.boxes()) == voxel_fields(ref["segments"])  # every double bit for bit
        assert list(r.dims) == ref["dims"]
        # result.write() produces the tool's files
        r.write(tmp_path / "py", outputs=["labels.npy", "segments.json"])
    assert json.loads((tmp_path / "py" / "segments.json").read_text()) == ref
    assert np.array_equal(np.load(tmp_path / "py" / "labels.npy"), ref_labels)


def test_read_map_gives_the_tools_result(cli, tmp_path, scene):
    ref_labels, ref = cli_segment(cli, tmp_path, scene)
    with occseg.read_map(tmp_path / "map.npy") as m:
        assert m.dims == (52, 44, 36) and m.voxel_size == 1.0 and m.origin == (0.0, 0.0, 0.0)
        assert np.array_equal(m.to_array(), scene)
        with m.segment(threads=1) as r:
            assert np.array_equal(r.labels, ref_labels)
            assert as_json_rows(r.segments, r.boxes()) == voxel_fields(ref["segments"])


@pytest.mark.parametrize("dtype", [np.float64, np.uint8, np.uint16])
def test_other_dtypes_identical_to_the_tool(cli, tmp_path, dtype):
    m = noisy_scene(seed=5)
    if dtype != np.float64:
        m = np.round(m * np.iinfo(dtype).max).astype(dtype)
    ref_labels, ref = cli_segment(cli, tmp_path, m)
    r = occseg.segment(m)
    assert np.array_equal(r.labels, ref_labels)
    assert as_json_rows(r.segments, r.boxes()) == voxel_fields(ref["segments"])
