"""What other tools see of the FMU (issue 14): the event flags at contact-mode switches, the peak
outputs for co-simulation users, the initial-state check, and what modelDescription.xml says."""

from __future__ import annotations

import math
from collections.abc import Callable
from ctypes import c_double
from typing import Any

import pytest

MakeFmu = Callable[..., tuple[Any, Any]]
STATES = ("body1.x", "body1.y", "body1.theta", "body1.vx", "body1.vy", "body1.omega")


def _me_in_flight(make_fmu: MakeFmu, vr: dict[str, int]):
    """A model-exchange instance of the central drop, out of contact, in continuous-time mode."""
    fmu, log = make_fmu("ME")
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.setBoolean([vr["flexure.enabled"], vr["friction.enabled"]], [False, False])
    fmu.setReal([vr["body1.x"], vr["body1.y"]], [0.0, 0.0])
    fmu.exitInitializationMode()
    info = fmu.newDiscreteStates()
    assert info[3] is False  # valuesOfContinuousStatesChanged: nothing switched at the start
    fmu.enterContinuousTimeMode()
    return fmu, log


def _indicator(fmu) -> float:
    z = (c_double * 1)()
    fmu.getEventIndicators(z, 1)
    return z[0]


def test_every_contact_mode_switch_asks_the_importer_to_restart(
    make_fmu: MakeFmu, vr: dict[str, int]
) -> None:
    """FMI 2.0 importers restart their integrator after an event when fmi2NewDiscreteStates
    reports valuesOfContinuousStatesChanged (or nominalsOfContinuousStatesChanged): the FMU sets
    it at the onset and at the release (the right-hand side switches there), returns the states
    unchanged, and a repeated call in the same event reports nothing (no event loop); the event
    indicator keeps its sign across the switch, so re-reading it starts no new event."""
    fmu, _ = _me_in_flight(make_fmu, vr)
    delta = 0.02
    for y, v, active in ((-delta - 1e-9, -0.5, True), (-delta + 1e-6, 0.5, False)):
        x = [0.0, y, 0.0, 0.0, v, 0.0]
        fmu.setTime(0.1)
        fmu.setContinuousStates((c_double * 6)(*x), 6)
        z_before = _indicator(fmu)
        fmu.enterEventMode()
        more, terminate, nominals, values, *_ = fmu.newDiscreteStates()
        assert (more, terminate, nominals, values) == (False, False, False, True)
        assert fmu.getBoolean([vr["contact.active"]])[0] == active
        states = (c_double * 6)()
        fmu.getContinuousStates(states, 6)
        assert list(states) == x
        z_after = _indicator(fmu)
        assert math.copysign(1, z_after) == math.copysign(1, z_before)
        assert fmu.newDiscreteStates()[3] is False  # nothing switches twice
        fmu.enterContinuousTimeMode()
    # an event that switches nothing (the importer's indicator noise) asks for no restart
    fmu.enterEventMode()
    assert fmu.newDiscreteStates()[3] is False


@pytest.fixture(scope="module")
def csfh_reference():
    """The harness's model-exchange run of the csfh scene (the FMU's start values) at rtol 1e-10:
    per contact, the peak F_N and indentation refined on CVODE's interpolant."""
    from csfh.model.scene import load_scene
    from csfh.runners.fmu import simulate_me

    return simulate_me(load_scene("csfh"), "LN_spheres", rtol=1e-10, output_interval=1e-3)


@pytest.mark.parametrize(("rtol", "tol"), [(None, 1e-3), (1e-10, 1e-6)])
def test_bare_co_simulation_reports_the_peaks(
    fmu_path, csfh_reference, rtol: float | None, tol: float
) -> None:
    """A bare co-simulation run (fmpy.simulate_fmu, 1e-2 s communication steps, the FMU's
    defaults) reports in each step that holds whole contacts the largest F_N and indentation the
    harness finds for them (relative error: the integrator's own, <= 1e-3 at the default rtol
    1e-6, where it is 1.6e-4; <= 1e-6 at rtol 1e-10): the peak is located inside the step, not
    sampled at the communication points, where F_N is at most 44 % of it."""
    import fmpy
    import numpy as np

    kwargs = {} if rtol is None else {"relative_tolerance": rtol}
    names = ["contact.F_N", "contact.F_N_peak", "contact.indentation_peak", "contact.F_T_peak"]
    r = fmpy.simulate_fmu(
        str(fmu_path), fmi_type="CoSimulation", output_interval=1e-2, output=names, **kwargs
    )
    t = r["time"]
    cr = csfh_reference.contact_records
    checked = 0
    for k in range(1, len(t)):
        inside = (cr["t_onset"] > t[k - 1]) & (cr["t_onset"] <= t[k])
        if not inside.any() or not np.all(cr["t_release"][inside] <= t[k]):
            continue  # no contact, or one that goes on into the next step
        for name, field in (
            ("contact.F_N_peak", "peak_F_N"),
            ("contact.indentation_peak", "max_indentation"),
        ):
            expected = float(np.max(cr[field][inside]))
            assert r[name][k] == pytest.approx(expected, rel=tol), (name, t[k])
        checked += 1
    assert checked >= 8
    assert np.max(r["contact.F_N"]) < 0.5 * np.max(cr["peak_F_N"])  # what sampling shows
    # F_T_peak: |F_T| <= f_d F_N at every instant, so also for the peaks; and it is not zero
    assert np.all(r["contact.F_T_peak"] <= 0.055 * r["contact.F_N_peak"] * (1 + 1e-12))
    assert np.max(r["contact.F_T_peak"]) > 0


def test_peaks_are_the_instantaneous_values_without_a_communication_step(
    make_fmu: MakeFmu, vr: dict[str, int]
) -> None:
    """Model exchange (no communication step) and co-simulation before its first step: the peak
    outputs are F_N, |F_T| and the indentation at the current state; a zero-length step keeps
    that."""
    peaks = [vr[n] for n in ("contact.F_N_peak", "contact.F_T_peak", "contact.indentation_peak")]
    now = [vr[n] for n in ("contact.F_N", "contact.F_T", "contact.indentation")]
    for kind in ("ME", "CS"):
        fmu, _ = make_fmu(kind)
        fmu.setupExperiment(startTime=0.0)
        fmu.enterInitializationMode()
        # in contact from the start, sliding: F_N, F_T and the indentation are all > 0
        fmu.setReal(
            [vr["body1.x"], vr["body1.y"], vr["body1.vx"], vr["body1.vy"]],
            [0.0, -0.02 - 5e-5, 0.3, -0.1],
        )
        fmu.exitInitializationMode()
        F_N, F_T, rho = fmu.getReal(now)
        assert F_N > 0 and F_T != 0 and rho > 0
        assert fmu.getReal(peaks) == [F_N, abs(F_T), rho]
        if kind == "CS":
            fmu.doStep(0.0, 0.0)
            assert fmu.getReal(peaks) == [F_N, abs(F_T), rho]


@pytest.mark.parametrize("kind", ["ME", "CS"])
def test_a_start_deep_in_the_bore_is_refused(
    make_fmu: MakeFmu, vr: dict[str, int], kind: str
) -> None:
    """q0 = [0.05, 0, 0] with the clearance 0.02 m is 0.03 m deep: fmi2ExitInitializationMode
    returns fmi2Error naming the state and the indentation (before: a silent run with
    F_N = 2.5e8 N); at the limit it starts, and the limit is a parameter."""
    from fmpy.fmi1 import FMICallException

    fmu, log = make_fmu(kind)
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.setReal([vr["body1.x"], vr["body1.y"]], [0.05, 0.0])
    with pytest.raises(FMICallException):
        fmu.exitInitializationMode()
    message = log.errors()[-1]
    assert "body1.x = 0.05 m, body1.y = 0 m, body1.theta = 0 rad" in message
    assert "contact.indentation = 0.03 m > contact.max_initial_indentation = 0.001 m" in message
    # just inside the limit: accepted; and a larger limit accepts the deep start
    for x, limit in ((0.02 + 0.999e-3, None), (0.05, 0.04)):
        fmu, log = make_fmu(kind)
        fmu.setupExperiment(startTime=0.0)
        fmu.enterInitializationMode()
        fmu.setReal([vr["body1.x"], vr["body1.y"]], [x, 0.0])
        if limit is not None:
            fmu.setReal([vr["contact.max_initial_indentation"]], [limit])
        fmu.exitInitializationMode()
        assert fmu.getBoolean([vr["contact.active"]])[0]


def test_scene_loader_refuses_a_deep_start(tmp_path) -> None:
    """The scene loader says the same in one line, and the CLI exits 2 with it."""
    import subprocess
    import sys

    from csfh.model.scene import SceneError, scene_from_dict

    with pytest.raises(SceneError) as info:
        scene_from_dict({"name": "deep", "initial": {"q": [0.05, 0.0, 0.0]}})
    assert "\n" not in str(info.value)
    assert "0.03 m deep" in str(info.value) and "contact.max_initial_indentation" in str(info.value)
    path = tmp_path / "huge.toml"
    path.write_text('name = "huge"\n[initial]\nq = [1e10, 0.0, 0.0]\n')
    r = subprocess.run(
        [sys.executable, "-m", "csfh", "run", str(path), "--law", "LN_spheres"],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert r.returncode == 2 and len(r.stderr.strip().splitlines()) == 1, r.stderr
    assert "deep in the bore" in r.stderr
    # an override of the limit lets a deeper start through (1.5e-3 m > 1e-3 m), up to the
    # harness's own limit of 1 % of R1 (1.8e-3 m: Hertz contact needs indentations small
    # against the radii), which no override raises
    scene_from_dict(
        {
            "name": "deep",
            "initial": {"q": [0.0215, 0.0, 0.0]},
            "parameters": {"contact.max_initial_indentation": 0.04},
        }
    )
    with pytest.raises(SceneError, match=r"at most 0\.01 contact\.R1 = 0\.0018 m"):
        scene_from_dict(
            {
                "name": "deep",
                "initial": {"q": [0.05, 0.0, 0.0]},
                "parameters": {"contact.max_initial_indentation": 0.04},
            }
        )


def test_model_exchange_runner_has_a_step_budget() -> None:
    from csfh.model.scene import load_scene
    from csfh.runners.fmu import SimulationError, simulate_me

    with pytest.raises(SimulationError, match="step budget"):
        simulate_me(load_scene("central"), "LN_spheres", max_steps=200)


# ---------------------------------------------------------------------------------------------
# what tools read in modelDescription.xml


def test_physical_variables_declare_their_quantity(model_description) -> None:
    """Every Real with a unit other than "1" names its physical quantity (tools group, convert
    and check connections by it); so do the dimensionless ones with a meaning of their own."""
    reals = [v for v in model_description.modelVariables if v.type == "Real"]
    missing = [v.name for v in reals if v.unit not in (None, "1") and not v.quantity]
    assert not missing
    quantity = {v.name: v.quantity for v in reals}
    assert quantity["contact.F_N"] == "Force" and quantity["body1.theta"] == "Angle"
    assert quantity["contact.E1"] == "ModulusOfElasticity"
    assert quantity["friction.fd"] == "CoefficientOfFriction"


def test_output_nominals_match_their_magnitude(fmu_path, model_description) -> None:
    """Tools scale tolerances and plots by the nominal (1 when absent): the nominal of every Real
    output is within a factor 100 of its largest magnitude in a co-simulation of the default
    scene (F_N peaks at 4.9e4 N, the indentation at 1e-4 m). The frame's acceleration a_frame is 0
    in that scene (no base acceleration, no shock pulse): its nominal is a_base's."""
    import fmpy
    import numpy as np

    outputs = [
        v for v in model_description.modelVariables if v.type == "Real" and v.causality == "output"
    ]
    r = fmpy.simulate_fmu(
        str(fmu_path),
        fmi_type="CoSimulation",
        output_interval=1e-4,
        output=[v.name for v in outputs],
    )
    by_name = {v.name: v for v in model_description.modelVariables}
    for v in outputs:
        largest = float(np.max(np.abs(r[v.name])))
        nominal = float(v.nominal) if v.nominal is not None else 1.0
        if v.name.startswith("a_frame["):
            assert largest == 0.0, v.name
            assert v.nominal == by_name[v.name.replace("a_frame", "a_base")].nominal
            continue
        assert largest > 0, v.name
        assert nominal / 100 <= largest <= 100 * nominal, (v.name, largest, nominal)


def test_min_and_max_are_what_the_fmu_accepts(make_fmu: MakeFmu, model_description) -> None:
    """min and max are inclusive in FMI: the FMU accepts exactly them and refuses the next value
    beyond (an open end of a range is written as the next double inside)."""
    from fmpy.fmi1 import FMICallException

    checked = 0
    for v in model_description.modelVariables:
        if v.causality != "parameter" or v.type not in ("Real", "Integer"):
            continue
        for bound, outward in ((v.min, -math.inf), (v.max, math.inf)):
            if bound is None:
                continue
            fmu, _ = make_fmu("CS")
            if v.type == "Real":
                inside, outside = float(bound), math.nextafter(float(bound), outward)
                fmu.setReal([v.valueReference], [inside])
                with pytest.raises(FMICallException):
                    fmu.setReal([v.valueReference], [outside])
            else:
                inside = int(bound)
                fmu.setInteger([v.valueReference], [inside])
                with pytest.raises(FMICallException):
                    fmu.setInteger([v.valueReference], [inside + (1 if outward > 0 else -1)])
            checked += 1
    assert checked >= 40


def test_generation_date_is_reproducible(tmp_path, model_description) -> None:
    """generationDateAndTime comes from SOURCE_DATE_EPOCH (the build uses the last commit's
    time when it is not set): the same sources give the same modelDescription.xml."""
    import datetime
    import os
    import subprocess
    import sys
    from pathlib import Path

    root = Path(__file__).resolve().parents[2]
    texts = []
    for k in range(2):
        out = tmp_path / f"gen{k}"
        env = {**os.environ, "SOURCE_DATE_EPOCH": "1700000000"}
        subprocess.run(
            [
                sys.executable,
                str(root / "modelDescription" / "generate.py"),
                str(root / "modelDescription" / "variables.toml"),
                str(out),
            ],
            check=True,
            env=env,
        )
        texts.append((out / "modelDescription.xml").read_text())
    assert texts[0] == texts[1]
    assert 'generationDateAndTime="2023-11-14T22:13:20Z"' in texts[0]
    stamp = model_description.generationDateAndTime
    assert stamp is not None
    datetime.datetime.strptime(stamp, "%Y-%m-%dT%H:%M:%SZ")


@pytest.mark.parametrize(
    ("enum", "number", "value"),
    [
        ("contact.law", "contact.law_number", 3),
        ("contact.esdu_reading", "contact.esdu_reading_number", 2),
        ("solver.method", "solver.method_number", 3),
    ],
)
def test_enumerations_can_be_chosen_as_integers(
    make_fmu: MakeFmu, vr: dict[str, int], enum: str, number: str, value: int
) -> None:
    """For importers that ignore Enumeration variables (libcosim): the Integer NAME_number, when
    not 0, sets the Enumeration at initialization; 0 (the start value) keeps it."""
    fmu, _ = make_fmu("CS")
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    start = fmu.getInteger([vr[enum]])[0]
    assert start != value and fmu.getInteger([vr[number]])[0] == 0
    fmu.setInteger([vr[number]], [value])
    fmu.exitInitializationMode()
    assert fmu.getInteger([vr[enum]])[0] == value
    fmu, _ = make_fmu("CS")
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    assert fmu.getInteger([vr[enum]])[0] == start
