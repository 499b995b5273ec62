"""The README's Python example (bindings/examples/segment_map.py) runs and prints the segments its
synthetic room must give: a box of 20 x 20 x 28 voxels, a pillar of 8 x 8 x 48, an unseen corner
of 10 x 20 x 48, and the free rest of the 48 x 64 x 64 room."""
import importlib.util
import os
import subprocess
import sys

import numpy as np
import pytest

EXAMPLE = os.path.join(os.path.dirname(__file__), "..", "..", "bindings", "examples", "segment_map.py")
HAVE_MATPLOTLIB = importlib.util.find_spec("matplotlib") is not None


def run(*args, cwd, hide_matplotlib=False):
    """Runs the example; hide_matplotlib makes `import matplotlib` fail as on a machine without it."""
    code = ("import sys\nif HIDE: sys.modules['matplotlib'] = None\n"
            "sys.argv = ARGV; exec(compile(open(ARGV[0]).read(), ARGV[0], 'exec'), {'__name__': '__main__'})")
    code = code.replace("HIDE", repr(hide_matplotlib)).replace("ARGV", repr([EXAMPLE, *args]))
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=cwd,
                       env=dict(os.environ, MPLBACKEND="Agg"))
    assert r.returncode == 0, r.stderr
    return r.stdout


@pytest.mark.parametrize("hide_matplotlib", [False, True])
def test_example_prints_the_expected_segments(tmp_path, hide_matplotlib):
    out = run("--save", str(tmp_path / "slice.png"), cwd=tmp_path, hide_matplotlib=hide_matplotlib)
    lines = out.splitlines()
    assert lines[0].startswith("occseg 0.") and " 4 segments in " in lines[0]
    total = 48 * 64 * 64
    assert lines[1:5] == [
        f"  segment 0: free, {total - 11200 - 3072 - 9600} voxels, mop 0.15, bbox (0, 0, 0)-(63, 63, 47)",
        "  segment 1: occupied, 11200 voxels, mop 0.87, bbox (12, 10, 0)-(39, 29, 19)",
        "  segment 2: occupied, 3072 voxels, mop 0.95, bbox (44, 44, 0)-(51, 51, 47)",
        "  segment 3: unknown, 9600 voxels, mop 0.50, bbox (0, 54, 0)-(19, 63, 47)",
    ]
    if HAVE_MATPLOTLIB and not hide_matplotlib:
        assert lines[5] == f"slice written to {tmp_path / 'slice.png'}"
        assert (tmp_path / "slice.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    else:
        assert lines[5] == "matplotlib is not installed: no picture" and not (tmp_path / "slice.png").exists()


def test_example_reads_a_map_file(tmp_path):
    m = np.full((10, 12, 14), 0.2, dtype=np.float32)
    m[2:5, 3:7, 4:9] = 0.9
    np.save(tmp_path / "room.npy", m)
    out = run(str(tmp_path / "room.npy"), "--save", str(tmp_path / "s.png"), cwd=tmp_path)
    assert " 2 segments in " in out and "  segment 1: occupied, 60 voxels, mop 0.90, bbox (4, 3, 2)-(8, 6, 4)" in out


def test_readme_shows_this_example_verbatim():
    readme = open(os.path.join(os.path.dirname(EXAMPLE), "..", "..", "README.md")).read()
    section = readme.split("\n## Python\n", 1)[1].split("\n## ", 1)[0]
    block = section.split("```python\n", 1)[1].split("```\n", 1)[0]
    assert block == open(EXAMPLE).read(), "README's Python example differs from bindings/examples/segment_map.py"
