"""The package's sizes (the project's rules): every module of python/csfh at most 500 lines, and,
where lizard is installed (the test extra), every function at most 80 lines with a cyclomatic
complexity of at most 15 (tools/test.sh's lint stage runs the same lizard command)."""

from __future__ import annotations

import importlib.util
import subprocess
import sys
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[2] / "python" / "csfh"
MAX_MODULE_LINES = 500


@pytest.mark.parametrize("module", sorted(PACKAGE.rglob("*.py")), ids=lambda p: p.name)
def test_a_module_has_at_most_500_lines(module: Path) -> None:
    lines = len(module.read_text(encoding="utf-8").splitlines())
    assert lines <= MAX_MODULE_LINES, f"{module.relative_to(PACKAGE)}: {lines} lines"


def test_functions_are_short_and_simple() -> None:
    if importlib.util.find_spec("lizard") is None:
        pytest.skip("lizard is not installed (pip install lizard, or the test extra)")
    proc = subprocess.run(
        [sys.executable, "-m", "lizard", "-L", "80", "-C", "15", "-w", str(PACKAGE)],
        capture_output=True,
        text=True,
        check=False,
    )
    assert proc.returncode == 0, proc.stdout + proc.stderr
