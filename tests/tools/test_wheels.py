"""The platform wheels of tools/build_wheels.sh (in $CSFH_WHEELS, else build/wheels): each holds
the same portable FMUs and its own platform's ctypes libraries; the Linux one is
manylinux_2_17_x86_64 (auditwheel) and runs `csfh compare` from a fresh virtual environment
whose PATH has no compiler, CMake, Ninja or zig; the Windows libraries, driven under wine by the
win64 build of tests/importers/ctypes_driver.c, reproduce the Linux ones; the macOS ones are
universal and export only the API (LLVM's tools).

Without the wheels (tools/build_wheels.sh not run) the tests are skipped, except in CI
(CI=true), where tools/test.sh builds them first."""

from __future__ import annotations

import base64
import hashlib
import os
import re
import shutil
import subprocess
import sys
import time
import zipfile
from pathlib import Path

import pytest
from fmpy import read_model_description

from csfh import load_scene
from csfh.model.core import INTERFACE

ROOT = Path(__file__).resolve().parents[2]
BUILD = ROOT / "build"
WHEELS = Path(os.environ.get("CSFH_WHEELS", BUILD / "wheels"))
FMUS = ("csfh.fmu", "combdrive.fmu", "fmi3/csfh.fmu", "fmi3/combdrive.fmu")
LIBRARIES = {
    "manylinux_2_17_x86_64": ("libcsfh_core.so", "libcsfh_batch.so"),
    "win_amd64": ("csfh_core.dll", "csfh_batch.dll"),
    "macosx_*_universal2": ("libcsfh_core.dylib", "libcsfh_batch.dylib"),
}
# what each library exports: its header's API (csfh_api.h, csfh_cs_batch.h), nothing else
EXPORTS = {"csfh_core": re.compile(r"^csfh_api_\w+$"), "csfh_batch": re.compile(r"^csfh_cs_\w+$")}
LINUX_NEEDED = {"libc.so.6", "libm.so.6", "libdl.so.2"}
WINDOWS_SYSTEM_DLL = re.compile(
    r"^(kernel32|ntdll|ucrtbase|api-ms-win-crt-[a-z]+-l1-1-0)\.dll$", re.IGNORECASE
)
# the states' scales (m, m, rad, m/s, m/s, rad/s), as the FMU's platform tests use them
STATE_SCALES = (0.01, 0.01, 0.1, 0.1, 0.1, 1.0)
WIN_LINUX = (("win64", ".exe"), ("linux64", ""))  # the ctypes drivers' platforms and suffixes


def need(condition: bool, reason: str) -> None:
    """Skip when `condition` is false, but fail in CI, where the wheels must be built."""
    if not condition:
        if os.environ.get("CI"):
            pytest.fail(f"{reason} (CI builds the wheels: tools/build_wheels.sh)")
        pytest.skip(reason)


def tool(*names: str) -> str:
    for name in names:
        found = shutil.which(name) or next(
            iter(sorted(Path("/usr/bin").glob(f"{name}-[0-9]*"))), None
        )
        if found:
            return str(found)
    need(False, f"none of {names} is installed")
    return ""


def output(*command: str, env: dict[str, str] | None = None) -> str:
    return subprocess.run(
        command, check=True, capture_output=True, text=True, env=env, timeout=600
    ).stdout


def wheel(tag: str) -> Path:
    found = sorted(WHEELS.glob(f"csfh-*-py3-none-{tag}.whl"))
    need(len(found) == 1, f"no csfh-*-py3-none-{tag}.whl in {WHEELS} (tools/build_wheels.sh)")
    return found[0]


def unpacked(tag: str, tmp_path_factory: pytest.TempPathFactory) -> Path:
    directory = tmp_path_factory.mktemp(tag.replace("*", "x"))
    with zipfile.ZipFile(wheel(tag)) as z:
        z.extractall(directory)
    return directory / "csfh"


@pytest.mark.parametrize("tag", sorted(LIBRARIES))
def test_each_wheel_has_the_portable_fmus_and_its_own_libraries(tag: str) -> None:
    with zipfile.ZipFile(wheel(tag)) as z:
        names = set(z.namelist())
        assert {f"csfh/{n}" for n in FMUS + LIBRARIES[tag]} | {"csfh/__init__.py"} <= names
        others = {n for t, libs in LIBRARIES.items() if t != tag for n in libs}
        assert not {f"csfh/{n}" for n in others} & names, sorted(names)
        meta = next(n for n in names if n.endswith(".dist-info/WHEEL"))
        assert re.search(
            rf"^Tag: py3-none-{tag.replace('*', '[0-9_]+')}$", z.read(meta).decode(), re.M
        )
        fmu = zipfile.ZipFile(z.open("csfh/csfh.fmu"))
        for platform in ("linux64/csfh.so", "win64/csfh.dll", "darwin64/csfh.dylib"):
            assert f"binaries/{platform}" in fmu.namelist()
    # the FMUs are the same files in every wheel
    linux = zipfile.ZipFile(wheel("manylinux_2_17_x86_64"))
    with zipfile.ZipFile(wheel(tag)) as z:
        for name in FMUS:
            assert z.read(f"csfh/{name}") == linux.read(f"csfh/{name}"), name


def test_linux_wheel_is_manylinux_2_17(tmp_path_factory: pytest.TempPathFactory) -> None:
    """auditwheel confirms the tag; the libraries need glibc <= 2.17, only libc, libm and libdl,
    and export only their API."""
    path = wheel("manylinux_2_17_x86_64")
    pytest.importorskip("auditwheel")
    report = " ".join(output(sys.executable, "-m", "auditwheel", "show", str(path)).split())
    assert re.search(
        r'consistent with the following platform tag:\s+"manylinux_2_17_x86_64"', report
    )
    package = unpacked("manylinux_2_17_x86_64", tmp_path_factory)
    for name in LIBRARIES["manylinux_2_17_x86_64"]:
        library = str(package / name)
        text = output(tool("objdump"), "-T", "-p", library)
        versions = {
            tuple(int(p) for p in v.split(".")) for v in re.findall(r"GLIBC_([0-9.]+)", text)
        }
        assert versions and max(versions) <= (2, 17), sorted(versions)
        assert set(re.findall(r"NEEDED\s+(\S+)", text)) <= LINUX_NEEDED, text
        symbols = output(tool("nm"), "-D", "--defined-only", library).split()[2::3]
        assert symbols and all(EXPORTS[name[3:-3]].match(s) for s in symbols), symbols


def test_linux_wheel_runs_compare_without_build_tools(tmp_path: Path) -> None:
    """pip installs the wheel (with its requirements from the index, wheels only) into a fresh
    environment whose PATH has no cc, CMake, Ninja or zig; `csfh compare` then runs from it,
    with the package's own FMUs and libraries."""
    path = wheel("manylinux_2_17_x86_64")
    venv = tmp_path / "venv"
    base = getattr(sys, "_base_executable", sys.executable)
    subprocess.run([base, "-m", "venv", str(venv)], check=True, timeout=300)
    env = {"PATH": str(venv / "bin"), "HOME": str(tmp_path), "MPLBACKEND": "Agg"}
    env.update(
        {k: v for k, v in os.environ.items() if k.startswith("PIP_") or k == "SSL_CERT_FILE"}
    )
    for program in ("cc", "gcc", "clang", "cmake", "ninja", "zig"):
        assert shutil.which(program, path=env["PATH"]) is None, program
    # only wheels, the requirements' too: nothing is built (fmpy's requirement `cmake` then
    # lands in the environment, but nothing runs it)
    pip = [str(venv / "bin" / "python"), "-m", "pip", "install", "-q", "--only-binary=:all:"]
    subprocess.run([*pip, str(path)], check=True, env=env, timeout=900, cwd=tmp_path)
    info = output(str(venv / "bin" / "csfh"), "info", env=env)
    used = re.findall(r"(/\S+) \((\w+)\)", info)  # every artefact: its path and its origin
    assert used and all(p.startswith(f"{venv}/") and o == "package" for p, o in used), info
    out = tmp_path / "compare"
    subprocess.run(
        [str(venv / "bin" / "csfh"), "compare", "central", "--out", str(out), "--quiet"],
        check=True,
        env=env,
        timeout=900,
        cwd=tmp_path,
    )
    assert (out / "summary.json").is_file(), sorted(p.name for p in out.iterdir())


# cases where the comparison is well conditioned: up to the first contacts (later, each contact
# amplifies the last-bit differences of glibc's and the Universal CRT's sin, cos, exp, pow)
DRIVER_CASES = [("central", "LN_spheres", 0.3), ("csfh", "LN_ESDU", 0.1)]


def driver_runs(
    command: list[str], library: Path, case: tuple[str, str, float], env: dict[str, str] | None
) -> dict[str, tuple[list[float], str]]:
    """tests/importers/ctypes_driver.c on `library`: the end state and counters of each run."""
    scene_name, law, stop = case
    scene = load_scene(scene_name)
    states = (v.name for v in INTERFACE.states)
    starts = {**scene.parameter_values(law), **dict(zip(states, scene.x0, strict=True))}
    args = [f"{k}={float(v)!r}" for k, v in starts.items()]
    text = output(*command, str(library), repr(stop), *args, env=env)
    runs = {}
    for line in text.splitlines():
        name, _, status, x, stats = line.split()
        assert status == "status=0", line
        runs[name] = ([float(v) for v in x.removeprefix("x=").split(",")], stats)
    assert set(runs) == {"moreau", "rk4"}, text
    return runs


@pytest.mark.parametrize("case", DRIVER_CASES, ids=[f"{s}-{law}" for s, law, _ in DRIVER_CASES])
def test_windows_libraries_under_wine_reproduce_linux(
    case: tuple[str, str, float], tmp_path_factory: pytest.TempPathFactory
) -> None:
    """The win64 driver on the Windows wheel's csfh_core.dll (under wine) and the linux64 driver
    on the manylinux wheel's libcsfh_core.so: the same counters (steps, contacts) and end states
    to 1e-9 of each state's scale, after contacts."""
    windows = unpacked("win_amd64", tmp_path_factory)
    linux = unpacked("manylinux_2_17_x86_64", tmp_path_factory)
    win_driver = BUILD / "platforms" / "win64" / "csfh_ctypes_driver.exe"
    linux_driver = BUILD / "platforms" / "linux64" / "csfh_ctypes_driver"
    need(
        win_driver.is_file() and linux_driver.is_file(),
        "the cross-built ctypes drivers are not in build/",
    )
    wine = tool("wine64", "/usr/lib/wine/wine64", "wine")
    env = dict(os.environ, WINEDEBUG="-all")
    env["WINEPREFIX"] = str(tmp_path_factory.mktemp("wineprefix"))
    on_windows = driver_runs([wine, str(win_driver)], windows / "csfh_core.dll", case, env)
    on_linux = driver_runs([str(linux_driver)], linux / "libcsfh_core.so", case, None)
    contacts = int(on_linux["rk4"][1].split(",")[4])
    assert contacts >= 1, on_linux  # (a comparison through contacts, not of a free flight)
    for run, (x, stats) in on_linux.items():
        assert on_windows[run][1] == stats, run
        errors = [
            abs(a - b) / s for a, b, s in zip(on_windows[run][0], x, STATE_SCALES, strict=True)
        ]
        assert max(errors) <= 1e-9, (run, on_windows[run], x)


def batch_run(command: list[str], library: Path, fmu: Path, env: dict[str, str] | None) -> str:
    """ctypes_driver.c's batch mode: one co-simulation run of `fmu` (a binary of the unpacked
    FMU) through csfh_cs_batch_run; its output line."""
    md = read_model_description(str(fmu.parents[2]))
    variables = {v.name: v for v in md.modelVariables}
    scene_name, law, stop = DRIVER_CASES[0]
    scene = load_scene(scene_name)
    states = [v.name for v in INTERFACE.states]
    starts = {**scene.parameter_values(law), **dict(zip(states, scene.x0, strict=True))}
    kind = {"Real": "r", "Boolean": "b"}
    args = [
        f"{variables[n].valueReference}:{kind.get(variables[n].type, 'i')}={float(v)!r}"
        for n, v in starts.items()
    ]
    outputs = ",".join(str(variables[n].valueReference) for n in states)
    text = output(*command, str(library), repr(stop), str(fmu), md.guid, outputs, *args, env=env)
    assert text.startswith("batch ") and " status=0 " in text, text
    return text


def test_windows_batch_library_under_wine_reproduces_linux(
    tmp_path_factory: pytest.TempPathFactory,
) -> None:
    """The Windows wheel's csfh_batch.dll runs the FMU's win64 binary under wine (driven by the
    win64 ctypes_driver), the manylinux libcsfh_batch.so its linux64 binary: the same end
    states to 1e-9 of each state's scale, through contacts."""
    windows = unpacked("win_amd64", tmp_path_factory)
    linux = unpacked("manylinux_2_17_x86_64", tmp_path_factory)
    fmu = tmp_path_factory.mktemp("fmu")
    with zipfile.ZipFile(linux / "csfh.fmu") as z:
        z.extractall(fmu)
    drivers = [BUILD / "platforms" / p / f"csfh_ctypes_driver{s}" for p, s in WIN_LINUX]
    need(all(d.is_file() for d in drivers), "the cross-built ctypes drivers are not in build/")
    env = dict(os.environ, WINEDEBUG="-all")
    env["WINEPREFIX"] = str(tmp_path_factory.mktemp("wineprefix"))
    wine = tool("wine64", "/usr/lib/wine/wine64", "wine")
    on_windows = batch_run(
        [wine, str(drivers[0])], windows / "csfh_batch.dll", fmu / "binaries/win64/csfh.dll", env
    )
    on_linux = batch_run(
        [str(drivers[1])], linux / "libcsfh_batch.so", fmu / "binaries/linux64/csfh.so", None
    )
    values = [
        [float(v) for v in line.split(" x=")[1].split()[0].split(",")]
        for line in (on_windows, on_linux)
    ]
    errors = [abs(a - b) / s for a, b, s in zip(*values, STATE_SCALES, strict=True)]
    assert max(errors) <= 1e-9, (on_windows, on_linux)


def test_windows_libraries_export_only_the_api_and_import_only_system_dlls(
    tmp_path_factory: pytest.TempPathFactory,
) -> None:
    windows = unpacked("win_amd64", tmp_path_factory)
    for name in LIBRARIES["win_amd64"]:
        text = output(tool("objdump"), "-p", str(windows / name))
        dlls = re.findall(r"DLL Name: (\S+)", text)
        assert dlls and all(WINDOWS_SYSTEM_DLL.match(d) for d in dlls), dlls
        table = text.split("[Ordinal/Name Pointer] Table", 1)[1].split("\n\n", 1)[0]
        exports = re.findall(r"\]\s+(\S+)", table)
        assert exports and all(EXPORTS[name[:-4]].match(e) for e in exports), exports


def test_macos_libraries_are_universal_and_export_only_the_api(
    tmp_path_factory: pytest.TempPathFactory,
) -> None:
    """Two slices, x86_64 and arm64, each exporting only the API, needing only libSystem, and
    built for the minimum macOS of the wheel's tag."""
    tag = "macosx_*_universal2"
    package = unpacked(tag, tmp_path_factory)
    for name in LIBRARIES[tag]:
        path = str(package / name)
        assert output(tool("llvm-lipo"), "-archs", path).split() == ["x86_64", "arm64"]
        for arch in ("x86_64", "arm64"):
            text = output(tool("llvm-nm"), "-g", "--defined-only", f"--arch={arch}", path)
            symbols = {line.split()[-1] for line in text.splitlines() if line.strip()}
            ours = symbols - {"__mh_dylib_header", "___dso_handle"}
            assert ours and all(EXPORTS[name[3:-6]].match(s[1:]) for s in ours), sorted(symbols)
            headers = output(
                tool("llvm-objdump"), "--macho", "--private-headers", f"--arch={arch}", path
            )
            minimum = re.search(r"LC_BUILD_VERSION.*?\n\s*minos (\d+)\.(\d+)", headers, re.S)
            assert minimum and f"macosx_{minimum[1]}_{minimum[2]}_" in wheel(tag).name, headers
            used = output(tool("llvm-objdump"), "--macho", "--dylibs-used", f"--arch={arch}", path)
            dylibs = [line.split()[0] for line in used.splitlines()[1:] if line.strip()]
            assert dylibs[1:] == ["/usr/lib/libSystem.B.dylib"], used


# ------------------------------------------------------------------------------------------
# tools/wheel.py on a build tree of stand-ins (no compiled files needed)


def fake_build(root: Path, fmi2_platforms: tuple[str, ...]) -> Path:
    """A build tree with FMUs holding `fmi2_platforms`' binaries (and the FMI 3.0 tuples of
    those) and stand-ins for every platform's ctypes libraries."""
    tuples = {"linux64": ["x86_64-linux"], "win64": ["x86_64-windows"]}
    tuples["darwin64"] = ["x86_64-darwin", "aarch64-darwin"]
    build = root / "build"
    for name in FMUS:
        path = build / name
        path.parent.mkdir(parents=True, exist_ok=True)
        fmi3 = name.startswith("fmi3/")
        platforms = [t for p in fmi2_platforms for t in tuples[p]] if fmi3 else fmi2_platforms
        with zipfile.ZipFile(path, "w") as z:
            for platform in platforms:
                z.writestr(f"binaries/{platform}/{Path(name).stem}.bin", platform)
    libraries = {
        "": LIBRARIES["manylinux_2_17_x86_64"],
        "platforms/linux64/lib": LIBRARIES["manylinux_2_17_x86_64"],
        "platforms/win64/lib": LIBRARIES["win_amd64"],
    }
    for directory, names in libraries.items():
        (build / directory).mkdir(parents=True, exist_ok=True)
        for name in names:
            (build / directory / name).write_bytes(name.encode())
    return build


def wheel_tool(*args: str) -> subprocess.CompletedProcess[str]:
    command = [sys.executable, str(ROOT / "tools" / "wheel.py"), *args]
    return subprocess.run(command, capture_output=True, text=True, timeout=120, check=False)


def test_a_platform_wheel_of_host_only_fmus_is_refused(tmp_path: Path) -> None:
    build = fake_build(tmp_path, ("linux64",))
    proc = wheel_tool("--build", str(build), "--platform", "win64", str(tmp_path / "out"))
    assert proc.returncode == 2, proc
    assert len(proc.stderr.splitlines()) == 1 and "csfh.fmu lacks win64, darwin64" in proc.stderr
    assert not list((tmp_path / "out").glob("*"))


def test_the_same_build_gives_the_same_wheel_and_its_record_holds(tmp_path: Path) -> None:
    """tools/setup.sh reinstalls only when the wheel's hash changes: the same files must give
    the same bytes; RECORD lists every file with its sha256 and size."""
    build = fake_build(tmp_path, ("linux64", "win64", "darwin64"))
    wheels = []
    for directory in ("a", "b"):
        out = wheel_tool("--build", str(build), "--platform", "win64", str(tmp_path / directory))
        wheels.append(Path(out.stdout.strip()))
        # the second wheel: later, of files with other modification times
        for path in build.rglob("*"):
            os.utime(path, (1e9, 1e9))
        time.sleep(2.1)  # (a zip's time stamps have a resolution of 2 s)
    first, second = wheels
    assert first.name.endswith("-py3-none-win_amd64.whl") and first.name == second.name
    assert first.read_bytes() == second.read_bytes()
    with zipfile.ZipFile(first) as z:
        record = next(n for n in z.namelist() if n.endswith(".dist-info/RECORD"))
        rows = [line.split(",") for line in z.read(record).decode().splitlines()]
        assert {r[0] for r in rows} == set(z.namelist())
        for name, digest, size in rows:
            if name != record:
                data = z.read(name)
                expected = base64.urlsafe_b64encode(hashlib.sha256(data).digest()).rstrip(b"=")
                assert digest == f"sha256={expected.decode()}" and int(size) == len(data), name
        assert z.read("csfh/csfh_core.dll") == b"csfh_core.dll"
