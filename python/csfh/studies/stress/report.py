"""The stress suite's report: stress.md (the verdicts explained, the cases, one row per run) and
stress.json."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from ...output import output_set, write_json, write_text
from . import suite
from .cases import Case
from .suite import Run


def write_report(cases: Sequence[Case], runs: Sequence[Run], out: Path) -> Path:
    """stress.json and stress.md in `out` (one output set: they replace the previous report's
    files as a whole); returns the path of stress.md."""
    with output_set(out, "stress"):
        return _write_report(cases, runs, out)


def _write_report(cases: Sequence[Case], runs: Sequence[Run], out: Path) -> Path:
    write_json(
        out / "stress.json",
        {
            "runs": [r.__dict__ for r in runs],
            "cases": [
                {"name": c.name, "group": c.group, "description": c.description} for c in cases
            ],
        },
    )
    counts = {v: sum(r.verdict == v for r in runs) for v in ("pass", "limit", "fail")}
    lines = [
        "# Stiff and extreme cases",
        "",
        f"{len(runs)} runs: {counts['pass']} pass, {counts['limit']} documented limits, "
        f"{counts['fail']} fail.",
        "",
        str(suite.__doc__).split("\n\n", 1)[1].strip(),
        "",
        "## Cases",
        "",
    ]
    for c in cases:
        lines.append(f"* **{c.name}**: {c.description}")
    lines += [
        "",
        "## Results",
        "",
        "| case | model | integrator | verdict | reason | wall [s] |",
        "|---|---|---|---|---|---|",
    ]
    for r in runs:
        verdict = {"pass": "pass", "limit": "**limit**", "fail": "**FAIL**"}[r.verdict]
        lines.append(
            f"| {r.case} | {r.model} | {r.integrator} | {verdict} | "
            f"{r.reason.replace('|', '/')} | {r.wall_time:.3g} |"
        )
    return write_text(out / "stress.md", "\n".join(lines) + "\n")
