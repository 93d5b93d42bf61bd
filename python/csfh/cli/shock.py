"""`csfh shock SCENE`: a half-sine shock pulse (by peak and duration, or a standard condition by
name) in one direction or a sweep of directions, every event-driven model; the peak flexure
stress and contact pressure against their allowables, pass or fail per direction; with
--tolerance, a Monte Carlo over tolerances that gives the probability of exceeding them."""

from __future__ import annotations

import argparse
import math
from typing import Any

from ..studies.shock import DEFAULT_DIRECTIONS
from .common import SCENE_HELP, CliError, add_command, add_execution_options, add_quiet, execution


def register(sub: Any) -> None:
    p = add_command(
        sub,
        "shock",
        help="shock survivability: peak stresses under a half-sine pulse, Monte Carlo",
        description="Shake the frame (body 2) with a half-sine acceleration pulse, by peak and "
        "duration or a standard condition by name (JESD22-B104-A..G, MIL-STD-883-2002-A..G; "
        "--list-conditions), in one direction or a sweep of directions over 360 degrees, with "
        "every event-driven model; write shock.md (peak flexure stress and contact pressure, "
        "margins, pass or fail per direction), shock.json and figures. With --tolerance FILE, "
        "sample the file's tolerances and give the probability of exceeding each allowable, "
        "with its Clopper-Pearson interval. Body 1 starts at the scene's configuration at rest. "
        "The runs are batched in the FMU's own binary and kept in the output directory (an "
        "interrupted command resumes).",
    )
    p.add_argument("scene", nargs="?", help=SCENE_HELP)
    _pulse_options(p)
    _study_options(p)
    add_quiet(p)
    p.set_defaults(func=cmd_shock)


def _pulse_options(p: argparse.ArgumentParser) -> None:
    """The pulse, its start and directions."""
    p.add_argument(
        "--condition",
        metavar="NAME",
        help="standard condition, e.g. JESD22-B104-B (default: JESD22-B104-B, 1500 g, 0.5 ms, "
        "unless --peak and --duration are given)",
    )
    p.add_argument(
        "--peak",
        metavar="G",
        help="peak acceleration in g (9.80665 m/s2), with --duration (default: the condition's)",
    )
    p.add_argument(
        "--duration",
        metavar="T",
        help="pulse duration in s, with --peak (default: the condition's)",
    )
    p.add_argument("--start", metavar="T", default="0", help="time at which the pulse starts, s")
    p.add_argument(
        "--direction",
        metavar="DEG",
        help="one direction of the frame's acceleration, degrees counter-clockwise from the "
        "global X axis (90: upward) (default: a sweep, see --directions)",
    )
    p.add_argument(
        "--directions",
        metavar="N",
        help="number of directions evenly over 360 degrees, from 0 (default: "
        f"{DEFAULT_DIRECTIONS})",
    )


def _study_options(p: argparse.ArgumentParser) -> None:
    """The models, the runs, the Monte Carlo, where and how the runs are computed."""
    p.add_argument(
        "--models",
        nargs="+",
        metavar="MODEL",
        help="event-driven models (default: all, LN_spheres LN_cylinders LN_ESDU HuntCrossley "
        "Flores)",
    )
    p.add_argument("--stop-time", metavar="T", help="horizon in s (default: the scene's stop_time)")
    p.add_argument(
        "--step",
        metavar="H",
        help="communication step of the runs in s: the peaks inside each step are located on "
        "the integrator's interpolant whatever it is (default: 10 x the scene's "
        "output_interval; the figure of stresses over time is drawn on the output_interval)",
    )
    p.add_argument(
        "--tolerance",
        metavar="FILE",
        help="Monte Carlo over the [tolerance] table of FILE (a tolerance file or a built-in "
        "one such as tolerance_csfh, tolerance_mems) at each model's worst direction (default: "
        "no Monte Carlo)",
    )
    p.add_argument(
        "--runs",
        metavar="N",
        help="Monte Carlo samples per model (default: the file's [montecarlo] runs, else 200)",
    )
    p.add_argument("--seed", metavar="S", help="random seed >= 0 (default: the file's, else 1)")
    add_execution_options(p, "shock")
    p.add_argument(
        "--list-conditions", action="store_true", help="print the standard conditions and exit"
    )


def _number(option: str, text: str | None, *, positive: bool = False) -> float | None:
    if text is None:
        return None
    try:
        value = float(text)
    except ValueError:
        raise CliError(f"{option} = {text!r} is not a number") from None
    if not math.isfinite(value) or (positive and not value > 0):
        raise CliError(
            f"{option} = {text!r} must be a finite number" + (" > 0" if positive else "")
        )
    return value


def _count(option: str, text: str | None, minimum: int) -> int | None:
    if text is None:
        return None
    try:
        value = int(text)
    except ValueError:
        raise CliError(f"{option} = {text!r} is not an integer") from None
    if value < minimum:
        raise CliError(f"{option} = {value} must be >= {minimum}")
    return value


def _pulse(args: argparse.Namespace, peak: float | None, duration: float | None) -> Any:
    from ..studies.shock import conditions

    if args.condition is not None and (peak is not None or duration is not None):
        raise CliError("give either --condition or --peak and --duration, not both")
    if (peak is None) != (duration is None):
        raise CliError("--peak and --duration go together")
    if peak is not None and duration is not None:
        return conditions.pulse(peak, duration)
    return conditions.condition(args.condition or conditions.DEFAULT_CONDITION)


def _request(args: argparse.Namespace) -> Any:
    """The study's request from the options, every number checked first (a typo costs no
    run)."""
    from ..studies.shock.run import ShockRequest

    peak = _number("--peak", args.peak, positive=True)
    duration = _number("--duration", args.duration)
    if duration is not None and not duration > 0:
        raise CliError(f"--duration = {args.duration!r} s must be > 0")
    start = _number("--start", args.start)
    assert start is not None
    if start < 0:
        raise CliError(f"--start = {args.start!r} s must be >= 0")
    direction = _number("--direction", args.direction)
    n_dirs = _count("--directions", args.directions, 1)
    if direction is not None and n_dirs is not None:
        raise CliError("give either --direction or --directions, not both")
    stop = _number("--stop-time", args.stop_time, positive=True)
    step = _number("--step", args.step, positive=True)
    runs = _count("--runs", args.runs, 1)
    seed = _count("--seed", args.seed, 0)
    if args.tolerance is None and (runs is not None or seed is not None):
        raise CliError("--runs and --seed need --tolerance FILE")
    return ShockRequest(
        scene=args.scene,
        pulse=_pulse(args, peak, duration),
        start=start,
        direction=direction,
        directions=n_dirs,
        models=tuple(args.models) if args.models else None,
        stop_time=stop,
        step=step,
        tolerance=args.tolerance,
        runs=runs,
        seed=seed,
    )


def _print(outcome: Any, quiet: bool) -> None:
    result, mc, info = outcome.result, outcome.montecarlo, outcome.run_info
    if not quiet:
        for m, r in result["models"].items():
            print(
                f"  {m:<13} worst {r['worst_direction']:g}°: flexure margin "
                f"{r['min_flexure_margin']:+.3f}, contact margin {r['min_contact_margin']:+.3f}"
                f" -> {'pass' if r['passed'] else 'FAIL'}"
            )
        for m, r in (mc["models"] if mc is not None else {}).items():
            p = r["probability"]["either"]
            print(
                f"  {m:<13} P(exceeding an allowable) = {p['p']:.3g} "
                f"[{p['low']:.3g}, {p['high']:.3g}] ({p['runs']} samples)"
            )
    print(
        f"shock: {'PASS' if outcome.passed else 'FAIL'}, {info['tasks']} runs "
        f"({info['computed']} computed, {info['reused']} reused, {info['executor']}) -> "
        f"{outcome.path}"
    )


def cmd_shock(args: argparse.Namespace) -> int:
    from ..studies.shock import conditions
    from ..studies.shock.run import run_shock

    if args.list_conditions:
        for c in conditions.CONDITIONS.values():
            print(f"{c.name:<20} {c.peak_g:>7g} g {c.duration * 1e3:>5g} ms   {c.source}")
        return 0
    if args.scene is None:
        raise CliError("shock needs a SCENE (a built-in scene or a .toml file)")
    request = _request(args)
    outcome = run_shock(request, execution(args))
    _print(outcome, args.quiet)
    return 0 if outcome.passed else 1
