"""Run against an installed prefix without the source tree (and without OCCSEG_LIBRARY, or with it
pointing elsewhere): proves the package loads the library it was installed with.
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
print(f"installed occseg {occseg.version()} from {where} loaded {occseg.library_path()}")
