"""`csfh info`, `csfh run`, `csfh compare` and `csfh plot`: one model, the paper's comparison, and
its figures again from a saved run."""

from __future__ import annotations

import argparse
from typing import Any

from .common import SCENE_HELP, add_command, add_quiet, out_dir


def _cmd_info(args: argparse.Namespace) -> int:
    from ..model.installation import summary

    info = summary()
    print(f"csfh {info.version}")
    for found in info.artefacts:
        if found.path is None:
            print(f"{found.label + ':':<26} {found.origin}")
            continue
        print(f"{found.label + ':':<26} {found.path} ({found.origin})")
        print(f"{'':<26} {found.details}")
    build = info.source_build or "none (an installed package uses its own files)"
    print(f"{'source build:':<26} {build}")
    print(f"{'models:':<26} {', '.join(info.models)}")
    print(f"{'built-in scenes:':<26} {', '.join(info.scenes)}")
    return 0


def _cmd_run(args: argparse.Namespace) -> int:
    from ..model.scene import load_scene
    from ..output import output_set
    from ..runners.simulate import simulate

    scene = load_scene(args.scene)
    out = out_dir(args, scene.name)
    tr = simulate(scene, args.law, interface=args.interface, quiet=args.quiet)
    with output_set(out, f"run.{tr.model}"):
        path = tr.write_csv(out / f"{tr.model}.csv")
    s = tr.summary()
    first = s["first_contact_time"]
    print(
        f"{scene.name} / {tr.model}: {s['contacts']} contacts"
        f"{f' (first at {first:.6f} s)' if first is not None else ''}, "
        f"max {tr.force_label()} {s['max_F_N']:.4g} N, max indentation "
        f"{s['max_indentation']:.3g} m, "
        f"{s['steps']} steps, {s['wall_time']:.2f} s -> {path}"
    )
    return 0


def _cmd_compare(args: argparse.Namespace) -> int:
    from ..model.scene import load_scene
    from ..studies.compare import compare

    scene = load_scene(args.scene)
    out = out_dir(args, scene.name)
    result = compare(scene, out, interface=args.interface, quiet=args.quiet)
    if not args.quiet:
        for tr in result.runs:
            s = tr.summary()
            first = s["first_contact_time"]
            print(
                f"  {tr.model:<13} first contact {first if first is None else f'{first:.6f}'}"
                f" s, {s['contacts']:3d} contacts, max {tr.force_label():<16} "
                f"{s['max_F_N']:10.4g} N, "
                f"{s['wall_time']:6.2f} s"
            )
    print(f"wrote {len(result.files)} files to {out}")
    return 0


def _cmd_plot(args: argparse.Namespace) -> int:
    from ..studies.compare import replot

    files = replot(args.directory)
    print(f"wrote {len(files)} figures to {args.directory}")
    return 0


def _scene_options(p: argparse.ArgumentParser) -> None:
    p.add_argument("scene", help=SCENE_HELP)
    p.add_argument("--out", help="output directory (default: results/SCENE)")
    p.add_argument(
        "--interface",
        choices=("me", "cs"),
        default="me",
        help="FMU interface of the event-driven models: me = model exchange with fmpy's CVode, "
        "cs = co-simulation, the integrator inside the FMU (auto: RK45, BDF where stiff)",
    )
    add_quiet(p)


def register(sub: Any) -> None:
    from ..model.model_info import MODELS, PAPER_MODELS

    p = add_command(
        sub,
        "info",
        help="show the version, the FMUs, libraries and scenes the package uses",
        description="Show the csfh version; the FMUs (FMI 2.0 and 3.0, the hinge and the "
        "comb-drive actuator) and the ctypes libraries in use, each with where it comes from "
        "(an environment variable, the package, a source build), an FMU's FMI version and the "
        "platforms it has binaries for, a library's ABI version; the models and the built-in "
        "scenes.",
    )
    p.set_defaults(func=_cmd_info)

    p = add_command(
        sub,
        "run",
        help="run one model on a scene and write its CSV",
        description="Run one model on a scene and write its output table, "
        "OUT/MODEL.csv (t, x, y, theta, vx, vy, omega, F_N, F_T, indentation, v_T, gap, "
        f"energy; units in the header). Models: {', '.join(MODELS)}.",
    )
    _scene_options(p)
    p.add_argument(
        "--law",
        required=True,
        choices=MODELS,
        metavar="MODEL",
        help=f"the model: {', '.join(MODELS)}",
    )
    p.set_defaults(func=_cmd_run)

    p = add_command(
        sub,
        "compare",
        help="the paper's four-model comparison on a scene",
        description="The paper's comparison (section 6): run the scene's models (default "
        f"{', '.join(PAPER_MODELS)}; a scene's `models` key chooses) and write each model's "
        "CSV and per-step records, summary.json and the figures equivalent to the paper's "
        "Figs. 6-12. `csfh plot OUT` draws the figures again from these files.",
    )
    _scene_options(p)
    p.set_defaults(func=_cmd_compare)

    p = add_command(
        sub,
        "plot",
        help="draw the figures of a saved comparison again",
        description="Read the output directory of `csfh compare` (summary.json, MODEL.csv, "
        "MODEL.steps.csv) and draw its figures again, without running anything.",
    )
    p.add_argument("directory", metavar="DIR", help="output directory of csfh compare")
    p.set_defaults(func=_cmd_plot)
