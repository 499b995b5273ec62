"""Checks of the arguments that cross into C, made before any C call.

ctypes converts silently where C would not see the problem: a str or bytes is handed over as a
char * that ends at its first NUL (so "a.npy\\0.nrrd" would write a.npy), and an int is cut to the
width of its C type (2**32 + 3 reaching an int parameter as 3). Every text, path and integer the
package passes to liboccseg goes through one of these helpers instead. They raise OccsegTypeError
(also a TypeError) for the wrong type and OccsegValueError (also a ValueError) for a value that
cannot cross unchanged, naming the function, the argument and the value.
"""
import ctypes
import numbers
import operator
import os

import numpy as np

from ._errors import OccsegTypeError, OccsegValueError, Status


def _no_nul(who, name, data, shown):
    at = data.find(b"\0")
    if at >= 0:
        raise OccsegValueError(Status.EINVAL, f"{who}: {name} {shown!r} contains a NUL character (at byte {at}); "
                                              "C would see only the text before it")
    return data


def path_bytes(who, name, value):
    """A path (str, bytes or os.PathLike) as the bytes C opens, as os.fsencode gives them; refused
    when it holds a NUL (Python's own open() refuses it too)."""
    try:
        data = os.fsencode(value)
    except TypeError:
        raise OccsegTypeError(Status.EINVAL, f"{who}: {name} must be a str, bytes or os.PathLike path, "
                                             f"not {type(value).__name__}") from None
    return _no_nul(who, name, data, value)


def text_bytes(who, name, value):
    """A name or value given as str, as the UTF-8 bytes C reads; refused when it holds a NUL or a
    character UTF-8 cannot encode (a lone surrogate)."""
    if not isinstance(value, str):
        raise OccsegTypeError(Status.EINVAL, f"{who}: {name} must be a str, not {type(value).__name__}")
    try:
        data = value.encode()
    except UnicodeEncodeError as e:
        raise OccsegValueError(Status.EINVAL, f"{who}: {name} {value!r} cannot be encoded as UTF-8 "
                               f"({e.reason})") from None
    return _no_nul(who, name, data, value)


def integer(who, name, value):
    """`value` as a Python int: int, NumPy integers and anything with __index__, but never bool
    (True is not a thread count or a segment id) nor float (1.5 is not truncated to 1)."""
    if not isinstance(value, (bool, np.bool_)):
        try:
            return operator.index(value)
        except TypeError:
            pass
    raise OccsegTypeError(Status.EINVAL, f"{who}: {name} must be an int, not {type(value).__name__}")


def _c_range(ctype):
    bits = 8 * ctypes.sizeof(ctype)
    signed = ctype(-1).value == -1
    return (-(1 << (bits - 1)), (1 << (bits - 1)) - 1) if signed else (0, (1 << bits) - 1)


def c_integer(who, name, value, ctype):
    """integer(), also refused when it does not fit C type `ctype` (which ctypes would cut)."""
    v = integer(who, name, value)
    lo, hi = _c_range(ctype)
    if not lo <= v <= hi:
        raise OccsegValueError(Status.EINVAL, f"{who}: {name} = {v} does not fit the C {ctype.__name__[2:]} "
                                              f"it is passed as ([{lo}, {hi}])")
    return v


def real(who, name, value):
    """A Python or NumPy real number as a float; bool and text are refused (float("0.5") and
    float(True) would pass them), as are ints too large for a double."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Real):
        raise OccsegTypeError(Status.EINVAL, f"{who}: {name} must be a number, not {type(value).__name__}")
    try:
        return float(value)
    except OverflowError:
        raise OccsegValueError(Status.EVALUE, f"{who}: {name} = {value} is too large for a double") from None


def flag(who, name, value):
    """A switch: True or False (Python or NumPy bool); anything else, which would be taken for its
    truth value (the text "no" as true), is refused."""
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    raise OccsegTypeError(Status.EINVAL, f"{who}: {name} must be True or False, not {type(value).__name__}")
