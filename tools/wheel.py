#!/usr/bin/env python3
"""Write a csfh wheel from a build tree, without compiling anything: the package's Python files
(python/csfh), the portable FMUs of the build (build/csfh.fmu, build/combdrive.fmu and their
FMI 3.0 builds in build/fmi3/) and one platform's ctypes libraries (cmake/ctypes.cmake).

The package loads only ctypes libraries (no CPython extension), so each wheel is `py3-none`:
one per platform serves every Python >= 3.11.

  host      the host build's libraries (build/), tag of this machine (linux_x86_64): what
            tools/setup.sh installs
  linux64   zig's glibc-2.17 build (build/platforms/linux64/lib/): manylinux_2_17_x86_64
  win64     build/platforms/win64/lib/: win_amd64
  darwin64  the universal x86_64 + arm64 files (build/platforms/darwin64/lib/):
            macosx_<minimum macOS of the slices>_universal2

A platform wheel needs FMUs with every platform's binary (CSFH_PLATFORMS=all): the FMU inside a
wheel is the same file for every platform. The zip is reproducible: entries sorted, every time
stamp $SOURCE_DATE_EPOCH (else 1980-01-01), so the same build gives the same wheel.

Usage: wheel.py [--build DIR] [--platform host|linux64|win64|darwin64] OUT_DIR
Prints the wheel's path.
"""

from __future__ import annotations

import argparse
import base64
import csv
import hashlib
import io
import os
import re
import struct
import sys
import sysconfig
import time
import tomllib
import zipfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
FMUS = ("csfh.fmu", "combdrive.fmu", "fmi3/csfh.fmu", "fmi3/combdrive.fmu")
# the binary directories of every platform, all of which a platform wheel's FMUs must have
# (FMI 2.0's platforms, FMI 3.0's platform tuples)
FMU_PLATFORMS = {
    2: ("linux64", "win64", "darwin64"),
    3: ("x86_64-linux", "x86_64-windows", "x86_64-darwin", "aarch64-darwin"),
}
LIBRARIES = {
    "host": ("", ("libcsfh_core.so", "libcsfh_batch.so")),
    "linux64": ("platforms/linux64/lib", ("libcsfh_core.so", "libcsfh_batch.so")),
    "win64": ("platforms/win64/lib", ("csfh_core.dll", "csfh_batch.dll")),
    "darwin64": ("platforms/darwin64/lib", ("libcsfh_core.dylib", "libcsfh_batch.dylib")),
}
"""platform: (directory in the build tree, the ctypes libraries' file names, csfh/paths.py)."""
LC_BUILD_VERSION = 0x32
MH_MAGIC_64 = 0xFEEDFACF
FAT_MAGIC = 0xCAFEBABE


class WheelError(Exception):
    pass


def macos_minimum(path: Path) -> tuple[int, int]:
    """The highest minimum macOS version (major, minor) of the slices of a universal Mach-O
    file (each slice's LC_BUILD_VERSION load command, mach-o/loader.h)."""
    data = path.read_bytes()
    magic, count = struct.unpack_from(">II", data, 0)
    if magic != FAT_MAGIC:
        raise WheelError(f"{path}: not a universal Mach-O file (magic {magic:#x})")
    found: list[tuple[int, int]] = []
    for i in range(count):
        _, _, offset, _, _ = struct.unpack_from(">iiIII", data, 8 + 20 * i)
        magic, _, _, _, ncmds, _ = struct.unpack_from("<IiIIII", data, offset)
        if magic != MH_MAGIC_64:
            raise WheelError(f"{path}: slice {i} is not a 64-bit Mach-O file")
        cursor = offset + 32
        for _ in range(ncmds):
            cmd, size = struct.unpack_from("<II", data, cursor)
            if cmd == LC_BUILD_VERSION:
                minos = struct.unpack_from("<I", data, cursor + 12)[0]
                found.append((minos >> 16, (minos >> 8) & 0xFF))
            cursor += size
    if len(found) != count:
        raise WheelError(f"{path}: a slice has no LC_BUILD_VERSION (minimum macOS)")
    return max(found)


def platform_tag(platform: str, libraries: list[Path]) -> str:
    if platform == "host":
        return re.sub(r"[-.]", "_", sysconfig.get_platform())
    if platform == "darwin64":
        major, minor = max(macos_minimum(p) for p in libraries)
        return f"macosx_{major}_{minor}_universal2"
    return {"linux64": "manylinux_2_17_x86_64", "win64": "win_amd64"}[platform]


def metadata(project: dict, version: str) -> str:
    """The core metadata (METADATA) from pyproject.toml's [project] table."""
    lines = [
        "Metadata-Version: 2.1",
        f"Name: {project['name']}",
        f"Version: {version}",
        f"Summary: {project['description']}",
        f"Keywords: {','.join(project.get('keywords', []))}",
        *(f"Author: {a['name']}" for a in project.get("authors", [])),
        *(f"Classifier: {c}" for c in project.get("classifiers", [])),
        *(f"Project-URL: {k}, {v}" for k, v in project.get("urls", {}).items()),
        f"Requires-Python: {project['requires-python']}",
        *(f"Requires-Dist: {d}" for d in project.get("dependencies", [])),
    ]
    for extra, requirements in project.get("optional-dependencies", {}).items():
        lines.append(f"Provides-Extra: {extra}")
        lines += [f'Requires-Dist: {r}; extra == "{extra}"' for r in requirements]
    lines.append("Description-Content-Type: text/markdown")
    readme = (ROOT / project["readme"]).read_text(encoding="utf-8")
    return "\n".join(lines) + "\n\n" + readme


def check_portable(fmu: Path, fmi_version: int) -> None:
    """WheelError unless `fmu` has the binaries of every platform."""
    names = zipfile.ZipFile(fmu).namelist()
    wanted = FMU_PLATFORMS[fmi_version]
    lacking = [p for p in wanted if not any(n.startswith(f"binaries/{p}/") for n in names)]
    if lacking:
        raise WheelError(
            f"{fmu} lacks {', '.join(lacking)}: a platform wheel needs the FMUs of every "
            "platform (cmake -DCSFH_PLATFORMS=all)"
        )


def package_files(build: Path, platform: str) -> tuple[dict[str, Path], list[Path]]:
    """(name in the wheel: file) of the package, and the platform's libraries."""
    files: dict[str, Path] = {}
    package = ROOT / "python" / "csfh"
    for path in sorted(package.rglob("*")):
        if path.is_file() and "__pycache__" not in path.parts and path.suffix != ".pyc":
            files["csfh/" + path.relative_to(package).as_posix()] = path
    for name in FMUS:
        path = build / name
        if not path.is_file():
            raise WheelError(f"{path}: no such FMU (build it: cmake --build {build})")
        if platform != "host":
            check_portable(path, 3 if name.startswith("fmi3/") else 2)
        files[f"csfh/{name}"] = path
    directory, names = LIBRARIES[platform]
    libraries = [build / directory / n for n in names]
    for path in libraries:
        if not path.is_file():
            raise WheelError(f"{path}: no such library (build it: cmake --build {build})")
        files[f"csfh/{path.name}"] = path
    return files, libraries


def record_line(name: str, data: bytes) -> list[str]:
    digest = base64.urlsafe_b64encode(hashlib.sha256(data).digest()).rstrip(b"=").decode()
    return [name, f"sha256={digest}", str(len(data))]


def write_wheel(build: Path, platform: str, out_dir: Path) -> Path:
    with open(ROOT / "pyproject.toml", "rb") as f:
        project = tomllib.load(f)["project"]
    version_text = (ROOT / "python" / "csfh" / "_version.py").read_text()
    version = re.search(r'^__version__ = "([^"]+)"$', version_text, re.M)
    if not version:
        raise WheelError('python/csfh/_version.py has no line __version__ = "X.Y.Z"')
    files, libraries = package_files(build, platform)
    tag = f"py3-none-{platform_tag(platform, libraries)}"
    dist_info = f"{project['name']}-{version[1]}.dist-info"
    scripts = "".join(f"{k} = {v}\n" for k, v in project.get("scripts", {}).items())
    generated = {
        f"{dist_info}/METADATA": metadata(project, version[1]),
        f"{dist_info}/WHEEL": (
            f"Wheel-Version: 1.0\nGenerator: csfh tools/wheel.py\nRoot-Is-Purelib: false\n"
            f"Tag: {tag}\n"
        ),
        f"{dist_info}/entry_points.txt": f"[console_scripts]\n{scripts}",
        f"{dist_info}/licenses/LICENSE": (ROOT / "LICENSE").read_text(encoding="utf-8"),
    }
    epoch = int(os.environ.get("SOURCE_DATE_EPOCH", "315532800"))
    stamp = time.gmtime(max(epoch, 315532800))[:6]
    out_dir.mkdir(parents=True, exist_ok=True)
    wheel = out_dir / f"{project['name']}-{version[1]}-{tag}.whl"
    partial = wheel.with_name(wheel.name + ".partial")
    record = io.StringIO()
    rows = csv.writer(record, lineterminator="\n")
    with zipfile.ZipFile(partial, "w", zipfile.ZIP_DEFLATED) as z:
        entries = [(n, p.read_bytes(), p in libraries) for n, p in files.items()]
        entries += [(n, text.encode(), False) for n, text in generated.items()]
        for name, data, executable in sorted(entries):
            info = zipfile.ZipInfo(name, stamp)
            info.external_attr = (0o755 if executable else 0o644) << 16
            info.compress_type = zipfile.ZIP_DEFLATED
            z.writestr(info, data)
            rows.writerow(record_line(name, data))
        rows.writerow([f"{dist_info}/RECORD", "", ""])
        info = zipfile.ZipInfo(f"{dist_info}/RECORD", stamp)
        info.external_attr = 0o644 << 16
        z.writestr(info, record.getvalue(), zipfile.ZIP_DEFLATED)
    os.replace(partial, wheel)
    return wheel


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("out_dir", type=Path, help="where the wheel is written")
    parser.add_argument("--build", type=Path, default=ROOT / "build", help="the build tree")
    parser.add_argument("--platform", choices=sorted(LIBRARIES), default="host")
    args = parser.parse_args(argv)
    try:
        print(write_wheel(args.build.resolve(), args.platform, args.out_dir))
    except (WheelError, OSError) as e:
        print(f"wheel.py: {e}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
