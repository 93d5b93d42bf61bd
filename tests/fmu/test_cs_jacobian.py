"""Co-simulation's BDF with the analytic Jacobian (solver.analytic_jacobian, docs/model.md §15):
the same trajectory as with CVODE's difference quotients within the integration tolerance, on
the csfh scene and on resting contact; CVODE forms its Jacobians from the model's (no right-hand
sides spent on them), and the default keeps the difference quotients."""

from __future__ import annotations

import numpy as np
import pytest
from fmi2_calls import METHODS, STATES, MakeFmu, apply_scene, cs_instance, grid, run, states
from fmpy.model_description import ModelDescription

from csfh.model.scene import Scene, load_scene
from csfh.studies.stress.cases import build_cases

RTOL = 1e-6


def resting() -> Scene:
    return next(c.scene for c in build_cases() if c.group == "resting")


def analytic_instance(make_fmu: MakeFmu, md: ModelDescription, scene: Scene, analytic: bool):
    """As cs_instance with BDF, solver.analytic_jacobian set in initialization mode."""
    refs = {v.name: v.valueReference for v in md.modelVariables}
    fmu, _ = make_fmu("CS")
    fmu.setupExperiment(tolerance=RTOL, startTime=0.0)
    fmu.enterInitializationMode()
    apply_scene(fmu, md, scene, "LN_spheres")
    fmu.setInteger([refs["solver.method"]], [METHODS["BDF"]])
    fmu.setBoolean([refs["solver.analytic_jacobian"]], [analytic])
    fmu.exitInitializationMode()
    return fmu, refs


def counted_run(
    make_fmu: MakeFmu, md: ModelDescription, scene: Scene, analytic: bool, t_end: float
) -> tuple[np.ndarray, dict[str, int]]:
    fmu, refs = analytic_instance(make_fmu, md, scene, analytic)
    run(fmu, grid(1e-2, t_end))
    names = ("integrator_steps", "rhs_evaluations", "jacobian_evaluations")
    counts = fmu.getInteger([refs[f"diagnostics.{n}"] for n in names])
    return states(fmu, refs), dict(zip(names, counts, strict=True))


@pytest.mark.parametrize("scene_name", ["csfh", "resting"])
def test_analytic_jacobian_gives_the_same_trajectory(
    make_fmu: MakeFmu, model_description: ModelDescription, scene_name: str
) -> None:
    scene = resting() if scene_name == "resting" else load_scene("csfh")
    t_end = 2.0 if scene_name == "resting" else 0.5
    dq, dq_counts = counted_run(make_fmu, model_description, scene, False, t_end)
    an, an_counts = counted_run(make_fmu, model_description, scene, True, t_end)
    # CVODE's error control: rtol |y| + atol per step, atol = rtol x the state's nominal value
    md = model_description
    nominal = np.array([next(v.nominal for v in md.modelVariables if v.name == n) for n in STATES])
    bound = 100 * RTOL * np.maximum(nominal.astype(float), np.abs(dq))
    assert np.all(np.abs(an - dq) <= bound), (an - dq, bound)
    assert not np.array_equal(an, dq)  # a different Newton matrix: not the same bits
    for counts in (dq_counts, an_counts):
        assert counts["jacobian_evaluations"] > 0 and counts["integrator_steps"] > 0
    # a difference-quotient Jacobian costs 6 right-hand sides; the analytic one none
    per_step_dq = (
        dq_counts["rhs_evaluations"] - 6 * dq_counts["jacobian_evaluations"]
    ) / dq_counts["integrator_steps"]
    per_step_an = an_counts["rhs_evaluations"] / an_counts["integrator_steps"]
    assert abs(per_step_an - per_step_dq) < 0.5 * per_step_dq, (dq_counts, an_counts)


def test_default_is_difference_quotients(
    make_fmu: MakeFmu, model_description: ModelDescription
) -> None:
    """The start value is false, and a run with it is bitwise the run that sets false."""
    md = model_description
    start = next(v.start for v in md.modelVariables if v.name == "solver.analytic_jacobian")
    assert start in ("false", False)
    scene = load_scene("csfh")
    refs = {v.name: v.valueReference for v in md.modelVariables}
    fmu, _ = cs_instance(make_fmu, md, scene, tolerance=RTOL, method="BDF")
    run(fmu, grid(1e-2, 0.2))
    default = states(fmu, refs)
    off, _ = counted_run(make_fmu, md, scene, False, 0.2)
    np.testing.assert_array_equal(default, off)


def test_rk45_forms_no_jacobian(make_fmu: MakeFmu, model_description: ModelDescription) -> None:
    refs = {v.name: v.valueReference for v in model_description.modelVariables}
    fmu, _ = cs_instance(make_fmu, model_description, load_scene("csfh"), method="RK45")
    run(fmu, grid(1e-2, 0.1))
    assert fmu.getInteger([refs["diagnostics.jacobian_evaluations"]]) == [0]
