#!/usr/bin/env python3
"""Write an FMU's documentation/index.html from its variables file (variables.toml, combdrive.toml).

A short summary of the model (its description, the interfaces, the states, inputs and outputs)
and the table of its parameters (start value, unit, range, description), all taken from the same
single source of truth as modelDescription.xml (generate.py), so the page cannot drift from it.

Usage: document.py [--version X.Y.Z] VARIABLES_TOML OUT_HTML
"""

from __future__ import annotations

import argparse
import html
import sys
import tomllib
from pathlib import Path
from typing import Any

from generate import SpecError, load, package_version, parse_range


def _value(v: dict[str, Any], enums: dict[str, dict[str, Any]]) -> str:
    if "start" not in v:
        return "calculated"
    start = v["start"]
    if v["type"] == "Boolean":
        return "true" if start else "false"
    if v["type"] == "Enumeration":
        items = {it["value"]: it["name"] for it in enums[v["declaredType"]]["items"]}
        return f"{items.get(int(start), start)} ({int(start)})"
    if v["type"] == "Integer":
        return str(int(start))
    return f"{float(start):.6g}"


def _range(v: dict[str, Any], enums: dict[str, dict[str, Any]]) -> str:
    if v["type"] == "Enumeration":
        return ", ".join(it["name"] for it in enums[v["declaredType"]]["items"])
    if "range" not in v:
        return ""
    lo, hi, lo_open, hi_open = parse_range(v["range"])
    left = "(" if lo_open else "["
    right = ")" if hi_open else "]"
    return f"{left}{lo:g}, {hi:g}{right}"


def _table(rows: list[list[str]], header: list[str]) -> list[str]:
    out = ["<table>", "<tr>" + "".join(f"<th>{html.escape(h)}</th>" for h in header) + "</tr>"]
    for row in rows:
        out.append("<tr>" + "".join(f"<td>{html.escape(c)}</td>" for c in row) + "</tr>")
    out.append("</table>")
    return out


def index_html(spec: dict[str, Any]) -> str:
    """The page: summary, states/inputs/outputs, parameters."""
    model = spec["model"]
    variables = spec["variables"]
    enums = {e["name"]: e for e in spec.get("enumerations", [])}
    name = html.escape(model["modelName"])

    def rows(selected: list[dict[str, Any]]) -> list[list[str]]:
        return [
            [
                v["name"],
                _value(v, enums),
                v.get("unit", ""),
                _range(v, enums),
                v.get("description", ""),
            ]
            for v in selected
        ]

    header = ["name", "start", "unit", "range", "description"]
    states = [v for v in variables if v.get("state")]
    inputs = [v for v in variables if v["causality"] == "input"]
    outputs = [v for v in variables if v["causality"] == "output" and not v.get("state")]
    parameters = [v for v in variables if v["causality"] == "parameter"]
    interfaces = "model exchange"
    if "cosimulation" in spec:
        interfaces += " and co-simulation (the FMU advances itself in fmi2DoStep)"
    out = [
        "<!DOCTYPE html>",
        '<html lang="en">',
        "<head>",
        '<meta charset="utf-8">',
        f"<title>{name}</title>",
        "<style>body{font-family:sans-serif;max-width:70em;margin:2em auto}"
        "table{border-collapse:collapse}td,th{border:1px solid #bbb;padding:2px 6px;"
        "text-align:left;vertical-align:top}</style>",
        "</head>",
        "<body>",
        f"<h1>{name}</h1>",
        f"<p>{html.escape(model['description'])}</p>",
        f"<p>FMI 2.0, {html.escape(interfaces)}; version {html.escape(model['version'])}, "
        f"{len(states)} continuous states, {model['numberOfEventIndicators']} event "
        f"indicator(s), {len(parameters)} parameters. Start values are the defaults of the "
        "parameter table below.</p>",
        "<p>The binaries are built from <code>sources/</code> (the model's own sources and the "
        "SUNDIALS modules it uses, with a fixed configuration header); compile every "
        "<code>sources/*.c</code> listed in modelDescription.xml with <code>-I sources</code> "
        "and the FMI 2.0 headers. SUNDIALS is distributed under the BSD 3-clause licence: "
        '<a href="licenses/SUNDIALS-LICENSE.txt">licence</a>, '
        '<a href="licenses/SUNDIALS-NOTICE.txt">notice</a>.</p>',
    ]
    for title, selected in (("States", states), ("Inputs", inputs), ("Outputs", outputs)):
        if selected:
            out.append(f"<h2>{title}</h2>")
            out.extend(_table(rows(selected), header))
    out.append("<h2>Parameters</h2>")
    out.extend(_table(rows(parameters), header))
    out += ["</body>", "</html>"]
    return "\n".join(out) + "\n"


def main(argv: list[str]) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--version", help="model version (default: python/csfh/_version.py)")
    ap.add_argument("variables", type=Path)
    ap.add_argument("out", type=Path)
    args = ap.parse_args(argv)
    try:
        spec = load(args.variables)
        spec["model"]["version"] = args.version or package_version()
        text = index_html(spec)
    except (SpecError, KeyError, OSError, tomllib.TOMLDecodeError) as exc:
        print(f"document.py: {args.variables}: {exc}", file=sys.stderr)
        return 1
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(text)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
