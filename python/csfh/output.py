"""Every file that csfh writes goes through this module, and so do the readers of the tables it
writes: text (reports), JSON, CSV tables with the unit of each column in the header, and figures.

All writers end in `_write_bytes`, the one place that decides how a file reaches the disk. (The
result store of batched runs, `csfh.batch.store`, keeps its own append-only index.)

CSV tables: one header line ``name [unit],name [unit],...``, then one row per sample, numbers with
ten significant digits (`read_table` gives the columns back to that precision)."""

from __future__ import annotations

import io
import json
import re
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

CSV_DIGITS = 10
"""Significant digits of the numbers in a CSV table."""
_HEADER_FIELD = re.compile(r"^\s*(?P<name>[^\[\]]+?)\s*(?:\[(?P<unit>[^\[\]]*)\])?\s*$")


def _write_bytes(path: Path, data: bytes) -> Path:
    path = Path(path)
    path.write_bytes(data)
    return path


def write_text(path: Path, text: str) -> Path:
    """A text file (UTF-8)."""
    return _write_bytes(path, text.encode("utf-8"))


def write_json(path: Path, data: Any) -> Path:
    """A JSON file, indented, keys in the order given."""
    return write_text(path, json.dumps(data, indent=2, sort_keys=False) + "\n")


def write_table(
    path: Path, columns: Mapping[str, np.ndarray], units: Mapping[str, str] | None = None
) -> Path:
    """A CSV table of equally long columns, in the order given; the header names each column and
    its unit (`units`, "-" where it has none)."""
    names = list(columns)
    if not names:
        raise ValueError(f"{path}: a table needs at least one column")
    units = units or {}
    header = ",".join(f"{n} [{units.get(n, '-')}]" for n in names)
    data = np.column_stack([np.asarray(columns[n], dtype=float) for n in names])
    buffer = io.StringIO()
    np.savetxt(buffer, data, delimiter=",", header=header, comments="", fmt=f"%.{CSV_DIGITS}g")
    return write_text(path, buffer.getvalue())


def read_table(path: Path) -> tuple[dict[str, np.ndarray], dict[str, str]]:
    """The columns and units of a CSV table that `write_table` wrote. Raises ValueError naming
    the file for anything else."""
    path = Path(path)
    with open(path, encoding="utf-8") as fh:
        header = fh.readline().rstrip("\r\n")
    if not header:
        raise ValueError(f"{path}: empty file, not a csfh table")
    names: list[str] = []
    units: dict[str, str] = {}
    for field in header.split(","):
        m = _HEADER_FIELD.match(field)
        if m is None or not m.group("name"):
            raise ValueError(f"{path}: header field {field!r} is not 'name [unit]'")
        name = m.group("name")
        if name in units:
            raise ValueError(f"{path}: column {name!r} appears twice")
        names.append(name)
        units[name] = m.group("unit") if m.group("unit") is not None else "-"
    try:
        data = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    except ValueError as exc:
        raise ValueError(f"{path}: not a table of numbers: {exc}") from None
    if data.size == 0:
        data = np.zeros((0, len(names)))
    if data.shape[1] != len(names):
        raise ValueError(f"{path}: {data.shape[1]} values per row, {len(names)} columns named")
    return {n: data[:, i].copy() for i, n in enumerate(names)}, units


def save_figure(fig: Any, path: Path, **savefig: Any) -> Path:
    """A matplotlib figure, in the format of the file's suffix (default png)."""
    path = Path(path)
    buffer = io.BytesIO()
    fig.savefig(buffer, format=path.suffix.lstrip(".") or "png", **savefig)
    return _write_bytes(path, buffer.getvalue())
