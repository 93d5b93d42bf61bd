"""The FMI calls of a loop straight through ctypes, with preallocated buffers, on an fmpy
instance: what the benchmarks time as "a direct ctypes call" (bench_cosim.py), apart from the
package, which runs its loops in C (csfh.runners.cs_steps).

fmpy's wrappers (FMU2Slave.doStep, getReal, ...) build new ctypes arrays and check and log on
every call: about 6-9 us each from Python, more than the FMU needs for a communication step of a
millisecond (CVODE takes about 4 us per internal step). A loop over a fine communication grid is
then mostly wrapper cost. `DirectCalls` keeps fmpy for everything else (loading, instantiation,
parameters) and calls fmi2DoStep / fmi2GetReal / fmi2GetInteger / fmi2GetBoolean on the same
instance directly, reading fixed sets of value references into reused buffers (about 1 us each).
"""

from __future__ import annotations

from collections.abc import Sequence
from ctypes import c_double, c_int, c_size_t, c_uint, c_void_p, cast
from typing import Any

from fmpy.fmi1 import FMICallException

_FMI2_WARNING = 1


def _function(dll: Any, name: str) -> Any:
    """A fresh function pointer to `name`, without argtypes: fmpy's copies convert every
    argument through its declared pointer types (about 2 us per call); this one passes the
    prepared ctypes objects as they are."""
    fn = dll._FuncPtr((name, dll))
    fn.restype = c_int
    return fn


class _Reader:
    """fmi2GetReal/Integer/Boolean of one fixed set of value references into one buffer."""

    def __init__(self, fn: Any, name: str, refs: Sequence[int], ctype: Any, component: Any) -> None:
        self._fn = fn
        self._name = name
        self._refs = (c_uint * len(refs))(*refs)
        self._n = c_size_t(len(refs))
        self._values = (ctype * len(refs))()
        self._component = component

    def __call__(self) -> list[Any]:
        status = self._fn(self._component, self._refs, self._n, self._values)
        if status > _FMI2_WARNING:
            raise FMICallException(function=self._name, status=status)
        return self._values[:]


class DirectCalls:
    """Direct calls on an instantiated fmpy FMU2Slave or FMU2Model (which stays the owner of the
    instance). `address` and `component` are what csfh.runners.cs_steps.CSteps takes."""

    def __init__(self, slave: Any) -> None:
        self._dll = slave.dll
        self._component = c_void_p(slave.component)
        self._do_step = _function(self._dll, "fmi2DoStep")
        self._true = c_int(1)
        self._t, self._h = c_double(), c_double()  # reused: cheaper than new ones per call

    @property
    def component(self) -> int:
        return self._component.value or 0

    def address(self, name: str) -> int:
        """The address of an fmi2 function of the instance's binary."""
        return cast(getattr(self._dll, name), c_void_p).value or 0

    def do_step(self, t: float, h: float) -> None:
        """fmi2DoStep(t, h); raises fmpy's FMICallException on fmi2Error or worse (the FMU's
        log says why)."""
        self._t.value = t
        self._h.value = h
        status = self._do_step(self._component, self._t, self._h, self._true)
        if status > _FMI2_WARNING:
            raise FMICallException(function="fmi2DoStep", status=status)

    def real_reader(self, refs: Sequence[int]) -> _Reader:
        """A callable returning the current values of these Real variables as a list."""
        fn = _function(self._dll, "fmi2GetReal")
        return _Reader(fn, "fmi2GetReal", refs, c_double, self._component)

    def integer_reader(self, refs: Sequence[int]) -> _Reader:
        """A callable returning the current values of these Integer variables as a list."""
        fn = _function(self._dll, "fmi2GetInteger")
        return _Reader(fn, "fmi2GetInteger", refs, c_int, self._component)

    def boolean_reader(self, refs: Sequence[int]) -> _Reader:
        """A callable returning these Boolean variables (fmi2Boolean is an int) as a list of
        ints."""
        fn = _function(self._dll, "fmi2GetBoolean")
        return _Reader(fn, "fmi2GetBoolean", refs, c_int, self._component)
