"""The package's view of the FMU's interface (csfh.model.interface, the generated modules): scenes
load and validate with no binary at all, and the interface refuses what the C core refuses."""

from __future__ import annotations

import math
import os
import shutil
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

ROOT = Path(__file__).resolve().parents[2]


NO_BINARY = """
import sys
from csfh import paths
from csfh.errors import SceneError
from csfh.model import model_info
from csfh.model.scene import BUILTIN_SCENES, load_scene, scene_from_dict

for find in (paths.fmu_path, paths.core_library_path, paths.combdrive_fmu_path):
    try:
        find()
    except FileNotFoundError:
        continue
    raise SystemExit(f"{find.__name__} found a binary")
for name in BUILTIN_SCENES:
    load_scene(name)
assert model_info.coerce("contact.law", "LN_ESDU") == 4
bad = {
    "contact.cr": 1.5,
    "contact.law": "Hertz",
    "friction.fd": -0.1,
    "solver.method_number": 7,
    "flexure.beta": 7.0,
}
for key, value in bad.items():
    try:
        scene_from_dict({"name": "bad", "parameters": {key: value}})
    except SceneError as exc:
        print(exc)
    else:
        raise SystemExit(f"{key} = {value} was accepted")
assert "fmpy" not in sys.modules, "an FMU was read"
"""


def test_scenes_load_and_validate_without_a_binary(tmp_path: Path) -> None:
    """The package alone, with no FMU, core library or build/ it could find: every built-in
    scene loads, and a bad parameter gets the FMU's message (from the generated interface)."""
    shutil.copytree(ROOT / "python" / "csfh", tmp_path / "python" / "csfh")
    env = {
        **os.environ,
        "PYTHONPATH": str(tmp_path / "python"),
        **{k: "/nonexistent" for k in ("CSFH_FMU", "CSFH_FMU3", "CSFH_CORE", "CSFH_COMBDRIVE_FMU")},
    }
    r = subprocess.run(
        [sys.executable, "-c", NO_BINARY], env=env, capture_output=True, text=True, cwd=tmp_path
    )
    assert r.returncode == 0, r.stderr + r.stdout
    assert r.stdout.splitlines() == [
        "<dict>: parameters: contact.cr = 1.5 is out of range (0, 1]",
        '<dict>: parameters: contact.law = "Hertz" is not one of none, LN_spheres, LN_cylinders, '
        "LN_ESDU, HuntCrossley, Flores",
        "<dict>: parameters: friction.fd = -0.1 is out of range [0, inf)",
        "<dict>: parameters: solver.method_number = 7 is out of range [0, 4]",
        "<dict>: parameters: flexure.beta = 7 is out of range (0, 6.283185307179586)",
    ]


@pytest.mark.parametrize(
    ("name", "value"),
    [
        ("contact.cr", 1.5),
        ("contact.cr", 0.0),
        ("contact.cr", 1.0),
        ("contact.nu1", 0.5),
        ("contact.nu1", 0.4999),
        ("friction.fd", -0.1),
        ("flexure.beta", 7.0),
        ("solver.method_number", 7),
        ("solver.method_number", 4),
        ("contact.law", 9),
        ("contact.law", 0),
        ("flexure.enabled", 2),
        ("contact.E1", math.inf),
        ("contact.E1", math.nan),
        ("body1.x", math.inf),
        ("shock.duration", 5e-324),
        ("shock.duration", 0.0),
    ],
)
def test_the_interface_refuses_what_the_core_refuses(name: str, value: float) -> None:
    """The generated interface's check and the C core's (csfh_check_value, through the same
    table) accept and refuse the same values, with the same message."""
    from csfh.errors import ParameterError
    from csfh.model import model_info
    from csfh.model.core import CoreModel

    def message(check: Any) -> str | None:
        try:
            check(name, value)
        except ParameterError as exc:
            return str(exc)
        return None

    assert message(model_info.check) == message(CoreModel().set)
