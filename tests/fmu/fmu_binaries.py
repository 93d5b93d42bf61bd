"""The FMUs' binaries as the tests read and run them: the functions FMI defines (from fmpy's
headers), the binary tools that read a binary, and the compiled co-simulation master
(benchmarks/master/bench_cs_master.c) that runs one."""

from __future__ import annotations

import glob
import json
import os
import re
import shutil
import subprocess
from pathlib import Path
from typing import Any

import fmpy
import pytest
from fmi2_calls import STATES
from fmpy.model_description import ModelDescription

HEADERS = Path(fmpy.__file__).parent / "c-code"


def fmi2_functions() -> set[str]:
    """Every function FMI 2.0 defines (fmi2Functions.h of the installed fmpy)."""
    header = HEADERS / "fmi2Functions.h"
    return set(re.findall(r"^#define\s+(fmi2\w+)\s+fmi2FullName\(", header.read_text(), re.M))


def fmi3_functions() -> set[str]:
    """Every function FMI 3.0 defines (fmi3Functions.h of the installed fmpy)."""
    text = (HEADERS / "fmi3Functions.h").read_text()
    return set(re.findall(r"^FMI3_Export\s+\w+TYPE\s+(fmi3\w+);", text, re.M))


def need(condition: bool, reason: str) -> None:
    """Skip when `condition` is false (a host-only build), but fail in CI, where every platform
    must be built and checked."""
    if not condition:
        if os.environ.get("CI"):
            pytest.fail(f"{reason} (CI must build and check every platform)")
        pytest.skip(reason)


def tool(*names: str) -> str:
    """The first of `names` found on PATH (versioned LLVM names too: llvm-lipo-14, ...)."""
    for name in names:
        found = shutil.which(name) or next(
            iter(sorted(glob.glob(f"/usr/bin/{name}-[0-9]*"), reverse=True)), None
        )
        if found:
            return found
    need(False, f"none of {names} is installed")
    return ""


def output(*command: str) -> str:
    return subprocess.run(command, check=True, capture_output=True, text=True).stdout


def run_cs_master(
    command: list[str],
    fmu_binary: Path,
    md: ModelDescription,
    starts: dict[str, Any],
    rtol: float = 1e-6,
    stop: float = 0.3,
    env: dict[str, str] | None = None,
) -> dict[str, Any]:
    """benchmarks/master/bench_cs_master.c, a plain C importer (dlopen, fmi2Instantiate, the start
    values, an fmi2DoStep loop of 1e-3 s steps; no fmpy), on a binary: its summary (steps, the
    states read at the end, contact.count)."""
    variables = {v.name: v for v in md.modelVariables}
    kind = {"Real": "r", "Boolean": "b"}
    args = [
        f"{variables[n].valueReference}:{kind.get(variables[n].type, 'i')}={float(v)!r}"
        for n, v in starts.items()
    ]
    text = subprocess.run(
        [
            *command,
            str(fmu_binary),
            md.guid,
            repr(rtol),
            "1e-3",
            repr(stop),
            "1",
            ",".join(str(variables[n].valueReference) for n in STATES),
            str(variables["contact.count"].valueReference),
            *args,
        ],
        check=True,
        capture_output=True,
        text=True,
        env=env,
        timeout=300,
    ).stdout
    return json.loads(text)
