"""occseg.Context: a caller-owned pool of worker threads kept between segmentations
(occseg_context_*), for programs that segment again and again."""
import ctypes

from ._args import c_integer
from ._errors import OccsegError, Status, check
from ._handles import Owned
from ._lib import has, lib
from ._result import Result


class Context(Owned):
    """A pool of `threads` threads in all (0: one per core), kept until close(). Pass it to
    occseg.segment(..., context=ctx): the stages run on its threads instead of starting new ones
    in each of them; the result is identical. One segmentation at a time per context (calls from
    several threads wait for each other). Needs a liboccseg with the occseg_context_* functions.

    close() never stops the threads under a running call: closed while a segmentation runs on it
    (from another thread, or from that segmentation's progress callback), the context refuses new
    calls at once and is freed when the running one returns."""

    _what = "occseg.Context"

    def __init__(self, threads=0):
        if not has("occseg_context_new"):
            raise OccsegError(Status.EUNSUPPORTED, "occseg.Context: the loaded liboccseg has no occseg_context_new")
        n = c_integer("occseg.Context", "threads", threads, ctypes.c_int)  # the library checks [0, 1024]
        out = ctypes.c_void_p()
        check(lib.occseg_context_new(ctypes.byref(out), n))
        self._own(out, "context", lib.occseg_context_free)

    @property
    def threads(self):
        """Threads a call runs on, the calling thread included."""
        return int(self._call(lib.occseg_context_threads))

    def recycle(self, result):
        """Hands back an occseg.Result you are done with: the next occseg.segment(...,
        context=self) writes its labels into that result's C label array instead of allocating
        fresh memory (about 7 % of a call on a 320 x 320 x 128 map; the context holds the array,
        4 bytes per voxel, until a call takes it; that call's peak is a plain call's). `result` is
        closed: its segments and timings stay usable (Python data), its labels (an array over
        the very memory handed back), states() and write() do not. If the caller still holds
        result.labels or an array from states(), or another thread is reading it (states(),
        write()), the result is closed and freed, not kept, when the last of those goes, so an
        array the caller holds is never overwritten. A closed result is ignored."""
        if not has("occseg_context_recycle"):
            raise OccsegError(Status.EUNSUPPORTED, "occseg.Context.recycle: the loaded liboccseg has no occseg_context_recycle")
        if not isinstance(result, Result):
            raise OccsegError(Status.EINVAL, f"occseg.Context.recycle: expected an occseg.Result, not {type(result).__name__}")
        with self._used() as context:  # ValueError if this context is closed, before the result is touched
            result._let_go()  # the labels array over the C result, unless the caller holds it
            handle = result._detach()
            if handle is not None:
                lib.occseg_context_recycle(context, handle)

    def __repr__(self):
        try:
            return f"<occseg.Context threads={self.threads}>"
        except ValueError:
            return "<occseg.Context closed>"
