"""FMUs through fmpy: each unpacked once per process, its model description read once, and a
co-simulation instance whose error messages are kept for the reports (the comb-drive actuator's
validation and the co-simulation masters use it)."""

from __future__ import annotations

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


class _Log:
    """FMI logger callbacks that keep the messages (for error reports)."""

    def __init__(self) -> None:
        from ctypes import byref

        from fmpy import calloc, free
        from fmpy.fmi2 import (
            fmi2CallbackAllocateMemoryTYPE,
            fmi2CallbackFreeMemoryTYPE,
            fmi2CallbackFunctions,
            fmi2CallbackLoggerTYPE,
        )
        from fmpy.logging import addLoggerProxy

        self.errors: list[str] = []
        self.callbacks = fmi2CallbackFunctions()
        self._logger = fmi2CallbackLoggerTYPE(self._log)
        self.callbacks.logger = self._logger
        self.callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
        self.callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
        addLoggerProxy(byref(self.callbacks))

    def _log(self, env: object, instance: bytes, status: int, category: bytes, msg: bytes) -> None:
        if status >= 3:  # fmi2Error, fmi2Fatal
            self.errors.append(msg.decode(errors="replace"))


class Slave:
    """One co-simulation FMU instance through fmpy, with typed set by name and error messages."""

    def __init__(self, path: str, name: str) -> None:
        from fmpy.fmi2 import FMU2Slave

        md = description(path)
        self.name = name
        self.vars = {v.name: v for v in md.modelVariables}
        self.log = _Log()
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
        """What went wrong in this instance: the FMU's last error message, else the exception."""
        detail = self.log.errors[-1] if self.log.errors else str(exc)
        return f"{self.name}: {detail}"

    def free(self) -> None:
        try:
            self.fmu.freeInstance()
        except Exception:
            pass
