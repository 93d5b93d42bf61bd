#!/usr/bin/env bash
# Set up csfh on a fresh Debian machine: the system packages it builds with, then the Python
# package (pip builds the FMU with CMake through scikit-build-core and ships it inside csfh/).
set -euo pipefail
cd "$(dirname "$0")/.."

missing=()
for pkg in libsundials-dev cmake ninja-build gcc; do
  dpkg -s "$pkg" >/dev/null 2>&1 || missing+=("$pkg")
done
if [ ${#missing[@]} -gt 0 ]; then
  sudo=""
  [ "$(id -u)" -ne 0 ] && sudo="sudo"
  echo "setup: installing ${missing[*]}"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq "${missing[@]}" >/dev/null
fi

python3 -m pip install -q --disable-pip-version-check ".[test,dask,cosim,docs]"
command -v pyenv >/dev/null 2>&1 && pyenv rehash || true
echo "setup: csfh $(python3 -c 'import csfh; print(csfh.__version__, csfh.fmu_path())')"
