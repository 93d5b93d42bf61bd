"""Shared fixtures: the built FMU, its model description, and FMU instances whose log lines are
captured so that tests can check the messages."""

from __future__ import annotations

import os
import shutil
from collections.abc import Iterator
from ctypes import byref
from pathlib import Path

import pytest
from fmpy import extract, read_model_description
from fmpy.fmi2 import (
    FMU2Model,
    FMU2Slave,
    fmi2CallbackAllocateMemoryTYPE,
    fmi2CallbackFreeMemoryTYPE,
    fmi2CallbackFunctions,
    fmi2CallbackLoggerTYPE,
)
from fmpy.model_description import ModelDescription

ROOT = Path(__file__).resolve().parents[1]


def _find_fmu() -> Path:
    env = os.environ.get("CSFH_FMU")
    if env:
        return Path(env)
    try:
        import csfh  # the installed package ships the FMU

        return csfh.fmu_path()
    except (ImportError, AttributeError, FileNotFoundError):
        return ROOT / "build" / "csfh.fmu"


@pytest.fixture(scope="session")
def fmu_path() -> Path:
    path = _find_fmu()
    if not path.exists():
        pytest.fail(f"{path} not found: build it with `cmake -S . -B build && cmake --build build`")
    return path


@pytest.fixture(scope="session")
def model_description(fmu_path: Path) -> ModelDescription:
    return read_model_description(str(fmu_path))


@pytest.fixture(scope="session")
def unzipped(fmu_path: Path, tmp_path_factory: pytest.TempPathFactory) -> Iterator[str]:
    directory = extract(str(fmu_path), unzipdir=str(tmp_path_factory.mktemp("fmu")))
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


@pytest.fixture
def make_fmu(model_description: ModelDescription, unzipped: str):
    """Factory: make_fmu(kind='ME'|'CS', logging=False) -> (fmu, log). Instances are freed."""
    created: list[FMU2Model | FMU2Slave] = []

    def factory(kind: str = "ME", logging: bool = False):
        cls = FMU2Model if kind == "ME" else FMU2Slave
        interface = (
            model_description.modelExchange if kind == "ME" else model_description.coSimulation
        )
        fmu = cls(
            guid=model_description.guid,
            unzipDirectory=unzipped,
            modelIdentifier=interface.modelIdentifier,
            instanceName="test",
        )
        log = LogCapture()
        fmu.instantiate(callbacks=log.callbacks, loggingOn=logging)
        fmu._csfh_log = log  # keep the callbacks alive as long as the instance
        created.append(fmu)
        return fmu, log

    yield factory
    for fmu in created:
        try:
            fmu.freeInstance()
        except Exception:
            pass


@pytest.fixture(scope="session")
def vr(model_description: ModelDescription) -> dict[str, int]:
    return {v.name: v.valueReference for v in model_description.modelVariables}
