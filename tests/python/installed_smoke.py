"""Run against an installed prefix without the source tree (and without OCCSEG_LIBRARY, or with it
pointing elsewhere): proves the package loads the library it was installed with.
With OCCSEG_SHARED_DATA set, an OctoMap tree is read with no load call and no plugin path: the
installed plugins are found next to the installed library on first use.
Usage: installed_smoke.py PREFIX LIBDIR"""
import os
import sys

import numpy as np

prefix, libdir = (os.path.realpath(a) for a in sys.argv[1:3])

import occseg  # noqa: E402

where = os.path.realpath(occseg.__file__)
assert where == os.path.join(prefix, "lib", "python3", "dist-packages", "occseg", "__init__.py"), where
assert occseg.library_path() == os.path.realpath(os.path.join(libdir, "liboccseg.so.0")), occseg.library_path()
m = np.full((20, 24, 28), 0.1, dtype=np.float32)
m[5:10, 6:12, 7:14] = 0.9
with occseg.segment(m) as r:
    occ = [s for s in r.segments if s.state == occseg.State.OCCUPIED]
    assert len(occ) == 1 and occ[0].voxels == 5 * 6 * 7 and occ[0].bbox == ((7, 6, 5), (13, 11, 9)), occ
data = os.environ.get("OCCSEG_SHARED_DATA")
if data and hasattr(occseg, "load_plugin"):
    assert "OCCSEG_PLUGIN_PATH" not in os.environ and "OCCSEG_NO_DEFAULT_PLUGINS" not in os.environ
    with occseg.read_map(os.path.join(data, "geb079.bt")) as t:
        assert t.dims == (487, 187, 39), t.dims
    reader = [p for p in occseg.plugins() if p.name == "octomap_reader"]
    assert len(reader) == 1 and reader[0].path.startswith(os.path.join(libdir, "occseg", "plugins")), reader
print(f"installed occseg {occseg.version()} from {where} loaded {occseg.library_path()}")
