"""Every bad argument of the Python API raises an occseg exception naming the argument, in the
Python spelling (issue 26): a NaN's error names nan_unknown=True (not the C flag
OCCSEG_IMPORT_NAN_UNKNOWN), a value outside [0, 1] clamp=True; an origin of two values, a
progress that cannot be called, a switch that is no bool, a ragged list and a closed handle are
OccsegError subclasses that are also the ValueError or TypeError Python code expects."""
import numpy as np
import pytest

import occseg
from occseg import OccsegError, OccsegTypeError, OccsegValueError, Status


def small():
    return np.full((4, 4, 4), 0.2, np.float32)


@pytest.mark.parametrize("call", [lambda a: occseg.segment(a), lambda a: occseg.Map.from_array(a)])
def test_nan_error_names_the_python_keyword(call):
    a = small()
    a[1, 2, 3] = np.nan
    with pytest.raises(OccsegError) as e:
        call(a)
    assert e.value.status == Status.EVALUE
    assert "voxel (3, 2, 1)" in e.value.message and "nan_unknown=True" in e.value.message
    assert "OCCSEG_IMPORT" not in e.value.message and "clamp" not in e.value.message
    with occseg.segment(a, nan_unknown=True) as r:  # and that keyword does accept it
        assert r.labels.shape == a.shape


def test_out_of_range_error_names_clamp():
    a = small()
    a[0, 0, 1] = 1.5
    with pytest.raises(OccsegError) as e:
        occseg.segment(a)
    assert "is outside [0, 1]" in e.value.message and "clamp=True" in e.value.message
    assert "OCCSEG_IMPORT" not in e.value.message and "nan_unknown" not in e.value.message
    a[0, 0, 1] = np.inf
    with pytest.raises(OccsegError) as e:
        occseg.segment(a)
    assert "is infinite" in e.value.message and "clamp=True" in e.value.message
    occseg.segment(a, clamp=True).close()


@pytest.mark.parametrize("origin", [(0, 0), (0, 0, 0, 0), ()])
def test_origin_of_the_wrong_length(origin):
    for call in (lambda: occseg.segment(small(), origin=origin), lambda: occseg.Map.from_array(small(), origin=origin)):
        with pytest.raises(OccsegValueError) as e:
            call()
        assert isinstance(e.value, ValueError) and e.value.status == Status.EINVAL
        assert "origin" in e.value.message and f"{len(origin)} values" in e.value.message


def test_progress_must_be_callable():
    with pytest.raises(OccsegTypeError) as e:
        occseg.segment(small(), progress=3)
    assert isinstance(e.value, TypeError) and "progress" in e.value.message and "int" in e.value.message


@pytest.mark.parametrize("name", ["clamp", "nan_unknown"])
@pytest.mark.parametrize("value", ["no", 1, None, object()])
def test_switches_are_bools(name, value):
    for call in (lambda: occseg.segment(small(), **{name: value}),
                 lambda: occseg.Map.from_array(small(), **{name: value})):
        with pytest.raises(OccsegTypeError) as e:
            call()
        assert name in e.value.message and type(value).__name__ in e.value.message
    occseg.segment(small(), **{name: np.bool_(True)}).close()


def test_context_of_the_wrong_type():
    with pytest.raises(OccsegTypeError) as e:
        occseg.segment(small(), context=3)
    assert "context" in e.value.message


def test_ragged_list():
    with pytest.raises(OccsegValueError) as e:
        occseg.segment([[0.1, 0.2], [0.3]])
    assert "probabilities" in e.value.message


def test_closed_handles():
    m = occseg.Map.from_array(small())
    m.close()
    for call in (lambda: m.dims, lambda: occseg.segment(m), lambda: m.write("x.npy")):
        with pytest.raises(OccsegValueError) as e:
            call()
        assert isinstance(e.value, ValueError) and "closed" in e.value.message
    c = occseg.Context(1)
    c.close()
    with pytest.raises(OccsegValueError, match="closed"):
        occseg.segment(small(), context=c)
