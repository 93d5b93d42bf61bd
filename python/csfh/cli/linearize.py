"""`csfh linearize SCENE`: the state-space model A, B, C, D of the hinge at an operating point
(the scene's start, a time of a run, or the static equilibrium under the scene's constant
inputs), its eigenvalues, natural frequencies and damping ratios, and a Bode plot."""

from __future__ import annotations

import argparse
from typing import Any

from .common import SCENE_HELP, add_command, add_quiet, out_dir


def register(sub: Any) -> None:
    p = add_command(
        sub,
        "linearize",
        help="state-space model A, B, C, D at an operating point; modes and a Bode plot",
        description="Linearize the model-exchange FMU of SCENE at an operating point: "
        "dx/dt = A dx + B du, dy = C dx + D du for the six states, the inputs F_ext[1], "
        "F_ext[2], M_ext, a_base[1], a_base[2] and the outputs (the states, contact.gap, "
        "contact.indentation, contact.F_N, contact.F_T, flexure.stress_max), in the contact "
        "mode the FMU has there. Write linearization.json (A, B, C, D, the names, the "
        "operating point, the eigenvalues, the natural frequencies and damping ratios of the "
        "oscillatory modes), linearization.npz, linearization.md and bode.png (from --input "
        "to --output).",
    )
    p.add_argument("scene", help=SCENE_HELP)
    p.add_argument(
        "--at",
        default="start",
        metavar="POINT",
        help="operating point: start (the scene's initial state), equilibrium (the static "
        "equilibrium under the scene's constant inputs, by Newton's method from the scene's "
        "configuration) or a time in s (the state of a model-exchange run of the scene at "
        "that time) (default: start)",
    )
    p.add_argument(
        "--model",
        metavar="LAW",
        help="contact law: LN_spheres, LN_cylinders, LN_ESDU, HuntCrossley, Flores or none "
        "(default: the scene's contact.law)",
    )
    p.add_argument(
        "--jacobian",
        metavar="SOURCE",
        help="fd (4th-order finite differences) or directional (the FMU's "
        "fmi2GetDirectionalDerivative) (default: directional where the FMU provides it, "
        "else fd)",
    )
    p.add_argument("--input", default="F_ext[2]", metavar="NAME", help="input of the Bode plot")
    p.add_argument("--output", default="body1.y", metavar="NAME", help="output of the Bode plot")
    p.add_argument("--out", help="output directory (default: results/linearize/SCENE)")
    add_quiet(p)
    p.set_defaults(func=cmd_linearize)


def cmd_linearize(args: argparse.Namespace) -> int:
    from ..model.scene import load_scene
    from ..studies.linearize.jacobian import check_names
    from ..studies.linearize.run import linearize, parse_at

    at = parse_at(args.at, "--at")
    check_names(args.input, args.output)
    scene = load_scene(args.scene)
    out = out_dir(args, "linearize", scene.name)
    lin = linearize(
        scene,
        args.model,
        at=at,
        jacobian=args.jacobian,
        out=out,
        input=args.input,
        output=args.output,
    )
    if not args.quiet:
        for k, m in enumerate(lin.modes, 1):
            print(f"  mode {k}: {m.frequency_hz:.6g} Hz, damping ratio {m.damping_ratio:.4g}")
    mode = "contact" if lin.in_contact else "flight"
    print(
        f"linearize: {lin.scene} ({lin.model}) at {lin.at}, {mode}, {len(lin.modes)} "
        f"oscillatory modes -> {out / 'linearization.json'}"
    )
    return 0
