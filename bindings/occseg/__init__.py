"""occseg: texture-based segmentation of 3D probabilistic occupancy maps, in Python.

Pure Python over liboccseg's C ABI (ctypes + NumPy): no compiled extension, so any build of
liboccseg.so.0 serves. See docs/python.md.

    import numpy as np, occseg
    m = np.full((32, 32, 32), 0.1, np.float32); m[8:16, 8:16, 8:16] = 0.9
    with occseg.segment(m) as r:
        for s in r.segments:
            print(s.id, s.state.name, s.voxels)
"""
from . import _lib
from ._context import Context
from ._errors import OccsegError, OccsegTypeError, OccsegValueError, Status
from ._handles import live_handles
from ._map import Map, read_map
from ._params import ParamInfo, param_table
from ._result import Box, Kind, Result, Segment, State, segment_colour
from ._segment import segment

__all__ = ["segment", "read_map", "Map", "Result", "Context", "Segment", "State", "Kind", "Status", "OccsegError", "Box",
           "segment_colour",
           "OccsegTypeError", "OccsegValueError", "ParamInfo",
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


# The plugin interface exists from the library version that added occseg_plugins_load and its
# companions to the C ABI. With an older library these names are absent from the package: test
# with hasattr(occseg, "load_plugin").
if _lib.has("occseg_plugins_load") and _lib.has("occseg_plugin_count") and _lib.has("occseg_stage_count"):
    from ._plugins import (PluginInfo, StageInfo, load_default_plugins, load_plugin, plugin_search_path,  # noqa: F401
                           plugins, stages)

    __all__ += ["load_plugin", "load_default_plugins", "plugin_search_path", "plugins", "stages", "PluginInfo",
                "StageInfo"]

# Clouds as arrays (occseg_fusion_*, occseg_result_point_labels): from the library version that
# added them; absent with an older library (test with hasattr(occseg, "fuse")).
if _lib.has("occseg_fusion_new") and _lib.has("occseg_result_point_labels"):
    from ._fusion import Fusion, fuse  # noqa: F401
    from ._result import NO_LABEL  # noqa: F401

    __all__ += ["fuse", "Fusion", "NO_LABEL"]
