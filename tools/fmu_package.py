#!/usr/bin/env python3
"""Write an FMU (a ZIP archive) from its parts, for cmake/fmu.cmake.

Usage: fmu_package.py OUT.fmu [--binary PLATFORM=FILE[,FILE...]] ... [--file ARCNAME=FILE] ...

  --binary linux64=csfh.so          stored as binaries/linux64/csfh.so
  --binary darwin64=x86.dylib,arm.dylib
                                    several thin Mach-O files: joined into one universal binary
                                    (tools/macho_fat.py), stored under the first file's name
  --file sources/cvode.c=/path/cvode.c
                                    any other member

Members are written in sorted order with a fixed timestamp, so the same inputs give the same
archive; the archive is written next to OUT and renamed, so OUT is never left half-written.
"""

from __future__ import annotations

import argparse
import os
import sys
import zipfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from macho_fat import MachOError, fat

TIMESTAMP = (2020, 1, 1, 0, 0, 0)


def _pair(text: str) -> tuple[str, str]:
    name, sep, value = text.partition("=")
    if not sep or not name or not value:
        raise argparse.ArgumentTypeError(f"expected NAME=VALUE, got {text!r}")
    return name, value


def members(binaries: list[tuple[str, str]], files: list[tuple[str, str]]) -> dict[str, bytes]:
    out: dict[str, bytes] = {}
    for platform, paths in binaries:
        thin = [Path(p) for p in paths.split(",")]
        name = f"binaries/{platform}/{thin[0].name}"
        if len(thin) == 1:
            out[name] = thin[0].read_bytes()
        else:
            out[name] = fat([(str(p), p.read_bytes()) for p in thin])
    for arcname, path in files:
        if arcname in out:
            raise ValueError(f"{arcname} given twice")
        out[arcname] = Path(path).read_bytes()
    return out


def main(argv: list[str]) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out", type=Path)
    ap.add_argument("--binary", type=_pair, action="append", default=[])
    ap.add_argument("--file", type=_pair, action="append", default=[])
    args = ap.parse_args(argv)
    try:
        content = members(args.binary, args.file)
    except (OSError, ValueError, MachOError) as exc:
        print(f"fmu_package.py: {args.out.name}: {exc}", file=sys.stderr)
        return 1
    tmp = args.out.with_name(args.out.name + ".tmp")
    with zipfile.ZipFile(tmp, "w", zipfile.ZIP_DEFLATED) as z:
        for name in sorted(content):
            info = zipfile.ZipInfo(name, TIMESTAMP)
            info.compress_type = zipfile.ZIP_DEFLATED
            info.external_attr = 0o644 << 16
            z.writestr(info, content[name])
    os.replace(tmp, args.out)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
