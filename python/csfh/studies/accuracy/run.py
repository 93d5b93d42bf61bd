"""The accuracy study as one call (`run_accuracy`): every integrator at every setting on the
scene's models, and the report (report.md, accuracy.json, work-precision figures)."""

from __future__ import annotations

from pathlib import Path

from ...model.scene import Scene, check_run_horizon
from .report import write_report
from .study import DEFAULT_SETTINGS, QUICK_SETTINGS, run_study


def run_accuracy(
    scene: Scene,
    out: Path,
    *,
    stop_time: float | None = None,
    quick: bool = False,
    repeats: int = 3,
    quiet: bool = True,
) -> Path:
    """Run the study (`quick`: fewer settings) up to `stop_time` (default: through the third
    contact + 20 %), timing each run as the median of `repeats`, and write its report into
    `out`; returns the path of report.md."""
    if stop_time is not None:
        check_run_horizon(scene, stop_time)
    study = run_study(
        scene,
        stop_time=stop_time,
        settings=QUICK_SETTINGS if quick else DEFAULT_SETTINGS,
        repeats=repeats,
        quiet=quiet,
    )
    write_report(study, out)
    return Path(out) / "report.md"
