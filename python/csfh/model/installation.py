"""What this installation of csfh uses (`csfh info`): the version, every built artefact where
csfh.paths finds it (and from where: an environment variable, the package, a source build), for
an FMU its FMI version, interfaces and the platforms it holds binaries for, for a ctypes library
its ABI version against the one this package needs, and the built-in scenes."""

from __future__ import annotations

import ctypes
import zipfile
from dataclasses import dataclass
from pathlib import Path
from xml.etree import ElementTree

from .. import paths
from .._version import __version__
from ..errors import InstallError
from ..scenes import BUILTIN_SCENES
from . import model_info
from ._csfh_variables import BATCH_ABI_VERSION, CORE_ABI_VERSION

LABELS = {
    "fmu": "FMU, FMI 2.0",
    "fmu3": "FMU, FMI 3.0",
    "combdrive": "comb-drive FMU, FMI 2.0",
    "combdrive3": "comb-drive FMU, FMI 3.0",
    "core": "core library",
    "batch": "batch library",
}
"""Each artefact of csfh.paths.ARTEFACTS, as `csfh info` names it."""
ABI = {
    "core": ("csfh_api_abi_version", CORE_ABI_VERSION),
    "batch": ("csfh_cs_batch_abi_version", BATCH_ABI_VERSION),
}
"""The ABI function of each ctypes library and the version this package needs."""


@dataclass(frozen=True)
class Found:
    """One artefact: its label, path (None: not found), where it comes from (or why it is
    missing) and what it holds."""

    label: str
    path: Path | None
    origin: str
    details: str = ""


def fmu_details(path: Path) -> str:
    """An FMU's FMI version, model, interfaces, the platforms of its binaries, and whether it
    carries its sources."""
    try:
        with zipfile.ZipFile(path) as archive:
            names = archive.namelist()
            root = ElementTree.fromstring(archive.read("modelDescription.xml"))
    except (OSError, KeyError, zipfile.BadZipFile, ElementTree.ParseError) as exc:
        return f"not a readable FMU ({exc})"
    platforms = sorted(
        {n.split("/")[1] for n in names if n.startswith("binaries/") and n.count("/") >= 2} - {""}
    )
    interfaces = [i for i in ("ModelExchange", "CoSimulation") if root.find(i) is not None]
    sources = ", sources" if any(n.startswith("sources/") for n in names) else ""
    model = " ".join(filter(None, (root.get("modelName"), root.get("version"))))
    return (
        f"FMI {root.get('fmiVersion')}, {model}, {' + '.join(interfaces)}; binaries: "
        f"{', '.join(platforms) or 'none'}{sources}"
    )


def library_details(key: str, path: Path) -> str:
    """A ctypes library's ABI version against the one this package needs."""
    function, needed = ABI[key]
    try:
        version = int(getattr(ctypes.CDLL(str(path)), function)())
    except (OSError, AttributeError) as exc:
        return f"cannot be loaded ({exc})"
    verdict = "" if version == needed else f": this package needs {needed}, rebuild or reinstall"
    return f"ABI {version}{verdict}"


def artefacts() -> list[Found]:
    """Every artefact of csfh.paths.ARTEFACTS, found or not."""
    out = []
    for key, artefact in paths.ARTEFACTS.items():
        try:
            path, origin = artefact.locate()
        except InstallError as exc:
            out.append(Found(LABELS[key], None, str(exc)))
            continue
        details = library_details(key, path) if key in ABI else fmu_details(path)
        out.append(Found(LABELS[key], path, origin, details))
    return out


@dataclass(frozen=True)
class Installation:
    """What `csfh info` prints: the version, the artefacts, the source build looked at (None
    for an installed package), the models and the built-in scenes."""

    version: str
    artefacts: list[Found]
    source_build: Path | None
    models: tuple[str, ...]
    scenes: tuple[str, ...]


def summary() -> Installation:
    return Installation(
        __version__, artefacts(), paths.source_build(), model_info.MODELS, BUILTIN_SCENES
    )
