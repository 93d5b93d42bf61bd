"""Directional and adjoint derivatives through fmpy's low-level API, FMI 2.0 and FMI 3.0, against
sixth-order central differences of getDerivatives / getReal (docs/model.md §15): model exchange
in flight and in contact (derivatives and continuous outputs with respect to the states and the
inputs), co-simulation (outputs with respect to the inputs), and bad arguments refused with a
message naming them."""

from __future__ import annotations

import ctypes
import math
import xml.etree.ElementTree as ET
import zipfile
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
from fmi2_calls import ERROR, MakeFmu
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import FMU2Model
from fmpy.fmi3 import FMU3Model, FMU3Slave, fmi3Float64
from fmpy.model_description import ModelDescription

STATES = ["body1.x", "body1.y", "body1.theta", "body1.vx", "body1.vy", "body1.omega"]
INPUTS = ["F_ext[1]", "F_ext[2]", "M_ext", "a_base[1]", "a_base[2]"]
DERIVATIVES = [f"der({s})" for s in STATES]
TOL = 1e-6  # of each row's largest entry


def continuous_outputs(md: ModelDescription) -> list[str]:
    return [
        v.name
        for v in md.modelVariables
        if v.causality == "output"
        and v.variability == "continuous"
        and v.type in ("Real", "Float64")
    ]


def step(name: str) -> float:
    """Small against the indentation (positions), the friction ramp (velocities)."""
    if name in STATES[:3]:
        return 1e-8
    return 1e-5 if name in STATES else 1e-3


def fd6(f: Callable[[float], np.ndarray], x: float, h: float) -> np.ndarray:
    d = [f(x + k * h) - f(x - k * h) for k in (1, 2, 3)]
    return (45.0 * d[0] - 9.0 * d[1] + d[2]) / (60.0 * h)


def assert_rows_close(analytic: np.ndarray, fd: np.ndarray, rows: list[str], what: str) -> None:
    for i, name in enumerate(rows):
        scale = max(float(np.max(np.abs(fd[i]))), float(np.max(np.abs(analytic[i]))), 1e-300)
        err = float(np.max(np.abs(analytic[i] - fd[i])))
        assert err <= TOL * scale, (what, name, analytic[i], fd[i])


def contact_start(rho: float, v_T: float, rho_dot: float, omega: float) -> dict[str, float]:
    """A start state indented by rho along -110 degrees (O1 at G1: the arm is -R1 n_c), sliding
    at v_T and approaching at rho_dot."""
    delta, R1, phi = 0.02, 0.18, math.radians(-110.0)
    e = (delta + rho) * np.array([math.cos(phi), math.sin(phi)])
    n = -e / np.linalg.norm(e)
    t = np.array([-n[1], n[0]])
    v = -rho_dot * n + (v_T + R1 * omega) * t  # v_T = t.v - R1 omega
    return dict(zip(STATES, [e[0], e[1], 0.0, v[0], v[1], omega], strict=True))


CASES = {
    "flight": dict(zip(STATES, [0.004, -0.006, 0.03, 0.2, -0.1, 1.5], strict=True)),
    "contact": contact_start(2e-5, 3e-3, 0.05, 0.2),
}
INPUT_VALUES = dict(zip(INPUTS, [3.0, -2.0, 0.4, 1.5, -0.7], strict=True))


# ------------------------------------------------------------------------------------------
# FMI 2.0


def me2(make_fmu: MakeFmu, vr: dict[str, int], start: dict[str, float]) -> FMU2Model:
    """A model-exchange instance (the tests' own callbacks: fmu_instances.py) in continuous-time
    mode at `start`, with the inputs of INPUT_VALUES."""
    fmu, _ = make_fmu("ME")
    fmu.setReal([vr[k] for k in start], list(start.values()))
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    fmu.newDiscreteStates()
    fmu.enterContinuousTimeMode()
    fmu.setReal([vr[k] for k in INPUTS], list(INPUT_VALUES.values()))
    return fmu


@pytest.mark.parametrize("case", list(CASES))
def test_fmi2_model_exchange_matches_differences(
    model_description: ModelDescription, make_fmu: MakeFmu, vr: dict[str, int], case: str
) -> None:
    md = model_description
    unknowns = DERIVATIVES + continuous_outputs(md)
    fmu = me2(make_fmu, vr, CASES[case])
    try:
        assert fmu.getBoolean([vr["contact.active"]])[0] == (case == "contact")
        x0 = np.array(fmu.getReal([vr[s] for s in STATES]))
        out_refs = [vr[u] for u in unknowns[6:]]

        def values() -> np.ndarray:
            der = (ctypes.c_double * 6)()
            fmu.getDerivatives(der, 6)
            return np.concatenate([np.array(der), np.array(fmu.getReal(out_refs))])

        analytic = np.zeros((len(unknowns), len(STATES + INPUTS)))
        fd = np.zeros_like(analytic)
        for j, known in enumerate(STATES + INPUTS):
            analytic[:, j] = fmu.getDirectionalDerivative(
                [vr[u] for u in unknowns], [vr[known]], [1.0]
            )
            if known in STATES:

                def f(s: float, j: int = j) -> np.ndarray:
                    x = x0.copy()
                    x[j] = s
                    fmu.setContinuousStates((ctypes.c_double * 6)(*x), 6)
                    return values()

                fd[:, j] = fd6(f, float(x0[j]), step(known))
                fmu.setContinuousStates((ctypes.c_double * 6)(*x0), 6)
            else:

                def g(s: float, known: str = known) -> np.ndarray:
                    fmu.setReal([vr[known]], [s])
                    return values()

                fd[:, j] = fd6(g, INPUT_VALUES[known], step(known))
                fmu.setReal([vr[known]], [INPUT_VALUES[known]])
        assert_rows_close(analytic, fd, unknowns, f"FMI 2.0 ME {case}")
        # a seed of several knowns is the sum of the columns
        seed = np.linspace(0.5, 1.5, len(STATES + INPUTS))
        both = fmu.getDirectionalDerivative(
            [vr[u] for u in unknowns], [vr[k] for k in STATES + INPUTS], seed.tolist()
        )
        np.testing.assert_allclose(
            both, analytic @ seed, rtol=1e-12, atol=1e-12 * np.abs(analytic).max()
        )
    finally:
        fmu.terminate()


def jacobian_me2(fmu: FMU2Model, vr: dict[str, int], unknowns: list[str]) -> np.ndarray:
    knowns = [vr[k] for k in STATES + INPUTS]
    return np.array(
        [fmu.getDirectionalDerivative([vr[u] for u in unknowns], [k], [1.0]) for k in knowns]
    ).T


def test_model_structure_matches_the_jacobian(
    model_description: ModelDescription, make_fmu: MakeFmu, vr: dict[str, int]
) -> None:
    """Every derivative and output depends on the knowns its ModelStructure entry names, and on
    no other (an entry outside the dependencies is 0 in flight and in contact); a "constant"
    dependency is the same number at both points, a "fixed" one too (the parameters are)."""
    md = model_description
    structure = [
        *md.derivatives,
        *(u for u in md.outputs if u.variable.name in continuous_outputs(md)),
    ]
    unknowns = [u.variable.name for u in structure]
    jacobians = []
    for case in CASES:
        fmu = me2(make_fmu, vr, CASES[case])
        jacobians.append(jacobian_me2(fmu, vr, unknowns))
        fmu.terminate()
    columns = {name: j for j, name in enumerate(STATES + INPUTS)}
    for i, u in enumerate(structure):
        named = {d.name for d in u.dependencies}
        kinds = dict(zip([d.name for d in u.dependencies], u.dependenciesKind or [], strict=False))
        for name, j in columns.items():
            if name not in named:
                assert all(J[i, j] == 0.0 for J in jacobians), (u.variable.name, name)
            elif kinds.get(name) in ("constant", "fixed"):
                assert jacobians[0][i, j] == jacobians[1][i, j] != 0.0, (u.variable.name, name)


def test_fmi2_co_simulation_outputs_by_inputs(
    model_description: ModelDescription, make_fmu: MakeFmu, vr: dict[str, int]
) -> None:
    """Co-simulation: the outputs' derivatives with respect to the inputs (the frame's
    acceleration follows a_base, nothing else depends on an input directly), equal to the
    differences of getReal after setReal; derivatives and states are refused."""
    md = model_description
    outputs = continuous_outputs(md)
    fmu, _ = make_fmu("CS")
    try:
        start = CASES["contact"]
        fmu.setReal([vr[k] for k in start], list(start.values()))
        fmu.setupExperiment(startTime=0.0)
        fmu.enterInitializationMode()
        fmu.exitInitializationMode()
        fmu.setReal([vr[k] for k in INPUTS], list(INPUT_VALUES.values()))
        fmu.doStep(0.0, 1e-4)
        refs = [vr[o] for o in outputs]
        for known in INPUTS:
            analytic = np.array(fmu.getDirectionalDerivative(refs, [vr[known]], [1.0]))

            def g(s: float, known: str = known) -> np.ndarray:
                fmu.setReal([vr[known]], [s])
                return np.array(fmu.getReal(refs))

            fd = fd6(g, INPUT_VALUES[known], 1e-3)
            fmu.setReal([vr[known]], [INPUT_VALUES[known]])
            np.testing.assert_allclose(analytic, fd, rtol=0, atol=1e-9)
            expected = {"a_base[1]": "a_frame[1]", "a_base[2]": "a_frame[2]"}.get(known)
            assert [o for o, d in zip(outputs, analytic, strict=True) if d != 0] == (
                [expected] if expected else []
            )
        with pytest.raises(FMICallException):
            fmu.getDirectionalDerivative([vr["der(body1.vx)"]], [vr["F_ext[1]"]], [1.0])
        with pytest.raises(FMICallException):
            fmu.getDirectionalDerivative([vr["contact.F_N"]], [vr["body1.x"]], [1.0])
    finally:
        fmu.terminate()


def test_fmi2_bad_arguments_are_refused_with_a_message(make_fmu, vr: dict[str, int]) -> None:
    fmu, log = make_fmu("ME", logging=True)
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    bad = {
        "unknowns[0] = 99999 (no variable) is not a derivative or a continuous output": (
            [99999],
            [vr["body1.x"]],
        ),
        f"knowns[0] = {vr['body1.m']} (body1.m) is not a continuous state or an input": (
            [vr["der(body1.vx)"]],
            [vr["body1.m"]],
        ),
        f"unknowns[0] = {vr['contact.count']} (contact.count) is not": (
            [vr["contact.count"]],
            [vr["body1.x"]],
        ),
    }
    for needle, (unknowns, knowns) in bad.items():
        with pytest.raises(FMICallException):
            fmu.getDirectionalDerivative(unknowns, knowns, [1.0])
        assert needle in log.text(), (needle, log.text())
    f = fmu.dll.fmi2GetDirectionalDerivative
    f.restype = ctypes.c_int
    one = (ctypes.c_uint * 1)(vr["der(body1.vx)"])
    out = (ctypes.c_double * 1)()
    assert f(fmu.component, one, 1, None, 1, (ctypes.c_double * 1)(1.0), out) == ERROR
    assert "knowns" in log.errors()[-1], log.errors()
    nan = (ctypes.c_double * 1)(math.nan)
    assert f(fmu.component, one, 1, one, 1, nan, out) == ERROR
    assert "seed[0] = nan is not finite" in log.text()
    # still usable
    assert len(fmu.getDirectionalDerivative([vr["der(body1.x)"]], [vr["body1.vx"]], [2.0])) == 1
    fmu.terminate()


# ------------------------------------------------------------------------------------------
# FMI 3.0


class Log:
    """FMI 3.0 log lines (the instance's own logger, kept alive with the instance)."""

    def __init__(self) -> None:
        self.lines: list[str] = []

    def __call__(self, env: object, status: int, category: bytes, message: bytes) -> None:
        self.lines.append(message.decode())


def refs3(md: ModelDescription) -> dict[str, int]:
    return {v.name: v.valueReference for v in md.modelVariables}


@pytest.mark.parametrize("case", list(CASES))
def test_fmi3_model_exchange_directional_and_adjoint(
    md3: ModelDescription, unzipped3: str, case: str
) -> None:
    vr = refs3(md3)
    unknowns = DERIVATIVES + continuous_outputs(md3)
    knowns = STATES + INPUTS
    fmu = FMU3Model(
        guid=md3.guid,
        unzipDirectory=unzipped3,
        modelIdentifier=md3.modelExchange.modelIdentifier,
        instanceName="dd3",
    )
    fmu.instantiate(logMessage=Log())
    try:
        start = CASES[case]
        fmu.setFloat64([vr[k] for k in start], list(start.values()))
        fmu.enterInitializationMode(startTime=0.0)
        fmu.exitInitializationMode()
        fmu.updateDiscreteStates()
        fmu.enterContinuousTimeMode()
        fmu.setFloat64([vr[k] for k in INPUTS], list(INPUT_VALUES.values()))
        x0 = np.array(fmu.getFloat64([vr[s] for s in STATES]))
        out_refs = [vr[u] for u in unknowns[6:]]

        def values() -> np.ndarray:
            der = (fmi3Float64 * 6)()
            fmu.getContinuousStateDerivatives(der, 6)
            return np.concatenate([np.array(der), np.array(fmu.getFloat64(out_refs))])

        u_refs, k_refs = [vr[u] for u in unknowns], [vr[k] for k in knowns]
        directional = np.zeros((len(unknowns), len(knowns)))
        fd = np.zeros_like(directional)
        for j, known in enumerate(knowns):
            directional[:, j] = fmu.getDirectionalDerivative(u_refs, [vr[known]], [1.0])

            def f(s: float, j: int = j, known: str = known) -> np.ndarray:
                if known in STATES:
                    x = x0.copy()
                    x[j] = s
                    fmu.setContinuousStates((fmi3Float64 * 6)(*x), 6)
                else:
                    fmu.setFloat64([vr[known]], [s])
                return values()

            at = float(x0[j]) if known in STATES else INPUT_VALUES[known]
            fd[:, j] = fd6(f, at, step(known))
            f(at)
        assert_rows_close(directional, fd, unknowns, f"FMI 3.0 ME {case}")
        adjoint = np.array(
            [
                fmu.getAdjointDerivative(u_refs, k_refs, list(seed), nSensitivity=len(knowns))
                for seed in np.eye(len(unknowns))
            ]
        )
        np.testing.assert_array_equal(adjoint, directional)
    finally:
        fmu.terminate()
        fmu.freeInstance()


def test_fmi3_co_simulation_outputs_by_inputs(md3: ModelDescription, unzipped3: str) -> None:
    vr = refs3(md3)
    fmu = FMU3Slave(
        guid=md3.guid,
        unzipDirectory=unzipped3,
        modelIdentifier=md3.coSimulation.modelIdentifier,
        instanceName="dd3cs",
    )
    fmu.instantiate(logMessage=Log())
    try:
        fmu.enterInitializationMode(startTime=0.0)
        fmu.exitInitializationMode()
        fmu.doStep(0.0, 1e-3)
        refs = [vr[o] for o in continuous_outputs(md3)]
        d = fmu.getDirectionalDerivative(refs, [vr["a_base[2]"]], [2.0])
        names = continuous_outputs(md3)
        assert {n: v for n, v in zip(names, d, strict=True) if v != 0} == {"a_frame[2]": 2.0}
        a = fmu.getAdjointDerivative(
            [vr["a_frame[1]"]], [vr[i] for i in INPUTS], [3.0], nSensitivity=len(INPUTS)
        )
        assert list(a) == [0.0, 0.0, 0.0, 3.0, 0.0]
        with pytest.raises(FMICallException):
            fmu.getDirectionalDerivative([vr["contact.F_N"]], [vr["body1.y"]], [1.0])
    finally:
        fmu.terminate()
        fmu.freeInstance()


def test_capabilities_are_declared(model_description: ModelDescription, fmu3: Path) -> None:
    assert model_description.modelExchange.providesDirectionalDerivative
    assert model_description.coSimulation.providesDirectionalDerivative
    root = ET.fromstring(zipfile.ZipFile(fmu3).read("modelDescription.xml"))
    for tag in ("ModelExchange", "CoSimulation"):
        interface = root.find(tag)
        assert interface is not None
        for flag in ("providesDirectionalDerivatives", "providesAdjointDerivatives"):
            assert interface.get(flag) == "true", (tag, flag)


def test_combdrive_provides_no_derivatives(fmu_path: Path) -> None:
    from fmpy import read_model_description

    md = read_model_description(str(fmu_path.parent / "combdrive.fmu"))
    assert not md.modelExchange.providesDirectionalDerivative
    assert not md.coSimulation.providesDirectionalDerivative
