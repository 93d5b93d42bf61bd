"""csfh: dynamics of a Conjugate-Surface Flexure Hinge with impacts and friction.

Scenes are TOML files (built-in: see `csfh run --help`). Models: the FMU's contact laws
LN_spheres, LN_cylinders, LN_ESDU, HuntCrossley, Flores (event-driven) and Moreau.
`csfh COMMAND --help` describes each command."""

# Only the standard library's sys is imported at the top: everything else (the commands, argparse,
# numpy, ...) is imported inside main's error handling, so that a Ctrl-C or a failure while the
# command starts up is reported like one that happens later (one line, no traceback).

from __future__ import annotations

import sys
from collections.abc import Sequence
from typing import Any


def build_parser() -> Any:
    """The argument parser (argparse.ArgumentParser) of every command."""
    from .._version import __version__
    from . import accuracy, common, cosim, design, linearize, run, shock, sweep

    parser = common.Parser(prog="csfh", description=__doc__, formatter_class=common.HelpFormatter)
    parser.add_argument("--version", action="version", version=f"csfh {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    # each module defines its commands
    for module in (run, accuracy, sweep, shock, design, cosim, linearize):
        module.register(sub)
    return parser


def reported_errors() -> tuple[type[BaseException], ...]:
    """Errors reported on one line (exit status 2): csfh's own (csfh.errors: bad input, a failed
    run, a file that cannot be read or written, a missing binary) and memory exhausted. Anything
    else is a bug in csfh and shows its traceback."""
    from ..errors import USER_ERRORS

    return USER_ERRORS


def one_line(exc: BaseException) -> str:
    """The message of an error on one line (messages of the FMU, CVODE or libcosim may hold
    line breaks)."""
    text = " ".join(str(exc).split())
    return text or type(exc).__name__


def main(argv: Sequence[str] | None = None) -> int:
    """The command line: 0 on success, 1 when a command's verdict fails (csfh stress, csfh
    shock), 2 with one line on standard error for bad input or a failed run, 130 on Ctrl-C (at
    any moment, also while the command starts up)."""
    try:
        try:
            from .common import check_paths

            parser = build_parser()
            args = parser.parse_args(argv)
            check_paths(args)
            return int(args.func(args))
        except Exception as exc:
            if isinstance(exc, reported_errors()):
                print(f"csfh: error: {one_line(exc)}", file=sys.stderr)
                return 2
            raise
    except KeyboardInterrupt:
        print("csfh: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    raise SystemExit(main())
