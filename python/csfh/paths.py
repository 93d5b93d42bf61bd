"""Where the built artefacts are: the FMUs (FMI 2.0 and 3.0, the hinge and the comb-drive
actuator) and the ctypes libraries (the core, the batch master).

Each is looked for, in this order:

1. the environment variable that names it (``CSFH_FMU``, ``CSFH_FMU3``, ``CSFH_COMBDRIVE_FMU``,
   ``CSFH_CORE``, ``CSFH_BATCH``): a variable that is set must name an existing file, else
   InstallError names the variable (never a silent fall-back to another build); the comb-drive
   FMUs are also looked for beside ``CSFH_FMU`` / ``CSFH_FMU3`` (the same build);
2. the installed package's own copy (inside ``csfh/``, where ``pip install .`` puts it);
3. only for a package that is not installed, a source checkout used with
   ``PYTHONPATH=python`` (the tests, the docs build): the checkout's ``build/`` directory. The
   package counts as a checkout's when it is ``python/csfh`` beside the checkout's
   ``CMakeLists.txt``; an installed package never looks outside its own files.

An FMU found so must be the FMU of its model (a zip archive whose modelDescription.xml names
the model, csfh or combdrive), else InstallError says what the file is instead."""

from __future__ import annotations

import os
import sys
import zipfile
from dataclasses import dataclass
from functools import cache
from pathlib import Path
from xml.etree import ElementTree

from .errors import InstallError, ParameterError

_PACKAGE_DIR = Path(__file__).resolve().parent


def source_build() -> Path | None:
    """The build directory of the source checkout this package is part of, or None for an
    installed package (module docstring, rule 3)."""
    root = _PACKAGE_DIR.parents[1]
    if _PACKAGE_DIR.parent.name != "python" or not (root / "CMakeLists.txt").is_file():
        return None
    return root / "build"


@dataclass(frozen=True)
class Artefact:
    """A built file: its path inside the package and the build tree, the environment variable
    that names it, and the variable of a file it is built beside (the same build)."""

    relative: str
    variable: str | None = None
    beside: str | None = None
    model: str | None = None  # an FMU: its modelName

    def candidates(self) -> list[tuple[Path, str]]:
        """(path, where it comes from) in the order they are tried."""
        found: list[tuple[Path, str]] = []
        if self.variable and os.environ.get(self.variable):
            path = Path(os.environ[self.variable])
            if not path.is_file():
                raise InstallError(
                    f"${self.variable} = {str(path)!r}: no such file (unset it to use the "
                    "package's own copy)"
                )
            found.append((path, f"${self.variable}"))
        if self.beside and os.environ.get(self.beside):
            sibling = Path(os.environ[self.beside]).parent / Path(self.relative).name
            if sibling.is_file():
                found.append((sibling, f"beside ${self.beside}"))
        found.append((_PACKAGE_DIR / self.relative, "package"))
        build = source_build()
        if build is not None:
            found.append((build / self.relative, "source build"))
        return found

    def locate(self) -> tuple[Path, str]:
        """The first existing candidate and where it comes from; InstallError naming every
        place looked at otherwise."""
        candidates = self.candidates()
        for path, origin in candidates:
            if path.is_file():
                if self.model is not None:
                    st = path.stat()
                    _check_fmu(path, origin, self.model, (st.st_size, st.st_mtime_ns))
                return path, origin
        looked = ", ".join(str(p) for p, _ in candidates)
        raise InstallError(
            f"{self.relative} not found (looked at {looked}): install the package (pip install .) "
            "or build it (cmake -S . -B build && cmake --build build)"
        )


@cache
def _check_fmu(path: Path, origin: str, model: str, version: tuple[int, int]) -> None:
    """InstallError naming where the file comes from unless it is an FMU of `model` (cached per
    file version: size and modification time)."""
    where = f"{origin} = {str(path)!r}" if origin.startswith("$") else f"{path} ({origin})"
    try:
        with zipfile.ZipFile(path) as archive:
            root = ElementTree.fromstring(archive.read("modelDescription.xml"))
    except zipfile.BadZipFile:
        raise InstallError(f"{where}: not an FMU (not a zip archive)") from None
    except KeyError:
        raise InstallError(f"{where}: not an FMU (no modelDescription.xml)") from None
    except ElementTree.ParseError as exc:
        raise InstallError(f"{where}: not an FMU (modelDescription.xml: {exc})") from None
    except OSError as exc:
        raise InstallError(f"{where}: cannot be read ({exc.strerror or exc})") from None
    found = root.get("modelName")
    if found != model:
        raise InstallError(
            f"{where}: the FMU of model {found!r}, not {model}'s FMU (modelName {model!r})"
        )


def library_file(name: str) -> str:
    """The file name of ctypes library `name` on this platform, as cmake/ctypes.cmake names it
    (each platform's wheel carries its own: tools/wheel.py)."""
    if sys.platform == "win32":
        return f"{name}.dll"
    if sys.platform == "darwin":
        return f"lib{name}.dylib"
    return f"lib{name}.so"


ARTEFACTS = {
    "fmu": Artefact("csfh.fmu", "CSFH_FMU", model="csfh"),
    "fmu3": Artefact("fmi3/csfh.fmu", "CSFH_FMU3", model="csfh"),
    "combdrive": Artefact(
        "combdrive.fmu", "CSFH_COMBDRIVE_FMU", beside="CSFH_FMU", model="combdrive"
    ),
    "combdrive3": Artefact("fmi3/combdrive.fmu", beside="CSFH_FMU3", model="combdrive"),
    "core": Artefact(library_file("csfh_core"), "CSFH_CORE"),
    "batch": Artefact(library_file("csfh_batch"), "CSFH_BATCH"),
}
"""Every artefact the package uses, by key (`csfh info` lists them)."""


def _fmi_key(base: str, fmi_version: int) -> str:
    if fmi_version not in (2, 3):
        raise ParameterError(f"fmi_version = {fmi_version!r}: the FMUs are built for FMI 2 and 3")
    return base if fmi_version == 2 else f"{base}3"


def fmu_path(fmi_version: int = 2) -> Path:
    """Path of csfh.fmu: $CSFH_FMU, the copy inside the package, or (a source checkout)
    build/csfh.fmu. fmi_version=3: the FMI 3.0 build of the same model, $CSFH_FMU3,
    fmi3/csfh.fmu inside the package or the build."""
    return ARTEFACTS[_fmi_key("fmu", fmi_version)].locate()[0]


def combdrive_fmu_path(fmi_version: int = 2) -> Path:
    """Path of combdrive.fmu (the comb-drive actuator for co-simulation): $CSFH_COMBDRIVE_FMU,
    beside $CSFH_FMU (the same build), the copy inside the package, or build/combdrive.fmu.
    fmi_version=3: beside $CSFH_FMU3, or fmi3/combdrive.fmu inside the package or the build."""
    return ARTEFACTS[_fmi_key("combdrive", fmi_version)].locate()[0]


def core_library_path() -> Path:
    """Path of libcsfh_core.so (csfh_core.dll, libcsfh_core.dylib: the physics core for the
    harness): $CSFH_CORE, the package copy, or build/libcsfh_core.so."""
    return ARTEFACTS["core"].locate()[0]


def batch_library_path() -> Path:
    """Path of libcsfh_batch.so (csfh_batch.dll, libcsfh_batch.dylib: the co-simulation loop and
    the batch master): $CSFH_BATCH, the package copy, or build/libcsfh_batch.so."""
    return ARTEFACTS["batch"].locate()[0]
