"""Ownership of C handles: each one is freed exactly once, by close() or when its Python owner is
collected, and a debug counter of live handles lets tests prove nothing leaks."""
import threading
import weakref

_lock = threading.Lock()
_live = {}


def live_handles():
    """Number of C handles the bindings currently own, by kind ("map", "result", "params")."""
    with _lock:
        return {k: v for k, v in _live.items() if v}


def _count(kind, delta):
    with _lock:
        _live[kind] = _live.get(kind, 0) + delta


def _release(free, kind, handle):
    free(handle)
    _count(kind, -1)


def own(owner, kind, free, handle):
    """Ties C `handle` to Python object `owner`: `free(handle)` runs when the returned finalizer is
    called (close) or when `owner` is collected, whichever comes first, and never twice."""
    _count(kind, +1)
    return weakref.finalize(owner, _release, free, kind, handle)
