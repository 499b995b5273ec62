"""Point clouds held as arrays: fuse() and Fusion (occseg_fusion_*), and the point arguments that
Result.point_labels() shares with them."""
import ctypes

import numpy as np

from ._args import c_integer, real
from ._errors import OccsegError, OccsegTypeError, OccsegValueError, Status, check
from ._handles import Owned
from ._lib import FusionOptions, c_double3, lib
from ._map import Map

_POINT_DTYPES = {np.dtype(np.float32): 0, np.dtype(np.float64): 1}  # OCCSEG_F32, OCCSEG_F64
c_double4 = ctypes.c_double * 4


def point_args(who, points):
    """`points` as (array kept alive, data address, occseg_dtype, count, byte stride, leading
    shape): an (N, 3) array, or an organized cloud (H, W, 3) (any array whose last axis holds x,
    y, z) of float32 or float64. Read in place when each point's x, y, z are adjacent and the
    points lie one stride apart; copied otherwise (and for a foreign byte order)."""
    arr = np.asarray(points)
    if arr.dtype.byteorder not in ("=", "|") and arr.dtype.newbyteorder("=") in _POINT_DTYPES:
        arr = arr.astype(arr.dtype.newbyteorder("="))
    if arr.dtype not in _POINT_DTYPES:
        raise OccsegTypeError(Status.EINVAL, f"{who}: points: dtype {arr.dtype} is not supported "
                                             "(use float32 or float64 coordinates)")
    if arr.ndim < 2 or arr.shape[-1] != 3:
        raise OccsegValueError(Status.EINVAL, f"{who}: points: shape {arr.shape} is not (N, 3) or (H, W, 3) "
                                              "(x, y, z along the last axis)")
    lead = arr.shape[:-1]
    flat = arr.reshape(-1, 3)  # a view whenever the leading axes can be merged
    if flat.shape[0] and flat.strides[1] != flat.itemsize:
        flat = np.ascontiguousarray(flat)
    if flat.shape[0] == 0:
        raise OccsegValueError(Status.EINVAL, f"{who}: points: the cloud has no point (shape {arr.shape})")
    return flat, flat.ctypes.data, _POINT_DTYPES[flat.dtype], flat.shape[0], flat.strides[0], lead


def pose_args(who, origin, orientation):
    """(c_double3, c_double4) of a sensor pose: origin (x, y, z) and orientation (w, x, y, z), as
    the command's --sensor-origin and --sensor-orientation take them."""
    return c_double3(*_numbers(who, "origin", origin, 3, "(x, y, z)")), \
        c_double4(*_numbers(who, "orientation", orientation, 4, "(w, x, y, z)"))


def _numbers(who, name, value, n, what):
    try:
        items = list(value)
    except TypeError:
        raise OccsegTypeError(Status.EINVAL, f"{who}: {name} must be a sequence of {n} numbers {what}, "
                                             f"not {type(value).__name__}") from None
    if len(items) != n:
        raise OccsegValueError(Status.EINVAL, f"{who}: {name} has {len(items)} values; expected {n} {what}")
    return [real(who, f"{name}[{k}]", v) for k, v in enumerate(items)]


def _options(who, voxel_size, bbox, margin, max_range, threads):
    o = FusionOptions()
    lib.occseg_fusion_options_init(ctypes.byref(o))
    o.voxel_size = real(who, "voxel_size", voxel_size)
    o.margin = real(who, "margin", margin)
    o.max_range = -1.0 if max_range is None else real(who, "max_range", max_range)
    o.threads = c_integer(who, "threads", threads, ctypes.c_int32)
    if bbox is not None:
        b = _numbers(who, "bbox", bbox, 6, "(xmin, ymin, zmin, xmax, ymax, zmax)")
        o.use_box = 1
        o.box_min = c_double3(*b[:3])
        o.box_max = c_double3(*b[3:])
    return o


class Fusion(Owned):
    """Fuses scans into an occupancy map by ray casting (occseg_fusion), one scan at a time, with
    the code that fuses a .pcd file: the same points, pose and options give the very same map.

        with occseg.Fusion(voxel_size=0.05) as f:
            for points, origin, orientation in scans:  # (N, 3) or (H, W, 3) arrays
                f.add(points, origin=origin, orientation=orientation)
            m = f.map()

    voxel_size: metres per voxel edge (default 0.05, as the .pcd reader).
    bbox: (xmin, ymin, zmin, xmax, ymax, zmax): a fixed grid box (as --bbox); every add() is
        ray-cast into it at once. None (the default): the box is fitted to all the scans and
        sensor origins when map() is called (padded by `margin` metres), as for a .pcd file;
        the scans are kept (a copy of the points) until then.
    max_range: metres (None: unlimited); longer returns mark free space only.
    threads: 0 = all cores; the map never depends on it."""

    _what = "occseg.Fusion"

    def __init__(self, voxel_size=0.05, *, bbox=None, margin=0.0, max_range=None, threads=0):
        o = _options("occseg.Fusion", voxel_size, bbox, margin, max_range, threads)
        out = ctypes.c_void_p()
        check(lib.occseg_fusion_new(ctypes.byref(out), ctypes.byref(o)))
        self._own(out, "fusion", lib.occseg_fusion_free)

    def add(self, points, origin=(0.0, 0.0, 0.0), orientation=(1.0, 0.0, 0.0, 0.0)):
        """Adds one scan: points (N, 3) or an organized (H, W, 3) cloud, float32 or float64, in
        the sensor frame; the pose maps them to the world (world = R(orientation) p + origin, the
        sensor at origin). The quaternion (w, x, y, z) is normalised; NaN points are skipped."""
        who = "occseg.Fusion.add"
        keep, data, dtype, count, stride, _ = point_args(who, points)
        o, q = pose_args(who, origin, orientation)
        with self._used() as h:
            check(lib.occseg_fusion_add_points(h, data, dtype, count, stride, o, q))
        del keep

    def map(self):
        """The map of all scans added so far (a new occseg.Map). More scans may follow."""
        out = ctypes.c_void_p()
        with self._used() as h:
            check(lib.occseg_fusion_map(ctypes.byref(out), h))
        return Map(out)

    @property
    def scans(self):
        """Number of scans added."""
        return self._counts()[0]

    @property
    def points(self):
        """Number of finite points added."""
        return self._counts()[1]

    def _counts(self):
        s, p = ctypes.c_uint64(), ctypes.c_uint64()
        with self._used() as h:
            check(lib.occseg_fusion_counts(h, ctypes.byref(s), ctypes.byref(p)))
        return s.value, p.value

    def __repr__(self):
        try:
            s, p = self._counts()
        except ValueError:
            return "<occseg.Fusion closed>"
        return f"<occseg.Fusion scans={s} points={p}>"


def fuse(points, origin=(0.0, 0.0, 0.0), orientation=(1.0, 0.0, 0.0, 0.0), *, voxel_size=0.05, bbox=None,
         margin=0.0, max_range=None, threads=0):
    """Fuses one cloud into a new occseg.Map by ray casting from the sensor (see Fusion): the map
    `occseg segment cloud.pcd --voxel-size V` (or occseg.read_map("cloud.pcd")) makes of the same
    points with the same pose, bit for bit. points: (N, 3) or (H, W, 3), float32 or float64, in the
    sensor frame; origin (x, y, z) and orientation (w, x, y, z) as --sensor-origin and
    --sensor-orientation take them (a .pcd file's VIEWPOINT)."""
    if isinstance(points, (list, tuple)) and points and isinstance(points[0], np.ndarray) and points[0].ndim >= 2:
        raise OccsegError(Status.EINVAL, "occseg.fuse: points is a list of clouds; fuse several scans with "
                                         "occseg.Fusion (add() each with its pose, then map())")
    with Fusion(voxel_size, bbox=bbox, margin=margin, max_range=max_range, threads=threads) as f:
        f.add(points, origin, orientation)
        return f.map()
