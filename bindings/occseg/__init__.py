"""occseg: texture-based segmentation of 3D probabilistic occupancy maps, in Python.

Pure Python over liboccseg's C ABI (ctypes + NumPy): no compiled extension, so any build of
liboccseg.so.0 serves. See docs/python.md.

    import numpy as np, occseg
    m = np.full((32, 32, 32), 0.1, np.float32); m[8:16, 8:16, 8:16] = 0.9
    with occseg.segment(m) as r:
        for s in r.segments:
            print(s.id, s.state.name, s.voxels)
"""
import os as _os

from . import _lib
from ._errors import OccsegError, Status
from ._handles import live_handles
from ._map import Map, read_map
from ._params import ParamInfo, param_table
from ._result import Result, Segment, State
from ._segment import segment

__all__ = ["segment", "read_map", "Map", "Result", "Segment", "State", "Status", "OccsegError", "ParamInfo",
           "param_table", "version", "version_number", "library_path", "live_handles"]


def version():
    """"MAJOR.MINOR.PATCH" of the loaded liboccseg."""
    return _lib.lib.occseg_version_string().decode()


def version_number():
    """major * 10000 + minor * 100 + patch of the loaded liboccseg."""
    return int(_lib.lib.occseg_version_number())


def library_path():
    """The file of the liboccseg the package loaded."""
    return _lib.path


# Plugin loading exists from the library version that adds occseg_plugins_load to the C ABI;
# with an older library, occseg has no load_plugin (test with hasattr(occseg, "load_plugin")).
if hasattr(_lib.lib, "occseg_plugins_load"):
    from ._errors import check as _check

    def load_plugin(path):
        """Loads one plugin file (occseg_plugins_load): its texture operators, similarity
        measures, map readers and parameters become available to segment() and read_map()."""
        _check(_lib.lib.occseg_plugins_load(_os.fsencode(path)))

    __all__.append("load_plugin")
