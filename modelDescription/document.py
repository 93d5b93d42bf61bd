#!/usr/bin/env python3
"""Write an FMU's documentation/index.html from its variables file (variables.toml, combdrive.toml).

A short summary of the model (its description, the interfaces, the states, inputs and outputs)
and the table of its parameters (start value, unit, range, description), all taken from the same
single source of truth as modelDescription.xml (generate.py), so the page cannot drift from it.
The page is built with ElementTree and written as HTML.

Usage: document.py [--version X.Y.Z] VARIABLES_TOML OUT_HTML
"""

from __future__ import annotations

import argparse
import sys
import tomllib
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any

from spec import SpecError, load, package_version, parse_range

STYLE = (
    "body{font-family:sans-serif;max-width:70em;margin:2em auto}"
    "table{border-collapse:collapse}td,th{border:1px solid #bbb;padding:2px 6px;"
    "text-align:left;vertical-align:top}"
)
HEADER = ["name", "start", "unit", "range", "description"]
Inline = str | tuple[str, dict[str, str], str]
"""A piece of a paragraph: text, or (tag, attributes, text) of an inline element."""


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


def _block(parent: ET.Element, tag: str, text: str = "", **attrs: str) -> ET.Element:
    """A block element on a line of its own."""
    element = ET.SubElement(parent, tag, attrs)
    element.text = text or None
    element.tail = "\n"
    return element


def _paragraph(parent: ET.Element, parts: list[Inline]) -> None:
    p = _block(parent, "p")
    last: ET.Element | None = None
    for part in parts:
        if isinstance(part, str):
            if last is None:
                p.text = (p.text or "") + part
            else:
                last.tail = (last.tail or "") + part
            continue
        tag, attrs, text = part
        last = ET.SubElement(p, tag, attrs)
        last.text = text


def _table(parent: ET.Element, rows: list[list[str]]) -> None:
    table = _block(parent, "table")
    table.text = "\n"
    for tag, cells in [("th", HEADER)] + [("td", row) for row in rows]:
        tr = _block(table, "tr")
        for cell in cells:
            ET.SubElement(tr, tag).text = cell


def _rows(selected: list[dict[str, Any]], enums: dict[str, dict[str, Any]]) -> list[list[str]]:
    return [
        [v["name"], _value(v, enums), v.get("unit", ""), _range(v, enums), v.get("description", "")]
        for v in selected
    ]


def _summary(body: ET.Element, spec: dict[str, Any]) -> None:
    model = spec["model"]
    variables = spec["variables"]
    interfaces = "model exchange"
    if "cosimulation" in spec:
        interfaces += " and co-simulation (the FMU advances itself in fmi2DoStep)"
    n_states = sum(1 for v in variables if v.get("state"))
    n_parameters = sum(1 for v in variables if v["causality"] == "parameter")
    _block(body, "h1", model["modelName"])
    _block(body, "p", model["description"])
    _block(
        body,
        "p",
        f"FMI 2.0, {interfaces}; version {model['version']}, {n_states} continuous states, "
        f"{model['numberOfEventIndicators']} event indicator(s), {n_parameters} parameters. "
        "Start values are the defaults of the parameter table below.",
    )
    _paragraph(
        body,
        [
            "The binaries are built from ",
            ("code", {}, "sources/"),
            " (the model's own sources and the SUNDIALS modules it uses, with a fixed "
            "configuration header); compile every ",
            ("code", {}, "sources/*.c"),
            " listed in modelDescription.xml with ",
            ("code", {}, "-I sources"),
            " and the FMI 2.0 headers. SUNDIALS is distributed under the BSD 3-clause licence: ",
            ("a", {"href": "licenses/SUNDIALS-LICENSE.txt"}, "licence"),
            ", ",
            ("a", {"href": "licenses/SUNDIALS-NOTICE.txt"}, "notice"),
            ".",
        ],
    )


def index_html(spec: dict[str, Any]) -> str:
    """The page: summary, states/inputs/outputs, parameters."""
    variables = spec["variables"]
    enums = {e["name"]: e for e in spec.get("enumerations", [])}
    html = ET.Element("html", lang="en")
    html.text = "\n"
    head = _block(html, "head")
    head.text = "\n"
    _block(head, "meta", charset="utf-8")
    _block(head, "title", spec["model"]["modelName"])
    _block(head, "style", STYLE)
    body = _block(html, "body")
    body.text = "\n"
    _summary(body, spec)
    sections = (
        ("States", [v for v in variables if v.get("state")]),
        ("Inputs", [v for v in variables if v["causality"] == "input"]),
        ("Outputs", [v for v in variables if v["causality"] == "output" and not v.get("state")]),
    )
    for title, selected in sections:
        if selected:
            _block(body, "h2", title)
            _table(body, _rows(selected, enums))
    _block(body, "h2", "Parameters")
    _table(body, _rows([v for v in variables if v["causality"] == "parameter"], enums))
    return "<!DOCTYPE html>\n" + ET.tostring(html, encoding="unicode", method="html") + "\n"


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
    args.out.write_text(text, encoding="utf-8")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
