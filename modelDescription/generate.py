#!/usr/bin/env python3
"""Generate modelDescription.xml, the C variable table and the Python module from variables.toml.

variables.toml is the single source of truth of the FMU interface: value references, names,
types, start values, ranges, units and the C storage of every variable. This script writes

    <outdir>/modelDescription.xml
    <outdir>/csfh_variables.h    (value references, enumerations, GUID)
    <outdir>/csfh_variables.c    (the table the FMI glue and the core library use)
    <outdir>/csfh_enums.h        (the enumerations as C enums)
    <outdir>/csfh_constants.h    (the defaults and ABI versions C and Python share)

and, with --python-dir, the Python module of the same interface and constants
(python/csfh/model/_csfh_variables.py, committed: python_module.py).

With --fmi-version 3 the model description is FMI 3.0's (the same variables, value references,
start values, ranges and instantiation token; the C files are the same): the FMI 3.0 build of
the FMU (fmu_src/fmu/fmi3/fmi3_glue.c) packages it. The FMI 3.0 co-simulation capabilities are the
[cosimulation] table's (translated) plus [fmi3_cosimulation]; the model-exchange event
indicators are the variables named by [model] event_indicator_variables (FMI 3.0 declares each
event indicator as a variable).

The same script serves every model of the repository (combdrive.toml: the comb-drive actuator).
Optional keys of [model] name the C side; their defaults are the csfh model's:

    c_prefix = "csfh"                 file names <prefix>_variables.h ..., macros <PREFIX>_...,
                                      the table <prefix>_variables[]
    c_struct = "csfh_model_t"         the C struct the table's offsets refer to
    c_include = "csfh_model.h"        the header that declares it
    log_events_description = "..."    description of the logEvents log category

The writers: fmi_xml.py (modelDescription.xml, one writer for both FMI versions), c_code.py (the
C files) and python_module.py; spec.py reads and checks the variables file. The model's
`version` is the package's (python/csfh/_version.py, the one place of the version; CMake passes
it as --version).

Usage: generate.py [--version X.Y.Z] [--fmi-version 2|3] VARIABLES_TOML [OUTDIR]
                   [--source-files NAME ...] [--python-dir DIR]
"""

from __future__ import annotations

import argparse
import sys
import tomllib
from pathlib import Path

from c_code import c_constants, c_enums, c_header, c_source
from fmi_xml import model_description
from python_module import module_name, python_module
from spec import Spec, SpecError, build_epoch, c_names, guid_of, load, package_version


def parse_args(argv: list[str]) -> argparse.Namespace:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--version", help="model version (default: python/csfh/_version.py)")
    ap.add_argument("variables", type=Path)
    ap.add_argument("outdir", type=Path, nargs="?", help="where the XML and the C files go")
    ap.add_argument(
        "--epoch",
        type=int,
        default=None,
        help="generationDateAndTime in seconds since 1970 (default: $SOURCE_DATE_EPOCH, else now)",
    )
    ap.add_argument(
        "--fmi-version",
        type=int,
        choices=(2, 3),
        default=2,
        help="the FMI version of modelDescription.xml (the C files are the same)",
    )
    ap.add_argument(
        "--source-files",
        nargs="+",
        default=[],
        metavar="NAME",
        help="the .c files under the FMU's sources/ (written as <SourceFiles>)",
    )
    ap.add_argument(
        "--python-dir",
        type=Path,
        metavar="DIR",
        help="write the Python module of the interface, _<prefix>_variables.py, into DIR "
        "(the package's copy: python/csfh/model)",
    )
    args = ap.parse_args(argv)
    if args.outdir is None and args.python_dir is None:
        ap.error("give OUTDIR, --python-dir or both")
    return args


def read_spec(args: argparse.Namespace) -> Spec:
    """The variables file with the model's version (SpecError when it is wrong)."""
    spec = load(args.variables)
    if "version" in spec["model"]:
        raise SpecError("[model] version: the version comes from python/csfh/_version.py")
    spec["model"]["version"] = args.version or package_version()
    return spec


def build_files(spec: Spec, args: argparse.Namespace) -> dict[str, str]:
    """modelDescription.xml and the C files, by name."""
    guid = guid_of(spec)
    prefix = c_names(spec)[0]
    source = args.variables.name
    description = model_description(
        spec, guid, build_epoch(args.epoch), args.fmi_version, tuple(args.source_files)
    )
    return {
        "modelDescription.xml": description,
        f"{prefix}_variables.h": c_header(spec, guid, source),
        f"{prefix}_enums.h": c_enums(spec, source),
        f"{prefix}_variables.c": c_source(spec, source),
        f"{prefix}_constants.h": c_constants(spec, source),
    }


def write_changed(directory: Path, files: dict[str, str]) -> None:
    """Write the files whose text changed (an unchanged file keeps its time: no rebuild)."""
    directory.mkdir(parents=True, exist_ok=True)
    for name, text in files.items():
        path = directory / name
        if not path.exists() or path.read_text(encoding="utf-8") != text:
            path.write_text(text, encoding="utf-8")


def main(argv: list[str]) -> int:
    args = parse_args(argv)
    try:
        spec = read_spec(args)
        if args.outdir is not None:
            write_changed(args.outdir, build_files(spec, args))
        if args.python_dir is not None:
            text = python_module(spec, args.variables.name)
            write_changed(args.python_dir, {module_name(spec): text})
    except (SpecError, KeyError, OSError, tomllib.TOMLDecodeError) as exc:
        print(f"generate.py: {args.variables}: {exc}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
