"""The harness: scenes, models, results.

Loads the built-in `central` scene (the paper's central impact), runs two event-driven laws
through the FMU and the Moreau stepper on it, compares their first contacts with the analytic
free fall, builds a scene of its own from a dict (preset `consistent`, a parameter override),
and writes CSV files.

    python3 examples/harness.py [OUTPUT_DIR]

The same from the command line: `csfh run central --law LN_spheres`, `csfh compare central`.
"""

from __future__ import annotations

import math
import sys
import tempfile
from pathlib import Path

import csfh


def main() -> None:
    out = Path(sys.argv[1]) if len(sys.argv) > 1 else Path(tempfile.mkdtemp(prefix="csfh-"))
    out.mkdir(parents=True, exist_ok=True)

    scene = csfh.load_scene("central")  # a built-in scene, or the path of a .toml file
    print(f"scene {scene.name}: {scene.description} (preset {scene.preset})")
    t_exact = math.sqrt(2 * 0.03 / 9.81)

    runs = [
        csfh.simulate(scene, "LN_spheres", stop_time=0.3),  # model exchange (fmpy's CVode)
        csfh.simulate(scene, "LN_cylinders", stop_time=0.3, interface="cs"),  # the FMU's integrator
        csfh.moreau(scene, stop_time=0.3),  # Moreau midpoint stepper, h = 1e-5 s
    ]
    for run in runs:
        s = run.summary()
        print(
            f"  {run.model:<13} first contact {s['first_contact_time']:.6f} s "
            f"(exact {t_exact:.6f}), {s['contacts']} contacts, max {run.force_label()} "
            f"{s['max_F_N']:.4g} N"
        )
        run.write_csv(out / f"{run.model}.csv")
        assert abs(s["first_contact_time"] - t_exact) < 2e-5, run.model  # Moreau: within 2 steps

    # a scene of one's own: the same drop with the `consistent` preset and a softer restitution
    mine = csfh.scene_from_dict(
        {
            "name": "soft_drop",
            "preset": "consistent",
            "stop_time": 0.3,
            "initial": {"q": [0.0, 0.01, 0.0]},
            "parts": {"flexure": False, "friction": False},
            "parameters": {"contact.cr": 0.5},
        }
    )
    run = csfh.simulate(mine, "LN_cylinders")
    first = run.contact_records
    rebound = first["release_speed"][0] / first["onset_speed"][0]
    print(
        f"  {mine.name}: linear cylinder law (preset consistent), c_r = 0.5 -> rebound ratio "
        f"{rebound:.3f} (LN cannot reach low restitution: docs/model.md §8)"
    )
    assert 0.5 < rebound < 1.0
    print(f"CSV files in {out}")


if __name__ == "__main__":
    main()
