"""`csfh info` and where the package finds its files (csfh.paths): every FMU and library with
where it comes from, the FMUs' platforms, the libraries' ABI, the built-in scenes; a set
variable that names no file is an error naming it; an installed package (not python/csfh of a
checkout) never looks at a source build."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import fmpy
import pytest
from csfh_command import run_csfh

import csfh
from csfh import paths
from csfh.errors import InstallError
from csfh.model import installation
from csfh.scenes import BUILTIN_SCENES, TOLERANCE_PREFIX

ROOT = Path(__file__).resolve().parents[2]
# the folder of the csfh this process imported (the installed package, or python/ of the checkout
# when PYTHONPATH names it), so that `python -m csfh` runs the same package as the test
PACKAGE_PARENT = str(Path(csfh.__file__).resolve().parents[1])
VARIABLES = ("CSFH_FMU", "CSFH_FMU3", "CSFH_COMBDRIVE_FMU", "CSFH_CORE", "CSFH_BATCH")


def clean_env(**extra: str) -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if k not in VARIABLES}
    return {**env, **extra}


def test_info_lists_every_artefact_its_platforms_and_the_scenes() -> None:
    proc = run_csfh("info", env=clean_env(PYTHONPATH=PACKAGE_PARENT))
    assert proc.returncode == 0, proc.stderr
    out = proc.stdout
    found = installation.artefacts()
    assert len(found) == len(paths.ARTEFACTS) == 6
    for item in found:
        assert item.path is not None and item.path.is_file(), item
        assert f"{item.label}:" in out and str(item.path) in out
    fmus = [f for f in found if "FMU" in f.label]
    # the host's binaries are in every FMU (FMI 2.0 and 3.0 name the platform differently)
    for f in fmus:
        assert "binaries: " in f.details and ("FMI 2.0" in f.details or "FMI 3.0" in f.details)
    assert fmpy.platform in fmus[0].details  # FMI 2.0: e.g. linux64
    assert fmpy.platform_tuple in fmus[1].details  # FMI 3.0: e.g. x86_64-linux
    assert out.count("ABI 2") == 2
    assert f"built-in scenes: {' ' * 10}{', '.join(BUILTIN_SCENES)}\n" in out
    assert "combdrive" in BUILTIN_SCENES


def test_the_built_in_scenes_are_the_scene_files() -> None:
    files = sorted(p.stem for p in (ROOT / "python/csfh/scenes").glob("*.toml"))
    assert list(BUILTIN_SCENES) == [f for f in files if not f.startswith(TOLERANCE_PREFIX)]
    from csfh.cli.common import SCENE_HELP
    from csfh.model.scene import load_scene

    for name in BUILTIN_SCENES:
        assert name in SCENE_HELP
        assert load_scene(name).name == name


def test_a_variable_that_names_no_file_is_an_error_naming_it(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    for variable, find in (
        ("CSFH_FMU", paths.fmu_path),
        ("CSFH_CORE", paths.core_library_path),
        ("CSFH_BATCH", paths.batch_library_path),
        ("CSFH_COMBDRIVE_FMU", paths.combdrive_fmu_path),
    ):
        monkeypatch.setenv(variable, str(tmp_path / "nowhere"))
        with pytest.raises(InstallError, match=rf"\${variable} = .*nowhere.*: no such file"):
            find()
        monkeypatch.delenv(variable)
        assert find().is_file()  # and without it, the build's


def test_info_and_a_run_with_a_bad_variable() -> None:
    env = clean_env(PYTHONPATH=PACKAGE_PARENT, CSFH_FMU="/nonexistent")
    proc = run_csfh("info", env=env)
    assert proc.returncode == 0 and "$CSFH_FMU = '/nonexistent': no such file" in proc.stdout
    proc = run_csfh("run", "central", "--law", "LN_spheres", "--quiet", env=env, cwd=Path("/tmp"))
    assert proc.returncode == 2
    assert proc.stderr.strip() == (
        "csfh: error: $CSFH_FMU = '/nonexistent': no such file (unset it to use the package's "
        "own copy)"
    )


def test_an_installed_package_does_not_look_at_a_source_build(tmp_path: Path) -> None:
    """The package outside a checkout (as pip installs it, without its binaries here): nothing
    found, and the checkout's build/ not among the places looked at."""
    site = tmp_path / "site-packages"
    shutil.copytree(ROOT / "python" / "csfh", site / "csfh")
    code = (
        "from csfh import paths\n"
        "assert paths.source_build() is None\n"
        "for artefact in paths.ARTEFACTS.values():\n"
        "    places = [str(p) for p, _ in artefact.candidates()]\n"
        "    assert places == [str(paths._PACKAGE_DIR / artefact.relative)], places\n"
    )
    env = clean_env(PYTHONPATH=str(site))
    proc = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    proc = run_csfh("info", env=env)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.count("not found") == 6 and str(ROOT / "build") not in proc.stdout
    assert "none (an installed package uses its own files)" in proc.stdout
