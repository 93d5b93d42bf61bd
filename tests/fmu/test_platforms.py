"""The FMUs' binaries for every platform (cmake/platforms.cmake): linux64 for glibc >= 2.17, win64
depending only on Windows system DLLs, darwin64 as a universal x86_64 + arm64 binary, each
exporting exactly the fmi2* functions; and the win64 binary, run under wine by the Windows
build of a C importer, reproduces the linux64 results.

A host-only build (CSFH_PLATFORMS=host, no zig) has only linux64: the other platforms' tests are
then skipped, except in CI (CI=true), where every platform must be there."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import zipfile
from pathlib import Path
from typing import Any

import fmpy
import pytest
from fmi2_calls import STATE_SCALES, STATES
from fmpy.model_description import ModelDescription
from fmu_binaries import fmi2_functions, need, output, run_cs_master, tool
from fmu_instances import fmu_file

import csfh
from csfh import Scene, load_scene

ROOT = Path(__file__).resolve().parents[2]
BUILD = ROOT / "build"
# what a Windows DLL may import: the kernel and the Universal CRT (part of Windows 10 and later)
WINDOWS_SYSTEM_DLL = re.compile(
    r"^(kernel32|ntdll|ucrtbase|api-ms-win-crt-[a-z]+-l1-1-0)\.dll$", re.IGNORECASE
)


@pytest.fixture(scope="module", params=["csfh", "combdrive"])
def fmu_dir(
    request: pytest.FixtureRequest, fmu_path: Path, tmp_path_factory: pytest.TempPathFactory
) -> Path:
    path = fmu_file(fmu_path, request.param)
    return Path(fmpy.extract(str(path), unzipdir=str(tmp_path_factory.mktemp(request.param))))


def binary(fmu_dir: Path, platform: str, identifier: str | None = None) -> Path:
    """binaries/<platform>/<identifier>.<suffix> (identifier: from the directory fmu_dir made)."""
    suffix = {"linux64": ".so", "win64": ".dll", "darwin64": ".dylib"}[platform]
    identifier = identifier or fmu_dir.name.rstrip("0123456789")
    path = fmu_dir / "binaries" / platform / f"{identifier}{suffix}"
    need(path.is_file(), f"{path.relative_to(fmu_dir)} not in the FMU (host-only build?)")
    return path


def test_every_platform_and_the_sources_are_in_the_fmu(fmu_path: Path) -> None:
    names = set(zipfile.ZipFile(fmu_path).namelist())
    need("binaries/win64/csfh.dll" in names, "csfh.fmu has no win64 binary (host-only build?)")
    assert {
        "binaries/linux64/csfh.so",
        "binaries/win64/csfh.dll",
        "binaries/darwin64/csfh.dylib",
        "sources/cvode.c",
        "sources/sundials/sundials_config.h",
        "documentation/index.html",
        "documentation/licenses/SUNDIALS-LICENSE.txt",
    } <= names


def test_linux64_needs_glibc_2_17_at_most(fmu_dir: Path) -> None:
    """The highest GLIBC_ symbol version the binary needs: <= 2.17 (CentOS 7, RHEL 8, Ubuntu
    20.04 and later load it; the host compiler's binary needs 2.29 for exp and 2.35 for hypot)."""
    need(
        (fmu_dir / "binaries" / "win64").is_dir(),
        "a host-only build: linux64 comes from the host compiler and its glibc",
    )
    text = output(tool("objdump"), "-T", str(binary(fmu_dir, "linux64")))
    versions = {tuple(int(p) for p in v.split(".")) for v in re.findall(r"GLIBC_([0-9.]+)", text)}
    assert versions, text
    assert max(versions) <= (2, 17), sorted(versions)


def test_win64_exports_only_fmi2_and_imports_only_system_dlls(fmu_dir: Path) -> None:
    text = output(tool("objdump"), "-p", str(binary(fmu_dir, "win64")))
    dlls = re.findall(r"DLL Name: (\S+)", text)
    assert dlls and [d for d in dlls if not WINDOWS_SYSTEM_DLL.match(d)] == [], dlls
    table = text.split("[Ordinal/Name Pointer] Table", 1)[1].split("\n\n", 1)[0]
    exports = set(re.findall(r"\]\s+(\S+)", table))
    n_fmi2 = len(fmi2_functions())
    assert len(exports) == n_fmi2 and all(e.startswith("fmi2") for e in exports), sorted(exports)


def test_darwin64_is_universal_and_exports_only_fmi2(fmu_dir: Path) -> None:
    path = binary(fmu_dir, "darwin64")
    lipo = tool("llvm-lipo")
    assert output(lipo, "-archs", str(path)).split() == ["x86_64", "arm64"]
    for arch in ("x86_64", "arm64"):
        text = output(tool("llvm-nm"), "-g", "--defined-only", f"--arch={arch}", str(path))
        symbols = {line.split()[-1] for line in text.splitlines() if line.strip()}
        # the two symbols every Mach-O dynamic library defines (the linker's, not ours)
        ours = symbols - {"__mh_dylib_header", "___dso_handle"}
        n_fmi2 = len(fmi2_functions())
        assert len(ours) == n_fmi2 and all(s.startswith("_fmi2") for s in ours), sorted(symbols)
        libraries = output(
            tool("llvm-objdump"), "--macho", "--dylibs-used", f"--arch={arch}", str(path)
        )
        used = [line.split()[0] for line in libraries.splitlines()[1:] if line.strip()]
        assert used[1:] == ["/usr/lib/libSystem.B.dylib"], libraries  # (used[0]: its own name)


# ------------------------------------------------------------------------------------------
# the win64 binary under wine


def wine() -> list[str]:
    for candidate in ("wine64", "/usr/lib/wine/wine64", "wine"):
        found = shutil.which(candidate)
        if found:
            return [found]
    need(False, "wine64 not installed")
    return []


def scene_starts(scene: Scene, law: str) -> dict[str, Any]:
    return {**scene.parameter_values(law), **dict(zip(STATES, scene.x0, strict=True))}


@pytest.fixture(scope="module")
def wine_env(tmp_path_factory: pytest.TempPathFactory) -> dict[str, str]:
    env = dict(os.environ)
    env.update(WINEDEBUG="-all", WINEPREFIX=str(tmp_path_factory.mktemp("wineprefix")))
    return env


# Where the comparison is well conditioned: the trajectory up to the first contacts. Later, every
# contact amplifies the platforms' last-bit differences of sin, cos, exp, pow (glibc against
# mingw-w64 / the Universal CRT): measured 1e-8 relative after 12 contacts of `csfh` at rtol
# 1e-12, 2e-7 at 1e-10 (docs/guide/platforms.md).
CASES: list[tuple[str, str, float, float]] = [
    ("central", "LN_spheres", 1e-6, 0.3),  # the drop and two contacts
    ("central", "LN_ESDU", 1e-10, 0.3),
    ("csfh", "LN_spheres", 1e-6, 0.1),  # flight with the flexure, the first contact
    ("csfh", "LN_ESDU", 1e-6, 0.1),
]


@pytest.mark.parametrize(("scene_name", "law", "rtol", "stop"), CASES)
def test_win64_under_wine_reproduces_linux64(
    fmu_path: Path,
    model_description: ModelDescription,
    wine_env: dict[str, str],
    tmp_path_factory: pytest.TempPathFactory,
    scene_name: str,
    law: str,
    rtol: float,
    stop: float,
) -> None:
    """The Windows build of the C co-simulation importer (bench_cs_master.exe, cross-built with
    the FMUs) runs binaries/win64/csfh.dll under wine; the Linux build of the same importer runs
    binaries/linux64/csfh.so: the same contacts, the states to 1e-9 of their scale."""
    fmu_dir = Path(fmpy.extract(str(fmu_path), unzipdir=str(tmp_path_factory.mktemp("wine"))))
    win_master = BUILD / "platforms" / "win64" / "bench_cs_master.exe"
    linux_master = BUILD / "bench_cs_master"
    need(win_master.is_file(), f"{win_master} not built (CSFH_PLATFORMS=all)")
    need(linux_master.is_file(), f"{linux_master} not built")
    dll = binary(fmu_dir, "win64", "csfh")
    command = wine()
    starts = scene_starts(load_scene(scene_name), law)
    so = binary(fmu_dir, "linux64", "csfh")
    windows = run_cs_master(
        [*command, str(win_master)], dll, model_description, starts, rtol, stop, wine_env
    )
    linux = run_cs_master([str(linux_master)], so, model_description, starts, rtol, stop)
    assert windows["steps"] == linux["steps"] == round(stop / 1e-3)
    assert windows["count"] == linux["count"] and linux["count"][0] >= 1
    for name, w, lin, scale in zip(
        STATES, windows["read"], linux["read"], STATE_SCALES, strict=True
    ):
        assert abs(w - lin) <= 1e-9 * max(abs(lin), scale), (name, w, lin)


# ------------------------------------------------------------------------------------------
# the conformance importers (tests/importers/, cross-built for win64 with the FMUs), under wine:
# each Windows build runs the win64 binary, the Linux build the linux64 one, same arguments.
# To add an importer: build it with the FMUs (tests/importers/CMakeLists.txt is included by the
# cross builds too) and add one line here: (name, its options, the events it must log at least).
WINE_IMPORTERS: list[tuple[str, tuple[str, ...], int]] = [
    ("me_cvode", ("--mode", "flags", "--rtol", "1e-10", "--interval", "1e-3"), 4),
    ("me_euler", ("--interval", "1e-3"), 4),
    ("cs_master", ("--rtol", "1e-8"), 0),  # (it logs no events)
    # the FMI 3.0 build through the FMI 3.0 importers (binaries/x86_64-windows/csfh.dll)
    ("fmi3_me_cvode", ("--mode", "flags", "--rtol", "1e-10", "--interval", "1e-3"), 4),
    ("fmi3_me_euler", ("--interval", "1e-3"), 4),
    ("fmi3_cs_master", ("--rtol", "1e-8"), 4),  # (it logs its early returns: two contacts)
]
IMPORTER_OUTPUTS = (*STATES, "contact.gap", "contact.F_N")


@pytest.mark.parametrize(
    ("name", "options", "min_events"), WINE_IMPORTERS, ids=[n for n, _, _ in WINE_IMPORTERS]
)
def test_conformance_importers_under_wine_reproduce_linux64(
    fmu_path: Path,
    wine_env: dict[str, str],
    tmp_path: Path,
    name: str,
    options: tuple[str, ...],
    min_events: int,
) -> None:
    """`central` to 0.3 s (the drop and two contacts, where the runs are well conditioned, see
    CASES): the same output rows and events, every output to 1e-9 of its scale. The fmi3_
    importers run the FMI 3.0 build."""
    fmi3 = name.startswith("fmi3_")
    fmu = csfh.fmu_path(fmi_version=3) if fmi3 else fmu_path
    fmu_dir = Path(fmpy.extract(str(fmu), unzipdir=str(tmp_path / "fmu")))
    linux = BUILD / "importers" / f"csfh_import_{name}"
    windows = BUILD / "platforms" / "win64" / "importers" / f"csfh_import_{name}.exe"
    need(linux.is_file() and windows.is_file(), f"{linux} or {windows} not built")
    if fmi3:
        dll = fmu_dir / "binaries" / "x86_64-windows" / "csfh.dll"
        need(dll.is_file(), "the FMI 3.0 csfh.fmu has no x86_64-windows binary (host-only build?)")
    else:
        binary(fmu_dir, "win64", "csfh")
    starts = [
        f"{n}={'true' if v is True else 'false' if v is False else repr(v)}"
        for n, v in scene_starts(load_scene("central"), "LN_spheres").items()
    ]
    tables = {}
    for platform, command, env in (
        ("linux64", [str(linux)], None),
        ("win64", [*wine(), str(windows)], wine_env),
    ):
        out, events = tmp_path / f"{platform}.csv", tmp_path / f"{platform}_events.csv"
        summary = tmp_path / f"{platform}.txt"
        result = subprocess.run(
            [
                *command,
                str(fmu_dir),
                "--outputs",
                ",".join(IMPORTER_OUTPUTS),
                "--out",
                str(out),
                "--events",
                str(events),
                "--summary",
                str(summary),
                "--stop",
                "0.3",
                *options,
                *starts,
            ],
            capture_output=True,
            text=True,
            env=env,
            timeout=600,
        )
        assert result.returncode == 0, (platform, result.stderr, summary.read_text())
        rows = [line.split(",") for line in out.read_text().splitlines()]
        tables[platform] = (rows[0], [[float(x) for x in r] for r in rows[1:]])
        tables[platform + " events"] = events.read_text().count("\n")
    header, linux_rows = tables["linux64"]
    assert tables["win64"][0] == header and len(tables["win64"][1]) == len(linux_rows) > 100
    assert tables["win64 events"] == tables["linux64 events"] >= 1 + min_events  # (+ the header)
    for j, column in enumerate(header):
        scale = max(max(abs(r[j]) for r in linux_rows), STATE_SCALES[j - 1] if 1 <= j <= 6 else 0)
        worst = max(abs(w[j] - r[j]) for w, r in zip(tables["win64"][1], linux_rows, strict=True))
        assert worst <= 1e-9 * scale, (column, worst, scale)
