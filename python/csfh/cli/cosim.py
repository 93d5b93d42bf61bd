"""`csfh cosim SCENE`: co-simulate the hinge with the comb-drive actuator of the scene's [cosim]
section (fmpy master loop or libcosimpy) and write a CSV and a figure."""

from __future__ import annotations

import argparse
from typing import Any

from .common import add_command, add_quiet, out_dir, positive_float


def _cmd_cosim(args: argparse.Namespace) -> int:
    from ..cosim.coupling import write_csv
    from ..cosim.figure import plot
    from ..cosim.run import cosimulate
    from ..model.instance import clearance
    from ..model.scene import load_scene
    from ..output import output_set

    scene = load_scene(args.scene)
    if args.export_ssp:
        from ..cosim.ssp import write_ssp

        path = write_ssp(scene, args.export_ssp, step=args.step, stop_time=args.stop_time)
        print(f"{scene.name}: coupled system (csfh.fmu, combdrive.fmu) as SSP 1.0 -> {path}")
        return 0
    out = out_dir(args, scene.name)
    tr = cosimulate(
        scene, engine=args.engine, step=args.step, stop_time=args.stop_time, quiet=args.quiet
    )
    engine = tr.stats["engine"]
    title = f"scene {scene.name} ({tr.stats['integrator']}):\n{scene.description}"
    with output_set(out, f"cosim.{engine}"):
        csv = write_csv(tr, out / f"cosim_{engine}.csv")
        png = plot(tr, out / f"cosim_{engine}.png", title, clearance(scene))
    first = f" (first at {tr.contacts[0]:.4f} s)" if len(tr.contacts) else ""
    print(
        f"{scene.name} / {tr.model}: {len(tr.contacts)} contacts{first}, "
        f"max F_N {float(tr['F_N'].max()):.4g} N, max actuator force "
        f"{float(tr['F_act'].max()):.4g} N, {tr.stats['communication_steps']} communication "
        f"steps, {tr.stats['wall_time']:.2f} s -> {csv}, {png}"
    )
    return 0


def register(sub: Any) -> None:
    from ..model.cosim_section import ENGINES

    p = add_command(
        sub,
        "cosim",
        help="co-simulate the hinge with the comb-drive actuator ([cosim] section of a scene)",
        description="Co-simulation of the csfh FMU with the comb-drive actuator FMU: the "
        "coupling, voltage ramp and step come from the scene's [cosim] section (built-in "
        "example: combdrive). Writes OUT/cosim_ENGINE.csv and OUT/cosim_ENGINE.png, or with "
        "--export-ssp the coupled system as an SSP file that fmpy and libcosim read.",
    )
    p.add_argument("scene", help="built-in scene (combdrive) or a .toml file with [cosim]")
    p.add_argument(
        "--engine",
        choices=ENGINES,
        help="master: fmpy loop or libcosimpy (default: the scene's, else fmpy)",
    )
    p.add_argument("--out", help="output directory (default: results/SCENE)")
    p.add_argument(
        "--step",
        type=positive_float,
        metavar="H",
        help="communication step in s (default: the scene's)",
    )
    p.add_argument(
        "--stop-time",
        type=positive_float,
        metavar="T",
        help="end time in s (default: the scene's)",
    )
    p.add_argument(
        "--export-ssp",
        metavar="FILE",
        help="write the coupled system as an SSP 1.0 archive (both FMUs, connections, "
        "parameters, voltage ramp, step and stop time) to FILE instead of running it "
        "(default: run it)",
    )
    add_quiet(p)
    p.set_defaults(func=_cmd_cosim)
