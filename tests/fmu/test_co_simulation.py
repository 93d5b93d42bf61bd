"""Co-simulation of the csfh FMU: fmi2DoStep with an integrator inside the FMU (CVODE, RK45).

Accuracy against model exchange, contact onsets located inside communication steps (several per
step), variable step sizes, rollback with fmi2Get/SetFMUstate in a master loop, a provoked
integrator failure, the peak outputs of a communication step, inputs held over the step, the
default tolerance and the capability flags. (The integration methods and auto's switching:
test_cs_methods.py.)

Tolerances: "tight" is a relative tolerance of 1e-10 for both integrators (the FMU's, set with
fmi2SetupExperiment; fmpy's CVode in model exchange). CS onset times are read from the FMU's
logEvents lines, which print the located event time with 17 digits (fmpy routes the log of every
live instance to the last one created, so instances whose log is read run one after the
other)."""

from __future__ import annotations

import math
import re
from ctypes import byref, c_double
from pathlib import Path
from typing import Any

import fmpy
import numpy as np
import pytest
from fmi2_calls import (
    ERROR,
    METHODS,
    STATES,
    TIGHT,
    MakeFmu,
    apply_scene,
    cs_instance,
    grid,
    run,
    states,
)
from fmpy.fmi1 import FMICallException
from fmpy.model_description import ModelDescription
from fmu_binaries import run_cs_master
from oracles import T_FIRST_CENTRAL, V_FIRST_CENTRAL, G

from csfh.model.scene import Scene, load_scene
from csfh.runners.co_simulation import simulate_cs
from csfh.runners.model_exchange import simulate_me

RHO_MAX_CENTRAL = 1.19279e-4  # docs/model.md §7.2, K_spheres, m: the indentation scale
R1 = 0.18  # m, contact.R1 of the paper's scenes (Table 2)


# ------------------------------------------------------------------------------------------
# helpers


def onsets(log: Any) -> np.ndarray:
    """Contact onset times located inside the steps, from the FMU's logEvents lines."""
    pattern = re.compile(r"t = (\S+): contact \d+ starts")
    return np.array([float(m.group(1)) for _, _, msg in log.lines if (m := pattern.match(msg))])


def me_onsets(
    fmu_path: Path, scene: Scene, stop_time: float, law: str = "LN_spheres"
) -> np.ndarray:
    """Contact onsets in model exchange: fmpy.simulate_fmu with its CVode (BDF, root finding on
    the event indicator) at rtol 1e-10; with record_events the row before a rise of
    contact.count is the event instant."""
    values: dict[str, Any] = dict(scene.parameter_values(law))
    values.update(dict(zip(STATES, scene.x0, strict=True)))
    result = fmpy.simulate_fmu(
        str(fmu_path),
        fmi_type="ModelExchange",
        stop_time=stop_time,
        relative_tolerance=TIGHT,
        output_interval=1e-3,
        start_values=values,
        record_events=True,
        output=["contact.count"],
    )
    rise = np.nonzero(np.diff(result["contact.count"]) > 0)[0]
    return np.asarray(result["time"][rise], dtype=float)


# ------------------------------------------------------------------------------------------
# accuracy against model exchange


_ME_ONSETS: dict[str, np.ndarray] = {}


@pytest.mark.parametrize("method", list(METHODS))
@pytest.mark.parametrize("name", ["central", "asymmetric", "csfh"])
def test_cs_matches_me_contact_times(
    make_fmu: MakeFmu, model_description: ModelDescription, fmu_path: Path, name: str, method: str
) -> None:
    """CS (the FMU's integrator, each method) and ME (fmpy's CVode), both at rtol 1e-10, 1 s: the
    contact sequences agree up to the first contact whose time differs by 1 % (impacts make the
    motion chaotic), and the first three contact times agree within 1e-6 s."""
    scene = load_scene(name)
    if name not in _ME_ONSETS:
        _ME_ONSETS[name] = me_onsets(fmu_path, scene, 1.0)
    me = _ME_ONSETS[name]
    fmu, log = cs_instance(make_fmu, model_description, scene, method=method)
    run(fmu, grid(1e-3, 1.0))
    cs = onsets(log)
    assert len(me) >= 3 and len(cs) >= 3
    n = min(len(me), len(cs))
    diverged = np.nonzero(np.abs(cs[:n] - me[:n]) > 0.01 * me[:n])[0]
    agree = int(diverged[0]) if len(diverged) else n
    assert agree >= 3, (cs[: agree + 1], me[: agree + 1])
    np.testing.assert_allclose(cs[:3], me[:3], rtol=0, atol=1e-6)


_ME_RECORDS: dict[str, dict[str, np.ndarray]] = {}


@pytest.mark.parametrize("method", list(METHODS))
@pytest.mark.parametrize("name", ["central", "asymmetric", "csfh"])
def test_default_tolerance_gives_accurate_impacts(name: str, method: str) -> None:
    """At the FMU's default tolerance (1e-6) every method gets the first three impacts right against
    model exchange at rtol 1e-12: onset times within 3e-5 s, onset and release speeds within
    3e-4 relative. (The contact force acts in the contact mode only: otherwise a CVODE step that
    reaches past an onset carries the stiff contact force into the interpolant the root finder
    uses, and Adams has the csfh scene's first onset speed 1e-3 off, the next onsets 1e-4 s.)"""
    scene = load_scene(name)
    if name not in _ME_RECORDS:
        _ME_RECORDS[name] = simulate_me(scene, "LN_spheres", rtol=1e-12).contact_records
    ref = _ME_RECORDS[name]
    cs = simulate_cs(
        scene,
        "LN_spheres",
        rtol=1e-6,
        communication_step=1e-2,
        parameters={"solver.method": METHODS[method]},
    ).contact_records
    np.testing.assert_allclose(cs["t_onset"][:3], ref["t_onset"][:3], rtol=0, atol=3e-5)
    for key in ("onset_speed", "release_speed"):
        np.testing.assert_allclose(cs[key][:3], ref[key][:3], rtol=3e-4, err_msg=key)


def test_onset_located_well_below_the_indentation_scale(
    make_fmu: MakeFmu, model_description: ModelDescription
) -> None:
    """At the default tolerance (1e-6) the first central onset is at the analytic instant to
    within 1e-3 of the indentation scale (|dt| v_imp < 1e-3 rho_max = 1.2e-7 m), although the
    step (1e-2 s) is 20 times the contact duration, and the onset indentation rate is captured
    (docs/model.md §7.1: 0.767203 m/s)."""
    scene = load_scene("central")
    fmu, log = cs_instance(make_fmu, model_description, scene, tolerance=None)
    refs = {v.name: v.valueReference for v in model_description.modelVariables}
    t = run(fmu, grid(1e-2, 0.07))
    fmu.doStep(t, 0.0785 - t)  # ends inside the first contact (4.6e-4 s long)
    (t_on,) = onsets(log)
    assert abs(t_on - T_FIRST_CENTRAL) * V_FIRST_CENTRAL < 1e-3 * RHO_MAX_CENTRAL
    assert fmu.getBoolean([refs["contact.active"]])[0]
    speed = fmu.getReal([refs["contact.onset_speed"]])[0]
    assert speed == pytest.approx(V_FIRST_CENTRAL, rel=1e-4)


def test_many_contacts_in_one_communication_step(
    make_fmu: MakeFmu, model_description: ModelDescription, fmu_path: Path
) -> None:
    """Steps of 0.1 s on the central scene for 1.6 s (the bounces crowd towards the end: up to
    seven contacts in the last step): every contact inside a step is found (the count after
    each step equals model exchange's) and located as with 1e-3 s steps."""
    scene = load_scene("central")
    refs = {v.name: v.valueReference for v in model_description.modelVariables}
    me = me_onsets(fmu_path, scene, 1.6)
    fmu, log = cs_instance(make_fmu, model_description, scene)
    counts = []
    t = 0.0
    for p in grid(0.1, 1.6):
        t = run(fmu, [p], t)
        counts.append(fmu.getInteger([refs["contact.count"]])[0])
    me_counts = [int(np.sum(me <= p + 1e-12)) for p in grid(0.1, 1.6)]
    assert counts == me_counts
    assert max(np.diff([0, *counts])) >= 5, "some step must hold many contacts"
    coarse = onsets(log)
    fine, fine_log = cs_instance(make_fmu, model_description, scene)
    run(fine, grid(1e-3, 1.6))
    np.testing.assert_allclose(coarse, onsets(fine_log), rtol=0, atol=1e-6)
    np.testing.assert_allclose(coarse[:3], me[:3], rtol=0, atol=1e-6)


# ------------------------------------------------------------------------------------------
# communication steps, rollback


@pytest.mark.parametrize("method", list(METHODS))
def test_variable_step_sizes_give_the_fixed_step_trajectory(
    make_fmu: MakeFmu,
    model_description: ModelDescription,
    vr: dict[str, int],
    method: str,
) -> None:
    """Random step sizes (1e-4 s to 0.1 s) against fixed 1e-3 s steps on the csfh scene (rtol
    1e-10): the communication points do not cut the integrator's steps (it steps past them and
    interpolates) and do not set its first step after an event, so both masters drive the very
    same integrator steps: the same number of them, the same contacts and, at every 0.1 s, the
    same state. "The same" is measured against what a different sequence of steps of the same
    accuracy makes: the fixed grid once more at rtol 1.1e-10 moves the states by ~1e-9 m,
    1e-8 m/s and the onsets by ~5e-9 s (a stop time at every communication point would make the
    two grids differ by up to 1e-7); the two grids must agree to a tenth of that, which
    leaves round-off (a few 1e-12 m) out of the question."""
    scene = load_scene("csfh")
    blocks = [0.1 * k for k in range(1, 6)]
    scale = np.array([1.0, 1.0, R1])  # theta as the arc length on body 1's surface

    def fixed_grid(tolerance: float) -> tuple[np.ndarray, np.ndarray, int]:
        fmu, log = cs_instance(make_fmu, model_description, scene, tolerance, method=method)
        t, out = 0.0, []
        for _ in blocks:
            t = run(fmu, grid(1e-3, 0.1) + t, t)
            out.append(states(fmu, vr))
        n_steps = fmu.getInteger([vr["diagnostics.integrator_steps"]])[0]
        return np.array(out) * np.tile(scale, 2), onsets(log), n_steps

    reference, fixed_onsets, fixed_steps = fixed_grid(TIGHT)
    other, other_onsets, _ = fixed_grid(1.1 * TIGHT)
    assert len(other_onsets) == len(fixed_onsets) >= 5
    tol_q = 0.1 * np.max(np.abs(other[:, :3] - reference[:, :3]))
    tol_u = 0.1 * np.max(np.abs(other[:, 3:] - reference[:, 3:]))
    tol_t = 0.1 * np.max(np.abs(other_onsets - fixed_onsets))
    assert tol_q > 1e-11 and tol_u > 1e-10 and tol_t > 1e-11, (tol_q, tol_u, tol_t)
    rng = np.random.default_rng(7)
    variable, variable_log = cs_instance(make_fmu, model_description, scene, method=method)
    t, sizes, result = 0.0, [], []
    for end in blocks:
        cuts = np.sort(rng.uniform(end - 0.1, end, size=rng.integers(2, 30)))
        points = [*cuts, end]
        sizes += list(np.diff([t, *points]))
        t = run(variable, points, t)
        result.append(states(variable, vr))
    b = np.array(result) * np.tile(scale, 2)
    assert min(sizes) < 1e-3 < max(sizes)
    np.testing.assert_allclose(b[:, :3], reference[:, :3], rtol=0, atol=tol_q)
    np.testing.assert_allclose(b[:, 3:], reference[:, 3:], rtol=0, atol=tol_u)
    np.testing.assert_allclose(onsets(variable_log), fixed_onsets, rtol=0, atol=tol_t)
    assert variable.getInteger([vr["diagnostics.integrator_steps"]])[0] == fixed_steps


def test_communication_grid_costs_no_integration_steps(
    make_fmu: MakeFmu, model_description: ModelDescription, vr: dict[str, int]
) -> None:
    """1 s of the csfh scene (default tolerance) in communication steps of 0.1 s and of 1e-4 s
    (10000 steps, ten times more than the integrator needs): the same number of integrator steps
    and right-hand side evaluations, and the same state at 1 s to round-off."""

    def steps_and_state(h: float) -> tuple[int, int, np.ndarray]:
        fmu, _ = cs_instance(make_fmu, model_description, load_scene("csfh"), tolerance=None)
        run(fmu, grid(h, 1.0))
        refs = [vr["diagnostics.integrator_steps"], vr["diagnostics.rhs_evaluations"]]
        n_steps, n_rhs = fmu.getInteger(refs)
        return n_steps, n_rhs, states(fmu, vr)

    coarse, fine = steps_and_state(0.1), steps_and_state(1e-4)
    assert coarse[0] < 5000
    assert fine[:2] == coarse[:2]
    np.testing.assert_allclose(fine[2], coarse[2], rtol=1e-12, atol=1e-14)


def test_a_compiled_master_runs_the_fmu(
    fmu_path: Path, model_description: ModelDescription
) -> None:
    """benchmarks/master/bench_cs_master.c, a plain C importer (dlopen, fmi2Instantiate, start
    values, fmi2DoStep loop; no fmpy), runs the FMU binary to the same state and contact count
    as csfh.simulate_cs (the trajectory does not depend on the communication grid)."""
    root = Path(__file__).resolve().parents[2]
    master = root / "build" / "bench_cs_master"
    if not master.is_file():
        if (root / "build").is_dir():
            pytest.fail(f"{master} not built: cmake --build build")
        pytest.skip("no build tree")
    scene = load_scene("csfh")
    directory = Path(fmpy.extract(str(fmu_path)))
    starts = {**scene.parameter_values("LN_spheres"), **dict(zip(STATES, scene.x0, strict=True))}
    result = run_cs_master(
        [str(master)], directory / "binaries" / "linux64" / "csfh.so", model_description, starts
    )
    tr = simulate_cs(scene, "LN_spheres", rtol=1e-6, communication_step=0.1, stop_time=0.3)
    final = np.array([tr.table[n][-1] for n in ("x", "y", "theta", "vx", "vy", "omega")])
    assert result["steps"] == 300
    assert result["count"][0] == len(tr.contact_records["t_onset"]) >= 3
    np.testing.assert_allclose(result["read"], final, rtol=1e-12, atol=1e-14)


def test_rollback_in_a_master_loop(
    make_fmu: MakeFmu, model_description: ModelDescription, vr: dict[str, int]
) -> None:
    """A master that rejects every 0.02 s step in which a contact starts, restores the FMU state
    from before the step and redoes it in ten substeps. The rollback is invisible (time, states
    and discrete state come back exactly), and the result is bitwise that of a master taking the
    same accepted steps directly (fmi2GetFMUstate restarts the integrator, so the reference takes
    the state at the same points)."""
    scene = load_scene("central")
    h, t_end = 0.02, 0.6

    def master(rollback: bool, refine: set[int]) -> tuple[np.ndarray, set[int]]:
        fmu, _ = cs_instance(make_fmu, model_description, scene, tolerance=1e-8)
        t, rows, refined = 0.0, [], set()
        for k in range(round(t_end / h)):
            saved = fmu.getFMUstate()
            before = (
                fmu.getInteger([vr["contact.count"]])[0],
                states(fmu, vr),
                fmu.getReal([vr["time"]])[0],
            )
            substeps = k in refine
            if rollback:
                fmu.doStep(t, h)
                if fmu.getInteger([vr["contact.count"]])[0] > before[0]:  # reject the step
                    fmu.setFMUstate(saved)
                    assert fmu.getReal([vr["time"]])[0] == before[2]
                    assert fmu.getInteger([vr["contact.count"]])[0] == before[0]
                    np.testing.assert_array_equal(states(fmu, vr), before[1])
                    substeps = True
            elif not substeps:
                fmu.doStep(t, h)
            if substeps:
                refined.add(k)
                run(fmu, t + np.arange(1, 11) * h / 10, t)
            fmu.freeFMUstate(saved)
            t = (k + 1) * h
            rows.append([*states(fmu, vr), fmu.getInteger([vr["contact.count"]])[0]])
        return np.array(rows), refined

    with_rollback, refined = master(True, set())
    assert len(refined) >= 3
    direct, _ = master(False, refined)
    np.testing.assert_array_equal(with_rollback, direct)


@pytest.mark.parametrize("method", list(METHODS))
def test_integrator_failure_is_an_error_with_its_message(
    make_fmu: MakeFmu, model_description: ModelDescription, vr: dict[str, int], method: str
) -> None:
    """An input of 1e308 N is finite (accepted), but no step can follow it: the integrator fails.
    The step returns fmi2Error, the log has the integrator's own message and return flag (CVODE's
    for BDF and Adams, RK45's for RK45 and auto, which starts with it), the instance holds the
    last successful state (finite, consistent with fmi2LastSuccessfulTime), refuses further
    steps, and a rollback to a saved state recovers it exactly."""
    scene = load_scene("central")
    fmu, log = cs_instance(make_fmu, model_description, scene, tolerance=1e-8, method=method)
    t = run(fmu, grid(1e-2, 0.05))
    saved = fmu.getFMUstate()
    before = states(fmu, vr)
    fmu.setReal([vr["F_ext[2]"]], [1e308])
    with pytest.raises(FMICallException) as info:
        fmu.doStep(t, 1e-2)
    assert info.value.status == ERROR
    errors = log.errors()
    if method in ("BDF", "Adams"):
        assert any(m.startswith("CVODE CVode: ") for m in errors), errors  # CVODE's own text
        assert any(re.search(r"CVode failed with CV_[A-Z_]+", m) for m in errors), errors
    else:
        assert any(m.startswith("RK45 rk45_step: ") for m in errors), errors  # RK45's own text
        assert any(re.search(r"rk45_step failed with RK45_[A-Z_]+", m) for m in errors), errors
    now = fmu.getReal([vr["time"]])[0]
    x = states(fmu, vr)
    assert np.all(np.isfinite(x)) and t <= now < t + 1e-2
    status = c_double()
    fmu.fmi2GetRealStatus(fmu.component, 2, byref(status))  # fmi2LastSuccessfulTime
    assert status.value == now
    with pytest.raises(FMICallException):
        fmu.doStep(now, 1e-2)
    assert "illegal call in state StepFailed" in log.text()

    fmu.setFMUstate(saved)  # rollback
    fmu.freeFMUstate(saved)
    np.testing.assert_array_equal(states(fmu, vr), before)
    fmu.setReal([vr["F_ext[2]"]], [0.0])
    run(fmu, t + grid(1e-2, 0.05), t)
    reference, _ = cs_instance(make_fmu, model_description, scene, tolerance=1e-8, method=method)
    t = run(reference, grid(1e-2, 0.05))
    reference.freeFMUstate(reference.getFMUstate())  # the same restart as above
    run(reference, t + grid(1e-2, 0.05), t)
    np.testing.assert_array_equal(states(fmu, vr), states(reference, vr))


# ------------------------------------------------------------------------------------------
# peak outputs

PEAKS = ("contact.F_N_peak", "contact.F_T_peak", "contact.indentation_peak")


@pytest.mark.parametrize("method", ["RK45", "auto", "Adams"])
def test_peaks_do_not_depend_on_when_they_are_read(
    make_fmu: MakeFmu, model_description: ModelDescription, vr: dict[str, int], method: str
) -> None:
    """The peak outputs of a communication step are the same, bit for bit, whether the master
    reads them after every step or only now and then: RK45's steps are analysed for them only
    when they are read (an output read, an FMU state taken, a value set), CVODE's when taken.
    A master that reads no output does not pay for them: fewer contact evaluations (RK45)."""
    scene = load_scene("csfh")
    points = grid(1e-2, 1.0)
    peak_refs = [vr[n] for n in PEAKS]

    def master(read_every: int) -> tuple[dict[int, list[float]], int]:
        fmu, _ = cs_instance(make_fmu, model_description, scene, tolerance=1e-6, method=method)
        t, seen = 0.0, {}
        for k, p in enumerate(points):
            fmu.doStep(t, p - t)
            t = float(p)
            if read_every and k % read_every == 0:
                seen[k] = fmu.getReal(peak_refs)
        return seen, fmu.getInteger([vr["diagnostics.contact_evaluations"]])[0]

    every, evaluations_every = master(1)
    sometimes, _ = master(7)
    _, evaluations_never = master(0)
    assert sum(v[0] > 0 for v in every.values()) >= 10  # steps that hold contacts
    for k, values in sometimes.items():
        assert values == every[k], (k, values, every[k])
    if method != "Adams":  # (CVODE's steps are analysed when taken)
        assert evaluations_never < 0.9 * evaluations_every, (evaluations_never, evaluations_every)


LOADS = (  # the outputs the FMU computes alone (csfh_model_load_outputs)
    *("contact.F_N", "contact.F_T", "contact.indentation", *PEAKS),
    *("flexure.stress_max", "flexure.stress_location", "flexure.stress_max_peak"),
    *("flexure.stress_margin", "contact.pressure_max", "contact.half_width"),
    *("contact.pressure_max_peak", "contact.pressure_margin"),
)
OTHERS = ("contact.gap", "contact.v_T", "contact.indentation_rate", "energy.total")
OTHERS += ("energy.kinetic", "energy.flexure", "energy.contact", "a_frame[1]", "a_frame[2]")


@pytest.mark.parametrize("method", ["RK45", "Adams"])
def test_the_loads_read_alone_are_those_of_all_outputs(
    make_fmu: MakeFmu, model_description: ModelDescription, vr: dict[str, int], method: str
) -> None:
    """A master that reads only the loads (forces, indentation, stresses, peaks, margins) gets
    them, bit for bit, as one that reads every output: the FMU computes the loads alone then
    (no flexure force for the energy: fewer flexure evaluations), and an output read after
    them in the same communication step is computed then, not left as it was. Reading the
    others first, or all in one call, gives the same values too."""
    scene = load_scene("csfh")
    points = grid(1e-3, 0.2)
    loads, others = [vr[n] for n in LOADS], [vr[n] for n in OTHERS]

    def master(reads: list[list[int]]) -> tuple[list[list[float]], int]:
        fmu, _ = cs_instance(make_fmu, model_description, scene, tolerance=1e-6, method=method)
        t, seen = 0.0, []
        for p in points:
            fmu.doStep(t, p - t)
            t = float(p)
            seen.append([x for refs in reads for x in fmu.getReal(refs)])
        return seen, fmu.getInteger([vr["diagnostics.flexure_evaluations"]])[0]

    together, n_together = master([loads + others])
    apart, n_apart = master([loads, others])
    others_first, _ = master([others, loads])
    alone, n_alone = master([loads])
    assert sum(v[3] > 0 for v in together) >= 2  # steps that hold contacts (F_N_peak > 0)
    assert apart == together
    assert [v[len(others) :] + v[: len(others)] for v in others_first] == together
    assert [v[: len(loads)] for v in together] == alone
    # one flexure force per point for the energy, none for the loads alone
    assert n_alone == n_together - len(points) and n_apart == n_together


@pytest.mark.parametrize("method", list(METHODS))
def test_peaks_match_a_fine_sampling(
    make_fmu: MakeFmu, model_description: ModelDescription, vr: dict[str, int], method: str
) -> None:
    """The peaks of 1e-2 s communication steps (central scene, three impacts, rtol 1e-8) against
    the largest F_N and indentation read at every point of a 2e-6 s grid in a second run (the
    trajectory does not depend on the grid): at least the sampled maximum (to round-off), and
    above it by no more than sampling can miss. A sample is at most dt = 1e-6 s from the
    maximum, where F_N = K rho^1.5 curves by |F''| / F = 1.5 K rho_max^0.5 / m (from
    m rho'' = -K rho^1.5 at rho' = 0) and rho by K rho_max^0.5 / m: a relative miss of at most
    that times dt^2 / 2 (3.9e-5 for F_N)."""
    scene = load_scene("central")
    t_end = 0.4
    coarse, _ = cs_instance(make_fmu, model_description, scene, tolerance=1e-8, method=method)
    fine, _ = cs_instance(make_fmu, model_description, scene, tolerance=1e-8, method=method)
    refs = [vr["contact.F_N"], vr["contact.indentation"]]
    peak_refs = [vr["contact.F_N_peak"], vr["contact.indentation_peak"]]
    K, m = coarse.getReal([vr["contact.K_spheres"], vr["body1.m"]])
    h, sub = 1e-2, 5000
    dt = 0.5 * h / sub
    t = 0.0
    checked = 0
    for k in range(round(t_end / h)):
        coarse.doStep(k * h, h)
        peaks = np.array(coarse.getReal(peak_refs))
        sampled = np.zeros(2)
        for i in range(sub):
            t_next = k * h + (i + 1) * h / sub
            fine.doStep(t, t_next - t)
            t = t_next
            sampled = np.maximum(sampled, fine.getReal(refs))
        if sampled[0] > 0:
            checked += 1
            curvature = K * math.sqrt(sampled[1]) / m * np.array([1.5, 1.0])  # |v''| / v, 1/s^2
            miss = curvature * dt**2 / 2
            assert np.all(peaks >= sampled * (1 - 1e-12)), (k, peaks, sampled)
            assert np.all(peaks <= sampled * (1 + miss)), (k, peaks, sampled, miss)
    assert checked == 3


@pytest.fixture(scope="module")
def csfh_reference():
    """The harness's model-exchange run of the csfh scene (the FMU's start values) at rtol 1e-10:
    per contact, the peak F_N and indentation refined on CVODE's interpolant."""
    from csfh.model.scene import load_scene
    from csfh.runners.model_exchange import simulate_me

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


# ------------------------------------------------------------------------------------------
# inputs, tolerance, capabilities


def test_inputs_are_held_over_the_step_free_flight(
    make_fmu: MakeFmu, model_description: ModelDescription, vr: dict[str, int]
) -> None:
    """No contact law, no flexure: body 1 flies freely under gravity and the inputs. Inputs set
    at a communication point are held over the step (zero-order hold), so the motion is the
    analytic piecewise parabola, whatever the step: F_ext = [3, 5] N, M_ext = 0.2 N m until
    0.25 s, then F_ext = [-2, 0] N, M_ext = 0."""
    scene = load_scene("central")
    m, inertia = 10.0, 0.1617
    fmu, _ = make_fmu("CS")
    fmu.setupExperiment(tolerance=TIGHT, startTime=0.0)
    fmu.enterInitializationMode()
    apply_scene(fmu, model_description, scene, "LN_spheres")
    fmu.setInteger([vr["contact.law"]], [1])  # none: no contact at all
    fmu.setReal([vr["body1.vx"]], [0.1])
    fmu.exitInitializationMode()

    def analytic(t: float) -> np.ndarray:
        def phase(x0: np.ndarray, F: tuple[float, float, float], dt: float) -> np.ndarray:
            acc = np.array([F[0] / m, F[1] / m - G, F[2] / inertia])
            return np.concatenate([x0[:3] + x0[3:] * dt + 0.5 * acc * dt**2, x0[3:] + acc * dt])

        x0 = np.array([0.0, 0.01, 0.0, 0.1, 0.0, 0.0])
        if t <= 0.25:
            return phase(x0, (3.0, 5.0, 0.2), t)
        return phase(phase(x0, (3.0, 5.0, 0.2), 0.25), (-2.0, 0.0, 0.0), t - 0.25)

    inputs = [vr["F_ext[1]"], vr["F_ext[2]"], vr["M_ext"]]
    fmu.setReal(inputs, [3.0, 5.0, 0.2])
    t = 0.0
    for p in (0.01, 0.05, 0.125, 0.25, 0.26, 0.3, 0.4):
        if t == 0.25:
            fmu.setReal(inputs, [-2.0, 0.0, 0.0])
        t = run(fmu, [p], t)
        np.testing.assert_allclose(states(fmu, vr), analytic(t), rtol=0, atol=1e-9)


def test_default_tolerance_is_1e_6(
    make_fmu: MakeFmu, model_description: ModelDescription, vr: dict[str, int]
) -> None:
    """Without a tolerance from fmi2SetupExperiment the FMU uses 1e-6 (the DefaultExperiment
    tolerance of modelDescription.xml): bitwise the run with tolerance 1e-6, not that with 1e-8."""
    assert model_description.defaultExperiment.tolerance == "1e-06"
    scene = load_scene("csfh")
    result = {}
    for tol in (None, 1e-6, 1e-8):
        fmu, _ = cs_instance(make_fmu, model_description, scene, tolerance=tol)
        run(fmu, grid(1e-2, 0.3))
        result[tol] = states(fmu, vr)
    np.testing.assert_array_equal(result[None], result[1e-6])
    assert not np.array_equal(result[None], result[1e-8])


def test_capability_flags_say_what_is_supported(
    make_fmu: MakeFmu, model_description: ModelDescription, vr: dict[str, int]
) -> None:
    """Every <CoSimulation> flag matches the behaviour: the false ones are refused with
    fmi2Error, the true ones work."""
    cs = model_description.coSimulation
    assert cs.canHandleVariableCommunicationStepSize  # test_variable_step_sizes_...
    assert cs.canGetAndSetFMUstate and cs.canSerializeFMUstate  # rollback tests
    assert cs.canNotUseMemoryManagementFunctions
    assert not cs.canBeInstantiatedOnlyOncePerProcess
    assert not cs.canInterpolateInputs and cs.maxOutputDerivativeOrder == 0
    assert not cs.canRunAsynchronuously
    assert cs.providesDirectionalDerivative  # test_directional_derivatives.py

    first, _ = cs_instance(make_fmu, model_description, load_scene("central"))
    fmu, log = cs_instance(make_fmu, model_description, load_scene("csfh"))  # two at once
    fmu.doStep(0.0, 1e-3)
    first.doStep(0.0, 5e-3)
    fmu.doStep(1e-3, 4e-3)  # another step size
    assert fmu.getReal([vr["body1.x"]])[0] != first.getReal([vr["body1.x"]])[0]
    state = fmu.getFMUstate()
    fmu.deSerializeFMUstate(fmu.serializeFMUstate(state))
    fmu.setFMUstate(state)

    ref = [vr["F_ext[1]"]]
    refused = {
        "fmi2SetRealInputDerivatives": lambda: fmu.setRealInputDerivatives(ref, [1], [0.0]),
        "fmi2GetRealOutputDerivatives": lambda: fmu.getRealOutputDerivatives(ref, [1]),
        "fmi2CancelStep": fmu.cancelStep,
    }
    for name, call in refused.items():
        with pytest.raises(FMICallException) as info:
            call()
        assert info.value.status == ERROR, name
        assert name in log.errors()[-1], (name, log.errors())
