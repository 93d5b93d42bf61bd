"""The shock pulse in the model, the batch co-simulation master and `csfh shock`
(docs/model.md §14.8).

* the pulse: in free flight (no contact, no flexure, no gravity) body 1's velocity relative to the
  frame changes by exactly -2 A T / pi along the pulse's direction and its position by the double
  integral, in co-simulation with one communication step over the whole pulse and in model
  exchange, because a(t) is evaluated in the right-hand side and CVODE stops at the pulse's ends;
  the same pulse held piecewise constant over communication steps through a_base is far off;
* without a pulse the trajectory is bitwise the one of a model without the shock parameters;
* the pulse's ends are time events in model exchange (nextEventTime);
* the batch master gives bitwise the single runs (trajectories, summaries), directly and through
  the task system, serially, on local processes and on Dask;
* the Clopper-Pearson interval covers a binomial proportion at least 95 % of the time, whatever
  the proportion (computed exactly), and its ends solve the binomial equations that define it;
* `csfh shock`: bad input gives one line and exit 2; the report of a small study is consistent
  with its runs.
"""

from __future__ import annotations

import json
import math
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from csfh_command import run_csfh
from fmpy.fmi2 import FMU2Model
from scipy.stats import binom

from csfh.batch.executors import run_tasks
from csfh.batch.store import ResultStore
from csfh.batch.tasks import Task, run_chunk
from csfh.cli.main import main
from csfh.model import model_info
from csfh.model.scene import load_scene
from csfh.runners.co_simulation import simulate_cs
from csfh.runners.cs_batch import cs_batch
from csfh.runners.fmu import start_values, unzipped_fmu
from csfh.runners.model_exchange import simulate_me
from csfh.studies.shock.conditions import CONDITIONS, G_STANDARD, condition
from csfh.studies.shock.study import clopper_pearson

A, T_PULSE, T0, ANGLE = 1500.0 * G_STANDARD, 5e-4, 3e-4, 0.7
FREE = {"g": 0.0, "flexure.enabled": False, "contact.law": "none"}
PULSE = {"shock.peak": A, "shock.duration": T_PULSE, "shock.start": T0, "shock.angle": ANGLE}


def free_flight_exact(t: float) -> tuple[float, float]:
    """Velocity and displacement of body 1 relative to the frame, along the pulse's direction,
    at time t after the pulse: v = -2AT/pi, x = -(A T/pi) (T + 2 (t - t0 - T))."""
    dv = 2 * A * T_PULSE / math.pi
    # during the pulse v(tau) = -(A T/pi)(1 - cos(pi tau/T)), its integral over T is -(A T^2/pi)
    dx = A * T_PULSE / math.pi * T_PULSE + dv * (t - T0 - T_PULSE)
    return -dv, -dx


@pytest.mark.parametrize("interface", ["cs", "me"])
def test_pulse_changes_the_velocity_by_its_integral(interface: str) -> None:
    scene = load_scene("central")
    t_end = 1e-2
    if interface == "cs":  # one communication step over the whole pulse
        tr = simulate_cs(
            scene,
            "LN_spheres",
            rtol=1e-10,
            communication_step=t_end,
            stop_time=t_end,
            parameters={**FREE, **PULSE},
        )
    else:
        tr = simulate_me(
            scene,
            "LN_spheres",
            rtol=1e-10,
            output_interval=t_end,
            stop_time=t_end,
            parameters={**FREE, **PULSE},
        )
    v, x = free_flight_exact(t_end)
    c, s = math.cos(ANGLE), math.sin(ANGLE)
    assert tr["vx"][-1] == pytest.approx(v * c, rel=1e-8)
    assert tr["vy"][-1] == pytest.approx(v * s, rel=1e-8)
    assert tr["x"][-1] - scene.q0[0] == pytest.approx(x * c, rel=1e-8)
    assert tr["y"][-1] - scene.q0[1] == pytest.approx(x * s, rel=1e-8)
    assert tr["theta"][-1] == 0.0 and tr["omega"][-1] == 0.0


def test_moreau_and_rk4_see_the_pulse_at_their_own_times() -> None:
    """The Moreau stepper evaluates the pulse at each step's midpoint (the midpoint rule: error
    (pi h / T)^2 / 24 of the velocity change) and the RK4 baseline at its stage times (in free
    flight, Simpson's rule on each step: error pi (pi h / T)^4 / 360 at most)."""
    from csfh.runners.moreau import moreau
    from csfh.runners.rk4 import rk4_event

    scene = load_scene("central")
    v, _ = free_flight_exact(2e-3)
    h = 1e-6
    rigid = moreau(scene, h=h, stop_time=2e-3, parameters={**FREE, **PULSE})
    midpoint_error = (math.pi * h / T_PULSE) ** 2 / 24
    assert rigid["vx"][-1] == pytest.approx(v * math.cos(ANGLE), rel=3 * midpoint_error)
    assert abs(rigid["vx"][-1] / (v * math.cos(ANGLE)) - 1) > midpoint_error / 3
    h = T_PULSE / 50
    rk4 = rk4_event(scene, "LN_spheres", h0=h, stop_time=2e-3, parameters={**FREE, **PULSE})
    simpson_error = math.pi * (math.pi * h / T_PULSE) ** 4 / 360  # 1.4e-7
    assert rk4["vy"][-1] == pytest.approx(v * math.sin(ANGLE), rel=simpson_error)


def test_pulse_held_over_communication_steps_is_not_accurate() -> None:
    """The same pulse given through the a_base input, held over each communication step (the
    value at the step's start, as a master would hold it): the velocity change misses by the
    sampling error (the test above would fail for it); with the pulse in the model it does not
    depend on the grid."""
    scene = load_scene("central")
    h = T_PULSE / 8
    n = round(1e-3 / h)
    from fmpy.fmi2 import FMU2Slave

    md = model_info.model_description()
    fmu = FMU2Slave(
        guid=md.guid, unzipDirectory=unzipped_fmu(), modelIdentifier="csfh", instanceName="held"
    )
    fmu.instantiate()
    try:
        fmu.setupExperiment(tolerance=1e-10, startTime=0.0, stopTime=1e-3)
        fmu.enterInitializationMode()
        vr = {v.name: v.valueReference for v in md.modelVariables}
        for name, kind, value in start_values(scene, "LN_spheres", FREE):
            if kind == "Real":
                fmu.setReal([vr[name]], [value])
            elif kind == "Boolean":
                fmu.setBoolean([vr[name]], [value])
            else:
                fmu.setInteger([vr[name]], [value])
        fmu.exitInitializationMode()
        for k in range(n):
            t = k * h
            a = A * math.sin(math.pi * (t - T0) / T_PULSE) if T0 <= t <= T0 + T_PULSE else 0.0
            fmu.setReal(
                [vr["a_base[1]"], vr["a_base[2]"]], [a * math.cos(ANGLE), a * math.sin(ANGLE)]
            )
            fmu.doStep(t, h)
        vx = fmu.getReal([vr["body1.vx"]])[0]
    finally:
        fmu.terminate()
        fmu.freeInstance()
    v, _ = free_flight_exact(1e-3)
    # zero-order hold at 8 steps per pulse: 5e-4 off, 10^4 times the in-model pulse's error
    assert abs(vx / (v * math.cos(ANGLE)) - 1) > 1e-4
    for step in (h, 1e-3):
        tr = simulate_cs(
            scene,
            "LN_spheres",
            rtol=1e-10,
            communication_step=step,
            stop_time=1e-3,
            parameters={**FREE, **PULSE},
        )
        assert tr["vx"][-1] == pytest.approx(v * math.cos(ANGLE), rel=1e-8)


def test_without_a_pulse_the_trajectory_is_bitwise_unchanged() -> None:
    scene = load_scene("csfh")
    plain = simulate_cs(scene, "LN_cylinders", stop_time=0.3, communication_step=1e-3)
    unset = simulate_cs(
        scene,
        "LN_cylinders",
        stop_time=0.3,
        communication_step=1e-3,
        parameters={
            "shock.peak": 0.0,
            "shock.duration": 1e-3,
            "shock.start": 0.01,
            "shock.angle": 1.0,
        },
    )
    for name in plain.table:
        assert np.array_equal(plain.table[name], unset.table[name]), name
    me_plain = simulate_me(scene, "LN_cylinders", stop_time=0.2)
    me_unset = simulate_me(
        scene, "LN_cylinders", stop_time=0.2, parameters={"shock.peak": 0.0, "shock.angle": 2.0}
    )
    for name in me_plain.table:
        assert np.array_equal(me_plain.table[name], me_unset.table[name]), name
    # and the pulse does change it
    pulsed = simulate_cs(
        scene,
        "LN_cylinders",
        stop_time=0.3,
        communication_step=1e-3,
        parameters={"shock.peak": 100.0, "shock.duration": 1e-3, "shock.start": 0.01},
    )
    assert not np.array_equal(plain["x"], pulsed["x"])


def test_pulse_ends_are_time_events_in_model_exchange() -> None:
    md = model_info.model_description()
    scene = load_scene("central")
    fmu = FMU2Model(
        guid=md.guid, unzipDirectory=unzipped_fmu(), modelIdentifier="csfh", instanceName="me"
    )
    fmu.instantiate()
    try:
        fmu.setupExperiment(startTime=0.0)
        fmu.enterInitializationMode()
        vr = {v.name: v.valueReference for v in md.modelVariables}
        for name, kind, value in start_values(scene, "LN_spheres", PULSE):
            if kind == "Real":
                fmu.setReal([vr[name]], [value])
            elif kind == "Boolean":
                fmu.setBoolean([vr[name]], [value])
            else:
                fmu.setInteger([vr[name]], [value])
        fmu.exitInitializationMode()
        info = fmu.newDiscreteStates()
        assert info[4] and info[5] == T0  # nextEventTimeDefined, nextEventTime: the start
        fmu.enterContinuousTimeMode()
        fmu.setTime(T0 + 0.25 * T_PULSE)
        a = fmu.getReal([vr["a_frame[1]"], vr["a_frame[2]"]])
        assert a[0] == pytest.approx(A * math.sin(math.pi / 4) * math.cos(ANGLE), rel=1e-14)
        assert a[1] == pytest.approx(A * math.sin(math.pi / 4) * math.sin(ANGLE), rel=1e-14)
        fmu.setTime(T0)
        fmu.enterEventMode()
        info = fmu.newDiscreteStates()
        assert info[4] and info[5] == T0 + T_PULSE  # the end
        fmu.enterContinuousTimeMode()
        fmu.setTime(T0 + T_PULSE)
        fmu.enterEventMode()
        info = fmu.newDiscreteStates()
        assert not info[4]  # no more
    finally:
        fmu.terminate()
        fmu.freeInstance()


# ------------------------------------------------------------------------------------------
# the batch master


def _same_trajectory(a: Any, b: Any) -> None:
    assert a.table.keys() == b.table.keys()
    for name in a.table:
        assert np.array_equal(a.table[name], b.table[name]), name
    for name in a.contact_records:
        assert np.array_equal(a.contact_records[name], b.contact_records[name], equal_nan=True)
    assert np.array_equal(a.contacts, b.contacts) and np.array_equal(a.releases, b.releases)


def test_batch_is_bitwise_the_single_runs() -> None:
    scene = load_scene("csfh")
    sets = [
        {"contact.R1": 0.18, "shock.peak": 0.0},
        {"contact.R1": 0.1801, "shock.peak": 50 * G_STANDARD},
        {"contact.R1": 0.1799, "shock.peak": 80 * G_STANDARD},
    ]
    pulse = {"shock.duration": 3e-3, "shock.start": 0.02, "flexure.track_stress_peak": True}
    sets = [{**s, **pulse} for s in sets]
    for law in ("LN_cylinders", "Flores"):
        batch = cs_batch(scene, law, sets, stop_time=0.25, communication_step=1e-3, record=True)
        assert list(batch.status) == [0, 0, 0]
        for i, p in enumerate(sets):
            single = simulate_cs(scene, law, stop_time=0.25, communication_step=1e-3, parameters=p)
            _same_trajectory(single, batch.trajectory(i))
            s, b = single.summary(), batch.summary(i)
            assert {k: s[k] for k in b} == b
        # the runs differ from each other: no state is shared between them
        assert len({batch.summary(i)["max_flexure_stress"] for i in range(3)}) == 3


def test_batch_reductions_are_those_of_the_recorded_points() -> None:
    """Without a record the master reads the final values only at the stop time and each value
    reference once: its reductions are bitwise those of the outputs it records at every point,
    on one instance reset between runs (a refused run in the middle makes it anew)."""
    scene = load_scene("csfh")
    sets = [
        {"contact.R1": 0.18, "shock.peak": 60 * G_STANDARD, "shock.start": 0.02},
        {"contact.R1": 0.25},  # R1 > R2: refused
        {"contact.R1": 0.1801, "flexure.track_stress_peak": True},
    ]
    sets = [
        {"shock.peak": 0.0, "shock.start": 0.0, "flexure.track_stress_peak": False, **s}
        for s in sets
    ]
    finals = tuple(
        (name, "final") for name in ("contact.F_N_peak", "contact.count", "contact.active")
    )
    outputs = (
        *finals,
        ("flexure.stress_max_peak", "max"),
        ("contact.F_N_peak", "absmax"),
        ("contact.F_N", "min"),
        ("contact.F_N_peak", "time_of_max"),
    )
    kw: dict[str, Any] = {"stop_time": 0.2, "communication_step": 1e-3, "check": False}
    plain = cs_batch(scene, "LN_cylinders", sets, outputs=outputs, **kw)
    recorded = cs_batch(scene, "LN_cylinders", sets, outputs=outputs, record=True, **kw)
    assert list(plain.status) == list(recorded.status) == [0, -1, 0]
    n = len(outputs)  # a record adds the table's outputs after these
    assert np.array_equal(plain.results, recorded.results[:, :n], equal_nan=True)
    for i in (0, 2):
        for j, (name, _) in enumerate(finals):
            assert plain.results[i, j] == recorded.column(i, name)[-1]
        assert (
            plain.value(i, "contact.F_N_peak", "absmax")
            == recorded.column(i, "contact.F_N_peak").max()
        )
    assert plain.value(0, "contact.count") > 0
    alone = cs_batch(scene, "LN_cylinders", sets[2:], outputs=outputs, **kw)
    assert np.array_equal(alone.results[0], plain.results[2])


def _start_values_one_by_one(scene: Any, law: str | None, extra: dict[str, Any] | None) -> list:
    """What a run sets, worked out for it alone: the scene's parameters with the law, the
    overrides, the start state, the inputs, each value as its FMI type is set."""
    from csfh.runners.fmu import STATE_NAMES

    values = dict(scene.parameter_values(law))
    values.update({k: model_info.coerce(k, v) for k, v in (extra or {}).items()})
    values.update(dict(zip(STATE_NAMES, scene.x0, strict=True)))
    values.update(scene.inputs)
    kinds = {"Real": float, "Boolean": bool}
    out = []
    for name, value in values.items():
        kind = model_info.variables()[name].type
        kind = kind if kind in kinds else "Integer"
        out.append((name, kind, kinds.get(kind, int)(value)))
    return out


def test_start_values_of_runs_are_each_runs_start_values() -> None:
    """The batch's start values (the scene's part worked out once) are those of each run alone:
    the same names, FMI types, values and order, whatever the overrides (new names, a Boolean,
    an Enumeration by name, a start state, which the scene's start state replaces)."""
    from csfh.runners.fmu import start_values_of_runs

    scene = load_scene("csfh")
    extras: list[dict[str, Any] | None] = [
        None,
        {},
        {"contact.R1": 0.1801, "flexure.track_stress_peak": True},
        {"solver.method": "RK45", "shock.peak": 5.0, "contact.law_number": 3},
        {"body1.x": 1e-3, "contact.cr": 0.5},
    ]
    for law in ("LN_cylinders", None):
        runs = start_values_of_runs(scene, law, extras)
        for run, extra in zip(runs, extras, strict=True):
            alone = _start_values_one_by_one(scene, law, extra)
            assert run == alone == start_values(scene, law, extra)
            assert [type(v) for _, _, v in run] == [type(v) for _, _, v in alone]
        assert runs[2] != runs[0] != runs[3]


def test_batch_reports_a_refused_run_and_runs_the_others() -> None:
    scene = load_scene("csfh")
    sets = [  # run 1: R1 > R2, refused
        {"contact.R1": 0.18, "flexure.h": 0.005},
        {"contact.R1": 0.25, "flexure.h": 0.005},
        {"contact.R1": 0.17, "flexure.h": 0.006},
    ]
    batch = cs_batch(scene, "LN_spheres", sets, stop_time=0.05, check=False)
    assert list(batch.status) == [0, -1, 0]
    assert "contact.R1" in batch.messages[1] and batch.messages[0] == ""
    assert np.all(np.isnan(batch.results[1]))
    stress = batch.values("flexure.stress_max_peak", "max")
    assert stress[0] > 0 and stress[2] > 0 and stress[0] != stress[2]
    with pytest.raises(Exception, match="run 1 of the batch failed"):
        batch.check()


def _tasks(interface: str, signals: bool) -> list[Task]:
    scene = load_scene("csfh")
    return [
        Task(
            scene=scene,
            model=model,
            parameters=(("contact.R1", r1), ("flexure.h", h)),
            stop_time=0.15,
            output_interval=1e-3,
            interface=interface,
            signals=signals,
        )
        for model in ("LN_spheres", "LN_ESDU")
        for r1, h in ((0.18, 0.005), (0.1801, 0.00501), (0.1799, 0.00499))
    ]


@pytest.mark.parametrize("signals", [False, True])
def test_task_chunks_run_as_batches_with_the_single_runs_results(signals: bool) -> None:
    from csfh.batch.tasks import run_alone

    tasks = _tasks("cs", signals)
    chunk = [t for t in tasks if t.model == "LN_ESDU"]
    batched = run_chunk(chunk)
    for task, (key, summary, sig, _) in zip(chunk, batched, strict=True):
        k1, s1, sig1, _ = run_alone(task)
        assert key == k1 == task.key and summary == s1
        assert "peak_flexure_stress" in summary
        if signals:
            assert sig is not None and sig1 is not None
            for name in sig1:
                assert np.array_equal(sig[name], sig1[name]), name
        else:
            assert sig is None and sig1 is None


def test_batched_tasks_give_the_same_results_serially_in_processes_and_on_dask(
    tmp_path: Path,
) -> None:
    tasks = _tasks("cs", False)
    serial = ResultStore(tmp_path / "serial")
    run_tasks(tasks, serial, workers=1, quiet=True)
    procs = ResultStore(tmp_path / "procs")
    rep = run_tasks(tasks, procs, workers=2, quiet=True, batch=2)
    assert rep.executor == "2 local processes"
    stores = [serial, procs]
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
    ) as cluster:
        dask = ResultStore(tmp_path / "dask")
        run_tasks(tasks, dask, dask_address=cluster.scheduler_address, quiet=True)
        stores.append(dask)
    for t in tasks:
        assert serial.summary(t.key) == procs.summary(t.key) == stores[-1].summary(t.key)


# ------------------------------------------------------------------------------------------
# the confidence interval


@pytest.mark.parametrize("n", [10, 50, 200])
def test_clopper_pearson_covers_at_least_the_confidence(n: int) -> None:
    intervals = [clopper_pearson(k, n) for k in range(n + 1)]
    ks = np.arange(n + 1)
    coverage = []
    for p in np.linspace(1e-4, 1 - 1e-4, 400):
        inside = np.array([lo <= p <= hi for lo, hi in intervals])
        coverage.append(float(np.sum(binom.pmf(ks, n, p)[inside])))
    assert min(coverage) >= 0.95 - 1e-9
    assert np.mean(coverage) < 0.99  # conservative, not absurdly so
    # the ends solve the equations that define them: P(X >= k | lo) = P(X <= k | hi) = 2.5 %
    for k in (0, 1, n // 3, n):
        lo, hi = intervals[k]
        if k > 0:
            assert binom.sf(k - 1, n, lo) == pytest.approx(0.025, rel=1e-8)
        else:
            assert lo == 0.0 and hi == pytest.approx(1 - 0.025 ** (1 / n), rel=1e-10)
        if k < n:
            assert binom.cdf(k, n, hi) == pytest.approx(0.025, rel=1e-8)


# ------------------------------------------------------------------------------------------
# the command


@pytest.mark.parametrize(
    ("args", "says"),
    [
        (["--peak", "1500", "--duration", "-0.0005"], "--duration = '-0.0005' s must be > 0"),
        (["--peak", "1500", "--duration=-5e-4"], "--duration = '-5e-4' s must be > 0"),
        (["--condition", "JESD22-B104-Z"], "unknown shock condition 'JESD22-B104-Z'"),
        (["--tolerance", "tolerance_mems", "--runs", "0"], "--runs = 0 must be >= 1"),
        (["--peak", "1500"], "--peak and --duration go together"),
        (["--directions", "0"], "--directions = 0 must be >= 1"),
        (["--models", "Moreau"], "'Moreau' is not an event-driven model"),
        (["--peak", "nan", "--duration", "1e-3"], "--peak = 'nan' must be a finite number > 0"),
    ],
)
def test_bad_shock_input_gives_one_line_and_exit_2(
    args: list[str], says: str, tmp_path: Path
) -> None:
    proc = run_csfh("shock", "mems", *args, "--out", str(tmp_path))
    assert proc.returncode == 2, proc.stderr
    assert len(proc.stderr.strip().splitlines()) == 1, proc.stderr
    assert says in proc.stderr
    assert not (tmp_path / "shock.md").exists()


def test_conditions_are_named_and_sourced() -> None:
    assert condition("jesd22-b104-b").peak_g == 1500 and condition("JESD22-B104-B").duration == 5e-4
    assert condition("MIL-STD-883-2002-E").peak_g == 10000
    for c in CONDITIONS.values():
        assert c.source and c.velocity_change == pytest.approx(
            2 * c.peak_g * 9.80665 * c.duration / math.pi
        )


def test_shock_report_is_consistent_with_its_runs(tmp_path: Path) -> None:
    out = tmp_path / "mems"
    code = main(
        [
            "shock",
            "mems",
            "--directions",
            "4",
            "--models",
            "LN_spheres",
            "Flores",
            "--stop-time",
            "4e-4",
            "--step",
            "1e-6",
            "--tolerance",
            "tolerance_mems",
            "--runs",
            "20",
            "--out",
            str(out),
            "--workers",
            "1",
            "--quiet",
        ]
    )
    data = json.loads((out / "shock.json").read_text())
    assert code == (0 if data["result"]["passed"] else 1)
    for name in ("shock.md", "shock_time.png", "shock_polar.png", "shock_montecarlo.png"):
        assert (out / name).stat().st_size > 0, name
    allow = data["result"]["allowables"]
    assert data["directions"] == [0.0, 90.0, 180.0, 270.0]
    store = ResultStore(out)
    scene = replace(load_scene("mems"), u0=(0.0, 0.0, 0.0))
    for model, r in data["result"]["models"].items():
        for row in r["directions"]:
            assert row["flexure_margin"] == pytest.approx(
                1 - row["flexure_stress"] / allow["flexure.stress_allowable"], rel=1e-12
            )
            assert row["passed"] == (row["flexure_margin"] >= 0 and row["contact_margin"] >= 0)
        # a row is the run: the same direction as a single run gives the same peaks
        row = r["directions"][1]
        single = simulate_cs(
            scene,
            model,
            stop_time=4e-4,
            communication_step=1e-6,
            parameters={
                "shock.peak": 1500 * G_STANDARD,
                "shock.duration": 5e-4,
                "shock.start": 0.0,
                "shock.angle": math.pi / 2,
                "flexure.track_stress_peak": True,
            },
        )
        assert single.summary()["max_flexure_stress"] == row["flexure_stress"]
        assert single.summary()["max_contact_pressure"] == row["contact_pressure"]
        mc = data["montecarlo"]["models"][model]
        values = np.array(mc["values"]["flexure_stress"])
        assert len(values) == 20 and len(set(values)) == 20  # every sample its own run
        p = mc["probability"]["flexure"]
        assert p["exceeded"] == int(np.sum(values > allow["flexure.stress_allowable"]))
        assert (p["low"], p["high"]) == clopper_pearson(p["exceeded"], 20)
    assert len(store) == 2 * 4 + 2 * 21
    md = (out / "shock.md").read_text()
    assert "JESD22-B104-B" in md and "Clopper-Pearson" in md and "Per direction" in md
    # the report is one output set (csfh.output): a run without the Monte Carlo replaces it whole
    manifest = json.loads((out / ".csfh" / "shock.json").read_text())
    assert set(manifest["files"]) == {
        "shock.md",
        "shock.json",
        "shock_time.png",
        "shock_polar.png",
        "shock_montecarlo.png",
    }
    assert (
        main(
            [
                "shock",
                "mems",
                "--directions",
                "4",
                "--models",
                "LN_spheres",
                "Flores",
                "--stop-time",
                "4e-4",
                "--step",
                "1e-6",
                "--out",
                str(out),
                "--workers",
                "1",
                "--quiet",
            ]
        )
        == code
    )
    assert not (out / "shock_montecarlo.png").exists()
    assert "Monte Carlo" not in (out / "shock.md").read_text()


def test_auto_switching_integrators_across_the_pulse_end() -> None:
    """The mems scene at rest (as `csfh shock` starts it) under JESD22-B104-B (1500 g, 0.5 ms) at
    135 degrees, LN_spheres, 1e-6 s communication steps: auto runs BDF with the pulse's end as
    its stop time, goes back to RK45, which passes the pulse's end itself, and later tries BDF
    again. CVODE's memory must not keep the stop time it was given before (SUNDIALS 6.4 clears
    it only when CVODE reaches it): the run failed with "tstop = 0.0005 is behind current t".
    It completes, and agrees with BDF alone (the same pulse, the same contacts) within the
    integration tolerance."""
    pulse = {
        "shock.peak": 1500 * G_STANDARD,
        "shock.duration": 5e-4,
        "shock.start": 0.0,
        "shock.angle": math.radians(135),
        "flexure.track_stress_peak": True,
    }
    scene = replace(load_scene("mems"), u0=(0.0, 0.0, 0.0))
    auto = simulate_cs(scene, "LN_spheres", communication_step=1e-6, parameters=pulse)
    bdf = simulate_cs(
        scene, "LN_spheres", communication_step=1e-6, parameters={**pulse, "solver.method": 2}
    )
    a, b = auto.summary(), bdf.summary()
    assert a["contacts"] == b["contacts"] >= 3
    assert a["max_F_N"] == pytest.approx(b["max_F_N"], rel=1e-4)
    scale = float(np.max(np.abs(bdf.table["y"])))
    np.testing.assert_allclose(auto.table["y"], bdf.table["y"], rtol=0, atol=1e-5 * scale)
