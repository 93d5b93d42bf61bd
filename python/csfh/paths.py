"""Where the built artefacts are: inside the installed package, or in a source build tree."""

from __future__ import annotations

import os
from pathlib import Path

_PACKAGE_DIR = Path(__file__).resolve().parent
_SOURCE_ROOT = _PACKAGE_DIR.parents[1]


def _first_existing(candidates: list[Path], what: str) -> Path:
    for path in candidates:
        if path.exists():
            return path
    raise FileNotFoundError(
        f"{what} not found: install the package (pip install .) or build it "
        "(cmake -S . -B build && cmake --build build)"
    )


def _check_fmi_version(fmi_version: int) -> None:
    if fmi_version not in (2, 3):
        raise ValueError(f"fmi_version = {fmi_version!r}: the FMUs are built for FMI 2 and 3")


def fmu_path(fmi_version: int = 2) -> Path:
    """Path of csfh.fmu: $CSFH_FMU, the copy inside the package, or build/csfh.fmu.

    fmi_version=3: the FMI 3.0 build of the same model, $CSFH_FMU3, the package's fmi3/csfh.fmu,
    or build/fmi3/csfh.fmu."""
    _check_fmi_version(fmi_version)
    candidates = []
    if fmi_version == 3:
        if os.environ.get("CSFH_FMU3"):
            candidates.append(Path(os.environ["CSFH_FMU3"]))
        candidates += [
            _PACKAGE_DIR / "fmi3" / "csfh.fmu",
            _SOURCE_ROOT / "build" / "fmi3" / "csfh.fmu",
        ]
        return _first_existing(candidates, "fmi3/csfh.fmu")
    if os.environ.get("CSFH_FMU"):
        candidates.append(Path(os.environ["CSFH_FMU"]))
    candidates += [_PACKAGE_DIR / "csfh.fmu", _SOURCE_ROOT / "build" / "csfh.fmu"]
    return _first_existing(candidates, "csfh.fmu")


def core_library_path() -> Path:
    """Path of libcsfh_core.so (the physics core for the harness): $CSFH_CORE, the package copy,
    or build/libcsfh_core.so."""
    candidates = []
    if os.environ.get("CSFH_CORE"):
        candidates.append(Path(os.environ["CSFH_CORE"]))
    candidates += [_PACKAGE_DIR / "libcsfh_core.so", _SOURCE_ROOT / "build" / "libcsfh_core.so"]
    return _first_existing(candidates, "libcsfh_core.so")


def combdrive_fmu_path(fmi_version: int = 2) -> Path:
    """Path of combdrive.fmu (the comb-drive actuator for co-simulation): $CSFH_COMBDRIVE_FMU,
    next to $CSFH_FMU (the same build), the copy inside the package, or build/combdrive.fmu.

    fmi_version=3: the FMI 3.0 build, next to $CSFH_FMU3, the package's fmi3/combdrive.fmu, or
    build/fmi3/combdrive.fmu."""
    _check_fmi_version(fmi_version)
    candidates = []
    if fmi_version == 3:
        if os.environ.get("CSFH_FMU3"):
            candidates.append(Path(os.environ["CSFH_FMU3"]).parent / "combdrive.fmu")
        candidates += [
            _PACKAGE_DIR / "fmi3" / "combdrive.fmu",
            _SOURCE_ROOT / "build" / "fmi3" / "combdrive.fmu",
        ]
        return _first_existing(candidates, "fmi3/combdrive.fmu")
    if os.environ.get("CSFH_COMBDRIVE_FMU"):
        candidates.append(Path(os.environ["CSFH_COMBDRIVE_FMU"]))
    if os.environ.get("CSFH_FMU"):
        candidates.append(Path(os.environ["CSFH_FMU"]).parent / "combdrive.fmu")
    candidates += [_PACKAGE_DIR / "combdrive.fmu", _SOURCE_ROOT / "build" / "combdrive.fmu"]
    return _first_existing(candidates, "combdrive.fmu")


def batch_library_path() -> Path:
    """Path of libcsfh_batch.so (the batch co-simulation master, csfh.runners.cs_batch):
    $CSFH_BATCH, the package copy, or build/libcsfh_batch.so."""
    candidates = []
    if os.environ.get("CSFH_BATCH"):
        candidates.append(Path(os.environ["CSFH_BATCH"]))
    candidates += [_PACKAGE_DIR / "libcsfh_batch.so", _SOURCE_ROOT / "build" / "libcsfh_batch.so"]
    return _first_existing(candidates, "libcsfh_batch.so")
