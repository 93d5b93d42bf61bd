"""The command line as a user runs it: `python -m csfh ...` in a subprocess."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path


def run_csfh(
    *args: str,
    cwd: Path | None = None,
    env: dict[str, str] | None = None,
    timeout: float | None = None,
) -> subprocess.CompletedProcess[str]:
    """`python -m csfh ARGS` with this interpreter; its status and output, captured as text."""
    return subprocess.run(
        [sys.executable, "-m", "csfh", *args],
        capture_output=True,
        text=True,
        cwd=cwd,
        env=env,
        timeout=timeout,
        check=False,
    )
