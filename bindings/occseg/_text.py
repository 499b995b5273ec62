"""Helpers for the C ABI's text conventions: snprintf-like getters and "key=value" option lists."""
import ctypes
import numbers

from ._args import text_bytes
from ._errors import OccsegError, Status, check


def get_text(fn, *args):
    """Calls an snprintf-like getter fn(*args, buf, size, length) twice: length, then text."""
    n = ctypes.c_size_t()
    check(fn(*args, None, 0, ctypes.byref(n)))
    buf = ctypes.create_string_buffer(n.value + 1)
    check(fn(*args, buf, len(buf), None))
    return buf.value.decode()


def _number(who, key, value):
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise OccsegError(Status.EINVAL, f"{who}: option '{key}': {value!r} ({type(value).__name__}) "
                                         "is not a number, text or sequence of numbers")
    if isinstance(value, numbers.Integral):
        return str(int(value))
    return repr(float(value))  # shortest text that reads back as the same double


def option_array(who, options):
    """A NULL-terminated const char *[] of "key=value" texts (or None for no options). A value is
    text, a number (floats in their shortest exact form) or a sequence of numbers, joined by
    commas as the library's readers expect (bbox=(x0, y0, z0, x1, y1, z1)). A name or text
    holding a NUL character is refused (OccsegValueError): C would read only the text before it."""
    if not options:
        return None
    texts = []
    for key, value in options.items():
        k = text_bytes(who, "option name", key)
        if isinstance(value, str):
            text = text_bytes(who, f"option '{key}'", value)
        elif isinstance(value, (list, tuple)) or (hasattr(value, "ndim") and getattr(value, "ndim") == 1):
            text = ",".join(_number(who, key, v) for v in value).encode()
        else:
            text = _number(who, key, value).encode()
        texts.append(k + b"=" + text)
    return (ctypes.c_char_p * (len(texts) + 1))(*texts, None)
