"""The csfh command line."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from pathlib import Path


class CliError(Exception):
    """A problem to report on one line, exit status 2."""


def _cmd_info(args: argparse.Namespace) -> int:
    from fmpy import read_model_description

    from ._paths import fmu_path

    path = fmu_path()
    md = read_model_description(str(path))
    print(f"FMU          {path}")
    print(f"model        {md.modelName} {md.version} (FMI {md.fmiVersion}, GUID {md.guid})")
    print(f"interfaces   {'ME ' if md.modelExchange else ''}{'CS' if md.coSimulation else ''}")
    print(f"variables    {len(md.modelVariables)}")
    return 0


def _cmd_run(args: argparse.Namespace) -> int:
    import fmpy
    import numpy as np

    from ._paths import fmu_path

    if not (args.stop_time > 0):
        raise CliError(f"--stop-time = {args.stop_time} must be > 0")
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    names = [
        "body1.x",
        "body1.y",
        "body1.theta",
        "contact.F_N",
        "contact.F_T",
        "contact.indentation",
        "contact.count",
        "energy.total",
    ]
    result = fmpy.simulate_fmu(
        str(fmu_path()),
        fmi_type="ModelExchange",
        stop_time=args.stop_time,
        output_interval=1e-4,
        relative_tolerance=1e-8,
        record_events=True,
        output=names,
    )
    path = out / "run.csv"
    np.savetxt(
        path,
        np.column_stack([result[n] for n in ["time", *names]]),
        delimiter=",",
        header=",".join(["time", *names]),
        comments="",
    )
    print(
        f"contacts {int(result['contact.count'][-1])}, max F_N {result['contact.F_N'].max():.4g} N"
        f" -> {path}"
    )
    return 0


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="csfh", description=__doc__)
    sub = parser.add_subparsers(dest="command", required=True)
    p = sub.add_parser("info", help="show the FMU that the package uses")
    p.set_defaults(func=_cmd_info)
    p = sub.add_parser("run", help="simulate the FMU's default experiment (the paper's csfh scene)")
    p.add_argument("--stop-time", type=float, default=1.0, help="end time, s (default 1)")
    p.add_argument("--out", default="results/run", help="output directory")
    p.set_defaults(func=_cmd_run)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args))
    except (CliError, FileNotFoundError, ValueError) as exc:
        print(f"csfh: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("csfh: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    raise SystemExit(main())
