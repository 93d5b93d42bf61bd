#!/usr/bin/env bash
# Run every test: the C unit tests under AddressSanitizer + UndefinedBehaviorSanitizer (ctest), the
# FMI fuzz tests and the failed-allocation test (ASan + UBSan + LeakSanitizer), then the Python
# tests (pytest, against the package installed in the virtual environment, with its FMU; they
# run examples/ too and check the platform wheels built from the same build/), the
# documentation build (Sphinx, warnings as errors) and the linters. Sets
# up first (tools/setup.sh --platforms all, with the extras the tests use: it builds every
# platform once in build/ and reinstalls only what changed), in $CSFH_VENV, else .venv.
set -euo pipefail
cd "$(dirname "$0")/.."

# each stage's header says when it started (the time since test.sh started), the last line the total
stage() { printf '\n== %s  (at %dm%02ds)\n' "$1" $((SECONDS / 60)) $((SECONDS % 60)); }

venv="${CSFH_VENV:-.venv}"
stage "setup (tools/setup.sh)"
tools/setup.sh --venv "$venv" --extras test,dask,cosim,docs,design --platforms all
# shellcheck disable=SC1091
. "$venv/bin/activate"
unset PYTHONPATH  # the tests use the installed package

stage "C unit tests (ASan + UBSan)"
cmake -S . -B build-asan -G Ninja -DCSFH_SANITIZE=ON -DCSFH_BUILD_FMU=OFF -DCMAKE_BUILD_TYPE=Debug >/dev/null
cmake --build build-asan
ctest --test-dir build-asan --output-on-failure

stage "FMI fuzz and failed-allocation tests of both FMUs (ASan + UBSan + LeakSanitizer)"
cmake -S . -B build-fuzz -G Ninja -DCSFH_FUZZ=ON -DCSFH_BUILD_TESTS=OFF -DCSFH_BUILD_BENCHMARKS=OFF \
  -DCSFH_PLATFORMS=host >/dev/null
cmake --build build-fuzz --target csfh_fuzz
ctest --test-dir build-fuzz -L fuzz --output-on-failure
ctest --test-dir build-fuzz -L alloc --output-on-failure

stage "the rest of build/ (the setup built every platform there: cmake/platforms.cmake)"
cmake --build build
ctest --test-dir build -L sundials --output-on-failure

stage "wheels of every platform from build/ (tools/build_wheels.sh: nothing is compiled again)"
CSFH_VENV="$venv" tools/build_wheels.sh build/wheels

stage "Python tests"
python3 -m pytest -q

stage "docs (Sphinx, warnings as errors)"
python3 -m sphinx -W --keep-going -q -b html docs build/docs
python3 tools/model_citations.py check

stage "lint"
python3 -m ruff check python tests modelDescription benchmarks examples tools docs/conf.py
python3 -m mypy
# the size of the functions (C, the generator's, the package's): <= 80 lines, cyclomatic
# complexity <= 15
python3 -m lizard -L 80 -C 15 -w fmu_src modelDescription python/csfh
printf '\n== all passed in %dm%02ds\n' $((SECONDS / 60)) $((SECONDS % 60))
