"""FMUs through fmpy: each unpacked once per process, its model description read once, and a
co-simulation instance whose error messages are kept for the reports (the comb-drive actuator's
validation and the co-simulation masters use it)."""

from __future__ import annotations

import itertools
import weakref
from functools import cache
from typing import Any


@cache
def unzipped(path: str) -> str:
    """The FMU unpacked into a temporary directory (removed when the process exits)."""
    import atexit
    import shutil
    import tempfile

    from fmpy import extract

    directory = tempfile.mkdtemp(prefix="csfh-cosim-")
    atexit.register(shutil.rmtree, directory, True)
    return extract(path, unzipdir=directory)


@cache
def description(path: str) -> Any:
    """The FMU's model description (fmpy's ModelDescription)."""
    from fmpy import read_model_description

    return read_model_description(path)


class FmuLog:
    """FMI logger callbacks that keep an instance's error messages (for error reports).

    fmpy's native logger proxy (which formats the variadic message) holds one Python logger for
    the whole process, the last one registered; so every instance registers the same dispatcher,
    and the FMU's componentEnvironment (a number per log) says which log a message belongs to."""

    def __init__(self) -> None:
        from ctypes import byref

        from fmpy import calloc, free
        from fmpy.fmi2 import (
            fmi2CallbackAllocateMemoryTYPE,
            fmi2CallbackFreeMemoryTYPE,
            fmi2CallbackFunctions,
        )
        from fmpy.logging import addLoggerProxy

        self.errors: list[str] = []
        self.key = next(_LOG_KEYS)
        _LOGS[self.key] = weakref.ref(self)
        self.callbacks = fmi2CallbackFunctions()
        self.callbacks.logger = _dispatcher()
        self.callbacks.componentEnvironment = self.key
        self.callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
        self.callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
        addLoggerProxy(byref(self.callbacks))

    def add(self, status: int, msg: bytes) -> None:
        if status >= 3:  # fmi2Error, fmi2Fatal
            self.errors.append(" ".join(msg.decode(errors="replace").split()))

    def reason(self, fallback: str) -> str:
        """The FMU's error messages so far on one line (a failed step logs the integrator's
        reason first, then what the FMU did), else `fallback`."""
        return "; ".join(self.errors) if self.errors else fallback


_LOGS: dict[int, weakref.ref[FmuLog]] = {}
_LOG_KEYS = itertools.count(1)


def _dispatch(env: int | None, instance: bytes, status: int, category: bytes, msg: bytes) -> None:
    ref = _LOGS.get(env or 0)
    log = ref() if ref is not None else None
    if log is not None:
        log.add(status, msg)


@cache
def _dispatcher() -> Any:
    """The one logger callback of the process (kept alive here)."""
    from fmpy.fmi2 import fmi2CallbackLoggerTYPE

    return fmi2CallbackLoggerTYPE(_dispatch)


class Slave:
    """One co-simulation FMU instance through fmpy, with typed set by name and error messages."""

    def __init__(self, path: str, name: str) -> None:
        from fmpy.fmi2 import FMU2Slave

        md = description(path)
        self.name = name
        self.vars = {v.name: v for v in md.modelVariables}
        self.log = FmuLog()
        self.fmu = FMU2Slave(
            guid=md.guid,
            unzipDirectory=unzipped(path),
            modelIdentifier=md.coSimulation.modelIdentifier,
            instanceName=name,
        )
        self.fmu.instantiate(callbacks=self.log.callbacks)

    def vr(self, name: str) -> int:
        return self.vars[name].valueReference

    def set(self, values: dict[str, Any]) -> None:
        for name, value in values.items():
            kind = self.vars[name].type
            if kind == "Real":
                self.fmu.setReal([self.vr(name)], [float(value)])
            elif kind == "Boolean":
                self.fmu.setBoolean([self.vr(name)], [bool(value)])
            else:
                self.fmu.setInteger([self.vr(name)], [int(value)])

    def message(self, exc: Exception) -> str:
        """What went wrong in this instance: the FMU's error messages, else the exception."""
        return f"{self.name}: {self.log.reason(str(exc))}"

    def free(self) -> None:
        try:
            self.fmu.freeInstance()
        except Exception:
            pass
