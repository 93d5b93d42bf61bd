#!/usr/bin/env bash
# Run every test: the C unit tests under AddressSanitizer + UndefinedBehaviorSanitizer (ctest),
# then the Python tests (pytest, against the installed package's FMU) and the linters.
set -euo pipefail
cd "$(dirname "$0")/.."

tools/setup.sh

echo "== C unit tests (ASan + UBSan)"
cmake -S . -B build-asan -G Ninja -DCSFH_SANITIZE=ON -DCSFH_BUILD_FMU=OFF -DCMAKE_BUILD_TYPE=Debug >/dev/null
cmake --build build-asan
ctest --test-dir build-asan --output-on-failure

echo "== FMU build tree (every platform: cmake/platforms.cmake)"
cmake -S . -B build -G Ninja -DCSFH_PLATFORMS=all >/dev/null
cmake --build build
ctest --test-dir build -L sundials --output-on-failure

echo "== Python tests"
python3 -m pytest -q

echo "== lint"
python3 -m ruff check python tests modelDescription benchmarks
