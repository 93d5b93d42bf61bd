"""The FMU in importers other than the harness.

Our own conformance importers (tests/importers/, plain C, built into build/importers/) run the
`central`, `asymmetric` and `csfh` scenes and are compared with fmpy model exchange at rtol 1e-10
(the harness's simulate_me):

  (a) model exchange, CVODE re-initialised only when fmi2NewDiscreteStates says so,
  (b) model exchange, CVODE re-initialised at every event,
  (c) model exchange, explicit Euler at the DefaultExperiment stepSize,
  (d) co-simulation, variable communication steps with rollback through the FMU state,

and the FMI 3.0 build (build/fmi3/csfh.fmu) through the FMI 3.0 importers, against the same FMI 2.0
references with the same tolerances:

  (a3) model exchange, CVODE re-initialised only when fmi3UpdateDiscreteStates says so (and (b3)
       always),
  (c3) model exchange, explicit Euler at the DefaultExperiment stepSize, time events (a shock
       pulse's ends) ending a step,
  (d3) co-simulation with early return (earlyReturnAllowed, eventModeUsed), variable
       communication steps restarting at every lastSuccessfulTime, rollback through
       fmi3GetFMUState/SetFMUState (in memory and serialized); every contact onset must end a
       communication step within 1e-9 s of the reference's onset.

Tolerances (stated per quantity, a few times what was observed, tied to the integrator):
the CVODE importers and the CS master at rtol 1e-10 agree with the reference (the CS master's:
fmpy model exchange at rtol 1e-13) on positions to 5e-8 m (observed <= 1e-8 m: two BDF runs at
1e-10 that differ in their step sequences), on the
contact times to 1e-7 s (observed <= 3e-8 s), on vy to 2e-4 m/s (the timing difference times
the contact deceleration, ~3e3 m/s^2) and on F_N to 2e-4 of its peak (same reason). Euler is
first order: before the first contact its error is the free-fall bound g h t / 2 (checked against
g h t); the first onset comes at most one step late plus that drift; over the whole run it must
stay physical: the gap never below -5e-4 m and no energy gain beyond 1 %.
"""

from __future__ import annotations

import os
import subprocess
from functools import cache
from pathlib import Path

import numpy as np
import pytest
from fmpy import read_model_description
from fmu_instances import built
from oracles import G

from csfh.model.scene import Scene, load_scene
from csfh.runners.fmu import STATE_NAMES, simulate_me

ROOT = Path(__file__).resolve().parents[2]
SCENES = ("central", "asymmetric", "csfh")
LAW = "LN_spheres"
OUTPUTS = (*STATE_NAMES, "contact.gap", "contact.F_N", "energy.total", "contact.F_N_peak")
COLUMN = {"body1.x": "x", "body1.y": "y", "body1.vy": "vy", "contact.F_N": "F_N"}


def importer(name: str) -> Path:
    directory = Path(os.environ.get("CSFH_IMPORTERS_DIR", ROOT / "build" / "importers"))
    return built(directory / f"csfh_import_{name}")


def start_values(scene: Scene) -> list[str]:
    """NAME=VALUE arguments: the scene's parameters, initial state and inputs."""
    values: dict[str, object] = dict(scene.parameter_values(LAW))
    values.update(zip(STATE_NAMES, scene.x0, strict=True))
    values.update(scene.inputs)
    args = []
    for name, value in values.items():
        if isinstance(value, bool):
            text = "true" if value else "false"
        else:
            text = repr(value)
        args.append(f"{name}={text}")
    return args


class Run:
    """One importer run: the CSV table, the events and the summary."""

    def __init__(self, directory: Path, tag: str) -> None:
        self.out = directory / f"{tag}.csv"
        self.events_path = directory / f"{tag}_events.csv"
        self.summary_path = directory / f"{tag}.txt"
        self.summary: dict[str, str] = {}

    def load(self) -> None:
        for line in self.summary_path.read_text().splitlines():
            key, _, value = line.partition(" = ")
            self.summary[key] = value
        data = np.genfromtxt(self.out, delimiter=",", names=True, deletechars="")
        self.table = {name: np.atleast_1d(data[name]) for name in data.dtype.names}
        self.event_times = np.zeros(0)
        if self.events_path.exists():
            rows = self.events_path.read_text().splitlines()[1:]
            self.event_times = np.array([float(r.split(",")[0]) for r in rows])

    def grid(self) -> np.ndarray:
        """Rows at output points (not the rows written at the events)."""
        return ~np.isin(self.table["time"], self.event_times)

    def value(self, key: str) -> float:
        return float(self.summary[key])


def run_importer(
    name: str, fmu_dir: str, scene: Scene, tmp: Path, *options: str, tag: str = "run"
) -> Run:
    run = Run(tmp, tag)
    cmd = [
        str(importer(name)),
        fmu_dir,
        "--outputs",
        ",".join(OUTPUTS),
        "--out",
        str(run.out),
        "--events",
        str(run.events_path),
        "--summary",
        str(run.summary_path),
        *options,
        *start_values(scene),
    ]
    result = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    assert run.summary_path.exists(), f"{name} wrote no summary: {result.stderr}"
    run.load()
    assert run.summary["status"] == "completed", (name, scene.name, run.summary, result.stderr)
    assert result.returncode == 0
    return run


@cache
def reference(scene_name: str, interval: float = 1e-3):
    return simulate_me(load_scene(scene_name), LAW, rtol=1e-10, output_interval=interval)


def reference_grid(ref) -> np.ndarray:
    events = np.concatenate([ref.contacts, ref.releases])
    return ~np.isin(ref.table["t"], events)


@pytest.mark.parametrize("fmi", [2, 3])
@pytest.mark.parametrize("mode", ["flags", "always"])
@pytest.mark.parametrize("scene_name", SCENES)
def test_me_cvode_importer_matches_fmpy(
    request: pytest.FixtureRequest, tmp_path: Path, scene_name: str, mode: str, fmi: int
) -> None:
    """(a) and (b), and (a3) and (b3) on the FMI 3.0 build: the FMU says at every contact-mode
    switch that the integrator must restart (fmi2NewDiscreteStates / fmi3UpdateDiscreteStates:
    valuesOfContinuousStatesChanged), so re-initialising only when told gives the same solution
    as re-initialising always, and both match fmpy (FMI 2.0) at rtol 1e-10. A wrong flag is
    caught: never set, `reinits` stays 0 (asserted equal to the number of events) and CVODE goes
    on with a stale history (mode `flags` then fails CVODE's error test at t = 0.072-0.137 s);
    set when nothing changed, `reinits` exceeds it only if there are
    extra events, which the event-time check catches."""
    scene = load_scene(scene_name)
    run = run_importer(
        "me_cvode" if fmi == 2 else "fmi3_me_cvode",
        request.getfixturevalue("unzipped" if fmi == 2 else "unzipped3"),
        scene,
        tmp_path,
        "--mode",
        mode,
        "--rtol",
        "1e-10",
        "--interval",
        "1e-3",
        "--stop",
        str(scene.stop_time),
    )
    ref = reference(scene_name)
    rows, ref_rows = run.grid(), reference_grid(ref)
    np.testing.assert_allclose(run.table["time"][rows], ref.table["t"][ref_rows], atol=1e-12)
    peak = float(np.max(ref.table["F_N"]))
    for name, tol in (
        ("body1.x", 5e-8),
        ("body1.y", 5e-8),
        ("body1.vy", 2e-4),
        ("contact.F_N", 2e-4 * peak),
    ):
        error = np.max(np.abs(run.table[name][rows] - ref.table[COLUMN[name]][ref_rows]))
        assert error <= tol, (name, error)
    # every onset and release, at the same instants
    ref_events = np.sort(np.concatenate([ref.contacts, ref.releases]))
    assert len(run.event_times) == len(ref_events) >= 20
    np.testing.assert_allclose(run.event_times, ref_events, rtol=0, atol=1e-7)
    # the FMU asked for a restart at every event (each one is a contact-mode switch)
    assert run.value("reinits") == len(ref_events)


@pytest.mark.parametrize("fmi", [2, 3])
@pytest.mark.parametrize("scene_name", SCENES)
def test_explicit_euler_at_the_default_step_stays_physical(
    request: pytest.FixtureRequest, tmp_path: Path, scene_name: str, fmi: int
) -> None:
    """(c), and (c3) on the FMI 3.0 build: explicit Euler with no settings but the
    DefaultExperiment (each build's own modelDescription.xml): stepSize as the fixed step,
    stopTime as the end."""
    fmu_dir = request.getfixturevalue("unzipped" if fmi == 2 else "unzipped3")
    experiment = read_model_description(fmu_dir).defaultExperiment
    h = float(experiment.stepSize)
    stop = float(experiment.stopTime)
    scene = load_scene(scene_name)
    assert stop == scene.stop_time
    run = run_importer(
        "me_euler" if fmi == 2 else "fmi3_me_euler", fmu_dir, scene, tmp_path, "--interval", "1e-3"
    )
    assert run.value("t_reached") == pytest.approx(stop, abs=1e-12)
    assert run.value("steps") == round(stop / h)
    ref = reference(scene_name)
    # physical over every step: -5e-4 m, and near the reference's deepest penetration
    deepest = -float(np.max(ref.contact_records["max_indentation"]))  # refined on the interpolant
    assert run.value("min contact.gap") >= -5e-4
    assert run.value("min contact.gap") >= 1.5 * deepest
    # no energy gain beyond 1 % of the start energy's scale (m g |y0| + the flexure's)
    e0 = float(ref.table["energy"][0])
    assert run.value("max energy.total") <= e0 + 0.01 * max(abs(e0), 1.0)
    # first order before the first contact: free fall plus the flexure, error <= g h t
    first = float(ref.contacts[0])
    rows = run.grid() & (run.table["time"] < first)
    ref_rows = reference_grid(ref)
    t = run.table["time"][rows]
    y_ref = ref.table["y"][ref_rows][: len(t)]
    np.testing.assert_allclose(t, ref.table["t"][ref_rows][: len(t)], atol=1e-12)
    assert np.all(np.abs(run.table["body1.y"][rows] - y_ref) <= G * h * t + 1e-12)
    # the first onset: detected at the end of the step that crosses, at most one step (plus the
    # drift above, ~1e-6 m at ~0.8 m/s) late
    assert first <= run.event_times[0] <= first + 2 * h
    if fmi == 3:
        # the same fixed steps through the FMI 2.0 importer on the FMI 2.0 build (the same model,
        # equal to 1e-10 in test_fmi3.py): the same events at the same steps, and the same
        # trajectory to 1e-10 m (rounding, not method error: Euler's is ~1e-6 m)
        run2 = run_importer(
            "me_euler",
            request.getfixturevalue("unzipped"),
            scene,
            tmp_path,
            "--interval",
            "1e-3",
            tag="fmi2",
        )
        np.testing.assert_array_equal(run.event_times, run2.event_times)
        np.testing.assert_array_equal(run.table["time"], run2.table["time"])
        for name in ("body1.x", "body1.y"):
            np.testing.assert_allclose(run.table[name], run2.table[name], rtol=0, atol=1e-10)


@pytest.mark.parametrize("fmi", [2, 3])
def test_euler_ends_a_step_at_each_time_event(
    unzipped: str, unzipped3: str, tmp_path: Path, fmi: int
) -> None:
    """(c) and (c3) with a shock pulse (docs/model.md §14.8): its start and end are time events
    (nextEventTime), both off the grid of fixed steps; the importer cuts the step that would pass
    each one so that it ends there, and the grid goes on unchanged (two more steps in all). In
    free flight along x the pulse changes vx by -2 A T / pi; Euler's rectangle rule over the
    pulse is exact to (pi h / T)^2 / 12 ~ 2e-5 relative (tested: 1e-4)."""
    fmu_dir = unzipped if fmi == 2 else unzipped3
    peak, start, duration, stop = 100.0, 0.0123456, 1e-3, 0.02
    h = float(read_model_description(fmu_dir).defaultExperiment.stepSize)
    assert min(abs(t / h - round(t / h)) for t in (start, start + duration)) > 0.1  # off the grid
    pulse = (f"shock.peak={peak!r}", f"shock.start={start!r}", f"shock.duration={duration!r}")
    scene = load_scene("central")
    args = ("--stop", str(stop), "--interval", "1e-3", *pulse)
    run = run_importer("me_euler" if fmi == 2 else "fmi3_me_euler", fmu_dir, scene, tmp_path, *args)
    np.testing.assert_allclose(run.event_times, [start, start + duration], rtol=0, atol=1e-15)
    assert run.value("steps") == round(stop / h) + 2
    assert run.value("t_reached") == pytest.approx(stop, abs=1e-12)
    end = run.table["time"] == run.event_times[1]
    vx = float(run.table["body1.vx"][end][0])
    assert vx == pytest.approx(-2 * peak * duration / np.pi, rel=1e-4)


@pytest.mark.parametrize("serialize", [False, True])
@pytest.mark.parametrize("scene_name", SCENES)
def test_cs_master_with_variable_steps_and_rollback(
    unzipped: str, tmp_path: Path, scene_name: str, serialize: bool
) -> None:
    """(d) variable communication steps (1e-2 s, a quarter after every rollback, doubling after
    every accepted step), a rollback whenever a contact began inside the step, every 7th step
    replayed from the saved state with bitwise the same outputs (checked by the master)."""
    scene = load_scene(scene_name)
    run = run_importer(
        "cs_master",
        unzipped,
        scene,
        tmp_path,
        "--rtol",
        "1e-10",
        "--step",
        "1e-2",
        "--watch",
        "contact.count",
        "--stop",
        str(scene.stop_time),
        "--mode",
        "serialize" if serialize else "memory",
    )
    assert run.value("rollbacks") >= 50  # contacts refined, and the replays
    steps = np.diff(run.table["time"])
    assert steps.min() < 1e-3 and steps.max() == pytest.approx(1e-2)  # the steps did vary
    # the reference 1000 times tighter than the run: at 1e-10 both ways, the FMU's RK45 (auto)
    # and fmpy's BDF differed by up to 3e-4 of the peak F_N, and the BDF run was the less
    # accurate of the two against rtol 1e-13 (central: 7.5 N against RK45's 3.7 N)
    ref = simulate_me(scene, LAW, rtol=1e-13, output_times=run.table["time"][1:])
    rows = np.isin(ref.table["t"], run.table["time"])
    np.testing.assert_array_equal(ref.table["t"][rows], run.table["time"])
    peak = float(np.max(ref.table["F_N"]))
    for name, tol in (
        ("body1.x", 5e-8),
        ("body1.y", 5e-8),
        ("body1.vy", 2e-4),
        ("contact.F_N", 2e-4 * peak),
    ):
        error = np.max(np.abs(run.table[name] - ref.table[COLUMN[name]][rows]))
        assert error <= tol, (name, error)


@pytest.mark.parametrize("serialize", [False, True])
@pytest.mark.parametrize("scene_name", SCENES)
def test_fmi3_cs_master_with_early_return_variable_steps_and_rollback(
    unzipped3: str, tmp_path: Path, scene_name: str, serialize: bool
) -> None:
    """(d3) the FMI 3.0 co-simulation master: earlyReturnAllowed and eventModeUsed, steps of
    1e-2 s / 64 after every early return doubling up to 1e-2 s, each step starting at the last
    one's end (lastSuccessfulTime after an early return), Event Mode whenever the FMU asks, every
    7th step replayed from the saved FMU state (memory or serialized) with bitwise the same
    outputs, earlyReturn and lastSuccessfulTime (checked by the master).

    What it catches: an FMU that does not return early (or returns a lastSuccessfulTime that is
    not the event time) puts the onsets on the communication grid, up to a step (>= 1.6e-4 s)
    away from the reference onsets, where 1e-9 s is required; one that returns early at no event
    makes more early returns than the reference has onsets and releases (their numbers must be
    equal); an FMU state that does not restore everything fails the master's replay (status not
    "completed"); a wrong state after an early return (the contact mode not switched) shows in
    the states against the reference.

    Tolerances: the onsets to 1e-9 s, with the FMU at rtol 1e-12 and the reference (fmpy model
    exchange of the FMI 2.0 build) at rtol 1e-13 (observed <= 6e-10 s; at the FMU's rtol 1e-10
    the onsets differ by up to 6e-8 s, the integrator's own error); the states with the stated
    tolerances of the module docstring against the same reference at the communication points.
    """
    scene = load_scene(scene_name)
    run = run_importer(
        "fmi3_cs_master",
        unzipped3,
        scene,
        tmp_path,
        "--rtol",
        "1e-12",
        "--step",
        "1e-2",
        "--watch",
        "contact.count",
        "--stop",
        str(scene.stop_time),
        "--mode",
        "serialize" if serialize else "memory",
    )
    assert run.value("t_reached") == pytest.approx(scene.stop_time, abs=1e-12)
    steps = np.diff(run.table["time"])
    assert steps.min() > 0  # each step starts where the last one ended
    assert steps.max() == pytest.approx(1e-2)  # the steps did vary, up to h_max
    assert run.value("rollbacks") >= run.value("steps") // 7 >= 10  # the replays
    rows = run.events_path.read_text().splitlines()[1:]
    kinds = np.array([r.split(",")[1] for r in rows])
    times = np.array([float(r.split(",")[0]) for r in rows])
    early, onsets = times[kinds == "early-return"], times[kinds == "watched-change"]
    ref = simulate_me(scene, LAW, rtol=1e-13, output_times=run.table["time"][1:])
    ref_onsets = np.asarray(ref.contacts)
    ref_events = np.sort(np.concatenate([ref.contacts, ref.releases]))
    # every onset ends a step: the step ends where contact.count changed are the onsets ...
    assert len(onsets) == len(ref_onsets) >= 10
    np.testing.assert_allclose(onsets, ref_onsets, rtol=0, atol=1e-9)
    assert np.all(np.isin(onsets, run.table["time"]))
    # ... because the FMU returned early there, and at every release, and nowhere else
    assert len(early) == len(ref_events)
    np.testing.assert_allclose(early, ref_events, rtol=0, atol=1e-9)
    assert np.all(np.isin(onsets, early))
    # the states at the communication points (the early-return points included)
    rows_ref = np.isin(ref.table["t"], run.table["time"])
    np.testing.assert_array_equal(ref.table["t"][rows_ref], run.table["time"])
    peak = float(np.max(ref.table["F_N"]))
    for name, tol in (
        ("body1.x", 5e-8),
        ("body1.y", 5e-8),
        ("body1.vy", 2e-4),
        ("contact.F_N", 2e-4 * peak),
    ):
        error = np.max(np.abs(run.table[name] - ref.table[COLUMN[name]][rows_ref]))
        assert error <= tol, (name, error)
