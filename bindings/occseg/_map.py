"""Map: an occseg_map handle, made from a NumPy array (without an intermediate copy) or a file."""
import ctypes
import os

import numpy as np

from ._errors import OccsegError, Status, check
from ._handles import Owned
from ._lib import c_double3, c_ptrdiff3, c_size3, has, lib
from ._text import option_array

# occseg_dtype of each accepted element type (native byte order).
_DTYPES = {np.dtype(np.float32): 0, np.dtype(np.float64): 1, np.dtype(np.uint8): 2, np.dtype(np.uint16): 3}
_IMPORT_CLAMP, _IMPORT_NAN_UNKNOWN = 1, 2
_EMPTY = ctypes.c_char(0)  # a valid address for zero-size arrays, so the C ABI reports their dims


def as_voxel_array(probabilities, who):
    """`probabilities` as an ndarray [z, y, x] or [y, x] of an accepted dtype: the caller's own
    array whenever possible (any strides); a copy only for foreign byte order or non-arrays."""
    arr = np.asarray(probabilities)
    if arr.dtype.byteorder not in ("=", "|") and arr.dtype.newbyteorder("=") in _DTYPES:
        arr = arr.astype(arr.dtype.newbyteorder("="))  # big-endian data: the C ABI reads native
    if arr.dtype not in _DTYPES:
        raise OccsegError(Status.EINVAL, f"{who}: probabilities: dtype {arr.dtype} is not supported "
                                         "(use float32, float64, uint8 or uint16)")
    if arr.ndim not in (2, 3):
        raise OccsegError(Status.EDIMS, f"{who}: probabilities: shape {arr.shape} has {arr.ndim} dimensions; "
                                        "expected 3 ([z, y, x]) or 2 ([y, x])")
    return arr


def buffer_args(arr):
    """(data address, occseg_dtype, dims, byte strides) describing ndarray `arr` [z, y, x] or [y, x]
    to occseg_map_from_buffer: x is the last axis, and NumPy's byte strides (negative ones too)
    are passed as they are."""
    shape, strides = arr.shape, arr.strides
    if arr.ndim == 2:
        shape, strides = (1,) + shape, (0,) + strides  # one z layer: its stride is never used
    dims = c_size3(shape[2], shape[1], shape[0])
    st = c_ptrdiff3(strides[2], strides[1], strides[0])
    data = arr.ctypes.data if arr.size else ctypes.addressof(_EMPTY)
    return data, _DTYPES[arr.dtype], dims, st


class Map(Owned):
    """A probabilistic occupancy grid held by liboccseg (occseg_map): nx * ny * nz probabilities,
    a voxel edge length in metres and the world position of the outer corner of voxel (0, 0, 0).

    Make one with Map.from_array() or occseg.read_map(). The C handle is freed by close(), at the
    end of a `with` block, or when the object is collected."""

    _what = "occseg.Map"

    def __init__(self, handle):
        """Takes ownership of a C occseg_map handle (a non-NULL ctypes.c_void_p or int)."""
        self._own(handle, "map", lib.occseg_map_free)

    @classmethod
    def from_array(cls, probabilities, voxel_size=1.0, origin=None, *, clamp=False, nan_unknown=False):
        """Copies a NumPy array indexed [z, y, x] (or [y, x] for a one-layer map) of float32,
        float64, uint8 or uint16 (0..max meaning 0..1) into a new map, reading it in place through
        its strides. Float values must lie in [0, 1] unless `clamp` (out-of-range values and
        infinities go to the nearest bound) or `nan_unknown` (NaN becomes 0.5) is set."""
        arr = as_voxel_array(probabilities, "occseg_map_from_buffer")
        data, dtype, dims, strides = buffer_args(arr)
        flags = (_IMPORT_CLAMP if clamp else 0) | (_IMPORT_NAN_UNKNOWN if nan_unknown else 0)
        out = ctypes.c_void_p()
        check(lib.occseg_map_from_buffer_flags(ctypes.byref(out), data, dtype, dims, strides, float(voxel_size), flags))
        return _configured(cls(out), None, origin)

    @property
    def dims(self):
        """(nx, ny, nz)."""
        d = c_size3()
        check(lib.occseg_map_dims(self.handle, d))
        return tuple(d)

    @property
    def shape(self):
        """(nz, ny, nx): the NumPy shape of to_array() and of a segmentation's labels."""
        return tuple(reversed(self.dims))

    @property
    def voxel_size(self):
        """Voxel edge length in metres (positive, finite)."""
        v = ctypes.c_double()
        check(lib.occseg_map_voxel_size(self.handle, ctypes.byref(v)))
        return v.value

    @voxel_size.setter
    def voxel_size(self, value):
        check(lib.occseg_map_set_voxel_size(self.handle, float(value)))

    @property
    def origin(self):
        """World (x, y, z) of the outer corner of voxel (0, 0, 0), in metres."""
        o = c_double3()
        check(lib.occseg_map_origin(self.handle, o))
        return tuple(o)

    @origin.setter
    def origin(self, value):
        x, y, z = (float(v) for v in value)
        check(lib.occseg_map_set_origin(self.handle, c_double3(x, y, z)))

    def to_array(self):
        """The probabilities as a new float32 array [z, y, x]."""
        out = np.empty(self.shape, dtype=np.float32)
        check(lib.occseg_map_values(self.handle, out.ctypes.data, out.size))
        return out

    def write(self, path, **options):
        """Writes the map with the library's writer for the path's extension (.npy: float32
        [z, y, x]; .nrrd: with voxel size and origin, in the space of the .nrrd the map was read
        from, else right-anterior-superior; more from plugins); keywords become writer options
        "key=value". All or nothing."""
        if has("occseg_map_write_options"):
            check(lib.occseg_map_write_options(self.handle, os.fsencode(path), option_array("occseg_map_write", options)))
        elif options:
            raise OccsegError(Status.EUNSUPPORTED, "occseg_map_write: options need a liboccseg with "
                                                   "occseg_map_write_options")
        else:
            check(lib.occseg_map_write(self.handle, os.fsencode(path)))

    def segment(self, preset="default", threads=0, **kwargs):
        """Same as occseg.segment(self, ...)."""
        from ._segment import segment
        return segment(self, preset, threads, **kwargs)

    def __repr__(self):
        if self.closed:
            return "<occseg.Map closed>"
        return f"<occseg.Map dims={self.dims} voxel_size={self.voxel_size:g} origin={self.origin}>"


def read_map(path, **options):
    """Reads a map through the library's readers (occseg_map_read_options): the extension picks
    the reader (.npy and .nrrd built in, more from plugins), and each keyword becomes a reader
    option "key=value" (e.g. voxel_size=0.05 for .npy; a reader refuses keys it does not know).
    A library older than the plugin interface reads .npy only, and takes voxel_size only."""
    out = ctypes.c_void_p()
    p = os.fsencode(path)
    if has("occseg_map_read_options"):
        check(lib.occseg_map_read_options(ctypes.byref(out), p, option_array("occseg_map_read", options)))
        return Map(out)
    options = dict(options)
    voxel_size = options.pop("voxel_size", None)
    if options:
        raise OccsegError(Status.EUNSUPPORTED, f"occseg_map_read: options {sorted(options)} need a liboccseg "
                                               "with occseg_map_read_options")
    check(lib.occseg_map_read(ctypes.byref(out), p))
    return _configured(Map(out), voxel_size, None)


def _configured(m, voxel_size, origin):
    """Applies optional settings to a new map; a bad one frees the map at once, then raises."""
    try:
        if voxel_size is not None:
            m.voxel_size = voxel_size
        if origin is not None:
            m.origin = origin
    except BaseException:
        m.close()
        raise
    return m
