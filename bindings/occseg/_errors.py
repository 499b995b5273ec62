"""OccsegError and the status codes of the C ABI."""
import enum

from ._lib import lib


class Status(enum.IntEnum):
    """occseg_status: the pinned status codes of occseg.h."""

    OK = 0
    EINVAL = -1
    EDIMS = -2
    EVALUE = -3
    ENOMEM = -4
    EIO = -5
    EFORMAT = -6
    ERANGE = -7
    ECANCELLED = -8
    EPLUGIN = -9
    EUNSUPPORTED = -10
    EINTERNAL = -11


class OccsegError(Exception):
    """A failure reported by liboccseg (or caught by the bindings before calling it).

    Attributes: `status` (Status, or the raw int for a code this version does not know), `code`
    (int), `name` ("OCCSEG_EVALUE", ...), `description` ("bad value", ...) and `message` (the
    occseg_last_error() text, which names the function, the argument and the offending value).
    """

    def __init__(self, code, message):
        code = int(code)
        try:
            self.status = Status(code)
        except ValueError:
            self.status = code
        self.code = code
        self.name = lib.occseg_status_name(code).decode()
        self.description = lib.occseg_status_string(code).decode()
        self.message = message
        super().__init__(f"{self.name} ({self.description}): {message}")

    def __reduce__(self):  # pickles (e.g. across multiprocessing) as (code, message)
        return (type(self), (self.code, self.message))


class OccsegTypeError(OccsegError, TypeError):
    """An argument of the wrong type (a float or bool segment id, a str thread count, ...), refused
    by the bindings before it reaches C: catch it as OccsegError or as TypeError."""


class OccsegValueError(OccsegError, ValueError):
    """An argument of the right type with a value the C ABI cannot take as it is (a NUL character
    inside a path or name, an integer beyond its C type, a change of a map a running call uses),
    refused by the bindings before it reaches C: catch it as OccsegError or as ValueError."""


def check(code):
    """Raises OccsegError with the calling thread's occseg_last_error() text if code != 0."""
    if code != 0:
        raise OccsegError(code, lib.occseg_last_error().decode(errors="replace"))
