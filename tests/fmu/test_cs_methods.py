"""The integration methods of co-simulation (solver.method: auto, BDF, Adams, RK45): auto stays
with RK45 while the motion is not stiff, switches to BDF where it is (resting contact, a damped
contact mode) and goes back to RK45 where BDF is no faster, whatever the communication grid."""

from __future__ import annotations

import math
import re
from dataclasses import replace

import numpy as np
import pytest
from fmi2_calls import METHODS, MakeFmu, cs_instance, grid, run, states
from fmpy.model_description import ModelDescription
from oracles import G

from csfh.model.scene import Scene, load_scene

TRIAL = "auto: trying BDF"  # auto's logEvents line when RK45 struggles


KEPT = "auto: BDF kept"  # ... when BDF's trial steps are long enough


BACK = "auto: back to RK45"  # ... when they are not


AUTO_WINDOW = 100  # integrator steps per decision of auto (auto_policy.c)


AUTO_BDF_COST = 2.0  # a BDF step costs that many RK45 steps (auto_policy.c, model §10.7)


def steps_and_log(
    make_fmu: MakeFmu, md: ModelDescription, scene: Scene, method: str, t_end: float
) -> tuple[int, np.ndarray, str, float]:
    """Integrator steps (diagnostics.integrator_steps), final state, log and final indentation
    divided by the static one (m g / K_spheres)^(2/3) of a run at rtol 1e-6 with 1e-2 s
    communication steps."""
    refs = {v.name: v.valueReference for v in md.modelVariables}
    fmu, log = cs_instance(make_fmu, md, scene, tolerance=1e-6, method=method)
    run(fmu, grid(1e-2, t_end))
    steps = fmu.getInteger([refs["diagnostics.integrator_steps"]])[0]
    m, K, ind = fmu.getReal(
        [refs[n] for n in ("body1.m", "contact.K_spheres", "contact.indentation")]
    )
    return steps, states(fmu, refs), log.text(), ind / (m * G / K) ** (2 / 3)


def test_auto_stays_with_rk45_while_not_stiff(
    make_fmu: MakeFmu, model_description: ModelDescription
) -> None:
    """The csfh scene's first second (flight, impacts, flexure, friction) is not stiff at the
    steps its accuracy needs: auto never tries BDF and is exactly RK45, whose steps are far fewer
    than Adams' and BDF's (longer: 5th order; each costs 6 right-hand sides but almost no
    bookkeeping, see benchmarks/bench_event_vs_rk4.py for the time)."""
    scene = load_scene("csfh")
    auto = steps_and_log(make_fmu, model_description, scene, "auto", 1.0)
    rk45 = steps_and_log(make_fmu, model_description, scene, "RK45", 1.0)
    adams = steps_and_log(make_fmu, model_description, scene, "Adams", 1.0)
    bdf = steps_and_log(make_fmu, model_description, scene, "BDF", 1.0)
    assert TRIAL not in auto[2]
    assert auto[0] == rk45[0]
    np.testing.assert_array_equal(auto[1], rk45[1])
    assert auto[0] < 0.5 * adams[0] and auto[0] < 0.5 * bdf[0], (auto[0], adams[0], bdf[0])


def test_auto_switches_to_bdf_in_resting_contact(
    make_fmu: MakeFmu, model_description: ModelDescription
) -> None:
    """Central drop with c_r = 0.9, no flexure, no friction (the stress suite's resting case):
    after about 1.5 s the body rests on the contact spring, which is stiff (its period is far
    below the time scale of the motion). RK45 alone is held to steps at its stability limit and
    Adams to steps of that period; auto tries BDF (logged), whose steps are far longer, and
    needs at most half of RK45's and of Adams' steps and no more than BDF's; all four end at
    rest at the static indentation (m g / K)^(2/3) (docs/model.md §7.2): within 1e-3 of it, except
    RK45 alone, which keeps an oscillation at its stability limit of the size its tolerance
    allows (the positions' absolute tolerance, 1e-6 x 0.01 m = 1e-8 m = 6e-3 of the static
    indentation 1.6e-6 m; measured 2e-3)."""
    scene = replace(
        load_scene("central").with_parameters(**{"contact.cr": 0.9}), flexure=False, friction=False
    )
    runs = {m: steps_and_log(make_fmu, model_description, scene, m, 4.0) for m in METHODS}
    assert TRIAL in runs["auto"][2]
    assert all(TRIAL not in runs[m][2] for m in ("Adams", "BDF", "RK45"))
    steps = {m: r[0] for m, r in runs.items()}
    assert steps["auto"] < 0.5 * steps["Adams"] and steps["auto"] < 0.5 * steps["RK45"], steps
    assert steps["auto"] <= steps["BDF"], steps
    static = (9.81 * 10.0 / 4.7353e10) ** (2 / 3)  # m (contact.K_spheres of the preset)
    for method, (_, x, _, static_ratio) in runs.items():
        assert np.all(np.abs(x[3:]) < 1e-4), (method, x)
        tolerance = 1e-8 / static if method == "RK45" else 1e-3
        assert static_ratio == pytest.approx(1.0, abs=tolerance), method


def pendulum_scene(cr: float, start_indentation: float) -> Scene:
    """Body 1 (no flexure, no friction) starts at rest in the bore at phi = 0.3 rad from the
    bottom, pressed into the wall by `start_indentation` x its static indentation there,
    rho_s = (m g cos(phi) / K_cylinders)^(2/3) (LN_cylinders, n = 1.5): it slides to and fro
    along the wall, a pendulum of length delta (period 2 pi sqrt(delta/g) = 0.28 s), on the
    contact spring, whose own period is ~1 ms."""
    phi, m, K = 0.3, 10.0, 2.2656e9
    rho_s = (m * G * math.cos(phi) / K) ** (2 / 3)
    r = 0.02 + start_indentation * rho_s
    base = load_scene("central").with_parameters(**{"contact.cr": cr})
    return replace(base, q0=(r * math.sin(phi), -r * math.cos(phi), 0.0), u0=(0.0, 0.0, 0.0))


def auto_runs(
    make_fmu: MakeFmu, md: ModelDescription, scene: Scene, tolerance: float, t_end: float
) -> dict[str, tuple[int, str]]:
    """Integrator steps and log of each method on the pendulum scene (LN_cylinders, 1e-2 s
    communication steps)."""
    refs = {v.name: v.valueReference for v in md.modelVariables}
    out = {}
    for method in METHODS:
        fmu, log = cs_instance(
            make_fmu, md, scene, tolerance=tolerance, law="LN_cylinders", method=method
        )
        run(fmu, grid(1e-2, t_end))
        out[method] = (fmu.getInteger([refs["diagnostics.integrator_steps"]])[0], log.text())
        fmu.terminate()
    return out


def decisions(log: str, what: str) -> list[float]:
    """The ratio of BDF's mean step to RK45's in each logged decision `what` of auto."""
    pattern = re.compile(re.escape(what) + r" \([^)]*mean step (\S+) s, RK45 (\S+) s\)")
    return [float(m.group(1)) / float(m.group(2)) for m in pattern.finditer(log)]


def test_auto_keeps_bdf_where_the_motion_is_stiff(
    make_fmu: MakeFmu, model_description: ModelDescription
) -> None:
    """The pendulum on the wall with c_r = 0.5: the LN damping, with the onset rate floored at
    contact.v_min = 1e-3 m/s, makes the contact's normal motion a strongly damped, stiff mode,
    while the motion itself is the slow pendulum. RK45's steps are held to the stiff mode's
    stability limit (its stiffness indicator flags them); auto tries BDF once, whose steps are
    then several times longer (the pendulum's accuracy sets them), and keeps it for the rest of
    the 4 s: one trial, one "BDF kept" with the mean steps' ratio above AUTO_BDF_COST, never
    back to RK45. So auto takes the steps of BDF (plus RK45's start: 10 % at most) and fewer
    than 35 % of RK45's (measured: 1673, 1782 and 8072 for auto, BDF and RK45; Adams 26161).
    With auto never keeping BDF (a cost of 15) it would fall back to RK45's steps. (With
    c_r = 0.9 BDF's steps are only 1.7 times RK45's, below the cost of a BDF step, and auto
    rightly goes back to RK45.)"""
    runs = auto_runs(make_fmu, model_description, pendulum_scene(0.5, 0.0), 1e-6, 4.0)
    log = runs["auto"][1]
    assert log.count(TRIAL) == 1 and log.count(KEPT) == 1 and BACK not in log, log
    (ratio,) = decisions(log, KEPT)
    assert ratio > AUTO_BDF_COST
    for method in ("Adams", "BDF", "RK45"):
        assert TRIAL not in runs[method][1] and KEPT not in runs[method][1]
    steps = {m: r[0] for m, r in runs.items()}
    assert steps["auto"] < 0.35 * steps["RK45"], steps
    assert steps["auto"] < 1.1 * steps["BDF"], steps


def test_auto_goes_back_to_rk45_where_bdf_is_no_faster(
    make_fmu: MakeFmu, model_description: ModelDescription
) -> None:
    """The pendulum on the wall with c_r = 1 (no damping), started at half its static
    indentation: the contact spring oscillates about the static indentation (amplitude rho_s/2,
    so it never lets go) all along the slide, and both methods must follow that oscillation:
    BDF's steps are half as long as RK45's (rtol 1e-9). RK45 fails often enough to make auto try
    BDF, and each trial ends "back to RK45" with the ratio of the mean steps below
    AUTO_BDF_COST, never "BDF kept"; the trials (two windows of AUTO_WINDOW steps each) cost at
    most their own steps over RK45's, and auto takes fewer steps than BDF alone (measured: auto
    5867, RK45 5174, BDF 10511, Adams 7140 in 1 s)."""
    runs = auto_runs(make_fmu, model_description, pendulum_scene(1.0, 0.5), 1e-9, 1.0)
    log = runs["auto"][1]
    trials, backs = log.count(TRIAL), decisions(log, BACK)
    assert KEPT not in log and trials >= 2 and len(backs) >= trials - 1, log
    assert max(backs) < AUTO_BDF_COST, backs
    assert "contact 2 starts" not in log  # one contact all along: no event restarts
    steps = {m: r[0] for m, r in runs.items()}
    assert steps["auto"] <= steps["RK45"] + trials * 2 * AUTO_WINDOW, (steps, trials)
    assert steps["auto"] < 0.85 * steps["BDF"], steps


def test_autos_decisions_do_not_depend_on_the_communication_grid(
    make_fmu: MakeFmu, model_description: ModelDescription, vr: dict[str, int]
) -> None:
    """auto decides at the end of every integrator step, also of a step that reaches or passes a
    communication point (it then switches there, or in the communication step that contains the
    step's end). On the undamped pendulum of the test above (several trials of BDF and returns
    to RK45 in 1 s), 1e-2 s communication steps and a random grid of 1e-5 s to 0.05 s steps give
    the same decisions at the same times, the same number of integrator steps and the same state
    at 1 s to round-off. (A step that reached a communication point and was not judged would
    have its window judged one step later, and the grid would change the trajectory.)"""
    scene = pendulum_scene(1.0, 0.5)
    lines = re.compile(r"t = \S+: auto: .*")

    def auto_run(points: np.ndarray) -> tuple[list[str], int, np.ndarray]:
        fmu, log = cs_instance(
            make_fmu, model_description, scene, tolerance=1e-9, law="LN_cylinders", method="auto"
        )
        run(fmu, points)
        n_steps = fmu.getInteger([vr["diagnostics.integrator_steps"]])[0]
        return (
            [m.group(0) for m in map(lines.match, log.text().splitlines()) if m],
            n_steps,
            states(fmu, vr),
        )

    rng = np.random.default_rng(11)
    sizes = np.exp(rng.uniform(np.log(1e-5), np.log(0.05), size=400))
    random_points = np.cumsum(sizes)
    random_points = np.append(random_points[random_points < 1.0], 1.0)
    coarse, fine = auto_run(grid(1e-2, 1.0)), auto_run(random_points)
    assert len(coarse[0]) >= 3, coarse[0]
    assert fine[0] == coarse[0]
    assert fine[1] == coarse[1]
    np.testing.assert_allclose(fine[2], coarse[2], rtol=1e-12, atol=1e-15)
