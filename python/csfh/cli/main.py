"""csfh: dynamics of a Conjugate-Surface Flexure Hinge with impacts and friction.

Scenes are TOML files (built-in: central, asymmetric, csfh, mems). Models: the FMU's contact laws
LN_spheres, LN_cylinders, LN_ESDU, HuntCrossley, Flores (event-driven) and Moreau.
`csfh COMMAND --help` describes each command."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence

from .._version import __version__
from ..errors import USER_ERRORS
from . import accuracy, common, cosim, run, sweep
from .common import CliError

COMMANDS = (run, accuracy, sweep, cosim)
"""The modules that define the commands: each has register(subparsers)."""
REPORTED: tuple[type[BaseException], ...] = (CliError, *USER_ERRORS)
"""Errors reported on one line (exit status 2)."""


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="csfh", description=__doc__, formatter_class=common.HelpFormatter
    )
    parser.add_argument("--version", action="version", version=f"csfh {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for module in COMMANDS:
        module.register(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """The command line: 0 on success, 1 when a command's verdict fails (csfh stress), 2 with
    one line on standard error for bad input or a failed run, 130 on Ctrl-C."""
    try:
        parser = build_parser()
        args = parser.parse_args(argv)
        return int(args.func(args))
    except REPORTED as exc:
        print(f"csfh: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("csfh: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    raise SystemExit(main())
