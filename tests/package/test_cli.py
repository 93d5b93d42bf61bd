"""The command line itself: fast to start, every command described with its defaults, a version,
the stress cases listed, one entry point, and a user's scene file run."""

from __future__ import annotations

import argparse
import os
import re
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from csfh_command import run_csfh

import csfh
from csfh.cli.main import build_parser, main

ROOT = Path(__file__).resolve().parents[2]
HEAVY = ("numpy", "scipy", "matplotlib", "fmpy", "tqdm", "distributed", "libcosimpy")


def test_help_starts_in_a_fraction_of_a_second() -> None:
    """`csfh --help` in under 0.3 s (best of five, interpreter start included)."""
    best = float("inf")
    for _ in range(5):
        t0 = time.perf_counter()
        proc = run_csfh("--help")
        best = min(best, time.perf_counter() - t0)
        assert proc.returncode == 0 and "usage: csfh" in proc.stdout
    assert best < 0.3, f"csfh --help took {best:.3f} s"


def test_help_imports_no_heavy_package() -> None:
    """The reason it is fast: numpy, matplotlib, fmpy ... are imported by the commands only."""
    code = (
        "import sys\nfrom csfh.cli.main import main\n"
        "try:\n    main(['--help'])\nexcept SystemExit:\n    pass\n"
        f"print(sorted(m for m in sys.modules if m.split('.')[0] in {HEAVY!r}), file=sys.stderr)"
    )
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=False)
    assert proc.returncode == 0, proc.stderr
    assert proc.stderr.strip() == "[]", proc.stderr


def test_version_is_the_packages_and_the_fmus() -> None:
    proc = run_csfh("--version")
    assert proc.returncode == 0
    assert proc.stdout.strip() == f"csfh {csfh.__version__}"
    assert re.fullmatch(r"\d+\.\d+\.\d+", csfh.__version__)
    from csfh.model import model_info
    from csfh.model.actuator import actuator_description

    assert model_info.model_description().version == csfh.__version__
    assert actuator_description().version == csfh.__version__


def commands() -> dict[str, argparse.ArgumentParser]:
    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return dict(sub.choices)


@pytest.mark.parametrize("name", sorted(commands()))
def test_every_command_has_a_description_and_shows_its_defaults(name: str) -> None:
    p = commands()[name]
    assert p.description and len(p.description) > 40, name
    text = p.format_help()
    assert " ".join(p.description.split())[:40] in " ".join(text.split())
    for action in p._actions:
        if not action.option_strings or action.help == argparse.SUPPRESS:
            continue
        help_text = p._get_formatter()._expand_help(action) if action.help else ""
        if action.default not in (None, False, argparse.SUPPRESS):
            assert "default" in help_text and str(action.default) in help_text, (
                name,
                action.option_strings,
                help_text,
            )
        elif action.default is None and not action.required and action.nargs != 0:
            # optional values without a fixed default say what happens without them
            assert "default" in help_text, (name, action.option_strings, help_text)


def test_stress_list_names_the_cases_and_runs_nothing() -> None:
    from csfh.studies.stress.cases import select_cases

    proc = run_csfh("stress", "--list", "--quick")
    assert proc.returncode == 0, proc.stderr
    lines = proc.stdout.strip().splitlines()
    cases = select_cases(quick=True)
    assert len(lines) == len(cases)
    for line, case in zip(lines, cases, strict=True):
        assert line.split()[0] == case.group and f" {case.name}: " in line
    proc = run_csfh("stress", "--list", "--only", "grazing")
    assert proc.returncode == 0 and len(proc.stdout.strip().splitlines()) == 1
    proc = run_csfh("stress", "--list", "--only", "no-such-case")
    assert proc.returncode == 2
    assert proc.stderr.strip() == (
        "csfh: error: --only = 'no-such-case' matches no case (csfh stress --list)"
    )


@pytest.mark.parametrize(
    ("argv", "expected"),
    [
        (
            ["accuracy", "central", "--repeats", "0"],
            "csfh accuracy: error: argument --repeats: '0' must be >= 1 (see csfh accuracy --help)",
        ),
        (
            ["shock", "mems", "--workers", "x"],
            "csfh shock: error: argument --workers: 'x' is not an integer (see csfh shock --help)",
        ),
        (["bogus"], "csfh: error: argument COMMAND: invalid choice: 'bogus'"),
        ([], "csfh: error: the following arguments are required: COMMAND (see csfh --help)"),
    ],
)
def test_a_bad_command_line_is_one_line(
    argv: list[str], expected: str, capsys: pytest.CaptureFixture[str]
) -> None:
    with pytest.raises(SystemExit) as info:
        main(argv)
    assert info.value.code == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith(expected), err


def test_module_and_console_script_are_the_same_entry_point() -> None:
    """`python -m csfh` and the `csfh` script (pyproject.toml) run csfh.cli.main:main."""
    import tomllib

    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    assert project["scripts"]["csfh"] == "csfh.cli.main:main"
    assert "from .cli.main import main" in (ROOT / "python/csfh/__main__.py").read_text()
    assert os.path.isfile(ROOT / "python/csfh/py.typed")


def test_user_scene_file_runs(tmp_path: Path) -> None:
    path = tmp_path / "mine.toml"
    path.write_text(
        'name = "mine"\nstop_time = 0.1\n[initial]\nq = [0.005, 0.0, 0.0]\n'
        '[parts]\nflexure = false\n[parameters]\n"contact.cr" = 0.5\n'
    )
    proc = run_csfh("run", str(path), "--law", "Flores", "--out", str(tmp_path / "out"), "--quiet")
    assert proc.returncode == 0, proc.stderr
    data = np.genfromtxt(tmp_path / "out" / "Flores.csv", delimiter=",", names=True)
    assert data["t_s"][-1] == pytest.approx(0.1)
