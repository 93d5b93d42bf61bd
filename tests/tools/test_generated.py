"""The files generated from modelDescription/*.toml: the committed Python modules are what the
generator writes today, and the C and Python sides of every shared constant agree."""

from __future__ import annotations

import importlib
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
GENERATE = ROOT / "modelDescription" / "generate.py"
MODELS = {"variables.toml": "csfh", "combdrive.toml": "combdrive"}


def _generate(tmp_path: Path, toml: str) -> Path:
    out = tmp_path / toml
    subprocess.run(
        [
            sys.executable,
            str(GENERATE),
            str(ROOT / "modelDescription" / toml),
            str(out / "c"),
            "--python-dir",
            str(out / "py"),
            "--version",
            "0.0.0",
            "--epoch",
            "0",
        ],
        check=True,
    )
    return out


@pytest.mark.parametrize("toml", MODELS)
def test_committed_module_is_what_the_generator_writes(tmp_path: Path, toml: str) -> None:
    """Regenerate with python3 modelDescription/generate.py --python-dir python/csfh/model
    modelDescription/<file>.toml when this fails."""
    name = f"_{MODELS[toml]}_variables.py"
    generated = (_generate(tmp_path, toml) / "py" / name).read_bytes()
    committed = (ROOT / "python" / "csfh" / "model" / name).read_bytes()
    assert committed == generated, f"python/csfh/model/{name} is stale: regenerate it"


@pytest.mark.parametrize("toml", MODELS)
def test_c_and_python_constants_agree(tmp_path: Path, toml: str) -> None:
    prefix = MODELS[toml]
    header = (_generate(tmp_path, toml) / "c" / f"{prefix}_constants.h").read_text()
    defines = dict(re.findall(rf"^#define {prefix.upper()}_(\w+) (\S+)$", header, re.M))
    module = importlib.import_module(f"csfh.model._{prefix}_variables")
    assert "DEFAULT_TOLERANCE" in defines
    for name, text in defines.items():
        value = getattr(module, name)
        assert float(text) == value and type(value)(text) == value, name


def test_libraries_report_the_generated_abi_versions() -> None:
    """The built libraries were compiled from the same [abi] numbers the package checks."""
    from csfh.model import _csfh_variables as generated
    from csfh.model import core
    from csfh.runners import cs_steps

    assert core.library().csfh_api_abi_version() == generated.CORE_ABI_VERSION
    assert cs_steps.library().csfh_cs_batch_abi_version() == generated.BATCH_ABI_VERSION
