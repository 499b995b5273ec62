"""The plugin registry of liboccseg (occseg_plugins_load and friends), for libraries that have it."""
import ctypes
import dataclasses

from ._args import path_bytes
from ._errors import OccsegError, OccsegTypeError, Status, check
from . import _lib
from ._lib import has, lib
from ._text import get_text

STAGE_KINDS = {"texture": 0, "similarity": 1, "reader": 2, "writer": 3}  # occseg_stage_kind


@dataclasses.dataclass(frozen=True)
class PluginInfo:
    """A loaded plugin: built-in ones ("builtin", "builtin_io") have path ""."""

    name: str
    version: str
    description: str
    path: str
    abi: tuple  # (major, minor) of the plugin ABI it was built for


@dataclasses.dataclass(frozen=True)
class StageInfo:
    """A registered stage: a texture operator, similarity, or reader/writer (name = extension)."""

    name: str
    description: str
    plugin: str


def _require(name):
    if not has(name):
        raise OccsegError(Status.EUNSUPPORTED, f"the loaded liboccseg ({_lib.path}) has no {name}: "
                                               "it predates plugins")


def load_plugin(path):
    """Loads one plugin file (occseg_plugins_load); its stages, readers, writers and parameters
    become available to segment(), read_map() and Map.write() in the whole process. Plugins are
    never unloaded. OccsegError EPLUGIN names the file and the reason when it cannot be loaded; a
    path holding a NUL character raises OccsegValueError (C would load the file before it)."""
    _require("occseg_plugins_load")
    check(lib.occseg_plugins_load(path_bytes("occseg.load_plugin", "path", path)))


def load_default_plugins():
    """Loads every plugin of the search path (plugin_search_path()); returns how many it loaded."""
    _require("occseg_plugins_load_default")
    n = ctypes.c_uint32()
    check(lib.occseg_plugins_load_default(ctypes.byref(n)))
    return n.value


def plugin_search_path():
    """The folders load_default_plugins() searches, in order."""
    _require("occseg_plugin_search_path")
    text = get_text(lib.occseg_plugin_search_path)
    return [d for d in text.split(":") if d]


def plugins():
    """The loaded plugins, built-in ones first, in load order."""
    _require("occseg_plugin_count")
    out = []
    for i in range(lib.occseg_plugin_count()):
        major, minor = ctypes.c_uint32(), ctypes.c_uint32()
        check(lib.occseg_plugin_abi(i, ctypes.byref(major), ctypes.byref(minor)))
        out.append(PluginInfo(lib.occseg_plugin_name(i).decode(), lib.occseg_plugin_version(i).decode(),
                              lib.occseg_plugin_description(i).decode(), lib.occseg_plugin_path(i).decode(),
                              (major.value, minor.value)))
    return out


def stages(kind):
    """The registered stages of one kind: "texture", "similarity", "reader" or "writer"."""
    _require("occseg_stage_count")
    if not isinstance(kind, str):
        raise OccsegTypeError(Status.EINVAL, f"stages: kind must be a str, not {type(kind).__name__}")
    if kind not in STAGE_KINDS:
        raise OccsegError(Status.EINVAL, f"stages: kind {kind!r} is not one of {', '.join(STAGE_KINDS)}")
    k = STAGE_KINDS[kind]
    return [StageInfo(lib.occseg_stage_name(k, i).decode(), lib.occseg_stage_description(k, i).decode(),
                      lib.occseg_stage_plugin(k, i).decode()) for i in range(lib.occseg_stage_count(k))]
