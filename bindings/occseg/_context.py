"""occseg.Context: a caller-owned pool of worker threads kept between segmentations
(occseg_context_*), for programs that segment again and again."""
import ctypes

from ._errors import OccsegError, Status, check
from ._handles import Owned
from ._lib import has, lib


class Context(Owned):
    """A pool of `threads` threads in all (0: one per core), kept until close(). Pass it to
    occseg.segment(..., context=ctx): the stages run on its threads instead of starting new ones
    in each of them; the result is identical. One segmentation at a time per context (calls from
    several threads wait for each other). Needs a liboccseg with the occseg_context_* functions."""

    _what = "occseg.Context"

    def __init__(self, threads=0):
        if not has("occseg_context_new"):
            raise OccsegError(Status.EUNSUPPORTED, "occseg.Context: the loaded liboccseg has no occseg_context_new")
        if isinstance(threads, bool) or not isinstance(threads, int):
            raise OccsegError(Status.EINVAL, f"occseg.Context: threads must be an int, not {type(threads).__name__}")
        out = ctypes.c_void_p()
        check(lib.occseg_context_new(ctypes.byref(out), threads))
        self._own(out, "context", lib.occseg_context_free)

    @property
    def threads(self):
        """Threads a call runs on, the calling thread included."""
        return int(lib.occseg_context_threads(self.handle))

    def __repr__(self):
        return "<occseg.Context closed>" if self.closed else f"<occseg.Context threads={self.threads}>"
