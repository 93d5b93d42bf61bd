"""Fixtures all the tests share: the built FMU, its model description, and FMU instances whose log
lines are captured so that tests can check the messages (fmu_instances.py)."""

from __future__ import annotations

import os
from collections.abc import Iterator
from pathlib import Path

import pytest
from fmpy import read_model_description
from fmpy.model_description import ModelDescription
from fmu_instances import Instances, built, unzip

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
    return built(_find_fmu())


@pytest.fixture(scope="session")
def model_description(fmu_path: Path) -> ModelDescription:
    return read_model_description(str(fmu_path))


@pytest.fixture(scope="session")
def unzipped(fmu_path: Path, tmp_path_factory: pytest.TempPathFactory) -> Iterator[str]:
    yield from unzip(fmu_path, tmp_path_factory, "fmu")


@pytest.fixture
def make_fmu(model_description: ModelDescription, unzipped: str):
    """Factory: make_fmu(kind='ME'|'CS', logging=False) -> (fmu, log). Instances are freed."""
    instances = Instances(model_description, unzipped, "test")

    def factory(kind: str = "ME", logging: bool = False):
        return instances.make(kind, logging)

    yield factory
    instances.free()


@pytest.fixture(scope="session")
def vr(model_description: ModelDescription) -> dict[str, int]:
    return {v.name: v.valueReference for v in model_description.modelVariables}
