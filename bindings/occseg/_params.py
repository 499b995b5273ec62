"""Parameter sets (occseg_params) built from Python keywords, and the parameter table."""
import ctypes
import dataclasses
import numbers

from ._args import real, text_bytes
from ._errors import OccsegTypeError, Status, check
from ._lib import has, lib
from ._text import get_text


@dataclasses.dataclass(frozen=True)
class ParamInfo:
    """One row of the library's parameter table."""

    name: str
    kind: str  # "int", "double" or "string"
    description: str
    min: float  # inclusive bounds (0, 0 for "string" parameters)
    max: float
    default: str = None  # as text; None with a library older than the plugin interface
    plugin: str = None  # "builtin" or the plugin that declared it; None likewise


def param_table():
    """Every parameter the loaded library (and its plugins) accepts, in table order."""
    rows = []
    for i in range(lib.occseg_param_count()):
        lo, hi = ctypes.c_double(), ctypes.c_double()
        check(lib.occseg_param_bounds(i, ctypes.byref(lo), ctypes.byref(hi)))
        extra = {}
        if has("occseg_param_default") and has("occseg_param_plugin"):
            extra = {"default": get_text(lib.occseg_param_default, i), "plugin": lib.occseg_param_plugin(i).decode()}
        rows.append(ParamInfo(lib.occseg_param_name(i).decode(), lib.occseg_param_kind(i).decode(),
                              lib.occseg_param_description(i).decode(), lo.value, hi.value, **extra))
    return rows


def set_param(handle, name, value):
    """Sets one parameter: ints and floats (Python or NumPy) through the typed setters, text as
    occseg_params_set parses it. Anything else (bool, bytes, None, ...) is refused, not guessed;
    so is a name or text holding a NUL character (OccsegValueError), which C would cut there."""
    key = text_bytes("occseg.segment", "parameter name", name)
    if isinstance(value, bool) or not isinstance(value, (numbers.Real, str)):
        raise OccsegTypeError(Status.EINVAL, f"occseg.segment: parameter '{name}': {value!r} "
                                             f"({type(value).__name__}) is not a number or text")
    if isinstance(value, str):
        check(lib.occseg_params_set(handle, key, text_bytes("occseg.segment", f"parameter '{name}'", value)))
    elif isinstance(value, numbers.Integral) and not -2**63 <= value < 2**63:
        check(lib.occseg_params_set(handle, key, str(value).encode()))  # the library names the bound
    elif isinstance(value, numbers.Integral):
        check(lib.occseg_params_set_int(handle, key, int(value)))
    else:
        check(lib.occseg_params_set_double(handle, key, real("occseg.segment", f"parameter '{name}'", value)))
