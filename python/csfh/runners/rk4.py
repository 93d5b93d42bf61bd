"""The paper's own event-driven scheme as a baseline: explicit RK4 with a nominal step h0 (paper:
2e-4 s), bisection of the step until the penetration at the contact onset is within the event
tolerance (paper: 1e-4 m), the reduced step kept through the contact. It runs in the C core
(fmu_src/solvers/csfh_rk4event.c) with the FMU's right-hand side, so that its cost can be compared
with the FMU's integrators evaluation for evaluation."""

from __future__ import annotations

import ctypes
import time
from typing import Any

import numpy as np

from ..errors import ParameterError, SimulationError
from ..model._csfh_variables import RK4_H0, RK4_TOL
from ..model.core import N_STATES, library
from ..model.instance import core_model
from ..model.scene import Scene
from ..trajectory import CONTACT_FIELDS, Trajectory

_RECORD = (
    "t",
    "x",
    "y",
    "theta",
    "vx",
    "vy",
    "omega",
    "F_N",
    "F_T",
    "indentation",
    "v_T",
    "gap",
    "energy",
)
_STATS = ("steps", "rejected_steps", "rhs_evaluations", "records", "contacts")


def rk4_event(
    scene: Scene,
    law: str,
    *,
    h0: float = RK4_H0,
    tol: float = RK4_TOL,
    h_min: float | None = None,
    output_interval: float | None = None,
    stop_time: float | None = None,
    parameters: dict[str, Any] | None = None,
    max_contacts: int = 100_000,
) -> Trajectory:
    """Run the paper's RK4 + bisection scheme with contact law `law` on `scene`."""
    if not (h0 > 0 and tol > 0):
        raise ParameterError(f"h0 = {h0!r} and tol = {tol!r} must be > 0")
    t_end = scene.stop_time if stop_time is None else stop_time
    dt_out = scene.integrator.output_interval if output_interval is None else output_interval
    h_min = h0 * 2.0**-40 if h_min is None else h_min
    lib = library()
    assert lib.csfh_api_rk4_record_columns() == len(_RECORD)
    assert lib.csfh_api_contact_record_columns() == len(CONTACT_FIELDS)
    model = core_model(scene, {**(parameters or {}), "contact.law": law})
    max_records = int(t_end / min(dt_out, h0)) + 16
    records = np.zeros((max_records, len(_RECORD)))
    contacts = np.zeros((max_contacts, len(CONTACT_FIELDS)))
    x0 = np.array(scene.x0, dtype=float)
    x_end = np.zeros(N_STATES)
    stats = (ctypes.c_longlong * len(_STATS))()
    dp = ctypes.POINTER(ctypes.c_double)
    wall = time.perf_counter()
    status = lib.csfh_api_rk4_run(
        model.handle,
        h0,
        tol,
        h_min,
        0.0,
        x0.ctypes.data_as(dp),
        t_end,
        dt_out,
        records.ctypes.data_as(dp),
        max_records,
        contacts.ctypes.data_as(dp),
        max_contacts,
        x_end.ctypes.data_as(dp),
        stats,
    )
    wall = time.perf_counter() - wall
    st: dict[str, Any] = dict(zip(_STATS, (int(v) for v in stats), strict=True))
    if status != 0:
        raise SimulationError(
            f"RK4 (h0 = {h0:g} s): non-finite state after {st['steps']} "
            "steps; the step is beyond the stability limit of the contact"
        )
    rec = records[: st["records"]]
    con = contacts[: st["contacts"]]
    tr = Trajectory(
        model=law,
        scene=scene.name,
        table={n: rec[:, i].copy() for i, n in enumerate(_RECORD)},
        contacts=con[:, 0].copy(),
        releases=con[:, 2][np.isfinite(con[:, 2])].copy(),
        contact_records={n: con[:, i].copy() for i, n in enumerate(CONTACT_FIELDS)},
    )
    st.update(
        {
            "integrator": f"RK4 + bisection h0={h0:g} s, event tolerance {tol:g} m",
            "wall_time": wall,
            "h0": h0,
            "tol": tol,
            "evaluations": model.counters(),
        }
    )
    tr.stats = st
    return tr
