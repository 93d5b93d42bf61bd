"""The FMUs are source FMUs that compile: modelDescription.xml lists the sources (<SourceFiles>),
sources/ holds them with the SUNDIALS modules they need and our fixed SUNDIALS configuration
header, and fmpy's build_platform_binary (an importer's generic CMake build: every listed file,
`-I sources`, nothing else) builds from them, with the binaries removed, a binary whose
co-simulation and model-exchange runs reproduce the shipped binary's and which, like it, exports
only the fmi2* functions."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path
from typing import Any

import fmpy
import numpy as np
import pytest
from fmpy.build import build_platform_binary
from fmu_binaries import fmi2_functions
from fmu_instances import fmu_file

NOMINAL = {"body1.x": 0.01, "body1.y": 0.01, "body1.theta": 0.1}
# the csfh FMU's own sources: the physics the FMU uses and the FMI glue, nothing of the harness
CSFH_SOURCES = {
    "fmi2_glue.c",
    "csfh_format.c",
    "fmu_instance.c",
    "fmu_log.c",
    "fmu_values.c",
    "fmu_state.c",
    "fmu_me.c",
    "fmu_derivatives.c",
    "fmu_step.c",
    "cosimulation.c",
    "integration.c",
    "integrator_rk45.c",
    "integrator_cvode.c",
    "kept_steps.c",
    "auto_policy.c",
    "rk45.c",
    "rk45_dense.c",
    "rk45_roots.c",
    "rk45_message.c",
    "csfh_fmu_model.c",
    "csfh_fmu.c",
    "csfh_peaks.c",
    "csfh_flexure.c",
    "csfh_contact.c",
    "csfh_normal_law.c",
    "csfh_friction.c",
    "csfh_model.c",
    "csfh_jacobian.c",
    "csfh_vartable.c",
    "csfh_variables.c",
    "csfh_sundials_alloc.c",  # SUNDIALS allocates through it (sundials/csfh_sundials_alloc.h)
}
NOT_IN_THE_FMU = {"csfh_moreau.c", "csfh_moreau_batch.c", "csfh_rk4event.c", "csfh_api.c"}


@pytest.fixture(scope="module", params=["csfh", "combdrive"])
def built(
    request: pytest.FixtureRequest, fmu_path: Path, tmp_path_factory: pytest.TempPathFactory
) -> tuple[str, Path, Path]:
    """(name, the shipped FMU unzipped, the same FMU rebuilt from its sources)."""
    if shutil.which("cmake") is None:
        pytest.fail("cmake is needed to build the source FMU")
    name = request.param
    shipped = Path(fmpy.extract(str(fmu_file(fmu_path, name)), str(tmp_path_factory.mktemp(name))))
    rebuilt = Path(
        fmpy.extract(str(fmu_file(fmu_path, name)), str(tmp_path_factory.mktemp(name + "_src")))
    )
    shutil.rmtree(rebuilt / "binaries")
    build_platform_binary(rebuilt.resolve(), build_dir=tmp_path_factory.mktemp(name + "_build"))
    return name, shipped, rebuilt


def source_files(fmu: Path) -> list[str]:
    md = fmpy.read_model_description(str(fmu))
    return md.buildConfigurations[0].sourceFileSets[0].sourceFiles


def test_source_files_are_exactly_the_fmus_own_and_the_sundials_modules(fmu_path: Path) -> None:
    listed = source_files(fmu_path)
    names = set(zipfile.ZipFile(fmu_path).namelist())
    assert len(listed) == len(set(listed))
    assert {f"sources/{f}" for f in listed} <= names  # every listed file is there
    ours = {f for f in listed if not f.startswith(("cvode", "sundials_", "sun", "nvector"))}
    assert ours == CSFH_SOURCES
    assert not {f"sources/{f}" for f in NOT_IN_THE_FMU} & names
    assert {"cvode.c", "nvector_serial.c", "sunlinsol_dense.c"} <= set(listed)
    # every .c file in sources/ is listed (none left out of the build)
    shipped_c = {n.removeprefix("sources/") for n in names if n.endswith(".c")}
    assert shipped_c == set(listed)


def test_documentation_has_the_parameter_table(fmu_path: Path) -> None:
    md = fmpy.read_model_description(str(fmu_path))
    page = zipfile.ZipFile(fmu_path).read("documentation/index.html").decode()
    parameters = [v for v in md.modelVariables if v.causality == "parameter"]
    assert parameters and all(f"<td>{v.name}</td>" in page for v in parameters)
    assert md.description.split(":")[0] in page


def _simulate(fmu_dir: Path, name: str, fmi_type: str) -> Any:
    if name == "csfh":
        start: dict[str, Any] = {"contact.law": 2}  # LN_spheres
        outputs = ["body1.x", "body1.y", "body1.theta", "contact.F_N"]
        stop = 0.3
    else:
        start = {"V": 300.0, "theta": 0.1}
        outputs = ["F_x", "F_y", "M"]
        stop = 0.01
    return fmpy.simulate_fmu(
        str(fmu_dir),
        fmi_type=fmi_type,
        start_values=start,
        stop_time=stop,
        output_interval=1e-3,
        relative_tolerance=1e-8,
        output=outputs,
    )


@pytest.mark.parametrize("fmi_type", ["CoSimulation", "ModelExchange"])
def test_binary_built_from_the_sources_reproduces_the_shipped_one(
    built: tuple[str, Path, Path], fmi_type: str
) -> None:
    name, shipped, rebuilt = built
    platform = fmpy.platform
    assert list((rebuilt / "binaries" / platform).iterdir()), "build_platform_binary built nothing"
    a = _simulate(shipped, name, fmi_type)
    b = _simulate(rebuilt, name, fmi_type)
    assert len(a) == len(b) > 10
    for field in a.dtype.names:
        scale = max(float(np.max(np.abs(a[field]))), NOMINAL.get(field, 0.0), 1e-300)
        np.testing.assert_allclose(b[field], a[field], rtol=0, atol=1e-9 * scale, err_msg=field)
    if name == "csfh":
        assert np.max(a["contact.F_N"]) > 0  # the runs go through contacts


def test_binary_built_from_the_sources_exports_only_the_fmi2_functions(
    built: tuple[str, Path, Path],
) -> None:
    """The importer compiles sources/ with its own flags (no -fvisibility=hidden, no version
    script): the binary must still export only the FMI functions, as the shipped one does, or an
    internal function (cs_free, fmu_log, SUNDIALS' cvEwtSet, ...) of the FMU could be interposed
    by a same-named symbol of another library in the importer's process."""
    nm = shutil.which("nm")
    if not sys.platform.startswith("linux") or nm is None:
        pytest.skip("the exported symbols are read with GNU nm on Linux")
    name, _, rebuilt = built
    binary = rebuilt / "binaries" / fmpy.platform / f"{name}{fmpy.sharedLibraryExtension}"
    assert os.path.isfile(binary), list((rebuilt / "binaries").rglob("*"))
    out = subprocess.run(
        [nm, "-D", "--defined-only", str(binary)], check=True, capture_output=True, text=True
    ).stdout
    symbols = {line.split()[-1] for line in out.splitlines() if line.strip()}
    expected = fmi2_functions()
    assert len(expected) == 44  # the FMI 2.0 standard's functions, both interfaces
    assert sorted(symbols - expected) == []
    assert symbols == expected
