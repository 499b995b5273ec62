"""occseg.segment(): one call from a NumPy array (or a Map) to a Result."""
import ctypes

from ._context import Context
from ._errors import OccsegError, Status, check
from ._handles import own
from ._lib import PROGRESS_FN, lib
from ._map import Map, as_voxel_array
from ._params import set_param
from ._result import Result


class _Params:
    """An occseg_params handle that lives for one call."""

    def __init__(self):
        out = ctypes.c_void_p()
        check(lib.occseg_params_create(ctypes.byref(out)))
        self.handle = out.value
        self._finalizer = own(self, "params", lib.occseg_params_free, self.handle)

    def close(self):
        self._finalizer()


class _Progress:
    """The C progress callback. Always installed, so that Ctrl-C (delivered while Python code
    runs, i.e. in here) cancels the run. Nothing raised in Python crosses into C: the exception
    is kept, the run is cancelled, and segment() re-raises it once the C call has returned."""

    def __init__(self, user_fn):
        self.user_fn = user_fn
        self.error = None
        self.c_fn = PROGRESS_FN(self._call)  # referenced by self for the whole call

    def _call(self, stage, fraction, _user):
        try:
            if self.user_fn is not None and self.user_fn(stage.decode(), fraction):
                return 1
            return 0
        except BaseException as e:  # noqa: B036 - KeyboardInterrupt and SystemExit too
            self.error = e
            return 1


def segment(probabilities, preset="default", threads=0, *, voxel_size=None, origin=None, progress=None,
            clamp=False, nan_unknown=False, context=None, **params):
    """Segments a probabilistic occupancy map into free, unknown and occupied segments.

    probabilities: NumPy array indexed [z, y, x] (or [y, x]) of float32, float64, uint8 or uint16
        (0..max meaning 0..1), any strides: it is read in place, not copied. Or an occseg.Map.
    preset: "default" (paper plus per-voxel safety rules) or "paper" (as published).
    threads: worker threads, 0 = all cores; results never depend on it.
    voxel_size, origin: of an array input (default 1 and (0, 0, 0)); a Map carries its own.
    progress: optional callable(stage: str, fraction: float); a true return value cancels
        (OccsegError ECANCELLED), and an exception it raises cancels and is re-raised here.
    clamp, nan_unknown: accept out-of-range or NaN float values (see Map.from_array).
    context: an occseg.Context whose threads run the stages (at most `threads` of them, 0: all);
        same result, without starting threads on every call.
    **params: any parameter of occseg.param_table(), e.g. smax=32, split_ratio=1.2.

    Returns a Result. Raises OccsegError for bad input, naming the problem."""
    if isinstance(probabilities, Map):
        if voxel_size is not None or origin is not None or clamp or nan_unknown:
            raise OccsegError(Status.EINVAL, "occseg.segment: voxel_size, origin, clamp and nan_unknown apply to "
                                             "arrays; a Map carries its own voxel size and origin")
        m, temporary = probabilities, False
        shape = m.shape
    else:
        arr = as_voxel_array(probabilities, "occseg.segment")
        m = Map.from_array(arr, 1.0 if voxel_size is None else voxel_size, origin,
                           clamp=clamp, nan_unknown=nan_unknown)
        temporary = True
        shape = arr.shape  # [y, x] inputs get [y, x] labels
    p = None
    try:
        p = _Params()
        check(lib.occseg_params_preset(p.handle, str(preset).encode()))
        set_param(p.handle, "threads", threads)
        for name, value in params.items():
            set_param(p.handle, name, value)
        cb = _Progress(progress)
        check(lib.occseg_params_set_progress(p.handle, cb.c_fn, None))
        out = ctypes.c_void_p()
        if context is None:
            rc = lib.occseg_segment(ctypes.byref(out), m.handle, p.handle)
        else:
            if not isinstance(context, Context):
                raise OccsegError(Status.EINVAL, "occseg.segment: context must be an occseg.Context, not "
                                                 f"{type(context).__name__}")
            rc = lib.occseg_context_segment(ctypes.byref(out), context.handle, m.handle, p.handle)
        if cb.error is not None:
            lib.occseg_result_free(out)  # NULL after a cancel; freed anyway should it ever not be
            raise cb.error
        check(rc)
        return Result(out, shape, m.voxel_size, m.origin)
    finally:
        if p is not None:
            p.close()
        if temporary:
            m.close()
