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


class Owned:
    """Base of the Python objects that own one C handle (Map, Result): the handle property, close(),
    `closed` and the context manager. Subclasses call _own(handle, kind, free) in __init__ and set
    _what ("occseg.Map", ...) for error messages."""

    _what = "occseg object"

    def _own(self, handle, kind, free):
        self._handle = handle.value if hasattr(handle, "value") else int(handle)
        self._kind = kind
        self._finalizer = own(self, kind, free, self._handle)

    def _detach(self):
        """Gives up the C handle without freeing it (another owner frees it now); None if the
        object is already closed."""
        if self._finalizer.detach() is None:
            return None
        _count(self._kind, -1)
        return self._handle

    @property
    def handle(self):
        """The C pointer as an int; ValueError once the object is closed."""
        if not self._finalizer.alive:
            raise ValueError(f"{self._what}: the {self._what.split('.')[-1].lower()} is closed")
        return self._handle

    @property
    def closed(self):
        return not self._finalizer.alive

    def close(self):
        """Frees the C handle now (later calls do nothing)."""
        self._finalizer()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
