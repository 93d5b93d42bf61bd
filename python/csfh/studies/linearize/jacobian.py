"""Where the Jacobians of a linearization come from: one protocol (`JacobianSource`), two
implementations, chosen by what the FMU declares.

* `FiniteDifferences`: fourth-order central differences of the model-exchange FMU's derivatives
  and outputs (four evaluations per column). The steps follow the model's own length and speed
  scales: in the contact mode 1e-3 of the indentation, so that no probe leaves the contact, whose
  force is non-smooth at zero indentation (docs/model.md §10.3); in flight 1e-3 of the
  clearance or, if smaller, of the deflection |r| (the peak stress |sigma| is homogeneous of
  degree one in it, §14.2) and of the eccentricity |e| (the gap (3.1) bends on that scale);
  speeds 1e-3 of friction.v0, inside the dead zone of Eq. (5.1) at rest. Truncation
  (h/l)^4 and round-off eps l/h then both stay near 1e-12 relative.
* `DirectionalDerivatives`: the FMU's fmi2GetDirectionalDerivative, one seed per state or
  input, where the model description declares providesDirectionalDerivative="true".

Both see the FMU as a `Plant`: an instance in continuous-time mode whose contact mode is frozen
between events, as an importer's integrator sees it."""

from __future__ import annotations

import ctypes
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np

from ...errors import ParameterError
from ...model import model_info

STATES = model_info.STATE_NAMES
INPUTS = ("F_ext[1]", "F_ext[2]", "M_ext", "a_base[1]", "a_base[2]")
"""The FMU's continuous inputs (docs/model.md §0, §14.1): the columns of B and D."""
OUTPUTS = (
    *STATES,
    "contact.gap",
    "contact.indentation",
    "contact.F_N",
    "contact.F_T",
    "flexure.stress_max",
)
"""The outputs of C and D: the states (as the FMU outputs them), the contact's gap, indentation
and forces, and the flexure's peak stress (§3, §4, §14.2)."""
model_info.require((*INPUTS, *OUTPUTS), "studies.linearize.jacobian")


def check_names(input_name: str, output_name: str) -> None:
    """ParameterError unless the Bode plot's input and output are among INPUTS and OUTPUTS."""
    if input_name not in INPUTS:
        raise ParameterError(f"input {input_name!r} is not one of {', '.join(INPUTS)}")
    if output_name not in OUTPUTS:
        raise ParameterError(f"output {output_name!r} is not one of {', '.join(OUTPUTS)}")


_dp = ctypes.POINTER(ctypes.c_double)


def _vr(name: str) -> int:
    return model_info.variables()[name].valueReference


@dataclass(frozen=True)
class Jacobians:
    """d(derivatives, outputs)/d(states, inputs) at one point: A, B, C, D."""

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray


class Plant:
    """A model-exchange instance (fmpy FMU2Model, continuous-time mode) at an operating point
    (states x, inputs u), with the outputs of C and D."""

    def __init__(self, fmu: Any, outputs: Sequence[str] = OUTPUTS) -> None:
        self.fmu = fmu
        self.outputs = tuple(outputs)
        self.der_vrs = [_vr(f"der({n})") for n in STATES]
        self.output_vrs = [_vr(n) for n in self.outputs]
        self.input_vrs = [_vr(n) for n in INPUTS]
        self.x = self._get_states()
        self.u = np.array(fmu.getReal(self.input_vrs), dtype=float)

    def _get_states(self) -> np.ndarray:
        x = np.empty(len(STATES))
        self.fmu.getContinuousStates(x.ctypes.data_as(_dp), len(STATES))
        return x

    def set_point(self, x: np.ndarray, u: np.ndarray) -> None:
        """Move the instance to states x and inputs u (the contact mode stays)."""
        x = np.ascontiguousarray(x, dtype=float)
        self.fmu.setContinuousStates(x.ctypes.data_as(_dp), len(STATES))
        self.fmu.setReal(self.input_vrs, [float(v) for v in u])

    def evaluate(self, x: np.ndarray, u: np.ndarray) -> np.ndarray:
        """[derivatives, outputs] at (x, u)."""
        self.set_point(x, u)
        xdot = np.empty(len(STATES))
        self.fmu.getDerivatives(xdot.ctypes.data_as(_dp), len(STATES))
        return np.concatenate([xdot, self.fmu.getReal(self.output_vrs)])

    def value(self, name: str) -> float:
        """An FMU variable at the instance's current point."""
        return float(self.fmu.getReal([_vr(name)])[0])

    def in_contact(self) -> bool:
        return bool(self.fmu.getBoolean([_vr("contact.active")])[0])

    def restore(self) -> None:
        """Back to the operating point the plant was made at."""
        self.set_point(self.x, self.u)


class JacobianSource(Protocol):
    """Computes A, B, C, D of a plant at a point."""

    name: str

    def jacobians(self, plant: Plant, x: np.ndarray, u: np.ndarray) -> Jacobians: ...


def _split(J: np.ndarray) -> Jacobians:
    n, m = len(STATES), len(INPUTS)
    return Jacobians(A=J[:n, :n], B=J[:n, n : n + m], C=J[n:, :n], D=J[n:, n : n + m])


def fd_steps(plant: Plant, x: np.ndarray, u: np.ndarray) -> np.ndarray:
    """The step of each state and input (module docstring)."""
    plant.evaluate(x, u)
    delta = plant.value("contact.R2") - plant.value("contact.R1")
    if plant.in_contact() and plant.value("contact.indentation") > 0.0:
        length = plant.value("contact.indentation")
    else:  # the deflection, or the eccentricity near the concentric point, if smaller
        e = delta - plant.value("contact.gap")
        length = min(delta, max(float(np.hypot(x[0], x[1])), e, 1e-3 * delta))
    speed = max(plant.value("friction.v0"), 1e-9 * delta)
    R1 = plant.value("contact.R1")
    scales = np.array(
        [length, length, length / R1, speed, speed, speed / R1, *np.ones(len(INPUTS))]
    )
    point = np.concatenate([x, u])
    relative = np.where(np.arange(len(point)) >= len(STATES), np.abs(point), 0.0)
    return 1e-3 * np.maximum(scales, relative)


class FiniteDifferences:
    """Fourth-order central differences (f(-2h) - 8 f(-h) + 8 f(h) - f(2h)) / 12h."""

    name = "finite differences (4th order, central)"

    def jacobians(self, plant: Plant, x: np.ndarray, u: np.ndarray) -> Jacobians:
        point = np.concatenate([x, u]).astype(float)
        steps = fd_steps(plant, x, u)
        n = len(STATES)
        columns = []
        for j, h in enumerate(steps):
            values = []
            for k in (-2, -1, 1, 2):
                p = point.copy()
                p[j] += k * h
                values.append(plant.evaluate(p[:n], p[n:]))
            columns.append((values[0] - 8 * values[1] + 8 * values[2] - values[3]) / (12 * h))
        plant.restore()
        return _split(np.column_stack(columns))


class DirectionalDerivatives:
    """fmi2GetDirectionalDerivative of the derivatives and outputs, seeded by one state or input
    at a time."""

    name = "directional derivatives (fmi2GetDirectionalDerivative)"

    def jacobians(self, plant: Plant, x: np.ndarray, u: np.ndarray) -> Jacobians:
        plant.set_point(x, u)
        unknowns = [*plant.der_vrs, *plant.output_vrs]
        knowns = [_vr(n) for n in STATES] + plant.input_vrs
        columns = [
            np.array(plant.fmu.getDirectionalDerivative(unknowns, [k], [1.0]), dtype=float)
            for k in knowns
        ]
        plant.restore()
        return _split(np.column_stack(columns))


SOURCES: dict[str, JacobianSource] = {
    "fd": FiniteDifferences(),
    "directional": DirectionalDerivatives(),
}
"""The Jacobian sources by the name `--jacobian` takes."""


def provides_directional_derivatives() -> bool:
    """Whether the built FMU declares fmi2GetDirectionalDerivative for model exchange."""
    md = model_info.model_description()
    return bool(md.modelExchange and md.modelExchange.providesDirectionalDerivative)


def source(name: str | None) -> JacobianSource:
    """The source by name; None: the FMU's directional derivatives where it provides them,
    else finite differences. ParameterError for an unknown name or directional derivatives the
    FMU does not provide."""
    if name is None:
        name = "directional" if provides_directional_derivatives() else "fd"
    if name not in SOURCES:
        raise ParameterError(f"jacobian = {name!r} is not one of {', '.join(SOURCES)}")
    if name == "directional" and not provides_directional_derivatives():
        raise ParameterError(
            'jacobian = "directional": the FMU declares providesDirectionalDerivative="false"'
        )
    return SOURCES[name]
