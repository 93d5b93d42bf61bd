#!/usr/bin/env bash
# Set up csfh on a Debian machine, in three steps:
#   1. the system packages it builds with, if missing: CMake, Ninja, a C compiler, dpkg-dev and a
#      deb-src entry (the build fetches SUNDIALS' source with `apt-get source sundials`,
#      cmake/sundials.cmake; the cross compiler is zig, from PyPI); with the `test` extra also
#      wine64 (runs the win64 FMU), llvm and binutils (checks of the win64 and darwin64
#      binaries), libsundials-dev (the comparison with Debian's unoptimised build,
#      benchmarks/bench_sundials_build.py) and libtbb12 (the Ecos engine of the tests);
#   2. a virtual environment with Python >= 3.11: .venv in the repository (created if missing);
#   3. the Python package into it (pip builds the FMU with CMake through scikit-build-core and ships
#      it inside csfh/); skipped when nothing it is built from has changed since the last install.
#
# Usage: tools/setup.sh [--extras LIST] [--venv DIR]
#   --extras LIST  optional parts, comma-separated: test (pytest, ruff, mypy, lizard), dask
#                  (sweeps on a Dask cluster), cosim (the libcosimpy engine), docs (Sphinx),
#                  design (SALib, the Sobol indices of csfh design), or all (default: none)
#   --venv DIR     the virtual environment (default: $CSFH_VENV, else .venv); an existing one is
#                  used as it is
# Environment: CSFH_PYTHON, the interpreter that creates the environment (default: the first of
# python3, python3.13, python3.12, python3.11 that is at least 3.11).
#
# Afterwards: . .venv/bin/activate (in each new shell), then csfh --help.
set -euo pipefail
cd "$(dirname "$0")/.."

extras=""
venv="${CSFH_VENV:-.venv}"
while [ $# -gt 0 ]; do
  case "$1" in
    --extras) extras="${2:?--extras needs a list, e.g. test,dask}"; shift 2 ;;
    --extras=*) extras="${1#--extras=}"; shift ;;
    --venv) venv="${2:?--venv needs a directory}"; shift 2 ;;
    --venv=*) venv="${1#--venv=}"; shift ;;
    -h|--help) awk 'NR > 1 && /^#/ { sub(/^# ?/, ""); print; next } NR > 1 { exit }' "$0"; exit 0 ;;
    *) echo "setup: unknown option $1 (tools/setup.sh --help)" >&2; exit 2 ;;
  esac
done
[ "$extras" = "all" ] && extras="test,dask,cosim,docs,design"
for extra in ${extras//,/ }; do
  case "$extra" in
    test|dask|cosim|docs|design) ;;
    *) echo "setup: --extras: unknown extra '$extra' (test, dask, cosim, docs, design, all)" >&2; exit 2 ;;
  esac
done

step() { printf '\nsetup [%s/3] %s  (%ss)\n' "$1" "$2" "$SECONDS"; }
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

step 3 "the csfh package${extras:+ with extras $extras} (pip builds the FMUs for every platform: several minutes the first time)"
stamp="$venv/.csfh-install-stamp"  # line 1: the hash of the sources, line 2: the extras installed
inputs_hash() {
  {
    "$vpy" -c 'import sys; print(sys.version)'
    find pyproject.toml CMakeLists.txt cmake tools/fmu_package.py tools/macho_fat.py python fmu_src modelDescription -type f \
      ! -path '*/__pycache__/*' ! -name '*.pyc' -print0 | LC_ALL=C sort -z | xargs -0 sha256sum
  } | sha256sum | cut -d' ' -f1
}
installed() { env -u PYTHONPATH "$vpy" -c 'import csfh.paths as p; p.fmu_path(); p.core_library_path()' 2>/dev/null; }
# the extras of `have` (comma lists) that `want` lacks
missing_extras() { local e out=""; for e in ${1//,/ }; do case ",$2," in *",$e,"*) ;; *) out+="${out:+,}$e" ;; esac; done; echo "$out"; }
hash="$(inputs_hash)"
had_extras=""
[ -f "$stamp" ] && had_extras="$(sed -n 2p "$stamp")"
if [ -f "$stamp" ] && [ "$(sed -n 1p "$stamp")" = "$hash" ] && installed; then
  new_extras="$(missing_extras "$extras" "$had_extras")"
  if [ -z "$new_extras" ]; then
    echo "setup: up to date (nothing csfh is built from has changed since it was installed)"
  else
    # the package is current: only the extras' own requirements (pyproject.toml), no rebuild
    echo "setup: csfh is up to date; adding the requirements of the extras $new_extras"
    mapfile -t requirements < <("$vpy" - "$new_extras" <<'PY'
import sys, tomllib
with open("pyproject.toml", "rb") as f:
    optional = tomllib.load(f)["project"]["optional-dependencies"]
for extra in sys.argv[1].split(","):
    print("\n".join(optional[extra]))
PY
)
    "$vpy" -m pip install --disable-pip-version-check "${requirements[@]}" 2>&1 \
      | sed -u '/^Requirement already satisfied/d'
    printf '%s\n%s\n' "$hash" "$had_extras${had_extras:+${new_extras:+,}}$new_extras" >"$stamp"
  fi
else
  rm -f "$stamp"
  spec="."
  [ -n "$extras" ] && spec=".[$extras]"
  "$vpy" -m pip install --disable-pip-version-check "$spec" 2>&1 \
    | sed -u '/^Requirement already satisfied/d'
  # extras installed before stay installed (pip removes nothing)
  new_extras="$(missing_extras "$extras" "$had_extras")"
  printf '%s\n%s\n' "$hash" "$had_extras${had_extras:+${new_extras:+,}}$new_extras" >"$stamp"
fi
echo
echo "setup: done in ${SECONDS}s: $(env -u PYTHONPATH "$vpy" -c 'import csfh, csfh.paths; print("csfh", csfh.__version__, "with", csfh.paths.fmu_path())')"
if [ "$(cd "$venv" && pwd -P)" != "$(cd "${VIRTUAL_ENV:-/nonexistent}" 2>/dev/null && pwd -P || true)" ]; then
  echo "setup: activate it in this shell:  . $venv/bin/activate"
fi
