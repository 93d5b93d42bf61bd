#!/usr/bin/env python3
"""Join thin Mach-O files (one per architecture) into one universal ("fat") Mach-O file.

What `lipo -create` does, for the darwin64 binary of the FMUs (x86_64 + arm64, each
cross-compiled by zig), without needing Apple's or LLVM's lipo. The fat format (mach-o/fat.h):
a big-endian header (magic 0xCAFEBABE, number of architectures), one fat_arch record per
architecture (CPU type, CPU subtype, offset, size, alignment as a power of two), then each thin
file unchanged at its offset, aligned to its page size.

Usage: macho_fat.py OUT THIN [THIN ...]
"""

from __future__ import annotations

import struct
import sys
from pathlib import Path

FAT_MAGIC = 0xCAFEBABE
MH_MAGIC_64 = 0xFEEDFACF  # a 64-bit thin Mach-O file, little-endian (x86_64, arm64)
CPU_SUBTYPE_MASK = 0xFF000000  # capability bits, not part of the subtype in a fat_arch
# the page size of each architecture: the alignment of its slice (log2)
ALIGN = {0x01000007: 12, 0x0100000C: 14}  # CPU_TYPE_X86_64, CPU_TYPE_ARM64
CPU_NAMES = {0x01000007: "x86_64", 0x0100000C: "arm64"}


class MachOError(ValueError):
    pass


def thin_cpu(data: bytes, name: str) -> tuple[int, int]:
    """(cputype, cpusubtype) of a thin 64-bit little-endian Mach-O file."""
    if len(data) < 32:
        raise MachOError(f"{name}: {len(data)} bytes, too short for a Mach-O header")
    magic, cputype, cpusubtype = struct.unpack_from("<IiI", data, 0)
    if magic != MH_MAGIC_64:
        raise MachOError(f"{name}: magic {magic:#x} is not a 64-bit little-endian Mach-O file")
    if cputype not in ALIGN:
        raise MachOError(f"{name}: CPU type {cputype:#x} is neither x86_64 nor arm64")
    return cputype, cpusubtype & ~CPU_SUBTYPE_MASK


def fat(thin: list[tuple[str, bytes]]) -> bytes:
    """The universal file of the thin files (name, content), in the given order."""
    if not thin:
        raise MachOError("no thin file given")
    cpus = [thin_cpu(data, name) for name, data in thin]
    if len({c for c, _ in cpus}) != len(cpus):
        raise MachOError("two thin files of the same CPU type")
    header = struct.pack(">II", FAT_MAGIC, len(thin))
    offset = len(header) + 20 * len(thin)
    records, slices = [], []
    for (cputype, subtype), (_, data) in zip(cpus, thin, strict=True):
        align = ALIGN[cputype]
        offset = -(-offset // (1 << align)) * (1 << align)
        records.append(struct.pack(">iIIII", cputype, subtype, offset, len(data), align))
        slices.append((offset, data))
        offset += len(data)
    out = bytearray(offset)
    out[: len(header)] = header
    pos = len(header)
    for r in records:
        out[pos : pos + 20] = r
        pos += 20
    for start, data in slices:
        out[start : start + len(data)] = data
    return bytes(out)


def read_fat(data: bytes) -> list[tuple[str, int, int]]:
    """(architecture, offset, size) of every slice of a universal file."""
    magic, n = struct.unpack_from(">II", data, 0)
    if magic != FAT_MAGIC:
        raise MachOError(f"magic {magic:#x} is not a universal Mach-O file")
    slices = []
    for i in range(n):
        cputype, _, offset, size, _ = struct.unpack_from(">iIIII", data, 8 + 20 * i)
        slices.append((CPU_NAMES.get(cputype, hex(cputype)), offset, size))
    return slices


def main(argv: list[str]) -> int:
    if len(argv) < 2:
        print(__doc__, file=sys.stderr)
        return 2
    out, inputs = Path(argv[0]), [Path(p) for p in argv[1:]]
    try:
        data = fat([(str(p), p.read_bytes()) for p in inputs])
    except (OSError, MachOError) as exc:
        print(f"macho_fat.py: {exc}", file=sys.stderr)
        return 1
    out.write_bytes(data)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
