"""Result: labels, the segment table and timings of one segmentation (an occseg_result handle)."""
import ctypes
import dataclasses
import enum
import os

import numpy as np

from ._errors import OccsegError, Status, check
from ._handles import Owned
from ._lib import SegmentInfo, c_size3, lib


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


class Result(Owned):
    """The output of occseg.segment().

    `labels` (uint32, the shape of the input: segment id per voxel), `segments` (list of Segment,
    index == id), `timings` ({stage: seconds}), `voxel_size` and `origin` are plain Python and NumPy
    data copied out at creation and stay usable after close(). states() and write() read the C
    result, which close(), the end of a `with` block or garbage collection frees."""

    _what = "occseg.Result"

    def __init__(self, handle, shape, voxel_size, origin):
        """Takes ownership of a C occseg_result handle; `shape` is the input's NumPy shape."""
        self._own(handle, "result", lib.occseg_result_free)
        d = c_size3()
        check(lib.occseg_result_dims(self._handle, d))
        self.dims = tuple(d)  # (nx, ny, nz)
        self.shape = tuple(shape)
        if int(np.prod(self.shape)) != d[0] * d[1] * d[2]:
            raise OccsegError(Status.EINTERNAL, f"result dims {self.dims} do not match the input shape {self.shape}")
        self.voxel_size = voxel_size
        self.origin = tuple(origin)
        self.labels = self._copy_out(lib.occseg_result_labels, np.uint32)
        self.labels.flags.writeable = False  # mask() and voxels() rely on it; copy to modify
        self.segments = [self._segment(i) for i in range(lib.occseg_result_segment_count(self._handle))]
        self.timings = {}
        for i in range(lib.occseg_result_stage_count(self._handle)):
            name, seconds = ctypes.c_char_p(), ctypes.c_double()
            check(lib.occseg_result_stage(self._handle, i, ctypes.byref(name), ctypes.byref(seconds)))
            self.timings[name.value.decode()] = seconds.value

    def _copy_out(self, fn, dtype):
        out = np.empty(self.shape, dtype=dtype)
        check(fn(self.handle, out.ctypes.data, out.size))
        return out

    def _segment(self, index):
        info = SegmentInfo(struct_size=ctypes.sizeof(SegmentInfo))
        check(lib.occseg_result_segment(self._handle, index, ctypes.byref(info)))
        return Segment(info.id, State(info.state), info.voxels, info.mop,
                       (tuple(info.bbox_min), tuple(info.bbox_max)), tuple(info.centroid))

    def states(self):
        """The state (State value) of each voxel, uint8, the shape of labels."""
        return self._copy_out(lib.occseg_result_states, np.uint8)

    def write(self, directory):
        """Writes labels.npy and segments.json into `directory`, the same files as
        `occseg segment --out directory`; all or nothing."""
        check(lib.occseg_result_write(self.handle, os.fsencode(directory)))

    def _checked(self, segment_id):
        if not 0 <= int(segment_id) < len(self.segments):
            raise OccsegError(Status.ERANGE, f"segment id {segment_id} is out of range "
                                             f"(the result has {len(self.segments)} segments)")
        return self.segments[int(segment_id)]

    def mask(self, segment_id):
        """Boolean array (the shape of labels), True on the segment's voxels."""
        self._checked(segment_id)
        return self.labels == segment_id

    def voxels(self, segment_id):
        """The segment's voxel indices as an (N, 3) int64 array of (x, y, z) rows, ordered with x
        fastest (as occseg.h stores voxels). Index the labels with labels3d[z, y, x]."""
        s = self._checked(segment_id)
        box = self.labels.reshape(self.dims[::-1])[s.slices]
        z, y, x = np.nonzero(box == s.id)
        lo = s.bbox[0]
        return np.stack([x + lo[0], y + lo[1], z + lo[2]], axis=1).astype(np.int64)

    def points(self, segment_id):
        """World (x, y, z) coordinates, in metres, of the centres of the segment's voxels."""
        return np.asarray(self.origin) + (self.voxels(segment_id) + 0.5) * self.voxel_size

    def __repr__(self):
        n = np.bincount([s.state for s in self.segments], minlength=3)
        return (f"<occseg.Result dims={self.dims} segments={len(self.segments)} "
                f"(free {n[0]}, unknown {n[1]}, occupied {n[2]}){' closed' if self.closed else ''}>")
