"""occseg.segment(): one call from a NumPy array (or a Map) to a Result."""
import contextlib
import ctypes

from ._args import flag, text_bytes
from ._context import Context
from ._errors import OccsegError, OccsegTypeError, Status, check
from ._handles import Owned
from ._lib import PROGRESS_FN, has, lib
from ._map import Map, as_voxel_array, map_dims, map_origin, map_voxel_size, python_flag_error
from ._params import set_param
from ._result import Result


class _Params(Owned):
    """An occseg_params handle that lives for one call (owned like every other handle)."""

    _what = "occseg parameter set"

    def __init__(self):
        out = ctypes.c_void_p()
        check(lib.occseg_params_create(ctypes.byref(out)))
        self._own(out, "params", lib.occseg_params_free)


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
        (0..max meaning 0..1), or int8 read as a ROS OccupancyGrid (-1 unknown, 0..100 percent;
        see Map.from_array), any strides and either byte order: it is read in place, not copied
        (Map.view; a dense native float32 array as it lies, other dtypes, layouts and byte
        orders through a converter, a few rows or planes at a time: no copy of the map either
        way). Or an occseg.Map.
    preset: "default" (paper plus per-voxel safety rules) or "paper" (as published).
    threads: worker threads, 0 = all cores; results never depend on it.
    voxel_size, origin: of an array input (default 1 and (0, 0, 0)); a Map carries its own.
    progress: optional callable(stage: str, fraction: float); a true return value cancels
        (OccsegError ECANCELLED), and an exception it raises cancels and is re-raised here.
    clamp, nan_unknown: accept out-of-range or NaN float values (see Map.from_array).
    context: an occseg.Context whose threads run the stages (at most `threads` of them, 0: all);
        same result, without starting threads on every call.
    **params: any parameter of occseg.param_table(), e.g. smax=32, split_ratio=1.2.

    Returns a Result, whose labels (and states()) are read-only arrays over the C result's memory,
    kept alive by them. Raises OccsegError for bad input, naming the problem.

    A Map or context closed while this runs (by another thread, or by `progress`) is freed only
    once the C call has returned; this call finishes normally."""
    who = "occseg.segment"
    preset_text = text_bytes(who, "preset", preset)
    if progress is not None and not callable(progress):
        raise OccsegTypeError(Status.EINVAL, f"{who}: progress must be a callable (stage, fraction) or None, "
                                             f"not {type(progress).__name__}")
    if context is not None and not isinstance(context, Context):
        raise OccsegTypeError(Status.EINVAL, f"{who}: context must be an occseg.Context, not {type(context).__name__}")
    if isinstance(probabilities, Map):
        if voxel_size is not None or origin is not None or flag(who, "clamp", clamp) or flag(who, "nan_unknown", nan_unknown):
            raise OccsegError(Status.EINVAL, "occseg.segment: voxel_size, origin, clamp and nan_unknown apply to "
                                             "arrays; a Map carries its own voxel size and origin")
        m, temporary = probabilities, False
        shape = None  # the map's, read under the use below
    else:
        arr = as_voxel_array(probabilities, "occseg.segment")
        # Read where it lies (Map.view keeps the array alive while the map views it); a library
        # without occseg_map_view_buffer gets a copy.
        make = Map.view if has("occseg_map_view_buffer") else Map.from_array
        m = make(arr, 1.0 if voxel_size is None else voxel_size, origin, clamp=clamp, nan_unknown=nan_unknown)
        temporary = True
        shape = arr.shape  # [y, x] inputs get [y, x] labels
    p = None
    try:
        p = _Params()
        cb = _Progress(progress)
        with p._used() as ph:
            check(lib.occseg_params_preset(ph, preset_text))
            set_param(ph, "threads", threads)
            for name, value in params.items():
                set_param(ph, name, value)
            check(lib.occseg_params_set_progress(ph, cb.c_fn, None))
            # Uses of the map and the context span the C call: a close() meanwhile (another
            # thread's, or the progress callback's) frees them only once the call has returned.
            with m._used() as mh, (context._used() if context is not None else contextlib.nullcontext()) as ch:
                voxel_size, origin = map_voxel_size(mh), map_origin(mh)
                if shape is None:
                    shape = tuple(reversed(map_dims(mh)))
                out = ctypes.c_void_p()
                if context is None:
                    rc = lib.occseg_segment(ctypes.byref(out), mh, ph)
                else:
                    rc = lib.occseg_context_segment(ctypes.byref(out), ch, mh, ph)
                if cb.error is None:
                    try:
                        check(rc)  # here: the deferred frees at the end of the uses come after the text is read
                    except OccsegError as e:
                        if not temporary:
                            raise
                        # An array viewed by this call: its values are checked as the pipeline reads
                        # them, so name the keywords (clamp=True, ...), as Map.from_array does.
                        raise python_flag_error(e) from None
        if cb.error is not None:
            lib.occseg_result_free(out)  # NULL after a cancel; freed anyway should it ever not be
            raise cb.error
        return Result(out, shape, voxel_size, origin)
    finally:
        if p is not None:
            p.close()
        if temporary:
            m.close()
