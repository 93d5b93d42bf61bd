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
