#!/usr/bin/env bash
# Set up csfh on a Debian machine, in five steps:
#   1. the system packages it builds with, if missing: CMake, Ninja, a C compiler, dpkg-dev and a
#      deb-src entry (the build fetches SUNDIALS' source with `apt-get source sundials`,
#      cmake/sundials.cmake); with the `test` extra also wine64 (runs the win64 FMU), llvm and
#      binutils (checks of the win64 and darwin64 binaries), libsundials-dev (the comparison with
#      Debian's unoptimised build, benchmarks/bench_sundials_build.py) and libtbb12 (the Ecos
#      engine of the tests);
#   2. a virtual environment with Python >= 3.11: .venv in the repository (created if missing);
#   3. the Python packages csfh and its extras need (pip; nothing when they are installed);
#   4. the FMUs and the ctypes libraries in build/ (CMake + Ninja, each step shown): for this
#      machine only by default, for every platform with --platforms all (zig cross builds, each
#      timed); the tests (tools/test.sh) and the wheels (tools/build_wheels.sh) use this tree too;
#   5. csfh into the environment, as a wheel of build/ (tools/wheel.py; pip compiles nothing);
#      skipped when the wheel is the one installed.
#
# Usage: tools/setup.sh [--extras LIST] [--platforms host|all] [--venv DIR]
#   --extras LIST       optional parts, comma-separated: test (pytest, ruff, mypy, lizard), dask
#                       (sweeps on a Dask cluster), cosim (the libcosimpy engine), docs (Sphinx),
#                       design (SALib, the Sobol indices of csfh design), or all (default:
#                       none); adding one installs only its requirements
#   --platforms P       host: the FMUs carry this machine's linux64 binary (the fastest set-up);
#                       all: also win64, darwin64 and glibc-2.17 linux64 (default: what build/
#                       was last configured with, else host)
#   --venv DIR          the virtual environment (default: $CSFH_VENV, else .venv); an existing
#                       one is used as it is
# Environment: CSFH_PYTHON, the interpreter that creates the environment (default: the first of
# python3, python3.13, python3.12, python3.11 that is at least 3.11).
#
# Afterwards: . .venv/bin/activate (in each new shell), then csfh --help.
set -euo pipefail
cd "$(dirname "$0")/.."

extras=""
platforms=""
venv="${CSFH_VENV:-.venv}"
while [ $# -gt 0 ]; do
  case "$1" in
    --extras) extras="${2:?--extras needs a list, e.g. test,dask}"; shift 2 ;;
    --extras=*) extras="${1#--extras=}"; shift ;;
    --platforms) platforms="${2:?--platforms needs host or all}"; shift 2 ;;
    --platforms=*) platforms="${1#--platforms=}"; shift ;;
    --venv) venv="${2:?--venv needs a directory}"; shift 2 ;;
    --venv=*) venv="${1#--venv=}"; shift ;;
    -h|--help) awk 'NR > 1 && /^#/ { sub(/^# ?/, ""); print; next } NR > 1 { exit }' "$0"; exit 0 ;;
    *) echo "setup: unknown option $1 (tools/setup.sh --help)" >&2; exit 2 ;;
  esac
done
[ "$extras" = "all" ] && extras="test,dask,cosim,docs,design"
if [ -z "$platforms" ]; then  # what build/ has, so a plain re-run keeps every platform
  platforms="$(sed -n 's/^CSFH_PLATFORMS:STRING=//p' build/CMakeCache.txt 2>/dev/null || true)"
  [ "$platforms" = all ] || platforms=host
fi
case "$platforms" in
  host|all) ;;
  *) echo "setup: --platforms: '$platforms' is neither host nor all" >&2; exit 2 ;;
esac
for extra in ${extras//,/ }; do
  case "$extra" in
    test|dask|cosim|docs|design) ;;
    *) echo "setup: --extras: unknown extra '$extra' (test, dask, cosim, docs, design, all)" >&2; exit 2 ;;
  esac
done

step() { printf '\nsetup [%s/5] %s  (%ss)\n' "$1" "$2" "$SECONDS"; }
sudo=""
[ "$(id -u)" -ne 0 ] && sudo="sudo"
apt_install() {
  echo "setup: installing $* (apt-get)"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "$@" >/dev/null
}

step 1 "system packages: cmake, ninja-build, gcc, dpkg-dev (+ deb-src)${extras:+, and what the extras need}"
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
packages=(cmake ninja-build gcc make dpkg-dev)
case ",$extras," in *,test,*) packages+=(wine64 llvm binutils libsundials-dev libtbb12) ;; esac
for pkg in "${packages[@]}"; do
  dpkg -s "$pkg" >/dev/null 2>&1 || missing+=("$pkg")
done
if [ ${#missing[@]} -gt 0 ]; then
  apt_install "${missing[@]}"
elif [ "$need_update" -eq 1 ]; then
  $sudo apt-get update -qq
else
  echo "setup: all present"
fi

step 2 "virtual environment $venv (Python >= 3.11)"
recent_enough() { "$1" -c 'import sys; sys.exit(sys.version_info < (3, 11))' 2>/dev/null; }
if [ -x "$venv/bin/python" ] && recent_enough "$venv/bin/python"; then
  echo "setup: using $venv ($("$venv/bin/python" --version))"
else
  [ -e "$venv" ] && { echo "setup: $venv exists but has no Python >= 3.11: remove it" >&2; exit 1; }
  python=""
  for candidate in ${CSFH_PYTHON:-} python3 python3.13 python3.12 python3.11; do
    if command -v "$candidate" >/dev/null 2>&1 && recent_enough "$candidate"; then
      python="$candidate"; break
    fi
  done
  if [ -z "$python" ]; then
    echo "setup: csfh needs Python >= 3.11; found $(python3 --version 2>&1 || echo 'no python3')." >&2
    echo "       Install one (Debian 12: apt-get install python3) or name it: CSFH_PYTHON=... $0" >&2
    exit 1
  fi
  if ! "$python" -m venv "$venv" 2>/dev/null; then  # Debian's Python keeps venv apart
    rm -rf "$venv"
    apt_install "python$("$python" -c 'import sys; print("%d.%d" % sys.version_info[:2])')-venv"
    "$python" -m venv "$venv"
  fi
  echo "setup: created $venv with $("$venv/bin/python" --version)"
fi
vpy="$venv/bin/python"
installed() { env -u PYTHONPATH "$vpy" -c 'import csfh.paths as p; p.fmu_path(); p.core_library_path()' 2>/dev/null; }

step 3 "Python packages: csfh's requirements${extras:+ and those of $extras}"
stamp="$venv/.csfh-install-stamp"  # line 1: the requirements installed, line 2: the wheel's hash
mapfile -t requirements < <("$vpy" - "$extras" "$platforms" <<'PY'
import sys, tomllib
with open("pyproject.toml", "rb") as f:
    toml = tomllib.load(f)
project = toml["project"]
wanted = list(project["dependencies"])
for extra in filter(None, sys.argv[1].split(",")):
    wanted += project["optional-dependencies"][extra]
if sys.argv[2] == "all":  # the cross compiler of the other platforms (cmake/platforms.cmake)
    wanted += [r for r in toml["build-system"]["requires"] if r.startswith("ziglang")]
print("\n".join(sorted(set(wanted))))
PY
)
requirements_line="$(printf '%s ' "${requirements[@]}")"
if [ -f "$stamp" ] && [ "$(sed -n 1p "$stamp")" = "$requirements_line" ]; then
  echo "setup: installed before (nothing to do)"
else
  "$vpy" -m pip install --disable-pip-version-check "${requirements[@]}" 2>&1 \
    | sed -u '/^Requirement already satisfied/d'
  printf '%s\n%s\n' "$requirements_line" "$(sed -n 2p "$stamp" 2>/dev/null || true)" >"$stamp.new"
  mv "$stamp.new" "$stamp"
fi

step 4 "build/: the FMUs and the ctypes libraries, $platforms platform$([ "$platforms" = all ] && echo s) (CMake + Ninja)"
# the host build first (what the first result needs), one build tree for setup, tests and wheels;
# the environment's CMake (a requirement of fmpy), as tools/test.sh and tools/build_wheels.sh
# use it: another CMake would regenerate build/ and compile everything again
cmake="cmake"
[ -x "$venv/bin/cmake" ] && cmake="$venv/bin/cmake"
configure=(-S . -B build -G Ninja -DCSFH_PLATFORMS="$platforms" -DPython3_EXECUTABLE="$(cd "$(dirname "$vpy")" && pwd)/$(basename "$vpy")")
"$cmake" "${configure[@]}" >/dev/null
if [ "$platforms" = all ]; then
  # each platform's cross build (zig) on its own, so that its time shows
  for slice in linux64 win64 darwin64-x86_64 darwin64-arm64; do
    start=$SECONDS
    echo "setup: cross build $slice (cmake/platforms.cmake)"
    "$cmake" --build build --target "csfh_platform_$slice"
    echo "setup: $slice took $((SECONDS - start))s"
  done
fi
start=$SECONDS
"$cmake" --build build --target csfh_wheel_files
echo "setup: build/ took $((SECONDS - start))s"

step 5 "the csfh package into $venv (a wheel of build/, tools/wheel.py: nothing is compiled again)"
wheel="$("$vpy" tools/wheel.py --build build build/wheels/host)"
wheel_hash="$(sha256sum "$wheel" | cut -d' ' -f1)"
if [ "$(sed -n 2p "$stamp")" = "$wheel_hash" ] && installed; then
  echo "setup: up to date ($(basename "$wheel"))"
else
  "$vpy" -m pip install --disable-pip-version-check --no-deps --force-reinstall "$wheel" 2>&1 \
    | sed -u '/^Requirement already satisfied/d'
  printf '%s\n%s\n' "$(sed -n 1p "$stamp")" "$wheel_hash" >"$stamp.new"
  mv "$stamp.new" "$stamp"
fi
echo
echo "setup: done in ${SECONDS}s: $(env -u PYTHONPATH "$vpy" -c 'import csfh, csfh.paths; print("csfh", csfh.__version__, "with", csfh.paths.fmu_path())')"
if [ "$platforms" = host ]; then
  echo "setup: the FMUs have the linux64 binary of this machine's compiler; for win64, darwin64 and"
  echo "       glibc-2.17 linux64 binaries too: tools/setup.sh --platforms all (3 to 6 min more on"
  echo "       2 cores, most of it zig's first build of its Windows runtime: docs/guide/install.md)"
fi
if [ "$(cd "$venv" && pwd -P)" != "$(cd "${VIRTUAL_ENV:-/nonexistent}" 2>/dev/null && pwd -P || true)" ]; then
  echo "setup: activate it in this shell:  . $venv/bin/activate"
fi
