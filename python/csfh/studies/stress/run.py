"""The stress suite as one call (`run_stress`): the selected cases, every run with its verdict,
and the report (stress.md, stress.json)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from ...errors import ParameterError
from .cases import Case, select_cases
from .report import write_report
from .suite import Run, run_suite

VERDICTS = ("pass", "limit", "fail")


@dataclass
class StressOutcome:
    """The runs of the suite, each with its verdict, and the report's path."""

    runs: list[Run]
    path: Path

    def counts(self) -> dict[str, int]:
        """How many runs got each verdict."""
        return {v: sum(r.verdict == v for r in self.runs) for v in VERDICTS}


def cases_of(quick: bool = False, only: str | None = None) -> list[Case]:
    """The selected cases (csfh.studies.stress.cases.select_cases); ParameterError if `only`
    matches none."""
    cases = select_cases(quick=quick, only=only)
    if not cases:
        raise ParameterError(f"--only = {only!r} matches no case (csfh stress --list)")
    return cases


def run_stress(
    out: Path, *, quick: bool = False, only: str | None = None, quiet: bool = True
) -> StressOutcome:
    """Run the selected cases (`quick`: the reduced suite; `only`: the cases whose name
    contains it or whose group it is) and write the report into `out`."""
    cases = cases_of(quick, only)
    runs = run_suite(cases, quiet=quiet)
    return StressOutcome(runs, write_report(cases, runs, out))
