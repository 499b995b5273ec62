"""Map: an occseg_map handle, made from a NumPy array (without an intermediate copy) or a file."""
import ctypes

import numpy as np

from ._args import flag, path_bytes, real
from ._errors import OccsegError, OccsegTypeError, OccsegValueError, Status, check
from ._handles import Owned
from ._lib import c_double3, c_ptrdiff3, c_size3, has, lib
from ._text import option_array

# occseg_dtype of each accepted element type (native byte order). int8 is read as a ROS
# nav_msgs/OccupancyGrid (OCCSEG_I8_OCCUPANCY: -1 unknown, 0..100 percent): no other int8 map
# convention exists, and it is the one type such a grid comes in.
_DTYPES = {np.dtype(np.float32): 0, np.dtype(np.float64): 1, np.dtype(np.uint8): 2, np.dtype(np.uint16): 3,
           np.dtype(np.int8): 4}
_IMPORT_CLAMP, _IMPORT_NAN_UNKNOWN, _IMPORT_BYTE_SWAPPED = 1, 2, 4
_EMPTY = ctypes.c_char(0)  # a valid address for zero-size arrays, so the C ABI reports their dims


def as_voxel_array(probabilities, who):
    """`probabilities` as an ndarray [z, y, x] or [y, x] of an accepted dtype, in either byte
    order: the caller's own array whenever possible (any strides, foreign byte order too: the C
    ABI reads it byte-swapped, OCCSEG_IMPORT_BYTE_SWAPPED); a copy only for what is not an array
    yet (np.asarray of a list, ...). Other dtypes are refused, never guessed at."""
    try:
        arr = np.asarray(probabilities)
    except (ValueError, TypeError) as e:  # a ragged list, say: NumPy's own error, as an occseg one
        raise OccsegValueError(Status.EINVAL, f"{who}: probabilities: not an array ({e})") from None
    if arr.dtype.newbyteorder("=") not in _DTYPES:
        raise OccsegError(Status.EINVAL, f"{who}: probabilities: dtype {arr.dtype} is not supported "
                                         "(use float32, float64, uint8 or uint16; int8 for a ROS OccupancyGrid)")
    if arr.ndim not in (2, 3):
        raise OccsegError(Status.EDIMS, f"{who}: probabilities: shape {arr.shape} has {arr.ndim} dimensions; "
                                        "expected 3 ([z, y, x]) or 2 ([y, x])")
    return arr


def _import_args(who, c_function, probabilities, voxel_size, origin, clamp, nan_unknown):
    """The checked arguments of Map.from_array() and Map.view() (`who`, for the errors; `c_function`,
    for the array's): the array, the voxel size, the origin (None: not given) and the import flags."""
    arr = as_voxel_array(probabilities, c_function)
    vs = real(who, "voxel_size", voxel_size)
    o = None if origin is None else _origin_arg(who, origin)
    flags = (_IMPORT_CLAMP if flag(who, "clamp", clamp) else 0) | \
        (_IMPORT_NAN_UNKNOWN if flag(who, "nan_unknown", nan_unknown) else 0)
    return arr, vs, o, flags


def buffer_args(arr):
    """(data address, occseg_dtype, dims, byte strides, byte-order flag) describing ndarray `arr`
    [z, y, x] or [y, x] to occseg_map_from_buffer_flags: x is the last axis, NumPy's byte strides
    (negative ones too) are passed as they are, and the flag is OCCSEG_IMPORT_BYTE_SWAPPED for
    items in the foreign byte order (else 0)."""
    shape, strides = arr.shape, arr.strides
    if arr.ndim == 2:
        shape, strides = (1,) + shape, (0,) + strides  # one z layer: its stride is never used
    dims = c_size3(shape[2], shape[1], shape[0])
    st = c_ptrdiff3(strides[2], strides[1], strides[0])
    data = arr.ctypes.data if arr.size else ctypes.addressof(_EMPTY)
    swapped = _IMPORT_BYTE_SWAPPED if arr.dtype.byteorder not in ("=", "|") else 0
    return data, _DTYPES[arr.dtype.newbyteorder("=")], dims, st, swapped


def _make(fn, arr, vs, flags):
    """fn(out, data, dtype, dims, strides, vs, flags) for `arr`; the new handle and the array it
    reads. A liboccseg older than OCCSEG_IMPORT_BYTE_SWAPPED refuses the flag (EINVAL naming
    occseg_import_flags): a foreign-order array is then converted to native order first."""
    data, dtype, dims, strides, swapped = buffer_args(arr)
    out = ctypes.c_void_p()
    rc = fn(ctypes.byref(out), data, dtype, dims, strides, vs, flags | swapped)
    if rc != 0 and swapped:
        try:
            check(rc)
        except OccsegError as e:
            if e.status != Status.EINVAL or "occseg_import_flags" not in e.message:
                raise
        arr = arr.astype(arr.dtype.newbyteorder("="))
        data, dtype, dims, strides, _ = buffer_args(arr)
        rc = fn(ctypes.byref(out), data, dtype, dims, strides, vs, flags)
    check(rc)
    return out, arr


class Map(Owned):
    """A probabilistic occupancy grid held by liboccseg (occseg_map): nx * ny * nz probabilities,
    a voxel edge length in metres and the world position of the outer corner of voxel (0, 0, 0).

    Make one with Map.from_array() or occseg.read_map(). The C handle is freed by close(), at the
    end of a `with` block, or when the object is collected; never under a running call: closed
    while a segmentation or write uses it (from another thread, or from the progress callback of
    that segmentation), it refuses new calls at once and is freed when the running one returns.
    Setting voxel_size or origin while a call uses the map raises OccsegValueError."""

    _what = "occseg.Map"

    def __init__(self, handle):
        """Takes ownership of a C occseg_map handle (a non-NULL ctypes.c_void_p or int)."""
        self._own(handle, "map", lib.occseg_map_free)

    @classmethod
    def from_array(cls, probabilities, voxel_size=1.0, origin=None, *, clamp=False, nan_unknown=False):
        """Copies a NumPy array indexed [z, y, x] (or [y, x] for a one-layer map) of float32,
        float64, uint8 or uint16 (0..max meaning 0..1) into a new map, reading it in place through
        its strides. Float values must lie in [0, 1] unless `clamp` (out-of-range values and
        infinities go to the nearest bound) or `nan_unknown` (NaN becomes 0.5) is set.

        An int8 array is a ROS nav_msgs/OccupancyGrid: -1 is unknown (p = 0.5), 0..100 the
        occupancy in percent (p = v / 100), anything else raises OccsegError (EVALUE) naming the first
        such cell (clamp and nan_unknown do not apply). Pass the message's data as it is,
        np.asarray(msg.data, dtype=np.int8).reshape(msg.info.height, msg.info.width) (row 0 is at
        the origin, y up, as occseg's rows are), with voxel_size=msg.info.resolution and
        origin=(position.x, position.y, 0)."""
        arr, vs, o, flags = _import_args("occseg.Map.from_array", "occseg_map_from_buffer", probabilities,
                                         voxel_size, origin, clamp, nan_unknown)
        try:
            out, _ = _make(lib.occseg_map_from_buffer_flags, arr, vs, flags)
        except OccsegError as e:
            raise python_flag_error(e) from None
        return _configured(cls(out), None, o)

    @classmethod
    def view(cls, probabilities, voxel_size=1.0, origin=None, *, clamp=False, nan_unknown=False):
        """A map that reads the array where it lies (occseg_map_view_buffer): no copy is made,
        and the Map keeps a reference to the array until its C handle is freed. Arguments,
        dtypes and strides as from_array(); the values are checked when a call reads them
        (segment(), to_array(), write()), which raises what from_array() would raise for the same
        array. The array must not change while a call reads the map (a data race); a change
        between calls is seen by the next one. A dense float32 array (C order, [z, y, x]) is read
        by the pipeline directly; segment() reads other dtypes, layouts and byte orders through a
        converter, a few rows or planes at a time, so no copy of the map is made either (to_array()
        and write() convert it whole). Needs a liboccseg with occseg_map_view_buffer."""
        if not has("occseg_map_view_buffer"):
            raise OccsegError(Status.EUNSUPPORTED, "occseg.Map.view: the loaded liboccseg has no occseg_map_view_buffer")
        arr, vs, o, flags = _import_args("occseg.Map.view", "occseg_map_view_buffer", probabilities, voxel_size,
                                         origin, clamp, nan_unknown)
        out, arr = _make(lib.occseg_map_view_buffer, arr, vs, flags)
        m = cls.__new__(cls)
        m._own(out, "map", lib.occseg_map_free, keep=arr)
        return _configured(m, None, o)

    @property
    def dims(self):
        """(nx, ny, nz)."""
        return self._call(map_dims)

    @property
    def shape(self):
        """(nz, ny, nx): the NumPy shape of to_array() and of a segmentation's labels."""
        return tuple(reversed(self.dims))

    @property
    def voxel_size(self):
        """Voxel edge length in metres (positive, finite)."""
        return self._call(map_voxel_size)

    @voxel_size.setter
    def voxel_size(self, value):
        v = real("occseg.Map.voxel_size", "voxel_size", value)
        self._exclusive("occseg.Map.voxel_size", lambda h: check(lib.occseg_map_set_voxel_size(h, v)))

    @property
    def origin(self):
        """World (x, y, z) of the outer corner of voxel (0, 0, 0), in metres."""
        return self._call(map_origin)

    @origin.setter
    def origin(self, value):
        o = _origin_arg("occseg.Map.origin", value)
        self._exclusive("occseg.Map.origin", lambda h: check(lib.occseg_map_set_origin(h, c_double3(*o))))

    def to_array(self):
        """The probabilities as a new float32 array [z, y, x]."""
        with self._used() as h:
            out = np.empty(tuple(reversed(map_dims(h))), dtype=np.float32)
            check(lib.occseg_map_values(h, out.ctypes.data, out.size))
        return out

    def write(self, path, **options):
        """Writes the map with the library's writer for the path's extension (.npy: float32
        [z, y, x]; .nrrd: with voxel size and origin, in the space of the .nrrd the map was read
        from, else right-anterior-superior; more from plugins); keywords become writer options
        "key=value". All or nothing. A path, option name or text value holding a NUL character
        raises OccsegValueError (C would see only the text before it)."""
        p = path_bytes("occseg.Map.write", "path", path)
        if has("occseg_map_write_options"):
            opts = option_array("occseg_map_write", options)
            _plugin_hint(lambda: self._call(lambda h: check(lib.occseg_map_write_options(h, p, opts))))
        elif options:
            raise OccsegError(Status.EUNSUPPORTED, "occseg_map_write: options need a liboccseg with "
                                                   "occseg_map_write_options")
        else:
            self._call(lambda h: check(lib.occseg_map_write(h, p)))

    def segment(self, preset="default", threads=0, **kwargs):
        """Same as occseg.segment(self, ...)."""
        from ._segment import segment
        return segment(self, preset, threads, **kwargs)

    def __repr__(self):
        try:
            with self._used() as h:
                return (f"<occseg.Map dims={map_dims(h)} voxel_size={map_voxel_size(h):g} "
                        f"origin={map_origin(h)}>")
        except ValueError:
            return "<occseg.Map closed>"


def python_flag_error(e):
    """`e` again, with the keywords of the import flags in place of their C names when the error is
    one that only such a flag accepts (else `e` itself)."""
    if e.status != Status.EVALUE or "OCCSEG_IMPORT_" not in e.message:
        return e
    return OccsegError(e.code, _python_flags(e.message))


def _python_flags(message):
    """The C error of a value only an import flag accepts, with the keyword that sets that flag in
    place of the flag's C name (the C text names OCCSEG_IMPORT_NAN_UNKNOWN for a NaN and
    OCCSEG_IMPORT_CLAMP for a value outside [0, 1])."""
    return message.replace("OCCSEG_IMPORT_NAN_UNKNOWN", "nan_unknown=True").replace("OCCSEG_IMPORT_CLAMP", "clamp=True")


# The queries of a map, on a C pointer the caller holds a use of.
def map_dims(h):
    d = c_size3()
    check(lib.occseg_map_dims(h, d))
    return tuple(d)


def map_voxel_size(h):
    v = ctypes.c_double()
    check(lib.occseg_map_voxel_size(h, ctypes.byref(v)))
    return v.value


def map_origin(h):
    o = c_double3()
    check(lib.occseg_map_origin(h, o))
    return tuple(o)


def _origin_arg(who, value):
    """(x, y, z) floats from a sequence of three real numbers."""
    try:
        items = list(value)
    except TypeError:
        raise OccsegTypeError(Status.EINVAL, f"{who}: origin must be a sequence of 3 numbers, "
                                             f"not {type(value).__name__}") from None
    if len(items) != 3:
        raise OccsegValueError(Status.EINVAL, f"{who}: origin has {len(items)} values; expected 3 (x, y, z)")
    return tuple(real(who, f"origin[{k}]", v) for k, v in enumerate(items))


def _plugin_hint(call):
    """Runs `call` (a check() of a read or write); an extension no reader or writer serves gets the
    Python spelling of the C error's advice added (the library has already searched the default
    plugin path by then, unless OCCSEG_NO_DEFAULT_PLUGINS is set)."""
    try:
        call()
    except OccsegError as e:
        if e.status != Status.EUNSUPPORTED or not ("no reader for" in e.message or "no writer for" in e.message):
            raise
        raise OccsegError(e.code, e.message + "; from Python: occseg.load_plugin(path) or "
                                              "occseg.load_default_plugins()") from None


def read_map(path, **options):
    """Reads a map through the library's readers (occseg_map_read_options): the extension picks
    the reader (.npy, .nrrd and .yaml built in, more from plugins: the first read of an extension
    no loaded reader serves loads the default plugin search path, unless OCCSEG_NO_DEFAULT_PLUGINS
    is set, so .bt, .ot, .graph and .pcd are read without a load call), and each keyword becomes a reader
    option "key=value" (e.g. voxel_size=0.05 for .npy; a reader refuses keys it does not know).
    A library older than the plugin interface reads .npy only, and takes voxel_size only."""
    out = ctypes.c_void_p()
    p = path_bytes("occseg.read_map", "path", path)
    if has("occseg_map_read_options"):
        opts = option_array("occseg_map_read", options)
        _plugin_hint(lambda: check(lib.occseg_map_read_options(ctypes.byref(out), p, opts)))
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
