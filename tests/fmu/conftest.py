"""Fixtures of the FMU conformance tests: the FMI 3.0 build of the FMU, unzipped."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest
from fmpy import read_model_description
from fmpy.model_description import ModelDescription
from fmu_instances import built, unzip

import csfh


@pytest.fixture(scope="session")
def fmu3() -> Path:
    return built(csfh.fmu_path(fmi_version=3))


@pytest.fixture(scope="session")
def md3(fmu3: Path) -> ModelDescription:
    return read_model_description(str(fmu3))


@pytest.fixture(scope="session")
def unzipped3(fmu3: Path, tmp_path_factory: pytest.TempPathFactory) -> Iterator[str]:
    yield from unzip(fmu3, tmp_path_factory, "fmu3")
