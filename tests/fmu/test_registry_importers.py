"""The FMU in co-simulation engines installed from the package registries: libcosim
(libcosimpy) and Ecos (ecospy), both installed by tools/setup.sh (pip install .[cosim]; ecospy
needs Debian's libtbb12). Both ignore FMI 2.0 Enumeration variables, so the contact law is chosen
through the Integer contact.law_number; both call fmi2DoStep with a fixed step and leave the
tolerance to the FMU (1e-6).

Each runs the csfh scene (the FMU's start values) with the cylinder law for 0.2 s at 1e-3 s
steps, compared with the harness's model exchange at rtol 1e-10: y within 1e-6 m (the FMU's
CVODE at its default rtol 1e-6 with absolute tolerance 1e-8 m; observed ~1e-7 m after two
impacts), the same number of contacts, and the peak F_N (contact.F_N_peak) within 1e-3 of the
harness's refined peak."""

from __future__ import annotations

import numpy as np
import pytest

from csfh.model.scene import load_scene
from csfh.runners.fmu import simulate_me

STEP, STOP, LAW, LAW_NUMBER = 1e-3, 0.2, "LN_cylinders", 3


def reference(times: np.ndarray):
    return simulate_me(load_scene("csfh"), LAW, rtol=1e-10, output_times=times, stop_time=STOP)


def check(t: np.ndarray, y: np.ndarray, peak: np.ndarray, count: int) -> None:
    ref = reference(t)
    rows = np.isin(ref.table["t"], t)
    np.testing.assert_allclose(ref.table["t"][rows], t, rtol=0, atol=1e-12)
    assert np.max(np.abs(y - ref.table["y"][rows])) <= 1e-6
    assert count == len(ref.contacts) >= 2
    assert np.max(peak) == pytest.approx(np.max(ref.contact_records["peak_F_N"]), rel=1e-3)


def test_libcosim(fmu_path) -> None:
    pytest.importorskip("libcosimpy")
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
    from libcosimpy.CosimObserver import CosimObserver
    from libcosimpy.CosimSlave import CosimLocalSlave

    log_output_level(CosimLogLevel.FATAL)  # fmi-library#21: see csfh.cosim.libcosim_master
    ex = CosimExecution.from_step_size(round(STEP * 1e9))
    slave = ex.add_local_slave(CosimLocalSlave(fmu_path=str(fmu_path), instance_name="hinge"))
    assert slave >= 0
    refs = {v.name.decode(): v.reference for v in ex.slave_variables(slave)}
    assert ex.integer_initial_value(slave, refs["contact.law_number"], LAW_NUMBER)
    last = CosimObserver.create_last_value()
    ex.add_observer(last)
    t, y, peak = [], [], []
    for k in range(round(STOP / STEP)):
        assert ex.step()
        t.append((k + 1) * STEP)
        y_k, peak_k = last.last_real_values(slave, [refs["body1.y"], refs["contact.F_N_peak"]])
        y.append(y_k)
        peak.append(peak_k)
    count = last.last_integer_values(slave, [refs["contact.count"]])[0]
    assert "contact.law" not in refs  # the Enumeration is invisible to libcosim
    check(np.array(t), np.array(y), np.array(peak), count)


def test_ecos(fmu_path) -> None:
    pytest.importorskip("ecospy")
    from ecospy import EcosLib, EcosSimulation, EcosSimulationStructure

    EcosLib.set_log_level("warn")
    t, y, peak = [], [], []
    with EcosSimulationStructure() as ss:
        ss.add_model("hinge", str(fmu_path))
        ss.add_parameter_set("initial", {"hinge::contact.law_number": LAW_NUMBER})
        with EcosSimulation(structure=ss, step_size=STEP) as sim:
            sim.init(parameter_set="initial")
            for k in range(round(STOP / STEP)):
                sim.step()
                assert sim.get_time() == pytest.approx((k + 1) * STEP, abs=1e-12)
                t.append((k + 1) * STEP)
                y.append(sim.get_real("hinge::body1.y"))
                peak.append(sim.get_real("hinge::contact.F_N_peak"))
            count = sim.get_integer("hinge::contact.count")
            assert sim.get_integer("hinge::contact.law_number") == LAW_NUMBER
            sim.terminate()
    check(np.array(t), np.array(y), np.array(peak), count)
