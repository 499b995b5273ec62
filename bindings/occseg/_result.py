"""Result: labels, the segment table and timings of one segmentation (an occseg_result handle)."""
import collections.abc
import ctypes
import dataclasses
import enum
import weakref

import numpy as np

from ._args import integer, path_bytes
from ._errors import OccsegError, Status, check
from ._handles import Borrow, Owned
from ._lib import BoxInfo, SegmentInfo, c_size3, has, lib

# The colours of occupied segments, as occseg/segment_colour.hpp gives them to every output of
# the command (pictures, segments.ot, segments.ply): hue = SEGMENT_HUES[(((id * 2654435761) mod
# 2^32) >> 16) % 16]. tests/python/test_boxes.py checks this copy against the header.
SEGMENT_HUES = ((235, 120, 40), (200, 40, 40), (150, 90, 30), (220, 60, 160), (230, 185, 30), (140, 50, 150),
                (90, 150, 50), (250, 100, 100), (30, 130, 130), (50, 70, 170), (170, 170, 40), (120, 210, 110),
                (110, 70, 220), (240, 150, 200), (130, 30, 70), (160, 220, 60))


def segment_colour(segment_id):
    """(r, g, b), 0..255, of an occupied segment: the same colour as in the command's outputs."""
    return SEGMENT_HUES[(((int(segment_id) * 2654435761) & 0xFFFFFFFF) >> 16) % len(SEGMENT_HUES)]


@dataclasses.dataclass(frozen=True)
class Box:
    """An oriented bounding box in the map's world frame, metres (occseg_box): `center`
    (x, y, z), full edge lengths `extents` along the box's own axes, and `quaternion` (w, x, y, z),
    the rotation from the map's axes to the box's (w >= 0). What a MoveIt CollisionObject's BOX
    primitive takes: dimensions = extents, pose = center and the quaternion (as x, y, z, w)."""

    center: tuple
    extents: tuple
    quaternion: tuple

    def rotation(self):
        """The 3 x 3 rotation matrix of `quaternion` (columns: the box's axes in the map)."""
        w, x, y, z = self.quaternion
        return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                         [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                         [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


class State(enum.IntEnum):
    """occseg_state: the state of a voxel or a segment."""

    FREE = 0
    UNKNOWN = 1
    OCCUPIED = 2


class Kind(enum.IntEnum):
    """occseg_kind: what a segment is in the scene (docs/algorithm.md, default preset rule 9)."""

    FREE = 0
    UNKNOWN = 1
    STRUCTURE = 2  # occupied, lying mostly on a support plane (floor, wall, table top)
    OBJECT = 3
    CLUTTER = 4  # occupied, fewer than min_object_voxels voxels


@dataclasses.dataclass(frozen=True)
class Segment:
    """One segment: a 6-connected region of voxels of one state. Index triples are (x, y, z),
    as in occseg.h and segments.json; `slices` gives the NumPy [z, y, x] view of its box."""

    id: int  # its label in Result.labels and its index in Result.segments
    state: State
    voxels: int  # number of voxels
    mop: float  # mean occupancy probability of its voxels
    bbox: tuple  # ((xmin, ymin, zmin), (xmax, ymax, zmax)), voxel indices, both inclusive
    centroid: tuple  # mean voxel index (x, y, z)
    kind: Kind = Kind.OBJECT  # free, unknown, structure, object or clutter

    @property
    def slices(self):
        """(z, y, x) slices of the bounding box: labels3d[segment.slices] is the box."""
        lo, hi = self.bbox
        return tuple(slice(lo[k], hi[k] + 1) for k in (2, 1, 0))


NO_LABEL = 0xFFFFFFFF  # OCCSEG_NO_LABEL: Result.point_labels of a point no voxel holds


class Segments(collections.abc.Sequence):
    """The segment table as a read-only sequence of Segment, index == id, made on access from
    the C result's own table (occseg_result_segments_view) instead of one C call and one Python
    object per segment up front (a noisy map has a segment per 80 voxels). Compares equal to any
    sequence of the same Segments (a list too)."""

    __slots__ = ("_table",)

    def __init__(self, table):
        self._table = table  # structured array, read-only

    def __len__(self):
        return len(self._table)

    def __getitem__(self, index):
        if isinstance(index, slice):
            return [self[i] for i in range(*index.indices(len(self)))]
        row = self._table[index]
        return Segment(int(row["id"]), State(int(row["state"])), int(row["voxels"]), float(row["mop"]),
                       (tuple(int(v) for v in row["bbox_min"]), tuple(int(v) for v in row["bbox_max"])),
                       tuple(float(v) for v in row["centroid"]), Kind(int(row["kind"])))

    def __iter__(self):
        return (self[i] for i in range(len(self)))

    def __eq__(self, other):
        if isinstance(other, Segments):
            return bool(np.array_equal(self._table, other._table))
        if not isinstance(other, collections.abc.Sequence) or isinstance(other, (str, bytes)):
            return NotImplemented
        return len(self) == len(other) and all(a == b for a, b in zip(self, other))

    def __ne__(self, other):
        eq = self.__eq__(other)
        return eq if eq is NotImplemented else not eq

    __hash__ = None

    def _detached(self):
        """The same table in memory of its own (for a result handed back to a context)."""
        return Segments(self._table.copy())

    def __repr__(self):
        return f"<occseg.Segments: {len(self)} segments>"


class Result(Owned):
    """The output of occseg.segment().

    `labels` (uint32, the shape of the input: segment id per voxel) is a read-only NumPy array over
    the C result's own label array, not a copy; states() likewise returns a read-only array over
    the result's states. Each such array keeps the C result alive: close(), the end of a `with`
    block or garbage collection free the C result only once the last array over it is gone (and
    after the last running states() or write() of another thread returns). Copy an array
    (labels.copy()) to modify it. `segments` (a sequence of Segment, index == id, made on access
    from the C result's table, which it also keeps alive; equal to a list of the same), `timings`
    ({stage: seconds}), `voxel_size` and `origin` are plain Python data. After close(), states()
    and write() raise ValueError; `labels` stays usable. After Context.recycle(result), `labels`
    is gone (ValueError) unless the caller still holds the array, in which case the result is not
    recycled but freed when that array goes (a recycled label array is rewritten by the next call).

    Segment ids (mask(), voxels(), points()) are ints (Python or NumPy integers): a float or bool
    raises OccsegTypeError, an id outside [0, len(segments)) OccsegError ERANGE."""

    _what = "occseg.Result"

    def __init__(self, handle, shape, voxel_size, origin):
        """Takes ownership of a C occseg_result handle; `shape` is the input's NumPy shape."""
        self._own(handle, "result", lib.occseg_result_free)
        with self._used() as h:
            self._copy_all(h, shape, voxel_size, origin)

    def _copy_all(self, h, shape, voxel_size, origin):
        d = c_size3()
        check(lib.occseg_result_dims(h, d))
        self.dims = tuple(d)  # (nx, ny, nz)
        self.shape = tuple(shape)
        if int(np.prod(self.shape)) != d[0] * d[1] * d[2]:
            raise OccsegError(Status.EINTERNAL, f"result dims {self.dims} do not match the input shape {self.shape}")
        self.voxel_size = voxel_size
        self.origin = tuple(origin)
        # mask() and voxels() rely on the labels being read-only; copy them to modify
        self._labels = self._in_place(h, "occseg_result_labels_view", lib.occseg_result_labels, np.uint32)
        self._labels_after_recycle = None  # a weak reference, once recycle() let the labels go
        if has("occseg_result_segments_view"):
            self._segments = None  # the table is read in place on first access (segments)
        else:
            self._segments = [self._segment(h, i) for i in range(lib.occseg_result_segment_count(h))]
        self.timings = {}
        for i in range(lib.occseg_result_stage_count(h)):
            name, seconds = ctypes.c_char_p(), ctypes.c_double()
            check(lib.occseg_result_stage(h, i, ctypes.byref(name), ctypes.byref(seconds)))
            self.timings[name.value.decode()] = seconds.value

    def _copy_out(self, h, fn, dtype):
        out = np.empty(self.shape, dtype=dtype)
        check(fn(h, out.ctypes.data, out.size))
        return out

    def _in_place(self, h, view_fn, copy_fn, dtype):
        """A read-only array over the C result's memory (kept alive by the array), or with a
        library that has no view function, a read-only copy."""
        if not has(view_fn):
            out = self._copy_out(h, copy_fn, dtype)
            out.flags.writeable = False
            return out
        address, count = ctypes.c_void_p(), ctypes.c_size_t()
        check(getattr(lib, view_fn)(h, ctypes.byref(address), ctypes.byref(count)))
        if count.value != int(np.prod(self.shape)) or not address.value:
            raise OccsegError(Status.EINTERNAL, f"{view_fn} gave {count.value} values for shape {self.shape}")
        return np.asarray(Borrow(self._h, address.value, self.shape, np.dtype(dtype).str))

    @property
    def segments(self):
        """The segment table (Segments, index == id), read from the C result on first access:
        80 bytes per segment held with the result from then on (a call that only needs labels
        never makes it). Made by close() and recycle() too, so it stays usable after them."""
        segments = self._segments
        if segments is None:
            segments = self._segments = Segments(self._call(self._table))
        return segments

    def close(self):
        if self._segments is None and not self.closed:
            try:
                self.segments  # stays usable after close(), like labels
            except (ValueError, OccsegError, MemoryError):
                pass  # closed meanwhile by another thread, or out of memory: it is then unavailable
        super().close()

    @property
    def labels(self):
        """Segment id per voxel (uint32, the input's shape), read-only, over the C result's memory."""
        labels = self._labels
        if labels is None:
            labels = self._labels_after_recycle() if self._labels_after_recycle is not None else None
            if labels is None:
                raise ValueError("occseg.Result: the labels went back to the context with recycle(); "
                                 "hold result.labels before recycling to keep them (the result is then freed, "
                                 "not recycled, once they go)")
        return labels

    def _let_go(self):
        """Drops the result's own reference to its labels (for Context.recycle): the array dies
        now unless the caller holds it, which then keeps the C result from being recycled."""
        if not self.closed:
            segments = self.segments
            if isinstance(segments, Segments):
                self._segments = segments._detached()  # a copy of the table: its view would hold the result
        labels, self._labels = self._labels, None
        if labels is not None and self._labels_after_recycle is None:
            self._labels_after_recycle = weakref.ref(labels)

    def _table(self, h):
        """The C result's segment table as a read-only structured array over its memory."""
        address, count = ctypes.c_void_p(), ctypes.c_size_t()
        check(lib.occseg_result_segments_view(h, ctypes.byref(address), ctypes.byref(count)))
        dtype = np.dtype(SegmentInfo)
        if count.value == 0:
            return np.zeros(0, dtype)
        raw = np.asarray(Borrow(self._h, address.value, (count.value * dtype.itemsize,), "|u1"))
        return raw.view(dtype)

    @staticmethod
    def _segment(h, index):
        info = SegmentInfo(struct_size=ctypes.sizeof(SegmentInfo))
        check(lib.occseg_result_segment(h, index, ctypes.byref(info)))
        return Segment(info.id, State(info.state), info.voxels, info.mop,
                       (tuple(info.bbox_min), tuple(info.bbox_max)), tuple(info.centroid), Kind(info.kind))

    def states(self):
        """The state (State value) of each voxel, uint8, the shape of labels: a read-only array
        over memory of the C result (made on the first call, 1 byte per voxel, kept with the
        result), which it keeps alive like `labels`. ValueError once the result is closed."""
        return self._call(self._in_place, "occseg_result_states_view", lib.occseg_result_states, np.uint8)

    # What write() writes: the files of `occseg segment` that liboccseg itself can write (the
    # pictures and segments.ot need libpng and OctoMap, which only the command links).
    LIBRARY_OUTPUTS = ("labels.npy", "labels.nrrd", "segments.json", "segments.ply")
    MAP2D_OUTPUTS = ("segmentation.pgm", "segmentation.yaml")

    def write(self, directory, outputs=None):
        """Writes the command's output files into `directory`, all or nothing (on an error every
        file there stays as it was; occseg_result_write_outputs). `outputs`: None for the command's
        default set as far as the library writes it: labels.nrrd (gzip-encoded, with the map's
        voxel size and origin), segments.json (with the map's frame and the oriented boxes) and,
        for a 2D map, segmentation.pgm + segmentation.yaml, byte for byte as the command writes
        them; "all" for those, labels.npy and segments.ply; or a list of file names. With a library older than
        occseg_result_write_outputs, only None works and writes labels.npy + segments.json. A path
        holding a NUL character raises OccsegValueError (C would see only the text before it)."""
        d = path_bytes("occseg.Result.write", "directory", directory)
        if outputs is None:
            names = ["labels.nrrd", "segments.json"]
        elif isinstance(outputs, str) and outputs == "all":
            names = list(self.LIBRARY_OUTPUTS)
        elif isinstance(outputs, str):
            raise OccsegError(Status.EINVAL, f"occseg.Result.write: outputs {outputs!r} is not 'all' or a list of names")
        else:
            names = [path_bytes("occseg.Result.write", "outputs", n).decode() for n in outputs]
        if (outputs is None or outputs == "all") and self.dims[2] == 1:
            names += list(self.MAP2D_OUTPUTS)
        if not has("occseg_result_write_outputs"):
            if outputs is not None:
                raise OccsegError(Status.EUNSUPPORTED, "occseg.Result.write: outputs= needs a liboccseg with "
                                                       "occseg_result_write_outputs")
            self._call(lambda h: check(lib.occseg_result_write(h, d)))
            return
        arr = (ctypes.c_char_p * (len(names) + 1))(*[n.encode() for n in names], None)
        self._call(lambda h: check(lib.occseg_result_write_outputs(h, d, arr)))

    def boxes(self):
        """The oriented bounding box (Box) of every segment, index == id (occseg_result_segment_box):
        for occupied segments the smallest box holding all their voxels among the map's axes, the
        principal axes and the best turn about z; for free and unknown ones their axis-aligned
        voxel box. Computed by the C library on the first call, then kept (usable after close())."""
        if getattr(self, "_boxes", None) is None:
            if not has("occseg_result_segment_box"):
                raise OccsegError(Status.EUNSUPPORTED, "occseg.Result.boxes: the loaded liboccseg has no "
                                                       "occseg_result_segment_box (too old)")
            self._boxes = self._call(self._copy_boxes)
        return list(self._boxes)

    def _copy_boxes(self, h):
        out = []
        for i in range(len(self.segments)):
            b = BoxInfo(struct_size=ctypes.sizeof(BoxInfo))
            check(lib.occseg_result_segment_box(h, i, ctypes.byref(b)))
            out.append(Box(tuple(b.center), tuple(b.extents), tuple(b.quaternion)))
        return out

    def box(self, segment_id):
        """The Box of one segment (see boxes())."""
        s = self._checked("box", segment_id)  # first: a bad id computes nothing
        return self.boxes()[s.id]

    def to_open3d(self, kind="points", states=(State.OCCUPIED,)):
        """The segmentation as an Open3D geometry coloured by segment (the command's colours):
        kind="points", a PointCloud of the voxel centres (metres); kind="voxels", a VoxelGrid of
        the map's voxel size. `states`: which segments (default: the occupied ones; free and
        unknown ones get their state's colour). Needs Open3D (Debian: apt-get install
        python3-open3d); without it raises ImportError saying so."""
        try:
            import open3d
        except ImportError as e:
            raise ImportError("occseg.Result.to_open3d needs Open3D, which is not installed "
                              "(Debian: apt-get install python3-open3d; elsewhere: pip install open3d); "
                              f"importing it failed: {e}") from e
        if kind not in ("points", "voxels"):
            raise OccsegError(Status.EINVAL, f"occseg.Result.to_open3d: kind {kind!r} is not 'points' or 'voxels'")
        wanted = {State(s) for s in states}
        pts, cols = [], []
        state_rgb = {State.FREE: (150, 200, 255), State.UNKNOWN: (245, 245, 245)}
        for s in self.segments:
            if s.state not in wanted:
                continue
            p = self.points(s.id)
            rgb = segment_colour(s.id) if s.state == State.OCCUPIED else state_rgb[s.state]
            pts.append(p)
            cols.append(np.tile(np.asarray(rgb, dtype=np.float64) / 255.0, (len(p), 1)))
        pcd = open3d.geometry.PointCloud()
        if pts:
            pcd.points = open3d.utility.Vector3dVector(np.concatenate(pts))
            pcd.colors = open3d.utility.Vector3dVector(np.concatenate(cols))
        if kind == "points":
            return pcd
        return open3d.geometry.VoxelGrid.create_from_point_cloud(pcd, voxel_size=self.voxel_size)

    def _checked(self, who, segment_id):
        """The Segment of an id: an int (not a bool, not a float), in range."""
        i = integer(f"occseg.Result.{who}", "segment id", segment_id)
        if not 0 <= i < len(self.segments):
            raise OccsegError(Status.ERANGE, f"occseg.Result.{who}: segment id {i} is out of range "
                                             f"(the result has {len(self.segments)} segments)")
        return self.segments[i]

    def mask(self, segment_id):
        """Boolean array (the shape of labels), True on the segment's voxels."""
        s = self._checked("mask", segment_id)
        return self.labels == s.id

    def voxels(self, segment_id):
        """The segment's voxel indices as an (N, 3) int64 array of (x, y, z) rows, ordered with x
        fastest (as occseg.h stores voxels). Index the labels with labels3d[z, y, x]."""
        return self._voxels(self._checked("voxels", segment_id))

    def _voxels(self, s):
        box = self.labels.reshape(self.dims[::-1])[s.slices]
        z, y, x = np.nonzero(box == s.id)
        lo = s.bbox[0]
        return np.stack([x + lo[0], y + lo[1], z + lo[2]], axis=1).astype(np.int64)

    def points(self, segment_id):
        """World (x, y, z) coordinates, in metres, of the centres of the segment's voxels."""
        s = self._checked("points", segment_id)
        return np.asarray(self.origin) + (self._voxels(s) + 0.5) * self.voxel_size

    def point_labels(self, points, origin=(0.0, 0.0, 0.0), orientation=(1.0, 0.0, 0.0, 0.0)):
        """The segment id of each input point (occseg_result_point_labels), as uint32: for an (N, 3)
        cloud an (N,) array, for an organized (H, W, 3) cloud an (H, W) label image. A point gets
        the label of the voxel it lies in, computed as the fusion computes the voxel of its
        return, so pass the pose the cloud was fused with (origin (x, y, z), orientation
        (w, x, y, z), as for occseg.fuse); NO_LABEL (2**32 - 1) for a point with a NaN or
        infinite coordinate or outside the grid. Uses the voxel size and origin of the map this
        result was computed on."""
        from ._fusion import point_args, pose_args
        who = "occseg.Result.point_labels"
        keep, data, dtype, count, stride, lead = point_args(who, points)
        o, q = pose_args(who, origin, orientation)
        out = np.empty(count, dtype=np.uint32)
        self._call(lambda h: check(lib.occseg_result_point_labels(h, None, data, dtype, count, stride, o, q,
                                                                  out.ctypes.data, out.size)))
        del keep
        return out.reshape(lead)

    def __repr__(self):
        n = np.bincount([s.state for s in self.segments], minlength=3)
        return (f"<occseg.Result dims={self.dims} segments={len(self.segments)} "
                f"(free {n[0]}, unknown {n[1]}, occupied {n[2]}){' closed' if self.closed else ''}>")
