"""Design-study throughput: a study of the `mems` scene with 10 000 sampled designs (the built-in
study's variables, shock and constraints; one direction of the shock, 90 degrees, unless
--directions says otherwise; a search of one population, no sensitivity analysis), run end to
end by `csfh.design` into a fresh directory: designs per second per core, and the runs per
second behind them, for the whole study (tasks, result store, the static parasitic solve of
every design, the Pareto front, the report and its figures) beside the runs' own time (summed
over the workers, as the result store records it).

Run: python benchmarks/bench_design.py [--designs 10000] [--directions 1] [--workers N] [--quick]
"""

from __future__ import annotations

import argparse
import tempfile
import time
import tomllib
from importlib import resources
from pathlib import Path


def study_text(designs: int, directions: int) -> str:
    """The built-in mems study with `designs` samples, `directions` directions, one search
    population and no sensitivity analysis."""
    text = resources.files("csfh.studies.design").joinpath("studies", "mems.toml").read_text()
    data = tomllib.loads(text)
    dirs = [90.0] if directions == 1 else None
    lines = ["[variables]"]
    lines += [f'"{k}" = [{lo!r}, {hi!r}]' for k, (lo, hi) in data["variables"].items()]
    shock = data["shock"]
    lines += [
        "[shock]",
        f'condition = "{shock["condition"]}"',
        f"directions = {dirs if dirs else directions}",
        f'law = "{shock["law"]}"',
        "[constraints]",
        *(f"{k} = {v!r}" for k, v in data["constraints"].items()),
        "[objectives]",
        f"names = {data['objectives']['names']}",
        f'search = "{data["objectives"]["search"]}"',
        f"parasitic_moment = {data['objectives']['parasitic_moment']!r}",
        "[sampling]",
        f"samples = {designs}",
        "[search]",
        "generations = 0",
        "population = 1",
        "[sensitivity]",
        "samples = 0",
    ]
    return "\n".join(lines).replace("'", '"') + "\n"


def _parasitic_time(designs: list[dict]) -> float:
    """The static parasitic solve of `designs` again, s per design."""
    from csfh import load_scene
    from csfh.studies.design.evaluate import parasitic

    scene = load_scene("mems")
    t0 = time.perf_counter()
    for d in designs:
        parasitic(scene, d["parameters"], 1e-9)
    return (time.perf_counter() - t0) / len(designs)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--designs", type=int, default=10_000)
    parser.add_argument("--directions", type=int, default=1)
    parser.add_argument("--workers", type=int, default=None, help="default: all cores")
    parser.add_argument("--quick", action="store_true", help="1000 designs (a smoke run)")
    args = parser.parse_args()
    from csfh.batch.executors import default_workers
    from csfh.batch.store import ResultStore
    from csfh.studies.design.run import design

    n = 1000 if args.quick else args.designs
    workers = args.workers or default_workers()
    with tempfile.TemporaryDirectory() as tmp:
        study = Path(tmp) / "study.toml"
        study.write_text(study_text(n, args.directions))
        t0 = time.perf_counter()
        outcome = design("mems", study, out=Path(tmp) / "out", workers=workers)
        wall = time.perf_counter() - t0
        records = ResultStore(Path(tmp) / "out").records
        inside = sum(float(r.get("wall_time", 0.0)) for r in records.values())
    result, info = outcome.result, outcome.run_info
    evaluated = len(result["samples"]) + result["search"]["evaluated"] + 3
    runs = info["tasks"]
    print(
        f"Design study of mems: {evaluated} designs x {args.directions} direction(s) = "
        f"{runs} shock runs ({info['computed']} computed) on {workers} worker(s)"
    )
    print(f"  whole study        {wall:8.1f} s  {evaluated / wall / workers:8.1f} designs/s/core")
    print(f"                                 {runs / wall / workers:8.1f} runs/s/core")
    print(f"  the runs alone     {inside:8.1f} s  {evaluated / inside:8.1f} designs/s/core")
    print(f"                                 {info['computed'] / inside:8.1f} runs/s/core")
    parasitic = _parasitic_time(result["designs"][:200])
    print(f"  the parasitic solve {parasitic * 1e3:7.2f} ms per design (in the parent)")
    share = parasitic * evaluated / (wall * workers)
    print(f"    {share:.2f} of the study's core time, {inside / (wall * workers):.2f} the runs")
    feasible = sum(d["feasible"] for d in result["designs"])
    print(f"  feasible {feasible} of {len(result['designs'])}, front {len(result['front'])}")


if __name__ == "__main__":
    main()
