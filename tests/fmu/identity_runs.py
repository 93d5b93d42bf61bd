"""The FMU runs whose trajectories a restructuring of the C code must reproduce bit for bit.

Each run is a plain fmpy.simulate_fmu call on the FMU (FMI 2.0 or 3.0): co-simulation with each
``solver.method``, or model exchange with fmpy's CVode, for the three event-driven laws on the
``central``, ``csfh`` and ``mems`` scenes. The start values of each run are stored with its
result (taken from the scenes once, when the reference is recorded), so the check does not go
through the harness and cannot be moved by a change to it.

Record the reference (only when a change is meant to move the trajectories, with the reason in
the commit): ``python tests/fmu/identity_runs.py --record``.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np

REFERENCE = Path(__file__).with_name("data") / "identity.npz"
SCENES = {  # name: (stop time s, output interval s)
    "central": (0.3, 1e-3),
    "csfh": (0.3, 1e-3),
    "mems": (1e-3, 1e-5),
    "central-resting": (3.0, 1e-2),  # auto tries BDF in the resting contact
    "mems-shock": (1e-3, 1e-5),  # time events (the pulse's ends), the stress peak tracked
}
VARIANTS = {  # scene: (built-in scene it starts from, parameter overrides)
    "central-resting": ("central", {"contact.cr": 0.9}),
    "mems-shock": (
        "mems",
        {
            "shock.peak": 1500 * 9.81,
            "shock.duration": 5e-4,
            "shock.start": 1e-4,
            "shock.angle": 1.0,
            "flexure.track_stress_peak": True,
        },
    ),
}
LAWS = ("LN_spheres", "LN_cylinders", "LN_ESDU")
CS_METHODS = {"auto": 1, "BDF": 2, "Adams": 3, "RK45": 4}  # SolverMethod values
SAMPLED_ROWS = 12  # rows kept in full per run, to show how far a changed run moved


@dataclass(frozen=True)
class Run:
    fmi_version: int
    scene: str
    law: str
    interface: str  # "CS-<method>" or "ME"

    @property
    def key(self) -> str:
        return f"fmi{self.fmi_version}/{self.scene}/{self.law}/{self.interface}"


def runs() -> list[Run]:
    interfaces = [f"CS-{m}" for m in CS_METHODS] + ["ME"]
    return [Run(v, s, law, i) for v in (2, 3) for s in SCENES for law in LAWS for i in interfaces]


def scene_start_values(scene: str, law: str) -> tuple[dict[str, float | int | bool], float]:
    """The start values of a run of the scene with the law, and the scene's tolerance (from the
    harness: only when recording)."""
    import csfh
    from csfh.runners.fmu import start_values

    base, overrides = VARIANTS.get(scene, (scene, {}))
    loaded = csfh.load_scene(base)
    values = {name: value for name, _kind, value in start_values(loaded, law)}
    values.update(overrides)
    return values, loaded.integrator.rtol


def simulate(fmu: str, run: Run, start: dict, rtol: float) -> np.ndarray:
    """The run's result: a structured array of time and every output."""
    from fmpy import simulate_fmu

    stop_time, interval = SCENES[run.scene]
    values = dict(start)
    kind = "ModelExchange"
    extra: dict = {}
    if run.interface.startswith("CS-"):
        kind = "CoSimulation"
        values["solver.method"] = CS_METHODS[run.interface[3:]]
    else:
        extra["solver"] = "CVode"
    return simulate_fmu(
        fmu,
        fmi_type=kind,
        start_time=0.0,
        stop_time=stop_time,
        output_interval=interval,
        relative_tolerance=rtol,
        start_values=values,
        validate=False,
        **extra,
    )


def matrix(result: np.ndarray) -> tuple[list[str], np.ndarray]:
    names = list(result.dtype.names)
    return names, np.column_stack([np.asarray(result[n], dtype=np.float64) for n in names])


def digest(data: np.ndarray) -> str:
    return hashlib.sha256(np.ascontiguousarray(data, dtype="<f8").tobytes()).hexdigest()


def sample(n_rows: int) -> np.ndarray:
    return np.unique(np.linspace(0, n_rows - 1, SAMPLED_ROWS).round().astype(int))


def record(fmu2: str, fmu3: str, out: Path) -> None:
    entries: dict[str, np.ndarray] = {}
    meta: dict[str, dict] = {}
    for run in runs():
        start, rtol = scene_start_values(run.scene, run.law)
        names, data = matrix(simulate(fmu2 if run.fmi_version == 2 else fmu3, run, start, rtol))
        rows = sample(len(data))
        meta[run.key] = {
            "start": start,
            "rtol": rtol,
            "names": names,
            "shape": list(data.shape),
            "sha256": digest(data),
            "rows": rows.tolist(),
            "scale": np.max(np.abs(data), axis=0).tolist(),
        }
        entries[run.key] = data[rows]
        print(f"{run.key}: {data.shape[0]} rows, {digest(data)[:12]}")
    out.parent.mkdir(parents=True, exist_ok=True)
    np.savez_compressed(out, meta=np.array(json.dumps(meta)), **entries)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--record", action="store_true", help="write the reference")
    args = parser.parse_args()
    if not args.record:
        parser.print_help()
        return 2
    import csfh

    record(str(csfh.fmu_path()), str(csfh.fmu_path(fmi_version=3)), REFERENCE)
    return 0


if __name__ == "__main__":
    sys.exit(main())
