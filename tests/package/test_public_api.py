"""The public API: every name of csfh.__all__ resolves and is imported on first use, the runners
take what csfh.load_scene takes, and csfh.fmu_path knows the FMI versions it ships."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import csfh
from csfh.model.scene import load_scene


def test_every_public_name_is_there_and_imported_on_first_use() -> None:
    """csfh's public names (csfh.__all__) resolve, and importing csfh loads none of them."""
    code = (
        "import sys, csfh\n"
        "loaded = sorted(m for m in sys.modules if m.startswith('csfh.'))\n"
        "names = [getattr(csfh, n) for n in csfh.__all__]\n"
        "print(loaded, len(names))"
    )
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=False)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip() == f"['csfh._version'] {len(csfh.__all__)}"
    assert sorted(set(csfh.__all__) - {"__version__"}) == sorted(csfh._PUBLIC)


@pytest.mark.parametrize("entry", ["simulate", "moreau"])
def test_public_runners_take_a_scene_name_or_file(entry: str, tmp_path: Path) -> None:
    """csfh.simulate / csfh.moreau accept what csfh.load_scene accepts (as the CLI does)."""
    import csfh

    by_object = csfh.simulate(load_scene("central"), "LN_ESDU", stop_time=0.1)
    if entry == "simulate":
        by_name = csfh.simulate("central", "LN_ESDU", stop_time=0.1)
    else:
        by_object = csfh.moreau(load_scene("central"), stop_time=0.1)
        by_name = csfh.moreau("central", stop_time=0.1)
    path = tmp_path / "mine.toml"
    path.write_text('name = "mine"\nstop_time = 0.1\n[initial]\nq = [0.0, 0.01, 0.0]\n')
    by_file = csfh.simulate(path, "LN_ESDU") if entry == "simulate" else csfh.moreau(str(path))
    assert by_name.scene == "central" and by_file.scene == "mine"
    np.testing.assert_array_equal(by_name["y"], by_object["y"])
    assert by_file.t[-1] == pytest.approx(0.1)


def test_fmu_path_refuses_unknown_fmi_version() -> None:
    with pytest.raises(ValueError, match="fmi_version = 4"):
        csfh.fmu_path(fmi_version=4)
