"""The files generated from modelDescription/*.toml: the committed Python modules are what the
generator writes today and what the built FMUs declare, and the C and Python sides of every
shared constant agree."""

from __future__ import annotations

import importlib
import math
import re
import subprocess
import sys
from pathlib import Path
from typing import Any

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


# ---------------------------------------------------------------------------------------------
# the interface module against the built FMU's modelDescription.xml


def _xml_bounds(v: Any) -> tuple[float | None, float | None]:
    """The range of the module's variable as modelDescription.xml writes it (inclusive: an open
    end is the next value inside)."""
    r = v.range
    if r is None:
        return None, None
    step = 1 if v.type == "Integer" else None

    def end(x: float, is_open: bool, inward: float) -> float | None:
        if math.isinf(x):
            return None
        if not is_open:
            return x
        return x + inward * step if step else math.nextafter(x, inward * math.inf)

    return end(r.low, r.low_open, 1.0), end(r.high, r.high_open, -1.0)


def _number(text: str | None) -> float | None:
    return None if text is None else float(text)


@pytest.mark.parametrize("model", ["csfh", "combdrive"])
def test_interface_module_is_the_fmus_model_description(model: str) -> None:
    """Every variable of the generated module as the built FMU declares it: value reference,
    type, causality, variability, initial, start, declared type, quantity, unit, display unit,
    nominal, min and max, description; the states; the enumerations' items."""
    from fmpy import read_model_description

    from csfh import paths

    path = paths.fmu_path() if model == "csfh" else paths.combdrive_fmu_path()
    md = read_model_description(str(path))
    interface = importlib.import_module(f"csfh.model._{model}_variables").INTERFACE
    assert [v.name for v in md.modelVariables] == [v.name for v in interface.variables]
    for xml, v in zip(md.modelVariables, interface.variables, strict=True):
        start = (
            None if v.start is None else str(v.start).lower() if v.type == "Boolean" else v.start
        )
        expected = {
            "valueReference": v.valueReference,
            "type": v.type,
            "causality": v.causality,
            "variability": v.variability,
            "initial": v.initial or xml.initial,  # None: FMI's default, as fmpy fills it in
            "declaredType": v.declaredType,
            "quantity": v.quantity,
            "unit": v.unit,
            "displayUnit": v.displayUnit,
            "description": v.description or None,
            "min_max": _xml_bounds(v),
        }
        declared = xml.declaredType.name if xml.declaredType is not None else None
        actual = {
            "valueReference": xml.valueReference,
            "type": xml.type,
            "causality": xml.causality,
            "variability": xml.variability,
            "initial": xml.initial,
            "declaredType": declared,
            "quantity": xml.quantity,
            "unit": xml.unit,
            "displayUnit": xml.displayUnit,
            "description": xml.description,
            "min_max": (_number(xml.min), _number(xml.max)),
        }
        assert actual == expected, v.name
        assert _number(xml.nominal) == v.nominal, v.name
        if start is None:
            assert xml.start is None, v.name
        elif v.type == "Boolean":
            assert xml.start == start, v.name
        else:
            assert float(xml.start) == start, v.name
    states = [d.variable.derivative.name for d in md.derivatives]
    assert states == [v.name for v in interface.states]
    for t in md.typeDefinitions:
        items = [(i.name, int(i.value), i.description) for i in t.items]
        expected_items = [
            (i.name, i.value, i.description) for i in interface.enumeration(t.name).items
        ]
        assert items == expected_items
    assert len(md.typeDefinitions) == len(interface.enumerations)


@pytest.mark.parametrize(
    ("kinds", "needle"),
    [
        ('{ "body1.y" = "constant" }', "depends_kind body1.y = constant"),  # not a dependency
        ('{ "body1.vx" = "linear" }', "depends_kind body1.vx = linear"),  # not a kind
    ],
)
def test_a_bad_dependency_kind_is_refused(tmp_path: Path, kinds: str, needle: str) -> None:
    """depends_kind names dependencies of its variable, each with a kind FMI knows."""
    text = (ROOT / "modelDescription" / "variables.toml").read_text("utf-8")
    good = 'depends = ["body1.vx"]\ndepends_kind = { "body1.vx" = "constant" }'
    assert good in text
    bad = tmp_path / "variables.toml"
    bad.write_text(text.replace(good, f'depends = ["body1.vx"]\ndepends_kind = {kinds}', 1))
    run = subprocess.run(
        [sys.executable, str(GENERATE), str(bad), str(tmp_path / "c"), "--epoch", "0"],
        capture_output=True,
        text=True,
    )
    assert run.returncode != 0 and needle in run.stderr + run.stdout, run.stderr
