"""Model exchange through fmpy with CVode against the analytic oracles of PHYSICS.md section 7."""

from __future__ import annotations

import math
from ctypes import POINTER, c_double
from pathlib import Path

import fmpy
import numpy as np
import pytest

G = 9.81
DELTA = 0.02
# PHYSICS.md 7.1: free fall of 0.03 m from q0 = [0, 0.01, 0] to y = -delta
T_FIRST_CENTRAL = math.sqrt(2 * 0.03 / G)

LAWS = ["LN_spheres", "LN_cylinders", "LN_ESDU", "HuntCrossley", "Flores"]


def law_value(model_description: fmpy.model_description.ModelDescription, name: str) -> int:
    law_type = next(t for t in model_description.typeDefinitions if t.name == "ContactLaw")
    return next(int(item.value) for item in law_type.items if item.name == name)


def first_onset_time(result: np.ndarray) -> float:
    """Time of the first contact onset: the first recorded event where contact.count rises."""
    count = result["contact.count"]
    i = int(np.argmax(count >= 1))
    assert count[i] >= 1, "no contact happened"
    # with record_events the sample just before the increment is the event instant itself
    return float(result["time"][i - 1])


def test_analytic_first_contact_time_is_right() -> None:
    assert T_FIRST_CENTRAL == pytest.approx(0.078206, abs=5e-7)


@pytest.mark.parametrize("law", LAWS)
def test_first_central_contact_time_every_law(fmu_path: Path, model_description, law: str) -> None:
    result = fmpy.simulate_fmu(
        str(fmu_path),
        fmi_type="ModelExchange",
        stop_time=0.1,
        output_interval=1e-3,
        relative_tolerance=1e-8,
        record_events=True,
        start_values={
            "body1.x": 0.0,
            "body1.y": 0.01,
            "flexure.enabled": False,
            "friction.enabled": False,
            "contact.law": law_value(model_description, law),
        },
        output=["contact.count", "contact.gap", "body1.y"],
    )
    t_onset = first_onset_time(result)
    assert abs(t_onset - T_FIRST_CENTRAL) < 1e-6, (law, t_onset)
    # the event is located on the gap: the recorded gap at the event is ~0
    i = int(np.argmax(result["contact.count"] >= 1)) - 1
    assert abs(result["contact.gap"][i]) < 1e-9


def test_energy_conserved_elastic_impacts(fmu_path: Path, model_description) -> None:
    """c_r = 1, no friction, no flexure: Hertz contact is conservative (PHYSICS.md 7.5)."""
    result = fmpy.simulate_fmu(
        str(fmu_path),
        fmi_type="ModelExchange",
        stop_time=0.8,
        output_interval=2e-4,
        relative_tolerance=1e-12,
        record_events=True,
        start_values={
            "body1.x": 0.0,
            "body1.y": 0.01,
            "body1.vx": 0.3,
            "body1.omega": 0.5,
            "contact.cr": 1.0,
            "flexure.enabled": False,
            "friction.enabled": False,
            "contact.law": law_value(model_description, "LN_spheres"),
        },
        output=["energy.total", "contact.count", "contact.indentation"],
    )
    assert result["contact.count"][-1] >= 10
    energy = result["energy.total"]
    assert energy[0] == pytest.approx(1.4512, abs=1e-4)  # PHYSICS.md 7.5
    drift = np.max(np.abs(energy - energy[0])) / energy[0]
    assert drift < 1e-6, drift
    # the contact energy is really part of the balance (it is not ~0 during contacts)
    assert result["contact.indentation"].max() > 1e-5


def test_switched_off_parts_are_not_evaluated(fmu_path: Path, model_description) -> None:
    common = {"body1.x": 0.0, "body1.y": 0.01}
    off = fmpy.simulate_fmu(
        str(fmu_path),
        fmi_type="ModelExchange",
        stop_time=0.2,
        output_interval=1e-3,
        start_values={
            **common,
            "flexure.enabled": False,
            "friction.enabled": False,
            "contact.law": law_value(model_description, "none"),
        },
        output=[
            "diagnostics.flexure_evaluations",
            "diagnostics.friction_evaluations",
            "diagnostics.contact_evaluations",
            "diagnostics.rhs_evaluations",
        ],
    )
    assert off["diagnostics.rhs_evaluations"][-1] > 0
    assert off["diagnostics.flexure_evaluations"][-1] == 0
    assert off["diagnostics.friction_evaluations"][-1] == 0
    assert off["diagnostics.contact_evaluations"][-1] == 0
    on = fmpy.simulate_fmu(
        str(fmu_path),
        fmi_type="ModelExchange",
        stop_time=0.2,
        output_interval=1e-3,
        start_values={"body1.x": 0.01, "body1.y": 0.01},
        output=[
            "diagnostics.flexure_evaluations",
            "diagnostics.friction_evaluations",
            "diagnostics.contact_evaluations",
        ],
    )
    assert on["diagnostics.flexure_evaluations"][-1] > 0
    assert on["diagnostics.friction_evaluations"][-1] > 0
    assert on["diagnostics.contact_evaluations"][-1] > 0


def test_contact_force_acts_in_the_contact_mode_only(make_fmu, vr: dict[str, int]) -> None:
    """A penetrating state that the integrator probes before the onset event is located sees
    the flight forces (the relation gap < 0 is frozen between events, as in FMI/Modelica), so
    the located onset lies on the smooth flight solution; after the event the force acts."""
    fmu, _ = make_fmu("ME")
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.setBoolean([vr["flexure.enabled"], vr["friction.enabled"]], [False, False])
    fmu.setReal([vr["body1.x"], vr["body1.y"]], [0.0, 0.01])
    fmu.exitInitializationMode()
    fmu.newDiscreteStates()
    fmu.enterContinuousTimeMode()
    penetration = 1e-5  # m
    x = np.array([0.0, -DELTA - penetration, 0.0, 0.0, -0.77, 0.0])
    fmu.setContinuousStates(x.ctypes.data_as(POINTER(c_double)), 6)
    z = np.zeros(1)
    fmu.getEventIndicators(z.ctypes.data_as(POINTER(c_double)), 1)
    assert z[0] == pytest.approx(-penetration, rel=1e-6)  # the importer sees the crossing
    dx = np.zeros(6)
    fmu.getDerivatives(dx.ctypes.data_as(POINTER(c_double)), 6)
    assert dx[4] == -G  # flight: gravity only
    assert fmu.getReal([vr["contact.F_N"]])[0] == 0.0
    fmu.enterEventMode()
    fmu.newDiscreteStates()
    fmu.enterContinuousTimeMode()
    fmu.getDerivatives(dx.ctypes.data_as(POINTER(c_double)), 6)
    F_N = fmu.getReal([vr["contact.F_N"]])[0]
    assert F_N > 100.0  # Hertz at 10 um: K 1e10 N/m^1.5 x (1e-5 m)^1.5 ~ 3e2 N
    assert dx[4] > 0.0
