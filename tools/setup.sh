#!/usr/bin/env bash
# Set up csfh on a fresh Debian machine: the system packages it builds with, then the Python
# package (pip builds the FMUs with CMake through scikit-build-core and ships them inside csfh/).
#
# System side: CMake, Ninja, gcc; dpkg-dev and a deb-src entry, so that the build can fetch
# SUNDIALS' source with `apt-get source sundials` (cmake/sundials.cmake); libsundials-dev (only
# for the comparison with Debian's unoptimised build, benchmarks/bench_sundials_build.py);
# wine64 (runs the win64 FMU in the tests) and llvm (llvm-nm, llvm-lipo, llvm-objdump: the
# checks of the win64 and darwin64 binaries). The cross compiler is zig, from PyPI (ziglang).
set -euo pipefail
cd "$(dirname "$0")/.."

sudo=""
[ "$(id -u)" -ne 0 ] && sudo="sudo"
need_update=0

# deb-src for the suite this machine runs (SUNDIALS' source package)
if ! grep -rqsE '^(deb-src |Types:.*deb-src)' /etc/apt/sources.list /etc/apt/sources.list.d/; then
  codename="$(. /etc/os-release && echo "${VERSION_CODENAME:-bookworm}")"
  echo "setup: adding deb-src entries for $codename"
  printf '%s\n' "Types: deb-src" "URIs: http://deb.debian.org/debian" \
    "Suites: $codename $codename-updates" "Components: main" \
    "Signed-By: /usr/share/keyrings/debian-archive-keyring.gpg" |
    $sudo tee /etc/apt/sources.list.d/debian-src.sources >/dev/null
  need_update=1
fi

missing=()
# libtbb12: the Ecos co-simulation engine (ecospy, tests/python/test_registry_importers.py)
for pkg in libsundials-dev cmake ninja-build gcc make dpkg-dev wine64 llvm binutils libtbb12; do
  dpkg -s "$pkg" >/dev/null 2>&1 || missing+=("$pkg")
done
if [ ${#missing[@]} -gt 0 ] || [ "$need_update" -eq 1 ]; then
  $sudo apt-get update -qq
fi
if [ ${#missing[@]} -gt 0 ]; then
  echo "setup: installing ${missing[*]}"
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends \
    "${missing[@]}" >/dev/null
fi

python3 -m pip install -q --disable-pip-version-check ".[test,dask,cosim,docs]"
command -v pyenv >/dev/null 2>&1 && pyenv rehash || true
echo "setup: csfh $(python3 -c 'import csfh; print(csfh.__version__, csfh.fmu_path())')"
