"""Model exchange through fmpy with CVode against the analytic oracles of docs/model.md §7 and
against the laws of sections 2 and 4 computed independently in the test (tests/oracles.py:
quadrature, scipy's integrators, the explicit direction of the ESDU law); and the event flags a
model-exchange importer sees at the contact-mode switches."""

from __future__ import annotations

import math
from ctypes import POINTER, c_double
from pathlib import Path
from typing import Any

import fmpy
import numpy as np
import oracles
import pytest
from fmi2_calls import STATES, MakeFmu
from oracles import T_FIRST_CENTRAL, V_FIRST_CENTRAL, G

from csfh.model.scene import load_scene
from csfh.runners.fmu import simulate_me

DELTA = 0.20 - 0.18  # R2 - R1 as the FMU computes it (0.02 + 1.7e-17)
M1, I1 = 10.0, 0.1617  # Table 1

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


def test_first_central_contact_is_the_free_fall(fmu_path: Path, model_description) -> None:
    """7.1: the flight before the first contact is a free fall (no law acts before the onset),
    located on the gap. At rtol 1e-8 CVode's position error is ~1e-8 x the 0.03 m fall, a time
    error of that over the impact speed, ~4e-10 s: 1e-8 s is tight and safe."""
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
            "contact.law": law_value(model_description, "LN_spheres"),
        },
        output=["contact.count", "contact.gap", "body1.y", "body1.vy"],
    )
    t_onset = first_onset_time(result)
    assert abs(t_onset - T_FIRST_CENTRAL) < 1e-8, t_onset
    i = int(np.argmax(result["contact.count"] >= 1)) - 1
    # the event is located on the gap: the recorded gap at the event is 0 to the root finder's
    # tolerance (the velocity times its time resolution)
    assert abs(result["contact.gap"][i]) < 1e-9
    assert result["body1.vy"][i] == pytest.approx(-V_FIRST_CENTRAL, rel=1e-7)


# ------------------------------------------------------------------------------------------
# each law's own physics: the central impact with gravity against the law integrated here


def _elastic_part(law: str, reading: str) -> Any:
    """F_el(rho) of the law with the paper preset's materials (E = 210 GPa, nu = 0.3), from
    docs/model.md §4.1-4.6 as written here."""
    K_sph, K_cyl = oracles.k_spheres(), oracles.k_cylinders()
    esdu = oracles.Esdu()
    if law in ("LN_spheres", "HuntCrossley", "Flores"):
        return lambda r: K_sph * r**1.5
    if law == "LN_cylinders":
        return lambda r: K_cyl * r**1.5
    if reading == "I2":
        return esdu.force
    return lambda r: esdu.tangent_stiffness(esdu.force(r)) * r**1.5  # I3, (4.12)


@pytest.mark.parametrize(
    ("law", "reading"),
    [
        ("LN_spheres", ""),
        ("LN_cylinders", ""),
        ("LN_ESDU", "I3"),
        ("LN_ESDU", "I2"),
        ("HuntCrossley", ""),
        ("Flores", ""),
    ],
)
def test_first_central_impact_every_law(law: str, reading: str) -> None:
    """The first impact of the central drop (c_r = 0.9): contact duration, largest indentation
    and exit speed against the law's own impact, m rho'' = m g - F_el(rho) max(0, 1 + xi rho' /
    v_imp) from rho' = v_imp, integrated here by scipy at rtol 1e-11 with F_el and xi written
    from docs/model.md §4 (sphere stiffness for Hunt-Crossley and Flores, (pi/4) E* L for the
    cylinders, the ESDU law from its explicit direction rho(F)). The FMU runs at rtol 1e-10; the
    two agree to ~1e-8 relative, so 1e-6 is tight: a stiffness off by 1 % moves the duration
    and the indentation by 0.4 %, the exit speed depends on xi."""
    scene = load_scene("central")
    parameters: dict[str, Any] = {}
    if reading:
        parameters["contact.esdu_reading"] = reading
    tr = simulate_me(scene, law, rtol=1e-10, stop_time=0.09, parameters=parameters)
    rec = tr.contact_records
    v_on = rec["onset_speed"][0]
    assert v_on == pytest.approx(V_FIRST_CENTRAL, rel=1e-8)
    expected = oracles.central_impact(
        _elastic_part(law, reading), oracles.xi(law, 0.9), v_in=float(v_on)
    )
    assert rec["t_release"][0] - rec["t_onset"][0] == pytest.approx(expected["duration"], rel=1e-6)
    assert rec["max_indentation"][0] == pytest.approx(expected["rho_max"], rel=1e-6)
    assert rec["release_speed"][0] == pytest.approx(expected["exit_speed"], rel=1e-6)


# ------------------------------------------------------------------------------------------
# each law's force at a given indentation and rate (one state, no integration)


def _contact_instance(
    make_fmu: Any,
    vr: dict[str, int],
    parameters: dict[str, Any],
    rho: float,
    rate: float,
    friction: bool = False,
) -> Any:
    """An initialized ME instance of the central geometry, started in contact at indentation
    rho [m] with indentation rate `rate` [m/s] (> 0 approaching: captured as the onset rate)."""
    fmu, _ = make_fmu("ME")
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.setBoolean([vr["flexure.enabled"], vr["friction.enabled"]], [False, friction])
    for name, value in parameters.items():
        if isinstance(value, bool):
            fmu.setBoolean([vr[name]], [value])
        elif isinstance(value, int):
            fmu.setInteger([vr[name]], [value])
        else:
            fmu.setReal([vr[name]], [float(value)])
    # the contact at the bottom of the bore: gap = delta - |r| = -rho, gamma_N = vy
    fmu.setReal([vr[n] for n in STATES], [0.0, -(DELTA + rho), 0.0, 0.0, -rate, 0.0])
    fmu.exitInitializationMode()
    fmu.newDiscreteStates()
    fmu.enterContinuousTimeMode()
    return fmu


def _indentation(rho: float) -> float:
    """The indentation the FMU sees at the state y = -(delta + rho): rho up to the rounding of
    delta + rho (an ulp of 0.02, 3.5e-18 m, is 3.5e-12 of rho = 1e-6 m)."""
    return abs(-(DELTA + rho)) - DELTA


def _set_rate(fmu: Any, rho: float, rate: float) -> None:
    x = np.array([0.0, -(DELTA + rho), 0.0, 0.0, -rate, 0.0])
    fmu.setContinuousStates(x.ctypes.data_as(POINTER(c_double)), 6)


LAW_NUMBER = {"LN_spheres": 2, "LN_cylinders": 3, "LN_ESDU": 4, "HuntCrossley": 5, "Flores": 6}


@pytest.mark.parametrize("law", ["LN_spheres", "LN_cylinders", "HuntCrossley", "Flores"])
@pytest.mark.parametrize("preset", ["paper", "consistent"])
def test_power_laws_force_at_an_indentation(
    make_fmu: Any, vr: dict[str, int], law: str, preset: str
) -> None:
    """F_N = K rho^n (1 + xi rho'/rho'-) (4.1) at indentations from 1e-6 to 5e-4 m, at the onset
    rate (factor 1 + xi) and separating at 0.3 of it (1 - 0.3 xi), with K from the materials
    (4.3: spheres, external radius for `paper`, internal for `consistent`; 4.4: cylinders,
    n = 1.5 or 1) and xi of the law (4.6), all computed here. Round-off only: 1e-12."""
    consistent = preset == "consistent"
    E = 100e9 if consistent else 210e9
    params: dict[str, Any] = {
        "contact.law": LAW_NUMBER[law],
        "contact.E1": E,
        "contact.E2": E,
        "contact.Reff_internal": consistent,
        "contact.n_cylinders": 1.0 if consistent else 1.5,
    }
    if law == "LN_cylinders":
        K, n = oracles.k_cylinders(E, E), (1.0 if consistent else 1.5)
    else:
        K, n = oracles.k_spheres(E, E, internal=consistent), 1.5
    xi = oracles.xi(law, 0.9)
    v = 0.5  # m/s, the onset rate (above contact.v_min)
    for rho in (1e-6, 1e-5, 1e-4, 5e-4):
        fmu = _contact_instance(make_fmu, vr, params, rho, v)
        rho = _indentation(rho)
        F_N = fmu.getReal([vr["contact.F_N"]])[0]
        assert F_N == pytest.approx(K * rho**n * (1 + xi), rel=1e-12), (rho, F_N)
        _set_rate(fmu, rho, -0.3 * v)
        F_N = fmu.getReal([vr["contact.F_N"]])[0]
        assert F_N == pytest.approx(K * rho**n * (1 - 0.3 * xi), rel=1e-12), (rho, F_N)


@pytest.mark.parametrize("E", [100e9, 210e9])
def test_esdu_law_force_indentation_pairs(make_fmu: Any, vr: dict[str, int], E: float) -> None:
    """ESDU-78035 (paper Eq. 18, docs/model.md §4.5): for forces F from 30 N to 3e5 N the test
    computes the indentation rho(F) = a F [ln(F*/F) + 1] (the equation's explicit direction; the FMU
    inverts it), starts the FMU at rest at that indentation (no damping) and reads F_N: reading
    I2 gives F itself, reading I3 the tangent stiffness K_t(F) = 1/(a ln(F*/F)) times rho^1.5
    (4.12). The FMU's Newton iteration is converged to 1e-15: 1e-10 relative."""
    esdu = oracles.Esdu(E, E)
    for F in (30.0, 1e3, 4.2e4, 3e5):
        rho = esdu.indentation(F)
        assert rho < 1e-3  # within contact.max_initial_indentation
        # the indentation the FMU sees differs from rho by the rounding of delta + rho (<= 1e-9
        # relative here); to first order (exact to ~1e-18) the force there is
        seen = _indentation(rho)
        F = F + (seen - rho) * esdu.tangent_stiffness(F)
        rho = seen
        for reading, expected in (
            ("I2", F),
            ("I3", esdu.tangent_stiffness(F) * rho**1.5),
        ):
            params = {
                "contact.law": LAW_NUMBER["LN_ESDU"],
                "contact.esdu_reading": 2 if reading == "I2" else 1,
                "contact.E1": E,
                "contact.E2": E,
            }
            fmu = _contact_instance(make_fmu, vr, params, rho, 0.0)
            F_N = fmu.getReal([vr["contact.F_N"]])[0]
            assert F_N == pytest.approx(expected, rel=1e-10), (reading, F, rho, F_N)


def test_ambrosio_friction_force_at_a_state(make_fmu: Any, vr: dict[str, int]) -> None:
    """Ambrosio friction (docs/model.md §5.1) at the bottom of the bore, indentation 1e-5 m, onset
    rate 0.5 m/s: F_T = -f_d c_d(|v_T|) F_N sgn(v_T), c_d = 0 below v0 = 1e-4 m/s, linear up
    to v1 = 1e-2 m/s, 1 above, with v_T of the contact point computed here from the corrected
    arm (3.4): n_c = [0, 1], t_c = [-1, 0], a = -R1 n_c, v_T = -v_x - R1 omega. F_N from the
    sphere law (4.1) computed here too. Round-off only: 1e-12."""
    fd, v0, v1, R1 = 0.055, 1e-4, 1e-2, 0.18
    rho, rate = 1e-5, 0.5
    params = {"contact.law": LAW_NUMBER["LN_spheres"]}
    fmu = _contact_instance(make_fmu, vr, params, rho, rate, friction=True)
    rho_seen = _indentation(rho)
    F_N = oracles.k_spheres() * rho_seen**1.5 * (1 + oracles.xi("LN", 0.9))
    for vx, omega in ((-5e-5, 0.0), (-4e-3, 0.0), (0.02, -0.2), (0.0, 0.3), (0.1, -0.5)):
        x = np.array([0.0, -(DELTA + rho), 0.0, vx, -rate, omega])
        fmu.setContinuousStates(x.ctypes.data_as(POINTER(c_double)), 6)
        v_T = -vx - R1 * omega
        c_d = min(1.0, max(0.0, (abs(v_T) - v0) / (v1 - v0)))
        F_T = fmu.getReal([vr["contact.F_T"]])[0]
        assert fmu.getReal([vr["contact.v_T"]])[0] == pytest.approx(v_T, rel=1e-12, abs=1e-18)
        assert fmu.getReal([vr["contact.F_N"]])[0] == pytest.approx(F_N, rel=1e-12)
        assert F_T == pytest.approx(
            -fd * c_d * F_N * math.copysign(1.0, v_T), rel=1e-12, abs=1e-12
        ), (vx, omega, v_T)


# ------------------------------------------------------------------------------------------
# the flexure: the force the FMU applies against the compliance integrated here


def _smooth_accelerations(fmu: Any, vr: dict[str, int], q: np.ndarray) -> np.ndarray:
    x = np.concatenate([q, np.zeros(3)])
    fmu.setContinuousStates(x.ctypes.data_as(POINTER(c_double)), 6)
    return np.array(fmu.getReal([vr[f"der({n})"] for n in STATES[3:]]))


def _flexure_instance(make_fmu: Any, vr: dict[str, int], bending_only: bool = False) -> Any:
    fmu, _ = make_fmu("ME")
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.setInteger([vr["contact.law"]], [1])  # none: the flexure alone (and inputs)
    fmu.setReal([vr["g"]], [0.0])
    fmu.setBoolean([vr["flexure.bending_only"]], [bending_only])
    fmu.exitInitializationMode()
    fmu.newDiscreteStates()
    fmu.enterContinuousTimeMode()
    return fmu


def test_flexure_static_deflection_holds_under_its_load(make_fmu: Any, vr: dict[str, int]) -> None:
    """Static deflection: at displaced states q (up to 1 cm and 0.2 rad) the test applies the
    load F_ext, M_ext = -Q_e(q) that holds body 1 there, with Q_e from its own compliance
    (Castigliano by quadrature in global coordinates, bending + axial + shear, docs/model.md §2.3)
    and the co-rotated law (2.7)-(2.9); the FMU must then be in equilibrium: accelerations
    ~0. The shear term alone moves the stiffness by ~3e-4 relative (the test sizes it), so a
    residual below 1e-9 of the load sees it; round-off is ~1e-13."""
    flex = oracles.Flexure()
    K0 = flex.stiffness()
    K0_no_shear = oracles.Flexure(shear=False).stiffness()
    assert np.max(np.abs(K0 - K0_no_shear)) / np.max(np.abs(K0)) > 1e-4  # the term is visible
    fmu = _flexure_instance(make_fmu, vr)
    inputs = [vr["F_ext[1]"], vr["F_ext[2]"], vr["M_ext"]]
    M = np.array([M1, M1, I1])
    for q in ([1e-3, 0.0, 0.0], [0.0, -1e-2, 0.0], [0.01, 0.01, 0.0], [-4e-3, 7e-3, 0.2]):
        q = np.array(q)
        Qe = flex.force(q, K0)
        fmu.setReal(inputs, list(-Qe))
        acc = _smooth_accelerations(fmu, vr, q)
        assert np.max(np.abs(acc * M)) < 1e-9 * np.max(np.abs(Qe)), (q, acc * M, Qe)


def test_flexure_natural_frequencies(make_fmu: Any, vr: dict[str, int]) -> None:
    """The natural frequencies of body 1 on the flexure (docs/model.md §7.7) from the FMU's forces
    (central differences of the accelerations at q = 0, step 1e-7: truncation ~1e-14 relative
    for the quadratic co-rotation terms, round-off ~1e-8) against det(K_G - w^2 M) = 0 with the
    test's own compliance: 1e-6 relative. With bending only (flexure.bending_only) they move by
    up to 2.4e-4 (the shear and axial terms): the test checks that too, against the test's
    bending-only compliance."""
    M = np.array([M1, M1, I1])
    for bending_only in (False, True):
        fmu = _flexure_instance(make_fmu, vr, bending_only)
        step = 1e-7
        KG = np.zeros((3, 3))
        for j in range(3):
            dq = np.zeros(3)
            dq[j] = step
            a_plus = _smooth_accelerations(fmu, vr, dq)
            a_minus = _smooth_accelerations(fmu, vr, -dq)
            KG[:, j] = -(a_plus - a_minus) * M / (2 * step)
        KG = 0.5 * (KG + KG.T)
        Mi = np.diag(1 / np.sqrt(M))
        f_fmu = np.sqrt(np.sort(np.linalg.eigvalsh(Mi @ KG @ Mi))) / (2 * math.pi)
        flex = oracles.Flexure(shear=not bending_only, axial=not bending_only)
        f_expected = oracles.natural_frequencies(flex)
        np.testing.assert_allclose(f_fmu, f_expected, rtol=1e-6)
    full = oracles.natural_frequencies(oracles.Flexure())
    bending = oracles.natural_frequencies(oracles.Flexure(shear=False, axial=False))
    assert np.max(np.abs(bending / full - 1)) > 1e-4  # the two differ far beyond the tolerance


# ------------------------------------------------------------------------------------------


def test_energy_conserved_elastic_impacts(fmu_path: Path, model_description) -> None:
    """c_r = 1, no friction, no flexure: Hertz contact is conservative (docs/model.md §7.5)."""
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
    # docs/model.md §7.5: kinetic (translation and rotation) + gravity at the start
    E0 = 0.5 * M1 * 0.3**2 + 0.5 * I1 * 0.5**2 + M1 * G * 0.01
    assert energy[0] == pytest.approx(E0, rel=1e-14)
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
    v = 0.77  # m/s, approaching
    x = np.array([0.0, -DELTA - penetration, 0.0, 0.0, -v, 0.0])
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
    # LN with the paper's sphere stiffness (4.3, E = 210 GPa, external radius: 4.7353e10
    # N/m^1.5) at 10 um, the onset rate captured at this event (the state's own rate): the
    # bracket is 1 + xi = 1.1425, F_N = 4.7353e10 x (1e-5)^1.5 x 1.1425 = 1711 N
    expected = oracles.k_spheres() * penetration**1.5 * (1 + oracles.xi("LN", 0.9))
    assert F_N == pytest.approx(expected, rel=1e-12)
    assert dx[4] == pytest.approx(F_N / M1 - G, rel=1e-12)


# ------------------------------------------------------------------------------------------
# what a model-exchange importer sees at the contact-mode switches


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
