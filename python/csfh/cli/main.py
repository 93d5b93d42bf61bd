"""csfh: dynamics of a Conjugate-Surface Flexure Hinge with impacts and friction.

Scenes are TOML files (built-in: central, asymmetric, csfh). Models: the FMU's contact laws
LN_spheres, LN_cylinders, LN_ESDU, HuntCrossley, Flores (event-driven) and Moreau."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from pathlib import Path


class CliError(Exception):
    """A problem to report on one line, exit status 2."""


def _out_dir(args: argparse.Namespace, default: str) -> Path:
    return Path(args.out) if args.out else Path("results") / default


def _cmd_info(args: argparse.Namespace) -> int:
    from ..model import model_info
    from ..paths import core_library_path, fmu_path

    md = model_info.model_description()
    print(f"FMU          {fmu_path()}")
    print(f"core library {core_library_path()}")
    print(f"model        {md.modelName} {md.version} (FMI {md.fmiVersion}, GUID {md.guid})")
    print(f"interfaces   {'ME ' if md.modelExchange else ''}{'CS' if md.coSimulation else ''}")
    print(f"variables    {len(md.modelVariables)}")
    print(f"models       {', '.join(model_info.MODELS)}")
    return 0


def _cmd_run(args: argparse.Namespace) -> int:
    from ..model.scene import load_scene
    from ..runners.simulate import simulate

    scene = load_scene(args.scene)
    out = _out_dir(args, scene.name)
    out.mkdir(parents=True, exist_ok=True)
    tr = simulate(scene, args.law, interface=args.interface, quiet=args.quiet)
    path = out / f"{tr.model}.csv"
    tr.write_csv(path)
    s = tr.summary()
    first = s["first_contact_time"]
    print(
        f"{scene.name} / {tr.model}: {s['contacts']} contacts"
        f"{f' (first at {first:.6f} s)' if first is not None else ''}, "
        f"max F_N {s['max_F_N']:.4g} N, max indentation {s['max_indentation']:.3g} m, "
        f"{s['steps']} steps, {s['wall_time']:.2f} s -> {path}"
    )
    return 0


def _cmd_compare(args: argparse.Namespace) -> int:
    from ..model.scene import load_scene
    from ..studies.compare import compare

    scene = load_scene(args.scene)
    out = _out_dir(args, scene.name)
    result = compare(scene, out, interface=args.interface, quiet=args.quiet)
    if not args.quiet:
        for tr in result.runs:
            s = tr.summary()
            first = s["first_contact_time"]
            print(
                f"  {tr.model:<13} first contact {first if first is None else f'{first:.6f}'}"
                f" s, {s['contacts']:3d} contacts, max F_N {s['max_F_N']:10.4g} N, "
                f"{s['wall_time']:6.2f} s"
            )
    print(f"wrote {len(result.files)} files to {out}")
    return 0


# Further commands live in their own modules; each defines register(subparsers), whose
# sub-parsers set `func`. Adding a command is adding its module here.
COMMAND_MODULES: tuple[str, ...] = ("accuracy", "sweep", "cosim")


def build_parser() -> argparse.ArgumentParser:
    import importlib

    from ..model import model_info

    parser = argparse.ArgumentParser(
        prog="csfh", description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    p = sub.add_parser("info", help="show the FMU and core library the package uses")
    p.set_defaults(func=_cmd_info)

    def common(p: argparse.ArgumentParser) -> None:
        p.add_argument("scene", help="built-in scene (central, asymmetric, csfh) or a .toml file")
        p.add_argument("--out", help="output directory (default results/SCENE)")
        p.add_argument(
            "--interface",
            choices=("me", "cs"),
            default="me",
            help="FMU interface for the event-driven models (default me)",
        )
        p.add_argument("--quiet", action="store_true", help="no progress bar, less output")

    p = sub.add_parser("run", help="run one model on a scene and write its CSV")
    common(p)
    p.add_argument(
        "--law",
        required=True,
        choices=model_info.MODELS,
        metavar="LAW",
        help=f"one of {', '.join(model_info.MODELS)}",
    )
    p.set_defaults(func=_cmd_run)

    p = sub.add_parser("compare", help="the paper's four-model comparison on a scene")
    common(p)
    p.set_defaults(func=_cmd_compare)

    for name in COMMAND_MODULES:
        importlib.import_module(f".{name}", __package__).register(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    from ..model.core import ParameterError
    from ..model.scene import SceneError
    from ..runners.fmu import SimulationError

    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args))
    except (
        CliError,
        SceneError,
        ParameterError,
        SimulationError,
        FileNotFoundError,
        ValueError,
        FloatingPointError,
        OSError,
    ) as exc:
        print(f"csfh: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("csfh: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    raise SystemExit(main())
