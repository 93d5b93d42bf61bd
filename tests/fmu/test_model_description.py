"""What tools read in modelDescription.xml: the quantity of every physical variable, output
nominals of their magnitude, min and max as the FMU accepts them, a reproducible generation
date, and the Integer twins of the Enumerations for importers that ignore Enumerations."""

from __future__ import annotations

import math

import pytest
from fmi2_calls import MakeFmu


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
