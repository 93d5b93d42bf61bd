"""The scripts in examples/ run and reach their own checks (each asserts its physics and exits
non-zero on a failure); the bare-FMU script does so without the csfh package."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = ROOT / "examples"


def _run(script: str, *args: str, env: dict[str, str] | None = None) -> str:
    proc = subprocess.run(
        [sys.executable, str(EXAMPLES / script), *args],
        capture_output=True,
        text=True,
        timeout=120,
        env=env,
        check=False,
    )
    assert proc.returncode == 0, f"{script} failed:\n{proc.stdout}\n{proc.stderr}"
    return proc.stdout


def test_every_example_is_tested() -> None:
    tested = {"fmu_fmpy.py", "harness.py", "cosim.py"}
    assert {p.name for p in EXAMPLES.glob("*.py")} == tested


def test_bare_fmu_example_needs_no_csfh(tmp_path: Path, fmu_path: Path) -> None:
    # a `csfh` package that refuses to be imported shadows the real one
    blocker = tmp_path / "blocker" / "csfh"
    blocker.mkdir(parents=True)
    (blocker / "__init__.py").write_text(
        'raise ImportError("the bare-FMU example must not import csfh")\n', encoding="utf-8"
    )
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(
        [str(blocker.parent), *filter(None, [env.get("PYTHONPATH")])]
    )
    out = _run("fmu_fmpy.py", str(fmu_path), env=env)
    assert "first contact, model exchange 0.0782" in out
    assert "contacts by 0.3 s: ME 2, CS 2" in out


def test_harness_example(tmp_path: Path) -> None:
    out = _run("harness.py", str(tmp_path))
    for model in ("LN_spheres", "LN_cylinders", "Moreau"):
        assert (tmp_path / f"{model}.csv").stat().st_size > 0, model
        assert model in out
    assert "soft_drop" in out


@pytest.mark.filterwarnings("ignore")
def test_cosim_example() -> None:
    out = _run("cosim.py")
    assert "actuator force at 333 V" in out
    assert "same coupling: largest position difference" in out
