"""Finds and loads liboccseg, and declares the C prototypes of every function the package calls.

Lookup order (the first library that loads and has the right ABI major wins):
  1. the package's own install location: the path `cmake --install` wrote into _config.py
     (relative to this folder, then absolute), or <package>/../../../liboccseg.so.0 when the
     package was copied without its _config.py;
  2. the OCCSEG_LIBRARY environment variable (a file, or a folder holding liboccseg.so.0);
  3. the system's library path (dlopen("liboccseg.so.0"), then ctypes.util.find_library).
"""
import ctypes
import ctypes.util
import os

ABI_MAJOR = 0  # the SONAME major these bindings speak (liboccseg.so.0)
SONAME = f"liboccseg.so.{ABI_MAJOR}"

c_size3 = ctypes.c_size_t * 3
c_ptrdiff3 = ctypes.c_ssize_t * 3  # ptrdiff_t and ssize_t have the same width on every ABI we run on
c_double3 = ctypes.c_double * 3
c_uint3 = ctypes.c_uint32 * 3


class SegmentInfo(ctypes.Structure):
    """occseg_segment_info (occseg.h); struct_size must be set to ctypes.sizeof(SegmentInfo)."""

    _fields_ = [
        ("struct_size", ctypes.c_uint32),
        ("id", ctypes.c_uint32),
        ("state", ctypes.c_int),  # occseg_state: a C enum, int-sized
        ("voxels", ctypes.c_uint64),
        ("mop", ctypes.c_double),
        ("bbox_min", c_uint3),
        ("bbox_max", c_uint3),
        ("centroid", c_double3),
        ("kind", ctypes.c_int),  # occseg_kind, appended after centroid
    ]


class FusionOptions(ctypes.Structure):
    """occseg_fusion_options (occseg.h); struct_size must be ctypes.sizeof(FusionOptions)."""
    _fields_ = [
        ("struct_size", ctypes.c_uint32),
        ("threads", ctypes.c_int32),
        ("voxel_size", ctypes.c_double),
        ("margin", ctypes.c_double),
        ("max_range", ctypes.c_double),
        ("use_box", ctypes.c_int32),
        ("box_min", c_double3),
        ("box_max", c_double3),
    ]


class BoxInfo(ctypes.Structure):
    """occseg_box (occseg.h); struct_size must be set to ctypes.sizeof(BoxInfo)."""

    _fields_ = [
        ("struct_size", ctypes.c_uint32),
        ("center", c_double3),
        ("extents", c_double3),
        ("quaternion", ctypes.c_double * 4),
    ]


# int (*occseg_progress_fn)(const char *stage, double fraction, void *user)
PROGRESS_FN = ctypes.CFUNCTYPE(ctypes.c_int, ctypes.c_char_p, ctypes.c_double, ctypes.c_void_p)

_P = ctypes.c_void_p  # every opaque handle travels as void*: never as a Python int
_S = ctypes.c_char_p
_I = ctypes.c_int

# name: (restype, argtypes). Every function the package uses, nothing implicit.
PROTOTYPES = {
    "occseg_version_number": (ctypes.c_uint32, []),
    "occseg_version_string": (_S, []),
    "occseg_status_string": (_S, [_I]),
    "occseg_status_name": (_S, [_I]),
    "occseg_last_error": (_S, []),
    "occseg_params_create": (_I, [ctypes.POINTER(_P)]),
    "occseg_params_free": (None, [_P]),
    "occseg_params_preset": (_I, [_P, _S]),
    "occseg_params_set": (_I, [_P, _S, _S]),
    "occseg_params_set_int": (_I, [_P, _S, ctypes.c_int64]),
    "occseg_params_set_double": (_I, [_P, _S, ctypes.c_double]),
    "occseg_params_get": (_I, [_P, _S, ctypes.c_char_p, ctypes.c_size_t, ctypes.POINTER(ctypes.c_size_t)]),
    "occseg_params_set_progress": (_I, [_P, PROGRESS_FN, _P]),
    "occseg_params_validate": (_I, [_P]),
    "occseg_param_count": (ctypes.c_uint32, []),
    "occseg_param_name": (_S, [ctypes.c_uint32]),
    "occseg_param_kind": (_S, [ctypes.c_uint32]),
    "occseg_param_description": (_S, [ctypes.c_uint32]),
    "occseg_param_bounds": (_I, [ctypes.c_uint32, ctypes.POINTER(ctypes.c_double), ctypes.POINTER(ctypes.c_double)]),
    "occseg_map_from_buffer_flags": (_I, [ctypes.POINTER(_P), _P, _I, c_size3, c_ptrdiff3, ctypes.c_double,
                                          ctypes.c_uint32]),
    "occseg_map_read": (_I, [ctypes.POINTER(_P), _S]),
    "occseg_map_write": (_I, [_P, _S]),
    "occseg_map_free": (None, [_P]),
    "occseg_map_dims": (_I, [_P, c_size3]),
    "occseg_map_voxel_size": (_I, [_P, ctypes.POINTER(ctypes.c_double)]),
    "occseg_map_set_voxel_size": (_I, [_P, ctypes.c_double]),
    "occseg_map_origin": (_I, [_P, c_double3]),
    "occseg_map_set_origin": (_I, [_P, c_double3]),
    "occseg_map_values": (_I, [_P, _P, ctypes.c_size_t]),
    "occseg_segment": (_I, [ctypes.POINTER(_P), _P, _P]),
    "occseg_result_free": (None, [_P]),
    "occseg_result_dims": (_I, [_P, c_size3]),
    "occseg_result_segment_count": (ctypes.c_uint32, [_P]),
    "occseg_result_segment": (_I, [_P, ctypes.c_uint32, ctypes.POINTER(SegmentInfo)]),
    "occseg_result_labels": (_I, [_P, _P, ctypes.c_size_t]),
    "occseg_result_states": (_I, [_P, _P, ctypes.c_size_t]),
    "occseg_result_stage_count": (ctypes.c_uint32, [_P]),
    "occseg_result_stage": (_I, [_P, ctypes.c_uint32, ctypes.POINTER(_S), ctypes.POINTER(ctypes.c_double)]),
    "occseg_result_write": (_I, [_P, _S]),
}

# Functions of later library versions (the plugin interface), declared only when the loaded
# library has them; the package offers what they back only then.
_U32 = ctypes.c_uint32
_PU32 = ctypes.POINTER(_U32)
OPTIONAL_PROTOTYPES = {
    "occseg_context_new": (_I, [ctypes.POINTER(_P), _I]),
    "occseg_context_free": (None, [_P]),
    "occseg_context_threads": (_I, [_P]),
    "occseg_context_segment": (_I, [ctypes.POINTER(_P), _P, _P, _P]),
    "occseg_context_recycle": (None, [_P, _P]),
    "occseg_plugins_load": (_I, [_S]),
    "occseg_plugins_load_default": (_I, [_PU32]),
    "occseg_plugin_search_path": (_I, [ctypes.c_char_p, ctypes.c_size_t, ctypes.POINTER(ctypes.c_size_t)]),
    "occseg_plugin_count": (_U32, []),
    "occseg_plugin_name": (_S, [_U32]),
    "occseg_plugin_version": (_S, [_U32]),
    "occseg_plugin_description": (_S, [_U32]),
    "occseg_plugin_path": (_S, [_U32]),
    "occseg_plugin_abi": (_I, [_U32, _PU32, _PU32]),
    "occseg_stage_count": (_U32, [_I]),
    "occseg_stage_name": (_S, [_I, _U32]),
    "occseg_stage_description": (_S, [_I, _U32]),
    "occseg_stage_plugin": (_S, [_I, _U32]),
    "occseg_param_plugin": (_S, [_U32]),
    "occseg_param_default": (_I, [_U32, ctypes.c_char_p, ctypes.c_size_t, ctypes.POINTER(ctypes.c_size_t)]),
    "occseg_map_read_options": (_I, [ctypes.POINTER(_P), _S, ctypes.POINTER(_S)]),
    "occseg_map_write_options": (_I, [_P, _S, ctypes.POINTER(_S)]),
    "occseg_fusion_options_init": (None, [ctypes.POINTER(FusionOptions)]),
    "occseg_fusion_new": (_I, [ctypes.POINTER(_P), ctypes.POINTER(FusionOptions)]),
    "occseg_fusion_free": (None, [_P]),
    "occseg_fusion_add_points": (_I, [_P, _P, _I, ctypes.c_size_t, ctypes.c_ssize_t, _P, _P]),
    "occseg_fusion_map": (_I, [ctypes.POINTER(_P), _P]),
    "occseg_fusion_counts": (_I, [_P, ctypes.POINTER(ctypes.c_uint64), ctypes.POINTER(ctypes.c_uint64)]),
    "occseg_result_point_labels": (_I, [_P, _P, _P, _I, ctypes.c_size_t, ctypes.c_ssize_t, _P, _P, _P,
                                        ctypes.c_size_t]),
    "occseg_result_segment_box": (_I, [_P, ctypes.c_uint32, ctypes.POINTER(BoxInfo)]),
    "occseg_result_write_outputs": (_I, [_P, _S, ctypes.POINTER(_S)]),
    "occseg_map_view_buffer": (_I, [ctypes.POINTER(_P), _P, _I, c_size3, c_ptrdiff3, ctypes.c_double,
                                    ctypes.c_uint32]),
    "occseg_result_labels_view": (_I, [_P, ctypes.POINTER(_P), ctypes.POINTER(ctypes.c_size_t)]),
    "occseg_result_states_view": (_I, [_P, ctypes.POINTER(_P), ctypes.POINTER(ctypes.c_size_t)]),
    "occseg_result_segments_view": (_I, [_P, ctypes.POINTER(_P), ctypes.POINTER(ctypes.c_size_t)]),
}


def has(name):
    """True when the loaded library exports the optional function `name`."""
    return hasattr(lib, name)


def _package_candidates():
    """Where an installed package expects its library, most specific first."""
    here = os.path.dirname(os.path.abspath(__file__))
    try:
        from . import _config  # written by cmake --install; absent in the source tree
    except ImportError:
        return [("the package's install location (no _config.py: the default layout)",
                 os.path.normpath(os.path.join(here, "..", "..", "..", SONAME)))]
    out = []
    if getattr(_config, "LIBRARY_RELATIVE", ""):
        out.append(("the package's install location", os.path.normpath(os.path.join(here, _config.LIBRARY_RELATIVE))))
    if getattr(_config, "LIBRARY_ABSOLUTE", ""):
        out.append(("the install prefix recorded in _config.py", _config.LIBRARY_ABSOLUTE))
    return out


def _candidates():
    """(description, path or name, is_file_path) in lookup order."""
    for what, path in _package_candidates():
        yield what, path, True
    env = os.environ.get("OCCSEG_LIBRARY", "")
    if env:
        yield "OCCSEG_LIBRARY", os.path.join(env, SONAME) if os.path.isdir(env) else env, True
    else:
        yield "OCCSEG_LIBRARY", None, True
    yield "the system library path", SONAME, False
    found = ctypes.util.find_library("occseg")
    if found and found != SONAME:
        yield "the system library path (ctypes.util.find_library)", found, False


def _try_load(path):
    """Loads one candidate; returns (CDLL, None) or (None, why it was rejected)."""
    try:
        lib = ctypes.CDLL(path)
    except OSError as e:
        return None, str(e)
    missing = [name for name in PROTOTYPES if not hasattr(lib, name)]
    if missing:
        return None, "lacks " + ", ".join(missing[:3]) + (" ..." if len(missing) > 3 else "") + " (too old?)"
    lib.occseg_version_number.restype = ctypes.c_uint32
    lib.occseg_version_number.argtypes = []
    major = lib.occseg_version_number() // 10000
    if major != ABI_MAJOR:
        return None, f"is version {major}.x; these bindings need {ABI_MAJOR}.x"
    return lib, None


def _declare(lib):
    for name, (restype, argtypes) in PROTOTYPES.items():
        f = getattr(lib, name)
        f.restype, f.argtypes = restype, argtypes
    for name, (restype, argtypes) in OPTIONAL_PROTOTYPES.items():
        if hasattr(lib, name):
            f = getattr(lib, name)
            f.restype, f.argtypes = restype, argtypes


def _mapped_path(name):
    """The file the dynamic loader picked for `name` (from /proc/self/maps), else `name`."""
    try:
        with open("/proc/self/maps") as f:
            for line in f:
                if line.rstrip().endswith("/" + name) or ("/" + name + ".") in line:
                    return os.path.realpath(line.split(None, 5)[-1].strip())
    except OSError:
        pass
    return name


def load():
    """Returns (CDLL, path) of the first usable liboccseg, or raises ImportError listing every
    place it looked and why each failed."""
    tried = []
    for what, path, is_file in _candidates():
        if path is None:
            tried.append(f"{what}: not set")
            continue
        if is_file and not os.path.exists(path):
            tried.append(f"{what}: {path}: no such file")
            continue
        lib, why = _try_load(path)
        if lib is not None:
            _declare(lib)
            return lib, os.path.realpath(path) if is_file else _mapped_path(path)
        tried.append(f"{what}: {path}: {why}")
    raise ImportError(
        f"occseg: cannot load {SONAME}, the occseg C library. Looked in:\n  "
        + "\n  ".join(tried)
        + f"\nInstall occseg with cmake --install, or set OCCSEG_LIBRARY to the path of {SONAME}.")


lib, path = load()
