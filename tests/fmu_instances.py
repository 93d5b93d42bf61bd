"""FMI 2.0 instances of the built FMUs for the tests: an FMU unzipped for the session, instances
whose log lines are captured so that tests can check the messages, freed at the end."""

from __future__ import annotations

import shutil
from collections.abc import Iterator
from ctypes import byref
from pathlib import Path

import pytest
from fmpy import extract
from fmpy.fmi2 import (
    FMU2Model,
    FMU2Slave,
    fmi2CallbackAllocateMemoryTYPE,
    fmi2CallbackFreeMemoryTYPE,
    fmi2CallbackFunctions,
    fmi2CallbackLoggerTYPE,
)
from fmpy.model_description import ModelDescription


def built(path: Path) -> Path:
    """A file the build makes; the test fails where it is missing."""
    if not path.exists():
        pytest.fail(f"{path} not found: build it with `cmake -S . -B build && cmake --build build`")
    return path


def fmu_file(fmu_path: Path, name: str) -> Path:
    """The csfh FMU or the comb-drive FMU built beside it."""
    return fmu_path if name == "csfh" else fmu_path.parent / f"{name}.fmu"


def unzip(path: Path, tmp_path_factory: pytest.TempPathFactory, name: str) -> Iterator[str]:
    """For a fixture to `yield from`: the FMU unzipped into a temporary directory, removed after."""
    directory = extract(str(path), unzipdir=str(tmp_path_factory.mktemp(name)))
    yield directory
    shutil.rmtree(directory, ignore_errors=True)


class LogCapture:
    """FMI callbacks that store every log line (status, category, message)."""

    def __init__(self) -> None:
        from fmpy import calloc, free
        from fmpy.logging import addLoggerProxy

        self.lines: list[tuple[int, str, str]] = []
        self.callbacks = fmi2CallbackFunctions()
        self._logger = fmi2CallbackLoggerTYPE(self._log)
        self.callbacks.logger = self._logger
        self.callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
        self.callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
        addLoggerProxy(byref(self.callbacks))

    def _log(
        self, component: object, instance: bytes, status: int, category: bytes, message: bytes
    ) -> None:
        self.lines.append((status, category.decode(), message.decode()))

    def errors(self) -> list[str]:
        return [m for s, _, m in self.lines if s >= 3]

    def text(self) -> str:
        return "\n".join(m for _, _, m in self.lines)


class Instances:
    """Instances of one unzipped FMU, each with its LogCapture; `free` frees them all."""

    def __init__(self, md: ModelDescription, directory: str, instance_name: str) -> None:
        self.md, self.directory, self.instance_name = md, directory, instance_name
        self.created: list[FMU2Model | FMU2Slave] = []

    def make(self, kind: str, logging: bool = False) -> tuple[FMU2Model | FMU2Slave, LogCapture]:
        """An instantiated 'ME' or 'CS' instance and its log."""
        cls = FMU2Model if kind == "ME" else FMU2Slave
        interface = self.md.modelExchange if kind == "ME" else self.md.coSimulation
        fmu = cls(
            guid=self.md.guid,
            unzipDirectory=self.directory,
            modelIdentifier=interface.modelIdentifier,
            instanceName=self.instance_name,
        )
        log = LogCapture()
        fmu.instantiate(callbacks=log.callbacks, loggingOn=logging)
        fmu._csfh_log = log  # keep the callbacks alive as long as the instance
        self.created.append(fmu)
        return fmu, log

    def free(self) -> None:
        for fmu in self.created:
            try:
                fmu.freeInstance()
            except Exception:
                pass
