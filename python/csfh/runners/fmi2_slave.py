"""An FMI 2.0 co-simulation instance of the csfh FMU through our own ctypes loading of its binary
(`fmu.resident_binary`): the calls a co-simulation run makes before and after its communication
loop, and the addresses of the functions and the instance that the loop in C
(`cs_steps.CSteps`) calls directly. The FMU's log goes to an `FmuLog`, whose messages make the
errors' reasons."""

from __future__ import annotations

import ctypes
import pathlib
from collections.abc import Sequence
from ctypes import POINTER, c_char_p, c_double, c_int, c_size_t, c_uint, c_void_p
from typing import Any

from ..model.fmus import FmuLog
from .fmu import binary_path, resident_binary

FMI2_WARNING = 1
FMI2_CO_SIMULATION = 1
_C_TYPES: dict[str, Any] = {"Real": c_double, "Integer": c_int, "Boolean": c_int}  # Boolean: int


class FmiCallError(Exception):
    """An FMI call that returned fmi2Error or worse: the function and its status (the FMU's log
    says why); `t`, where a caller knows it, the time of the failure."""

    def __init__(self, function: str, status: int, t: float | None = None) -> None:
        super().__init__(f"{function} returned status {status}")
        self.function = function
        self.status = status
        self.t = t
        self.chunk: Any = None  # a loop's points before the failed call, where it keeps them


def _declare(lib: ctypes.CDLL) -> None:
    """The signatures of the fmi2 functions used here (FMI 2.0, fmi2FunctionTypes.h)."""
    comp = [c_void_p]
    for name in ("fmi2EnterInitializationMode", "fmi2ExitInitializationMode", "fmi2Terminate"):
        getattr(lib, name).argtypes, getattr(lib, name).restype = comp, c_int
    lib.fmi2Instantiate.argtypes = [c_char_p, c_int, c_char_p, c_char_p, c_void_p, c_int, c_int]
    lib.fmi2Instantiate.restype = c_void_p
    lib.fmi2FreeInstance.argtypes, lib.fmi2FreeInstance.restype = comp, None
    lib.fmi2SetupExperiment.argtypes = [c_void_p, c_int, c_double, c_double, c_int, c_double]
    lib.fmi2SetupExperiment.restype = c_int
    lib.fmi2DoStep.argtypes, lib.fmi2DoStep.restype = [c_void_p, c_double, c_double, c_int], c_int
    for kind, ctype in _C_TYPES.items():
        for verb in ("Get", "Set"):
            fn = getattr(lib, f"fmi2{verb}{kind}")
            fn.argtypes = [c_void_p, POINTER(c_uint), c_size_t, POINTER(ctype)]
            fn.restype = c_int


class Fmi2Slave:
    """One co-simulation instance of the FMU unzipped in `unzip_dir` (model description `md`,
    fmpy's), instantiated with a log that keeps the FMU's error messages."""

    def __init__(self, unzip_dir: str, md: Any, instance_name: str = "csfh") -> None:
        identifier = md.coSimulation.modelIdentifier
        self.lib = resident_binary(unzip_dir, identifier)
        self.binary = binary_path(unzip_dir, identifier)
        _declare(self.lib)
        self.log = FmuLog()
        resources = pathlib.Path(unzip_dir, "resources").as_uri()
        self.component = self.lib.fmi2Instantiate(
            instance_name.encode(),
            FMI2_CO_SIMULATION,
            md.guid.encode(),
            resources.encode(),
            ctypes.addressof(self.log.callbacks),
            0,
            0,
        )
        if not self.component:
            raise FmiCallError("fmi2Instantiate", 3)

    def _call(self, name: str, *args: Any) -> None:
        status = getattr(self.lib, name)(self.component, *args)
        if status > FMI2_WARNING:
            raise FmiCallError(name, status)

    def setup_experiment(self, tolerance: float, stop_time: float) -> None:
        """fmi2SetupExperiment from t = 0 with a tolerance and a stop time."""
        self._call("fmi2SetupExperiment", 1, tolerance, 0.0, 1, stop_time)

    def enter_initialization_mode(self) -> None:
        self._call("fmi2EnterInitializationMode")

    def exit_initialization_mode(self) -> None:
        self._call("fmi2ExitInitializationMode")

    def terminate(self) -> None:
        self._call("fmi2Terminate")

    def do_step(self, t: float, h: float) -> None:
        """fmi2DoStep from t over h (no FMU state will be set before t)."""
        self._call("fmi2DoStep", t, h, 1)

    def set(self, kind: str, refs: Sequence[int], values: Sequence[Any]) -> None:
        """fmi2SetReal / Integer / Boolean (kind: the FMI type)."""
        ctype = _C_TYPES[kind]
        n = len(refs)
        self._call(f"fmi2Set{kind}", (c_uint * n)(*refs), n, (ctype * n)(*values))

    def get(self, kind: str, refs: Sequence[int]) -> list[Any]:
        """fmi2GetReal / Integer / Boolean (kind: the FMI type); Booleans as ints."""
        n = len(refs)
        values = (_C_TYPES[kind] * n)()
        self._call(f"fmi2Get{kind}", (c_uint * n)(*refs), n, values)
        return values[:]

    def address(self, name: str) -> int:
        """The address of an fmi2 function of the binary (for a loop in C)."""
        return ctypes.cast(getattr(self.lib, name), c_void_p).value or 0

    def reason(self, fallback: str) -> str:
        """The FMU's error messages so far, else `fallback`."""
        return self.log.reason(fallback)

    def free(self) -> None:
        """fmi2FreeInstance (the binary stays loaded: `fmu.resident_binary`)."""
        if self.component:
            self.lib.fmi2FreeInstance(self.component)
            self.component = None
