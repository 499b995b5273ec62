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
from ._lib import SegmentInfo, c_size3, has, lib


class State(enum.IntEnum):
    """occseg_state: the state of a voxel or a segment."""

    FREE = 0
    UNKNOWN = 1
    OCCUPIED = 2


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

    @property
    def slices(self):
        """(z, y, x) slices of the bounding box: labels3d[segment.slices] is the box."""
        lo, hi = self.bbox
        return tuple(slice(lo[k], hi[k] + 1) for k in (2, 1, 0))


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
                       tuple(float(v) for v in row["centroid"]))

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
                       (tuple(info.bbox_min), tuple(info.bbox_max)), tuple(info.centroid))

    def states(self):
        """The state (State value) of each voxel, uint8, the shape of labels: a read-only array
        over memory of the C result (made on the first call, 1 byte per voxel, kept with the
        result), which it keeps alive like `labels`. ValueError once the result is closed."""
        return self._call(self._in_place, "occseg_result_states_view", lib.occseg_result_states, np.uint8)

    def write(self, directory):
        """Writes labels.npy and segments.json into `directory`, the same files as
        `occseg segment --out directory`; all or nothing. A path holding a NUL character raises
        OccsegValueError (C would see only the text before it)."""
        d = path_bytes("occseg.Result.write", "directory", directory)
        self._call(lambda h: check(lib.occseg_result_write(h, d)))

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

    def __repr__(self):
        n = np.bincount([s.state for s in self.segments], minlength=3)
        return (f"<occseg.Result dims={self.dims} segments={len(self.segments)} "
                f"(free {n[0]}, unknown {n[1]}, occupied {n[2]}){' closed' if self.closed else ''}>")
