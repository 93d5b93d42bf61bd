"""Bad input on the command line: every bad scene, and every run that fails, ends within seconds
in exit status 2 and one line on standard error naming the file, the key and the value (or, for
a failed run, the file and the FMU's own reason); a Ctrl-C at any moment, also while the command
or its worker processes start up, ends in "csfh: interrupted" without a traceback.

Each case runs the command line in a subprocess, as a user would."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest
from csfh_command import run_csfh

ROOT = Path(__file__).resolve().parents[2]
TIME_LIMIT = 20.0
"""s: generous for a loaded two-core machine; each case takes 1-3 s (starting Python, numpy and
fmpy is most of it)."""


def csfh_env(**extra: str) -> dict[str, str]:
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(
        [*extra.pop("PREPEND", "").split(os.pathsep), str(ROOT / "python")]
    ).strip(os.pathsep)
    env.update(extra)
    return env


def run_cli(
    args: list[str], cwd: Path, env: dict[str, str] | None = None
) -> tuple[subprocess.CompletedProcess[str], float]:
    t0 = time.perf_counter()
    proc = run_csfh(*args, cwd=cwd, env=env or csfh_env(), timeout=120)
    return proc, time.perf_counter() - t0


SHORT = "stop_time = 0.05\n"
# (case id, scene text, command (SCENE = the file), what the one line must contain besides the
# file name)
CASES: list[tuple[str, str, list[str], list[str]]] = [
    (
        "stop_time_1e12",
        "stop_time = 1e12\n",
        ["run", "SCENE", "--law", "Moreau"],
        ["stop_time = 1e+12"],
    ),
    (
        "stop_time_1e12_me",
        "stop_time = 1e12\n",
        ["run", "SCENE", "--law", "LN_spheres"],
        ["stop_time = 1e+12"],
    ),
    (
        "output_interval_tiny",
        SHORT + "[integrator]\noutput_interval = 1e-300\n",
        ["run", "SCENE", "--law", "LN_spheres"],
        ["integrator.output_interval = 1e-300"],
    ),
    (
        "output_interval_huge",
        SHORT + "[integrator]\noutput_interval = 1e12\n",
        ["run", "SCENE", "--law", "Moreau"],
        ["integrator.output_interval = 1e+12"],
    ),
    (
        "moreau_h_1",
        SHORT + "[integrator]\nmoreau_h = 1\n",
        ["run", "SCENE", "--law", "Moreau"],
        ["integrator.moreau_h = 1 "],
    ),
    (
        "moreau_h_tiny",
        SHORT + "[integrator]\nmoreau_h = 1e-300\n",
        ["run", "SCENE", "--law", "Moreau"],
        ["integrator.moreau_h = 1e-300"],
    ),
    (
        "rtol_tiny",
        SHORT + "[integrator]\nrtol = 1e-300\n",
        ["run", "SCENE", "--law", "LN_spheres"],
        ["integrator.rtol = 1e-300"],
    ),
    (
        "u_huge_cs",
        SHORT + "[initial]\nu = [0, -1e200, 0]\n",
        ["run", "SCENE", "--law", "LN_spheres", "--interface", "cs"],
        ["initial.u[1] = -1e+200"],
    ),
    (
        "u_huge_moreau",
        SHORT + "[initial]\nu = [0, -1e200, 0]\n",
        ["run", "SCENE", "--law", "Moreau"],
        ["initial.u[1] = -1e+200"],
    ),
    (
        "omega_huge",
        SHORT + "[initial]\nu = [0, 0, 1e6]\n",
        ["run", "SCENE", "--law", "LN_spheres"],
        ["initial.u[2] = 1000000.0"],
    ),
    (
        "theta_huge",
        SHORT + "[initial]\nq = [0, 0, 1e10]\n",
        ["run", "SCENE", "--law", "LN_spheres", "--interface", "cs"],
        ["initial.q[2] = 10000000000.0"],
    ),
    (
        "q_deep",
        SHORT + "[initial]\nq = [1e10, 0, 0]\n",
        ["run", "SCENE", "--law", "LN_spheres"],
        ["initial.q = [10000000000.0, 0.0, 0.0]", "contact.max_initial_indentation"],
    ),
    (
        "q_deep_limit_raised",
        SHORT
        + '[initial]\nq = [1e10, 0, 0]\n[parameters]\n"contact.max_initial_indentation" = 1e11\n',
        ["run", "SCENE", "--law", "LN_spheres"],
        ["initial.q = [10000000000.0, 0.0, 0.0]", "contact.R1"],
    ),
    (
        "name_up",
        'name = "../../x"\n' + SHORT,
        ["run", "SCENE", "--law", "Moreau"],
        ["name = '../../x'"],
    ),
    (
        "name_absolute",
        'name = "/tmp/csfh-escaped"\n' + SHORT,
        ["compare", "SCENE"],
        ["name = '/tmp/csfh-escaped'"],
    ),
    (
        "E_overflow",
        SHORT + '[parameters]\n"contact.E1" = 1e308\n"contact.E2" = 1e308\n',
        ["run", "SCENE", "--law", "LN_ESDU"],
        ["contact.esdu_F_max = inf is not finite", "contact.E1 = 1e+308", "contact.E2 = 1e+308"],
    ),
    (
        "sweep_stop_time",
        "",
        ["sweep", "SCENE", "--stop-time", "5000"],
        ["--stop-time = 5000", "integrator.output_interval = 0.0001"],
    ),
    ("cosim_step", "", ["cosim", "SCENE", "--step", "1e-300"], ["step = 1e-300"]),
]


@pytest.mark.parametrize(
    ("text", "args", "needles"), [c[1:] for c in CASES], ids=[c[0] for c in CASES]
)
def test_bad_scene_is_one_line_naming_file_key_and_value(
    tmp_path: Path, text: str, args: list[str], needles: list[str]
) -> None:
    scene = tmp_path / "bad scene.toml"
    if args[0] == "cosim":
        text = (ROOT / "python/csfh/scenes/combdrive.toml").read_text() + text
    scene.write_text(text)
    argv = [str(scene) if a == "SCENE" else a for a in args]
    proc, wall = run_cli([*argv, "--out", str(tmp_path / "out"), "--quiet"], tmp_path)
    lines = proc.stderr.splitlines()
    assert proc.returncode == 2, proc.stderr
    assert len(lines) == 1 and lines[0].startswith("csfh: error: "), proc.stderr
    assert str(scene) in lines[0], lines[0]
    for needle in needles:
        assert needle in lines[0], (needle, lines[0])
    assert "Traceback" not in proc.stdout + proc.stderr
    assert wall < TIME_LIMIT, wall
    assert not (tmp_path / "out").exists() or not any((tmp_path / "out").iterdir())
    assert not Path("/tmp/csfh-escaped").exists()


def test_non_utf8_scene_names_the_file_and_the_byte(tmp_path: Path) -> None:
    scene = tmp_path / "latin1.toml"
    scene.write_bytes(b'name = "x"\ndescription = "caf\xe9"\n')
    proc, wall = run_cli(["run", str(scene), "--law", "Moreau", "--out", str(tmp_path)], tmp_path)
    lines = proc.stderr.splitlines()
    assert proc.returncode == 2 and len(lines) == 1, proc.stderr
    assert str(scene) in lines[0] and "not UTF-8" in lines[0] and "0xe9 at line 2" in lines[0]
    assert wall < TIME_LIMIT


# A scene that passes every check but whose run fails inside the FMU (a mass of 1e-150 kg, just
# above what the model's Delassus check refuses: the integrator's first step underflows; in model
# exchange a force of 1e200 N on it makes the first derivative overflow). The FMU's reason must
# reach the one line, and nothing the standard output.
FAILING = 'stop_time = 0.05\n[parameters]\n"body1.m" = 1e-150\n'
FAILING_ME = '[inputs]\n"F_ext[2]" = 1e200\n'


STEP_FAILED = "fmi2DoStep: the step from t = 0 to 0.0001 failed"
"""What the csfh FMU logs when a co-simulation step fails (after CVODE's own message)."""


@pytest.mark.parametrize(
    ("args", "reason"),
    [
        (["run", "SCENE", "--law", "LN_spheres", "--interface", "cs"], STEP_FAILED),
        (["run", "SCENE", "--law", "LN_spheres"], "fmi2GetDerivatives: non-finite derivative"),
        (["cosim", "SCENE", "--engine", "fmpy", "--stop-time", "0.01"], STEP_FAILED),
        (["cosim", "SCENE", "--engine", "libcosimpy", "--stop-time", "0.01"], STEP_FAILED),
    ],
    ids=["cs", "me", "cosim-fmpy", "cosim-libcosimpy"],
)
def test_failed_run_is_one_line_with_the_fmus_reason(
    tmp_path: Path, args: list[str], reason: str
) -> None:
    if "libcosimpy" in args:
        pytest.importorskip("libcosimpy")
    scene = tmp_path / "light.toml"
    text = FAILING if "cs" in args else FAILING + FAILING_ME
    if args[0] == "cosim":
        text = (
            ROOT / "python/csfh/scenes/combdrive.toml"
        ).read_text() + '\n[parameters]\n"body1.m" = 1e-150\n'
    scene.write_text(text)
    argv = [str(scene) if a == "SCENE" else a for a in args]
    proc, wall = run_cli([*argv, "--out", str(tmp_path / "out"), "--quiet"], tmp_path)
    lines = proc.stderr.splitlines()
    assert proc.returncode == 2, proc.stderr
    assert len(lines) == 1, proc.stderr
    assert str(scene) in lines[0]
    assert reason in lines[0], lines[0]  # the FMU's own words
    if "fmpy" in args or "cs" in args:
        # and the integrator's (auto: RK45 through this start), logged before
        assert "RK45 rk45_step: the step size" in lines[0], lines[0]
    assert "Traceback" not in proc.stdout + proc.stderr
    assert proc.stdout == ""
    assert wall < TIME_LIMIT


# ------------------------------------------------------------------------------------------
# Ctrl-C at a controlled point: a sitecustomize module (found first on PYTHONPATH) sends SIGINT
# to the process group (what a terminal's Ctrl-C does) when a given module is first imported,
# in the main process or in the worker processes of `--workers`.

SITECUSTOMIZE = textwrap.dedent(
    """
    import os, signal, sys  # noqa: E401

    _MODULE = os.environ.get("CSFH_TEST_SIGINT_ON_IMPORT")
    _WHERE = os.environ.get("CSFH_TEST_SIGINT_IN", "main")


    class _Trigger:
        fired = False

        def find_spec(self, name, path=None, target=None):
            worker = os.getpid() != os.getpgrp()  # csfh itself leads its process group
            if name == _MODULE and not self.fired and worker == (_WHERE == "worker"):
                self.fired = True
                os.killpg(os.getpgrp(), signal.SIGINT)
            return None


    if _MODULE:
        sys.meta_path.insert(0, _Trigger())
    """
)


def interrupted_run(tmp_path: Path, module: str, where: str, args: list[str]) -> tuple[int, str]:
    hook = tmp_path / "hook"
    hook.mkdir(exist_ok=True)
    (hook / "sitecustomize.py").write_text(SITECUSTOMIZE)
    env = csfh_env(PREPEND=str(hook), CSFH_TEST_SIGINT_ON_IMPORT=module, CSFH_TEST_SIGINT_IN=where)
    t0 = time.perf_counter()
    proc = subprocess.Popen(
        [sys.executable, "-m", "csfh", *args],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        cwd=tmp_path,
        env=env,
        start_new_session=True,  # its own process group: the SIGINT stays there
    )
    try:
        _, err = proc.communicate(timeout=120)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
    assert time.perf_counter() - t0 < 60
    return proc.returncode, err


SWEEP = ["sweep", "--quick", "--params", "R1", "--stop-time", "0.05", "--quiet"]


@pytest.mark.parametrize(
    ("module", "where", "args"),
    [
        ("argparse", "main", ["run", "central", "--law", "Moreau"]),
        ("csfh.cli.common", "main", ["run", "central", "--law", "Moreau"]),
        ("numpy", "main", ["run", "central", "--law", "Moreau"]),
        ("csfh.batch.tasks", "worker", [*SWEEP, "--workers", "2"]),
        ("numpy", "worker", [*SWEEP, "--workers", "2"]),
    ],
    ids=["argparse", "cli", "numpy", "worker-csfh", "worker-numpy"],
)
def test_ctrl_c_while_starting_up_is_one_line(
    tmp_path: Path, module: str, where: str, args: list[str]
) -> None:
    rc, err = interrupted_run(tmp_path, module, where, [*args, "--out", str(tmp_path / "out")])
    assert "Traceback" not in err, err
    assert err.strip().splitlines()[-1] == "csfh: interrupted", err
    # 130, or killed by SIGINT after the clean-up (CPython does that when an exec'd string saw
    # the KeyboardInterrupt; a shell shows 130 for both)
    assert rc in (130, -signal.SIGINT), (rc, err)


def test_cli_unknown_scene_and_law(tmp_path: Path) -> None:
    proc = run_csfh("run", "nowhere", "--law", "Moreau", cwd=tmp_path)
    assert proc.returncode == 2 and "unknown scene 'nowhere'" in proc.stderr
    proc = run_csfh("run", "central", "--law", "Bogus", cwd=tmp_path)
    assert proc.returncode == 2 and "Bogus" in proc.stderr


# ------------------------------------------------------------------------------------------
# csfh's own errors (csfh.errors) are one line and exit status 2; anything else is a bug and
# shows its traceback


class RaisingRunner:
    """The Moreau runner's place in the registry, raising `error` when it runs."""

    interface, models = "core", ("Moreau",)
    batches = same_parameters = exclusive = False

    def __init__(self, error: BaseException) -> None:
        self.error = error

    def run(self, *args: object, **kwargs: object) -> object:
        raise self.error

    run_many = run


USER_ERRORS = [
    "SceneError",
    "ParameterError",
    "SimulationError",
    "ResultsError",
    "InstallError",
    "CliError",
]


@pytest.mark.parametrize("name", USER_ERRORS)
def test_each_user_error_is_one_line_with_status_2(
    name: str, monkeypatch: pytest.MonkeyPatch, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from csfh import errors
    from csfh.cli.main import main
    from csfh.runners import registry

    error = getattr(errors, name)(f"the {name}\nover two lines")
    monkeypatch.setitem(registry.RUNNERS, "core", RaisingRunner(error))
    status = main(["run", "central", "--law", "Moreau", "--out", str(tmp_path), "--quiet"])
    assert status == 2
    where = "central (built-in): " if name == "SimulationError" else ""  # a run names its scene
    assert capsys.readouterr().err.splitlines() == [
        f"csfh: error: {where}the {name} over two lines"
    ]


BUG = """
import sys
from csfh.runners import registry

class Broken:
    interface, models = "core", ("Moreau",)
    batches = same_parameters = exclusive = False

    def run(self, *args, **kwargs):
        raise ValueError("a programming bug")

registry.RUNNERS["core"] = Broken()
from csfh.cli.main import main
sys.exit(main(["run", "central", "--law", "Moreau", "--out", sys.argv[1], "--quiet"]))
"""


def test_a_bug_shows_its_traceback(tmp_path: Path) -> None:
    """A ValueError from inside a run is not the user's: the command line does not turn it into
    one line, it ends with the traceback (exit status 1)."""
    proc = subprocess.run(
        [sys.executable, "-c", BUG, str(tmp_path / "out")],
        capture_output=True,
        text=True,
        env=csfh_env(),
        timeout=120,
    )
    assert proc.returncode == 1
    assert "Traceback (most recent call last)" in proc.stderr
    assert proc.stderr.strip().splitlines()[-1] == "ValueError: a programming bug"
    assert "csfh: error" not in proc.stderr


def test_an_output_directory_that_is_a_file_is_one_line(tmp_path: Path) -> None:
    target = tmp_path / "a file"
    target.write_text("not a directory\n")
    proc, _ = run_cli(["run", "central", "--law", "Moreau", "--out", str(target)], tmp_path)
    assert proc.returncode == 2, proc.stderr
    lines = proc.stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"csfh: error: {target}: "), proc.stderr
    assert "Traceback" not in proc.stderr and target.read_text() == "not a directory\n"
