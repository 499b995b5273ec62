"""Ownership of C handles: each one is freed exactly once, never while a call uses it, and a debug
counter of live handles lets tests prove nothing leaks.

Every C call on a handle runs inside a *use* (Owned._used()): a per-handle lock guards a count of
the calls running on it. close() (also the end of a `with` block, collection and interpreter exit)
marks the handle closed at once, so no new call can start on it (ValueError, as a closed file
gives), but the C free waits for the last running call: it runs when that call returns, on its
thread. So a map closed by another thread while it is segmented, or closed (or its context
closed) from inside the progress callback of that very segmentation, is never freed under the C
call. The lock is only ever held for counting and for a short C call that calls no Python code,
never across a call that runs a callback: a callback that touches the handle cannot deadlock.

Calls that change a handle (Map.voxel_size = ..., Map.origin = ...) need it to themselves: the C
ABI forbids changing a map while another call reads it. They raise OccsegValueError while the
handle is in use instead of waiting, since the call using it may be the caller's own (a
progress callback of a segmentation of that map)."""
import threading
import weakref

from ._errors import OccsegValueError, Status

_lock = threading.Lock()
_live = {}


def live_handles():
    """Number of C handles the bindings currently own, by kind ("map", "result", "params", "context", "fusion")."""
    with _lock:
        return {k: v for k, v in _live.items() if v}


def _count(kind, delta):
    with _lock:
        _live[kind] = _live.get(kind, 0) + delta


class _Handle:
    """One C handle and its state, shared by its owner and the owner's finalizer. It never refers
    to the owner (the finalizer would keep the owner alive). Invariant: `value` is None once the
    handle has been freed or given away, and then `closed` is true and `users` is 0."""

    __slots__ = ("lock", "value", "kind", "free", "what", "users", "closed", "keep")

    def __init__(self, value, kind, free, what, keep=None):
        self.lock = threading.Lock()
        self.value, self.kind, self.free, self.what = value, kind, free, what
        self.keep = keep  # what the C object refers to (a map's viewed array): released after the free
        self.users = 0  # calls running on the handle
        self.closed = False
        _count(kind, +1)

    def _free(self, value):
        self.free(value)
        self.keep = None
        _count(self.kind, -1)

    def closed_error(self):
        # An OccsegValueError: a ValueError, as a closed file's, and an occseg error like every
        # other bad argument.
        return OccsegValueError(Status.EINVAL, f"{self.what}: the {self.what.split('.')[-1].lower()} is closed")

    def acquire(self):
        with self.lock:
            if self.closed:
                raise self.closed_error()
            self.users += 1
            return self.value

    def release(self):
        with self.lock:
            self.users -= 1
            last = self.closed and self.users == 0 and self.value is not None
            value = self.value
            if last:
                self.value = None
        if last:  # closed while in use: the last call frees it
            self._free(value)

    def close(self):
        with self.lock:
            if self.closed:
                return
            self.closed = True
            if self.users:
                return  # release() of the last running call frees it
            value, self.value = self.value, None
        self._free(value)

    def detach(self):
        """Closes the handle and hands its C pointer over (the caller frees it from now on); None
        if it is already closed, or in use (then it is freed as close() does)."""
        with self.lock:
            if self.closed:
                return None
            self.closed = True
            if self.users:
                return None
            value, self.value = self.value, None
        _count(self.kind, -1)
        return value

    def exclusive(self, who, fn):
        """fn(pointer), with no call running on the handle and none starting meanwhile. `fn` must be
        a short C call that never calls back into Python: it runs under the handle's lock."""
        with self.lock:
            if self.closed:
                raise self.closed_error()
            if self.users:
                raise OccsegValueError(Status.EINVAL, f"{who}: the {self.what.split('.')[-1].lower()} is in use by "
                                                      f"{self.users} running call(s) (segment, write, ...) of this or "
                                                      "another thread; change it before or after them")
            return fn(self.value)


class _Use:
    """`with owner._used() as pointer:` a running call on the handle (see the module's text)."""

    __slots__ = ("_h",)

    def __init__(self, handle):
        self._h = handle

    def __enter__(self):
        return self._h.acquire()

    def __exit__(self, *exc):
        self._h.release()


class Borrow:
    """The base of a NumPy array over memory a C handle owns (a result's labels): it holds a use
    of the handle, so that close() of the owner, and the owner's collection, free the C object
    only once the last such array is gone. Read-only arrays: the C memory is shared."""

    __slots__ = ("_h", "__array_interface__", "__weakref__")

    def __init__(self, handle, address, shape, typestr):
        self._h = None
        handle.acquire()  # ValueError when the owner is closed
        self._h = handle
        self.__array_interface__ = {"version": 3, "shape": tuple(shape), "typestr": typestr,
                                    "data": (address, True)}  # True: read-only

    def __del__(self):
        h, self._h = self._h, None
        if h is not None:
            h.release()


class Owned:
    """Base of the Python objects that own one C handle (Map, Result, Context, the parameter sets of
    segment()): close(), `closed`, the context manager, and uses of the handle. Subclasses call
    _own(handle, kind, free) in __init__ and set _what ("occseg.Map", ...) for error messages.

    close() never frees the C handle under a running call: it marks the object closed at once and
    the free follows when the last call using the handle returns (see _handles.py)."""

    _what = "occseg object"

    def _own(self, handle, kind, free, keep=None):
        """`keep`: an object the C handle refers to (the array a map views), kept alive until
        the handle is freed, whenever that is."""
        value = handle.value if hasattr(handle, "value") else int(handle)
        self._h = _Handle(value, kind, free, self._what, keep)
        self._finalizer = weakref.finalize(self, self._h.close)

    def _used(self):
        """A use of the handle for the duration of a `with` block, which gives the C pointer;
        ValueError once the object is closed."""
        return _Use(self._h)

    def _call(self, fn, *args):
        """fn(pointer, *args) as one use of the handle."""
        with self._used() as h:
            return fn(h, *args)

    def _exclusive(self, who, fn):
        """fn(pointer) with the handle to itself (a change of the object): OccsegValueError naming
        `who` while a call uses it. `fn` must be a short C call that never calls Python."""
        return self._h.exclusive(who, fn)

    def _detach(self):
        """Closes the object and gives its C handle away without freeing it (the caller frees it
        now); None if the object is already closed or a call is using it (it is then closed, and
        freed when that call returns)."""
        self._finalizer.detach()
        return self._h.detach()

    @property
    def handle(self):
        """The C pointer as an int; ValueError once the object is closed. Unguarded: a close() from
        another thread may free it at any time; the package's own calls go through uses."""
        with self._h.lock:
            if self._h.closed:
                raise self._h.closed_error()
            return self._h.value

    @property
    def closed(self):
        """True once close() has been called (the C free may still be waiting for a running call)."""
        return self._h.closed

    def close(self):
        """Closes the object: no new call can start on it (ValueError). The C handle is freed now,
        or, while a call (in this or another thread, e.g. the segmentation whose progress callback
        is running) still uses it, as soon as the last such call returns. Later calls do nothing."""
        self._finalizer()
        self._h.close()  # after _detach the finalizer is gone; close() must still close

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
