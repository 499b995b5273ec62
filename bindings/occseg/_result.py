"""Result: labels, the segment table and timings of one segmentation (an occseg_result handle)."""
import ctypes
import dataclasses
import enum

import numpy as np

from ._args import integer, path_bytes
from ._errors import OccsegError, Status, check
from ._handles import Owned
from ._lib import SegmentInfo, c_size3, lib


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


class Result(Owned):
    """The output of occseg.segment().

    `labels` (uint32, the shape of the input: segment id per voxel), `segments` (list of Segment,
    index == id), `timings` ({stage: seconds}), `voxel_size` and `origin` are plain Python and NumPy
    data copied out at creation and stay usable after close(). states() and write() read the C
    result, which close(), the end of a `with` block or garbage collection frees (after the last
    running states() or write() of another thread returns, if one is running).

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
        self.labels = self._copy_out(h, lib.occseg_result_labels, np.uint32)
        self.labels.flags.writeable = False  # mask() and voxels() rely on it; copy to modify
        self.segments = [self._segment(h, i) for i in range(lib.occseg_result_segment_count(h))]
        self.timings = {}
        for i in range(lib.occseg_result_stage_count(h)):
            name, seconds = ctypes.c_char_p(), ctypes.c_double()
            check(lib.occseg_result_stage(h, i, ctypes.byref(name), ctypes.byref(seconds)))
            self.timings[name.value.decode()] = seconds.value

    def _copy_out(self, h, fn, dtype):
        out = np.empty(self.shape, dtype=dtype)
        check(fn(h, out.ctypes.data, out.size))
        return out

    @staticmethod
    def _segment(h, index):
        info = SegmentInfo(struct_size=ctypes.sizeof(SegmentInfo))
        check(lib.occseg_result_segment(h, index, ctypes.byref(info)))
        return Segment(info.id, State(info.state), info.voxels, info.mop,
                       (tuple(info.bbox_min), tuple(info.bbox_max)), tuple(info.centroid), Kind(info.kind))

    def states(self):
        """The state (State value) of each voxel, uint8, the shape of labels."""
        return self._call(self._copy_out, lib.occseg_result_states, np.uint8)

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
