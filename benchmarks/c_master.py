"""Run the co-simulation loop of the FMU in the compiled master (master/bench_cs_master.c, built
as build/bench_cs_master): fmi2DoStep from grid point to grid point as a C/C++ importer runs the
FMU, with no Python per communication point. Shared by bench_cosim.py and bench_event_vs_rk4.py.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
from dataclasses import dataclass, replace
from functools import cache
from pathlib import Path
from typing import Any

import fmpy

from csfh import load_scene
from csfh.model import model_info
from csfh.model.scene import Scene
from csfh.runners.fmu import STATE_NAMES

DEFAULT_MASTER = Path(__file__).parents[1] / "build" / "bench_cs_master"


def default_master() -> Path:
    """The compiled master: $CSFH_CS_MASTER, else build/bench_cs_master."""
    return Path(os.environ.get("CSFH_CS_MASTER", DEFAULT_MASTER))


@cache
def _binary() -> str:
    from csfh.paths import fmu_path

    directory = fmpy.extract(str(fmu_path()))
    return str(Path(directory) / "binaries" / "linux64" / "csfh.so")


def start_values(scene: Scene, law: str, extra: dict[str, Any] | None = None) -> dict[str, Any]:
    """The scene's parameters for `law`, its initial state and inputs, and `extra`."""
    values: dict[str, Any] = dict(scene.parameter_values(law))
    values.update(dict(zip(STATE_NAMES, scene.x0, strict=True)))
    values.update(scene.inputs)
    values.update(extra or {})
    return values


@dataclass(frozen=True)
class MasterRun:
    loop_seconds: float  # median over the timed repeats (after one untimed warm-up run)
    steps: int  # communication steps per run
    final: list[float]  # the READ reals at the end
    counts: list[int]  # the COUNT integers at the end


def master_command(
    master: Path,
    scene: Scene,
    law: str,
    *,
    rtol: float,
    communication_step: float,
    repeats: int,
    read: tuple[str, ...] = STATE_NAMES,
    count: tuple[str, ...] = ("contact.count",),
    extra: dict[str, Any] | None = None,
    binary: Path | None = None,
) -> list[str]:
    """The compiled master's command line for `scene` with `law` (run_c_master's arguments)."""
    variables = model_info.variables()
    starts = []
    for name, value in start_values(scene, law, extra).items():
        kind = {"Real": "r", "Boolean": "b"}.get(variables[name].type, "i")
        starts.append(f"{variables[name].valueReference}:{kind}={float(value)!r}")
    return [
        str(master),
        str(binary) if binary is not None else _binary(),
        model_info.model_description().guid,
        repr(rtol),
        repr(communication_step),
        repr(scene.stop_time),
        str(repeats),
        ",".join(str(variables[n].valueReference) for n in read),
        ",".join(str(variables[n].valueReference) for n in count),
        *starts,
    ]


def run_c_master(
    master: Path,
    scene: Scene,
    law: str,
    *,
    rtol: float,
    communication_step: float,
    repeats: int,
    read: tuple[str, ...] = STATE_NAMES,
    count: tuple[str, ...] = ("contact.count",),
    extra: dict[str, Any] | None = None,
    binary: Path | None = None,
) -> MasterRun:
    """Run `scene` with `law` in the compiled master; the loop's median wall time and results.
    `binary`: the FMU binary to load (default: binaries/linux64/csfh.so of the FMU in use)."""
    command = master_command(
        master,
        scene,
        law,
        rtol=rtol,
        communication_step=communication_step,
        repeats=repeats,
        read=read,
        count=count,
        extra=extra,
        binary=binary,
    )
    out = subprocess.run(command, check=True, capture_output=True, text=True)
    result = json.loads(out.stdout)
    return MasterRun(
        loop_seconds=float(result["loop_seconds"]),
        steps=int(result["steps"]),
        final=[float(v) for v in result["read"]],
        counts=[int(v) for v in result["count"]],
    )


LAWS = ("LN_spheres", "LN_cylinders", "LN_ESDU")
"""The event-driven laws the A/B benchmarks of two builds compare."""


def add_build_comparison_arguments(ap: argparse.ArgumentParser) -> None:
    """The options of a benchmark of this build's FMU binary against another build's, on the
    first contacts of `central` in the compiled master."""
    ap.add_argument("--baseline", type=Path, required=True, help="the other build's csfh.so")
    ap.add_argument("--binary", type=Path, default=None, help="default: the FMU in use")
    ap.add_argument("--laws", nargs="+", default=list(LAWS), choices=LAWS)
    ap.add_argument("--horizon", type=float, default=0.42, help="s (first three contacts)")
    ap.add_argument("--master", type=Path, default=default_master())


def compared_builds(args: argparse.Namespace) -> tuple[dict[str, Path], Scene]:
    """The two binaries ("baseline", "this") and the scene of add_build_comparison_arguments."""
    binaries = {
        "baseline": args.baseline,
        "this": args.binary if args.binary is not None else Path(_binary()),
    }
    return binaries, replace(load_scene("central"), stop_time=args.horizon)
