"""Our optimised build of SUNDIALS (cmake/sundials.cmake) does not move the results: the FMU
binary it is in (the shipped linux64 binary, and the host compiler's) and the same FMU sources
linked with Debian's unoptimised libsundials-dev give the same trajectories, to round-off, for
every co-simulation method (benchmarks/bench_sundials_build.py measures the speed-up)."""

from __future__ import annotations

import os
from pathlib import Path

import fmpy
import pytest
from fmi2_calls import STATE_SCALES, STATES
from fmpy.model_description import ModelDescription
from fmu_binaries import run_cs_master

from csfh import load_scene

ROOT = Path(__file__).resolve().parents[2]
METHODS = {"auto": 1, "BDF": 2, "Adams": 3}


def run(master: Path, binary: Path, md: ModelDescription, scene: str, method: int) -> dict:
    sc = load_scene(scene)
    values = {
        **sc.parameter_values("LN_spheres"),
        **dict(zip(STATES, sc.x0, strict=True)),
        "solver.method": method,
    }
    return run_cs_master([str(master)], binary, md, values)


@pytest.mark.parametrize("scene", ["csfh", "central"])
@pytest.mark.parametrize("method", list(METHODS))
def test_optimised_sundials_gives_debians_results(
    fmu_path: Path, model_description: ModelDescription, tmp_path: Path, scene: str, method: str
) -> None:
    debian = ROOT / "build" / "bench" / "debian_sundials" / "csfh.so"
    master = ROOT / "build" / "bench_cs_master"
    if not (debian.is_file() and master.is_file()):
        if os.environ.get("CI"):
            pytest.fail(f"{debian} or {master} not built (libsundials-dev installed?)")
        pytest.skip("no build tree with the Debian-linked FMU binary")
    shipped = Path(fmpy.extract(str(fmu_path), str(tmp_path))) / "binaries" / "linux64" / "csfh.so"
    host = ROOT / "build" / "binaries" / "csfh" / "linux64" / "csfh.so"
    reference = run(master, debian, model_description, scene, METHODS[method])
    assert reference["count"][0] >= 2  # through contacts
    for binary in (shipped, host):
        result = run(master, binary, model_description, scene, METHODS[method])
        assert result["count"] == reference["count"]
        for name, a, b, s in zip(
            STATES, result["read"], reference["read"], STATE_SCALES, strict=True
        ):
            assert abs(a - b) <= 1e-12 * s, (binary, name, a, b)
