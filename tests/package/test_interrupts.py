"""Ctrl-C during a model-exchange run: CVODE calls back into Python (the right-hand side, the
root function, its error handler, the FMU's logger), and a KeyboardInterrupt raised inside a
ctypes callback is printed and lost ("Exception ignored on calling ctypes callback function"),
after which CVODE fails ("CVode failed ... flag -12"). Whenever the SIGINT comes, the command must
end in "csfh: interrupted" with status 130 and nothing else on standard error.

The SIGINT is sent from inside the callbacks (on their Nth call: deterministic, the moment the
fault needs) and from outside at several delays after the start."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from test_cli_errors import csfh_env

ARGS = ["run", "csfh", "--law", "LN_spheres", "--quiet"]

# Run the command line with one CvodeStepper callback wrapped so that its Nth call sends SIGINT
# to the process itself, before the callback's own code runs.
IN_CALLBACK = """
import os, signal, sys  # noqa: E401
from csfh.runners import cvode

callback, nth, out, ARGS = sys.argv[1], int(sys.argv[2]), sys.argv[3], sys.argv[4:]
original = getattr(cvode.CvodeStepper, callback)
calls = [0]


def wrapped(self, *args):
    calls[0] += 1
    if calls[0] == nth:
        os.kill(os.getpid(), signal.SIGINT)
    return original(self, *args)


setattr(cvode.CvodeStepper, callback, wrapped)
from csfh.cli.main import main  # noqa: E402

sys.exit(main([*ARGS, "--out", out]))
"""


def _check(returncode: int, stderr: str) -> None:
    assert stderr.strip().splitlines() == ["csfh: interrupted"], stderr
    assert returncode in (130, -signal.SIGINT), (returncode, stderr)


@pytest.mark.parametrize(
    ("callback", "nth"),
    [("_rhs", 1), ("_rhs", 40), ("_rhs", 400), ("_roots", 1), ("_roots", 200)],
)
def test_ctrl_c_inside_a_cvode_callback(tmp_path: Path, callback: str, nth: int) -> None:
    proc = subprocess.run(
        [sys.executable, "-c", IN_CALLBACK, callback, str(nth), str(tmp_path / "out"), *ARGS],
        capture_output=True,
        text=True,
        env=csfh_env(),
        timeout=120,
        check=False,
    )
    _check(proc.returncode, proc.stderr)
    assert not (tmp_path / "out" / "LN_spheres.csv").exists()


@pytest.mark.parametrize("delay", [0.8, 1.2, 1.6, 2.0])
def test_ctrl_c_from_outside_at_several_moments(tmp_path: Path, delay: float) -> None:
    """The delays span the start (imports, the FMU unpacked) and the integration (about a
    second on an idle machine); a run that ends before the signal is not a failure of this
    test but tells nothing, so the run is made long (stop time 5 s)."""
    scene = tmp_path / "long.toml"
    scene.write_text(
        (Path(__file__).resolve().parents[2] / "python/csfh/scenes/csfh.toml")
        .read_text()
        .replace("stop_time = 1.0", "stop_time = 5.0")
    )
    args = [str(scene) if a == "csfh" else a for a in ARGS]
    proc = subprocess.Popen(
        [sys.executable, "-m", "csfh", *args, "--out", str(tmp_path / "out")],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=csfh_env(),
        start_new_session=True,
    )
    time.sleep(delay)
    os.killpg(proc.pid, signal.SIGINT)
    try:
        _, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
    _check(proc.returncode, err)


# Co-simulation: the communication loop runs in C and calls back into Python only through the
# FMU's logger. A body so light that the first impact's step size underflows makes the FMU log
# an error mid-way; the wrapped logger sends SIGINT on its first message.
IN_LOGGER = """
import os, signal, sys  # noqa: E401
from csfh.model import fmus

original = fmus._dispatch


def wrapped(*args):
    os.kill(os.getpid(), signal.SIGINT)
    return original(*args)


fmus._dispatch = wrapped
from csfh.cli.main import main  # noqa: E402

sys.exit(main(sys.argv[1:]))
"""


def test_ctrl_c_inside_the_fmu_logger_of_a_co_simulation(tmp_path: Path) -> None:
    scene = tmp_path / "light.toml"
    scene.write_text(
        (Path(__file__).resolve().parents[2] / "python/csfh/scenes/central.toml")
        .read_text()
        .replace("stop_time = 1.0", "stop_time = 0.2")
        + '\n[parameters]\n"body1.m" = 1e-30\n'
    )
    args = ["run", str(scene), "--law", "LN_spheres", "--interface", "cs", "--quiet"]
    proc = subprocess.run(
        [sys.executable, "-c", IN_LOGGER, *args, "--out", str(tmp_path / "out")],
        capture_output=True,
        text=True,
        env=csfh_env(),
        timeout=120,
        check=False,
    )
    _check(proc.returncode, proc.stderr)
    assert not (tmp_path / "out" / "LN_spheres.csv").exists()
