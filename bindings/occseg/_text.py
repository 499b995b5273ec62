"""Helpers for the C ABI's text conventions: snprintf-like getters and "key=value" option lists."""
import ctypes
import numbers

from ._errors import OccsegError, Status, check


def get_text(fn, *args):
    """Calls an snprintf-like getter fn(*args, buf, size, length) twice: length, then text."""
    n = ctypes.c_size_t()
    check(fn(*args, None, 0, ctypes.byref(n)))
    buf = ctypes.create_string_buffer(n.value + 1)
    check(fn(*args, buf, len(buf), None))
    return buf.value.decode()


def option_array(who, options):
    """A NULL-terminated const char *[] of "key=value" texts (or None for no options). Values may
    be text or numbers (floats in their shortest exact form); anything else is refused."""
    if not options:
        return None
    texts = []
    for key, value in options.items():
        if isinstance(value, bool) or not isinstance(value, (str, numbers.Real)):
            raise OccsegError(Status.EINVAL, f"{who}: option '{key}': {value!r} ({type(value).__name__}) "
                                             "is not a number or text")
        if isinstance(value, str):
            text = value
        elif isinstance(value, numbers.Integral):
            text = str(int(value))
        else:
            text = repr(float(value))  # shortest text that reads back as the same double
        texts.append(f"{key}={text}".encode())
    return (ctypes.c_char_p * (len(texts) + 1))(*texts, None)
