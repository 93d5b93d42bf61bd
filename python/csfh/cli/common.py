"""What every command of the command line shares: the one-line error, the help layout (every
command has a description, every option its default), argument types and the output directory.

Command modules import only the standard library, this module and constants of light modules at
their top (this module takes the one-line error from csfh.errors and the built-in scenes' names
from csfh.scenes; cli/shock.py its default from csfh.studies.shock); everything else is imported
inside the command, so that `csfh --help` starts in a fraction of a second."""

from __future__ import annotations

import argparse
import math
import re
import textwrap
from pathlib import Path
from typing import Any, NoReturn

from ..errors import CliError as CliError  # the commands' one-line error
from ..scenes import BUILTIN_SCENES

SCENE_HELP = f"built-in scene ({', '.join(BUILTIN_SCENES)}) or the path of a .toml scene file"


NEGATIVE_NUMBER = re.compile(r"^-(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?$|^-(inf|infinity|nan)$", re.I)
"""What an argument that starts with '-' must look like to be a value, not an option."""


class Parser(argparse.ArgumentParser):
    """An argument parser that reports a bad command line on one line, and takes every negative
    number (-1e-3, -.5, -inf) as an option's value, so that the option's own check names it;
    argparse takes only -5 and -0.5 so, and reports "-1e-3" as a missing value. No option of
    csfh looks like a number."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self._negative_number_matcher = NEGATIVE_NUMBER

    def error(self, message: str) -> NoReturn:
        """A bad command line is one line, as every other error (argparse prints the usage
        first); --help shows the usage."""
        self.exit(2, f"{self.prog}: error: {' '.join(message.split())} (see {self.prog} --help)\n")


EMPTY_PATH_OPTIONS = ("out", "export_ssp", "notes", "tolerance")
"""Options that name a file or directory: an empty value is refused, not taken as no value."""


def check_paths(args: argparse.Namespace) -> None:
    """CliError for an empty path (`--out ''` would otherwise mean the default results/...)."""
    for dest in EMPTY_PATH_OPTIONS:
        if getattr(args, dest, None) == "":
            option = "--" + dest.replace("_", "-")
            raise CliError(f"{option} '': an empty path (give a path, or leave {option} out)")


class HelpFormatter(argparse.HelpFormatter):
    """Descriptions wrapped paragraph by paragraph; every option that has a default shows it."""

    def _fill_text(self, text: str, width: int, indent: str) -> str:
        paragraphs = [" ".join(p.split()) for p in text.strip().split("\n\n")]
        return "\n\n".join(
            textwrap.fill(p, width, initial_indent=indent, subsequent_indent=indent)
            for p in paragraphs
        )

    def _get_help_string(self, action: argparse.Action) -> str | None:
        text = action.help or ""
        default = action.default
        if (
            "%(default)" in text
            or "default" in text
            or default is None
            or default is False
            or default is argparse.SUPPRESS
            or not action.option_strings
        ):
            return text
        return f"{text} (default: %(default)s)"


def add_command(
    subparsers: Any, name: str, *, help: str, description: str
) -> argparse.ArgumentParser:
    """A sub-command with its one-line help (in `csfh --help`) and its description."""
    return subparsers.add_parser(
        name, help=help, description=description, formatter_class=HelpFormatter
    )


def add_quiet(p: argparse.ArgumentParser) -> None:
    p.add_argument("--quiet", action="store_true", help="no progress bar, less output")


def out_dir(args: argparse.Namespace, *default: str) -> Path:
    """--out, else results/<default...>: checked now, before the command computes anything
    (a directory it cannot write is found before the run, not after)."""
    from ..output import results_dir
    from ..safepath import check_output_directory

    return check_output_directory(results_dir(args.out, *default))


def add_execution_options(p: argparse.ArgumentParser, command: str) -> None:
    """--out, --workers and --dask of a study of many runs (csfh.studies.execution): the output
    directory keeps every finished run, so that an interrupted study resumes."""
    p.add_argument(
        "--out",
        help="output directory, where finished runs are kept and reused (default: "
        f"results/{command}/SCENE)",
    )
    p.add_argument(
        "--workers",
        type=positive_int,
        metavar="N",
        help="local processes (default: all cores; 1 = serial in this process)",
    )
    p.add_argument(
        "--dask",
        metavar="ADDRESS",
        help="run on an existing Dask distributed scheduler, e.g. tcp://host:8786 (default: "
        "local processes, see --workers)",
    )


def execution(args: argparse.Namespace) -> Any:
    """How a study runs (csfh.studies.execution.Execution), from add_execution_options' options
    and --quiet."""
    from ..studies.execution import Execution

    return Execution(Path(args.out) if args.out else None, args.workers, args.dask, args.quiet)


def positive_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not an integer") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"{text!r} must be >= 1")
    return value


def positive_float(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
    if not (value > 0 and math.isfinite(value)):
        raise argparse.ArgumentTypeError(f"{text!r} must be a finite number > 0")
    return value
