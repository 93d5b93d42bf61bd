"""The bare FMU in an importer: fmpy only, no csfh import.

A central drop without flexure or friction (the paper's Section 6.1): body 1 falls from
y = 0.01 m onto the bore (clearance 0.02 m) and bounces. The script simulates it by model
exchange (fmpy's CVode calls the FMU; the gap is the event indicator) and by co-simulation (the
FMU's own integrator, solver.method auto: RK45, BDF where stiff), and checks the first contact
against free fall: t = sqrt(2 * 0.03 m / g).

    python3 examples/fmu_fmpy.py "$(python3 -c 'import csfh; print(csfh.fmu_path())')"

The FMU is the argument (the installed package's copy, as above; `csfh info` prints it too), else
$CSFH_FMU, else build/csfh.fmu of a CMake build of this tree. Any other importer works the same
way: load csfh.fmu, set the start values below, simulate.
"""

from __future__ import annotations

import math
import os
import sys
from pathlib import Path

import fmpy
import numpy as np

START_VALUES = {
    "contact.law": "LN_cylinders",  # enumeration item, turned into its value below
    "flexure.enabled": False,
    "friction.enabled": False,
    "body1.x": 0.0,  # m, G1 relative to O2
    "body1.y": 0.01,  # m
}
OUTPUTS = ["body1.y", "contact.F_N", "contact.indentation", "contact.count"]


def find_fmu() -> str:
    if len(sys.argv) > 1:
        return sys.argv[1]
    if os.environ.get("CSFH_FMU"):
        return os.environ["CSFH_FMU"]
    path = Path(__file__).resolve().parent.parent / "build" / "csfh.fmu"
    if not path.exists():
        sys.exit(
            "no FMU given: pass its path, e.g. the installed package's "
            "(python3 -c 'import csfh; print(csfh.fmu_path())'), or set $CSFH_FMU"
        )
    return str(path)


def enumeration_value(md: fmpy.model_description.ModelDescription, variable: str, item: str) -> int:
    """The integer value of an enumeration item (fmpy sets enumerations as integers)."""
    var = next(v for v in md.modelVariables if v.name == variable)
    return next(i.value for i in var.declaredType.items if i.name == item)


def first_contact(result: np.ndarray) -> float:
    """Time of the first output row with contact.count >= 1 (the event instant: fmpy records
    the state at every event)."""
    return float(result["time"][np.argmax(result["contact.count"] >= 1)])


def main() -> None:
    fmu = find_fmu()
    md = fmpy.read_model_description(fmu)
    print(f"{md.modelName} {md.version}: {md.description}")
    g = 9.81
    t_exact = math.sqrt(2 * 0.03 / g)  # fall from y = 0.01 to y = -delta = -0.02
    start = dict(START_VALUES)
    start["contact.law"] = enumeration_value(md, "contact.law", START_VALUES["contact.law"])

    me = fmpy.simulate_fmu(
        fmu,
        fmi_type="ModelExchange",
        stop_time=0.3,
        output_interval=1e-3,
        relative_tolerance=1e-8,
        start_values=start,
        output=OUTPUTS,
        record_events=True,
    )
    cs = fmpy.simulate_fmu(
        fmu,
        fmi_type="CoSimulation",
        stop_time=0.3,
        output_interval=1e-3,  # the communication step; contacts inside it are still located
        relative_tolerance=1e-8,
        start_values=start,
        output=OUTPUTS,
    )
    t_me = first_contact(me)
    print(f"first contact, exact          {t_exact:.6f} s")
    print(f"first contact, model exchange {t_me:.6f} s (error {t_me - t_exact:+.1e} s)")
    n_me, n_cs = int(me["contact.count"][-1]), int(cs["contact.count"][-1])
    print(f"contacts by 0.3 s: ME {n_me}, CS {n_cs}")
    print(f"peak F_N: ME {me['contact.F_N'].max():.4g} N, CS {cs['contact.F_N'].max():.4g} N")
    print(f"max indentation: ME {me['contact.indentation'].max():.3g} m")
    assert abs(t_me - t_exact) < 1e-6, "first contact time"
    assert me["contact.count"][-1] == cs["contact.count"][-1] == 2, "two contacts by 0.3 s"


if __name__ == "__main__":
    main()
