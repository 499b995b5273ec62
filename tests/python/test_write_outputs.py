"""Result.write writes the command's files, the map's frame included (occseg_result_write_outputs):
byte for byte what `occseg segment` writes for the same map, 3D and 2D."""
import os

import numpy as np
import pytest

import occseg

SHARED = os.environ.get("OCCSEG_SHARED_DATA", "")


def test_default_set_matches_the_command_with_the_frame(cli, tmp_path, scene):
    np.save(tmp_path / "map.npy", scene)
    cli("segment", tmp_path / "map.npy", "--out", tmp_path / "cli", "--voxel-size", "0.05")
    with occseg.segment(scene, voxel_size=0.05) as r:
        r.write(tmp_path / "py")
    for name in ("labels.nrrd", "segments.json"):
        assert (tmp_path / "py" / name).read_bytes() == (tmp_path / "cli" / name).read_bytes(), name
    assert sorted(os.listdir(tmp_path / "py")) == ["labels.nrrd", "segments.json"]
    r2 = occseg.segment(scene, voxel_size=0.05)
    with r2:
        r2.write(tmp_path / "py_npy", outputs=["labels.npy"])
    cli("segment", tmp_path / "map.npy", "--out", tmp_path / "cli_npy", "--voxel-size", "0.05", "--outputs", "labels.npy")
    assert (tmp_path / "py_npy" / "labels.npy").read_bytes() == (tmp_path / "cli_npy" / "labels.npy").read_bytes()


def test_all_adds_the_mesh_and_names_are_checked(tmp_path):
    m = np.full((6, 6, 6), 0.1, np.float32)
    m[2:4, 2:4, 2:4] = 0.9
    with occseg.segment(m, voxel_size=0.5, origin=(1, 2, 3)) as r:
        r.write(tmp_path / "all", outputs="all")
        assert sorted(os.listdir(tmp_path / "all")) == ["labels.npy", "labels.nrrd", "segments.json", "segments.ply"]
        ply = (tmp_path / "all" / "segments.ply").read_bytes()
        assert ply.startswith(b"ply\nformat binary_little_endian 1.0\n")
        assert b"element vertex 26\n" in ply and b"element face 24\n" in ply  # a 2 x 2 x 2 block
        r.write(tmp_path / "some", outputs=["segments.json"])
        assert os.listdir(tmp_path / "some") == ["segments.json"]
        with pytest.raises(occseg.OccsegError) as e:
            r.write(tmp_path / "png", outputs=["segmentation.png"])
        assert e.value.status == occseg.Status.EUNSUPPORTED and "occseg command only" in e.value.message
        with pytest.raises(occseg.OccsegError) as e:
            r.write(tmp_path / "bad", outputs=["labels.nrrd", "nonsense.txt"])
        assert e.value.status == occseg.Status.EINVAL and "'nonsense.txt'" in e.value.message
    assert not (tmp_path / "png").exists() and not (tmp_path / "bad").exists()


@pytest.mark.skipif(not os.path.exists(os.path.join(SHARED, "tb3_sandbox.yaml")), reason="no shared data")
def test_2d_map_gets_the_map_server_pair_as_the_command_writes_it(cli, tmp_path):
    path = os.path.join(SHARED, "tb3_sandbox.yaml")
    cli("segment", path, "--out", tmp_path / "cli")
    with occseg.read_map(path) as m:
        r = occseg.segment(m)
    with r:
        r.write(tmp_path / "py")
    for name in ("labels.nrrd", "segments.json", "segmentation.pgm", "segmentation.yaml"):
        assert (tmp_path / "py" / name).read_bytes() == (tmp_path / "cli" / name).read_bytes(), name
