"""The compliant models through the FMU (csfh.runners: simulate, simulate_me): the first central
contact of every model, the first rebound against docs/model.md §7.3, switched-off parts never
evaluated, the model-exchange driver against fmpy's, and its step budget."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import fmpy
import numpy as np
import pytest
from oracles import T_FIRST_CENTRAL

from csfh.model.scene import Scene, load_scene
from csfh.runners.fmu import STATE_NAMES, simulate_me
from csfh.runners.moreau import moreau


def test_all_models_reach_the_first_central_contact_together() -> None:
    """7.1: every model meets the bore at t = sqrt(2 * 0.03 / g) (Moreau: within one step)."""
    scene = load_scene("central")
    for law in ("LN_spheres", "LN_cylinders", "LN_ESDU"):
        tr = simulate_me(scene, law, stop_time=0.1)
        assert abs(tr.contacts[0] - T_FIRST_CENTRAL) < 1e-6, law
    tr = moreau(scene, stop_time=0.1)
    h = scene.integrator.moreau_h
    assert abs(tr.contacts[0] - T_FIRST_CENTRAL) <= h


@pytest.mark.parametrize(
    ("law", "duration", "e_eff", "max_indentation", "second_contact"),
    [
        ("LN_spheres", 4.6251e-4, 0.9128, 1.1524e-4, 0.221437),
        ("LN_cylinders", 1.5621e-3, 0.9118, 3.8984e-4, 0.222383),
        ("Flores", None, 0.8934, None, 0.218412),
        ("HuntCrossley", None, 0.9086, None, 0.220783),
    ],
)
def test_first_rebound_matches_physics_7_3(
    law: str,
    duration: float | None,
    e_eff: float,
    max_indentation: float | None,
    second_contact: float,
) -> None:
    """7.3 (with gravity, Table 2 stiffness): contact duration, effective restitution, maximum
    indentation and the time of the second contact, each within 1e-3 (relative)."""
    scene = load_scene("central")
    tr = simulate_me(
        scene, law, rtol=1e-10, stop_time=0.25, parameters={"contact.K_from_materials": False}
    )
    t_on, t_off = tr.contacts[0], tr.releases[0]
    tab = tr.table
    v_on = tab["vy"][np.nonzero(tab["t"] == t_on)[0][0]]
    v_off = tab["vy"][np.nonzero(tab["t"] == t_off)[0][0]]
    assert -v_off / v_on == pytest.approx(e_eff, rel=1e-3)
    assert tr.contacts[1] == pytest.approx(second_contact, rel=1e-3)
    if duration is not None:
        assert t_off - t_on == pytest.approx(duration, rel=1e-3)
    if max_indentation is not None:
        assert np.max(tr.steps["indentation"]) == pytest.approx(max_indentation, rel=1e-3)


@pytest.mark.parametrize("interface", ["me", "cs"])
def test_switched_off_parts_are_never_evaluated(interface: str) -> None:
    """A scene runs only what it needs: flexure/friction off means never evaluated (counters of
    the FMU and of the core library); on means evaluated."""
    from csfh.runners.simulate import simulate

    off = load_scene("central").with_parameters()  # no flexure, no friction
    for model in ("LN_spheres", "Moreau"):
        ev = simulate(off, model, interface=interface, stop_time=0.2).stats["evaluations"]
        assert ev["flexure"] == 0 and ev["friction"] == 0, (model, ev)
        assert ev["contact"] > 0
    on = load_scene("csfh")
    for model in ("LN_spheres", "Moreau"):
        ev = simulate(on, model, interface=interface, stop_time=0.2).stats["evaluations"]
        assert ev["flexure"] > 0 and ev["friction"] > 0, (model, ev)


def simulate_fmpy(
    fmu_path: Path, scene: Scene, law: str, *, rtol: float, output_interval: float
) -> np.ndarray:
    """fmpy.simulate_fmu in model exchange with CVode, as fmpy does it (mind fmpy's limit of 500
    internal CVode steps per output interval)."""
    values: dict[str, Any] = dict(scene.parameter_values(law))
    values.update(dict(zip(STATE_NAMES, scene.x0, strict=True)))
    values.update(scene.inputs)
    return fmpy.simulate_fmu(
        str(fmu_path),
        fmi_type="ModelExchange",
        stop_time=scene.stop_time,
        relative_tolerance=rtol,
        output_interval=output_interval,
        start_values=values,
        record_events=True,
        output=[*STATE_NAMES, "contact.count"],
    )


def test_me_driver_agrees_with_fmpy_simulate_fmu(fmu_path: Path) -> None:
    """Our one-step model-exchange driver and fmpy.simulate_fmu give the same trajectory."""
    scene = load_scene("asymmetric")
    ours = simulate_me(scene, "LN_spheres", rtol=1e-9, stop_time=0.2)
    theirs = simulate_fmpy(
        fmu_path,
        scene.__class__(**{**scene.__dict__, "stop_time": 0.2}),
        "LN_spheres",
        rtol=1e-9,
        output_interval=1e-4,
    )
    for col, name in (("x", "body1.x"), ("y", "body1.y"), ("theta", "body1.theta")):
        t_grid = np.arange(0, 0.2, 1e-3)
        a = np.interp(t_grid, ours.t, ours[col])
        b = np.interp(t_grid, theirs["time"], theirs[name])
        np.testing.assert_allclose(a, b, atol=2e-6)


def test_model_exchange_runner_has_a_step_budget() -> None:
    from csfh.model.scene import load_scene
    from csfh.runners.fmu import SimulationError, simulate_me

    with pytest.raises(SimulationError, match="step budget"):
        simulate_me(load_scene("central"), "LN_spheres", max_steps=200)
