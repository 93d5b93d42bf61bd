#!/usr/bin/env bash
# Write csfh's wheels into DIR, one per platform, each `py3-none` (the package loads only ctypes
# libraries, so a wheel serves every Python >= 3.11):
#   csfh-V-py3-none-manylinux_2_17_x86_64.whl   Linux x86_64 with glibc >= 2.17
#   csfh-V-py3-none-win_amd64.whl               Windows 10 and later, x86_64
#   csfh-V-py3-none-macosx_11_0_universal2.whl  macOS 11 and later, x86_64 and arm64
# Each holds the portable FMUs (every platform's binaries and the sources) and its platform's
# ctypes libraries, cross-built with zig as the FMU binaries are (cmake/platforms.cmake,
# cmake/ctypes.cmake). The build is build/, the same tree tools/setup.sh and tools/test.sh use:
# what is built there already is not built again.
#
# Usage: tools/build_wheels.sh DIR   (replaces the csfh wheels DIR has)
# Needs: tools/setup.sh --platforms all run before (CMake, Ninja, zig, the virtual environment);
# auditwheel (pip install auditwheel), if installed, confirms the Linux wheel's tag.
# Environment: CSFH_VENV, the virtual environment (default: .venv).
set -euo pipefail
[ $# -eq 1 ] || { echo "usage: tools/build_wheels.sh DIR" >&2; exit 2; }
out="$(mkdir -p "$1" && cd "$1" && pwd)"
cd "$(dirname "$0")/.."
venv="${CSFH_VENV:-.venv}"
vpy="$venv/bin/python"
[ -x "$vpy" ] || { echo "build_wheels: no $vpy: run tools/setup.sh --platforms all first" >&2; exit 2; }
"$vpy" -c 'import ziglang' 2>/dev/null ||
  { echo "build_wheels: no zig in $venv: run tools/setup.sh --platforms all first" >&2; exit 2; }

# the CMake tools/setup.sh builds with (the environment's, a requirement of fmpy): another
# version would regenerate build/ and compile everything again
cmake="cmake"
[ -x "$venv/bin/cmake" ] && cmake="$venv/bin/cmake"
start=$SECONDS
"$cmake" -S . -B build -G Ninja -DCSFH_PLATFORMS=all \
  -DPython3_EXECUTABLE="$(cd "$(dirname "$vpy")" && pwd)/$(basename "$vpy")" >/dev/null
"$cmake" --build build --target csfh_wheel_files csfh_ctypes_driver
echo "build_wheels: build/ up to date in $((SECONDS - start))s"

rm -f "$out"/csfh-*-py3-none-*.whl  # (the wheels of an earlier build: one per platform in DIR)
for platform in linux64 win64 darwin64; do
  wheel="$("$vpy" tools/wheel.py --build build --platform "$platform" "$out")"
  echo "build_wheels: $wheel ($(du -h "$wheel" | cut -f1))"
  if [ "$platform" = linux64 ] && "$vpy" -c 'import auditwheel' 2>/dev/null; then
    # auditwheel: the libraries' symbol versions and dependencies fit the tag
    report="$("$vpy" -m auditwheel show "$wheel")"
    if ! tr -s ' \n' '  ' <<<"$report" | grep -q 'consistent with the following platform tag: "manylinux_2_17_x86_64"'; then
      echo "build_wheels: auditwheel does not confirm manylinux_2_17_x86_64:" >&2
      echo "$report" >&2
      exit 1
    fi
    echo "build_wheels: auditwheel confirms manylinux_2_17_x86_64"
  fi
done
