"""Shared fixtures of the Python suite. The package is imported from bindings/ (PYTHONPATH) and
liboccseg from the build tree (OCCSEG_LIBRARY), both set by tests/python/CMakeLists.txt."""
import os
import subprocess

import numpy as np
import pytest


def noisy_scene(seed=20240611, shape=(36, 44, 52)):
    """Graded free space, two occupied boxes, an unknown (0.5) slab and sensor-like noise, [z, y, x]
    float64: all three states and non-trivial segment boundaries."""
    rng = np.random.default_rng(seed)
    nz, ny, nx = shape
    m = rng.uniform(0.05, 0.3, size=shape)
    m[4:14, 6:18, 5:15] = rng.uniform(0.8, 0.99, size=(10, 12, 10))
    m[20:31, 25:40, 28:47] = rng.uniform(0.7, 0.95, size=(11, 15, 19))
    m[:, 30:36, 0:20] = 0.5
    return m


@pytest.fixture
def scene():
    return noisy_scene().astype(np.float32)


@pytest.fixture
def cli():
    """Runs `occseg ARGS...` (the C++ tool, path from OCCSEG_CLI) and checks it succeeded."""
    tool = os.environ.get("OCCSEG_CLI")
    if not tool:
        pytest.fail("OCCSEG_CLI is not set: run the suite through ctest (tests/python/CMakeLists.txt)")

    def run(*args):
        r = subprocess.run([tool, *map(str, args)], capture_output=True, text=True)
        assert r.returncode == 0, r.stderr
        return r

    return run
