"""Hostile scene files, options and environment: integers beyond any double, deeply nested TOML,
a byte-order mark, a file in the working directory named like a built-in scene, an empty --out,
negative numbers as option values, a $CSFH_FMU that is not csfh's FMU. Each ends in one line
naming the key, the option or the file (or, for a byte-order mark, in the scene it holds)."""

from __future__ import annotations

import subprocess
from pathlib import Path

import pytest
from csfh_command import run_csfh
from test_cli_errors import csfh_env

from csfh.model.scene import SceneError, load_scene

ROOT = Path(__file__).resolve().parents[2]
HUGE = "1" + "0" * 400
"""An integer literal of 10^400: valid TOML, beyond every double."""
COSIM = (ROOT / "python/csfh/scenes/combdrive.toml").read_text()


def _with(text: str, key: str, value: str) -> str:
    """`text` with the line `key = ...` (the first one) set to `value`."""
    lines = text.splitlines()
    i = next(k for k, line in enumerate(lines) if line.split("=")[0].strip() == key)
    lines[i] = f"{key} = {value}"
    return "\n".join(lines) + "\n"


# (case id, scene text, what the error must name)
BIG_INTEGERS = [
    ("stop_time", f"stop_time = {HUGE}\n", "stop_time = 1.000e+400"),
    ("initial.q", f"[initial]\nq = [0, {HUGE}, 0]\n", "initial.q[1] = 1.000e+400"),
    ("initial.u", f"[initial]\nu = [-{HUGE}, 0, 0]\n", "initial.u[0] = -1.000e+400"),
    ("parameter", f'[parameters]\n"contact.cr" = {HUGE}\n', "contact.cr = 1.000e+400"),
    ("enumeration", f'[parameters]\n"contact.law" = {HUGE}\n', "contact.law = 1.000e+400"),
    ("input", f'[inputs]\n"F_ext[1]" = {HUGE}\n', "inputs.F_ext[1] = 1.000e+400"),
    *(
        (f"integrator.{k}", f"[integrator]\n{k} = {HUGE}\n", f"integrator.{k} = 1.000e+400")
        for k in ("rtol", "output_interval", "moreau_h", "v_eps", "g_tol")
    ),
    ("cosim.step", _with(COSIM, "step", HUGE), "cosim.step = 1.000e+400"),
    (
        "cosim.tolerance",
        COSIM.replace("[cosim.actuator]", f"tolerance = {HUGE}\n[cosim.actuator]", 1),
        "cosim.tolerance = 1.000e+400",
    ),
    ("cosim.fingers", _with(COSIM, "fingers", HUGE), "cosim.actuator.fingers = 1.000e+400"),
    ("cosim.voltage", _with(COSIM, "V1", HUGE), "cosim.voltage.V1 = 1.000e+400"),
]


@pytest.mark.parametrize(
    ("text", "needle"), [c[1:] for c in BIG_INTEGERS], ids=[c[0] for c in BIG_INTEGERS]
)
def test_an_integer_beyond_a_double_names_its_key(tmp_path: Path, text: str, needle: str) -> None:
    path = tmp_path / "big.toml"
    path.write_text(text)
    with pytest.raises(SceneError) as info:
        load_scene(path)
    message = str(info.value)
    assert message.startswith(f"{path}: ") and needle in message, message
    assert "\n" not in message and len(message) < 400, message


def test_an_integer_of_thousands_of_digits_is_one_line(tmp_path: Path) -> None:
    """Beyond Python's limit of 4300 digits for integer text the TOML reader itself fails."""
    path = tmp_path / "long.toml"
    path.write_text(f"stop_time = 1{'0' * 5000}\n")
    with pytest.raises(SceneError, match=r"long\.toml: .*4300 digits"):
        load_scene(path)


def test_deeply_nested_toml_is_one_line(tmp_path: Path) -> None:
    path = tmp_path / "nested.toml"
    path.write_text("a = " + "[" * 500 + "\n")
    with pytest.raises(SceneError, match=r"nested\.toml: not valid TOML: .*nested"):
        load_scene(path)


def test_a_byte_order_mark_is_accepted(tmp_path: Path) -> None:
    path = tmp_path / "bom.toml"
    path.write_bytes(b"\xef\xbb\xbfstop_time = 0.05\n")
    assert load_scene(path).stop_time == 0.05


def test_cosim_tolerance_below_the_fmus_range_names_the_key(tmp_path: Path) -> None:
    path = tmp_path / "tol.toml"
    path.write_text(COSIM.replace("[cosim.actuator]", "tolerance = 1e-300\n[cosim.actuator]", 1))
    with pytest.raises(SceneError, match=r"cosim\.tolerance = 1e-300 must be in \[2\.2"):
        load_scene(path)


# ------------------------------------------------------------------------------------------
# a bare name: the built-in scene, a file of that name, a directory


def test_a_file_named_like_a_builtin_scene_is_refused(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)
    (tmp_path / "mems").write_text("stop_time = 0.05\n")
    with pytest.raises(SceneError) as info:
        load_scene("mems")
    message = str(info.value)
    assert "'mems'" in message and "built-in" in message and "./mems" in message, message
    assert load_scene("./mems").stop_time == 0.05  # a path is the file
    assert load_scene("./mems").source == "mems"


def test_a_directory_named_like_a_builtin_scene_is_not_a_scene(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)
    (tmp_path / "csfh").mkdir()
    assert load_scene("csfh").source == "csfh (built-in)"
    (tmp_path / "elsewhere").mkdir()
    with pytest.raises(SceneError, match=r"^elsewhere: a directory, not a scene file"):
        load_scene("elsewhere")


# ------------------------------------------------------------------------------------------
# the command line


def _one_line(proc: subprocess.CompletedProcess[str]) -> str:
    """The one line of a refused command (exit status 2, nothing else on standard error)."""
    lines = proc.stderr.splitlines()
    assert proc.returncode == 2 and len(lines) == 1, proc.stderr
    assert lines[0].startswith("csfh: error: "), proc.stderr
    return lines[0]


def test_an_empty_out_is_refused(tmp_path: Path) -> None:
    proc = run_csfh("run", "central", "--law", "Moreau", "--out", "", cwd=tmp_path, env=csfh_env())
    assert "--out" in _one_line(proc)
    assert not (tmp_path / "results").exists()


def test_a_negative_number_reaches_the_options_check(tmp_path: Path) -> None:
    proc = run_csfh(
        "shock",
        "central",
        "--peak",
        "100",
        "--duration",
        "-1e-3",
        "--out",
        str(tmp_path),
        cwd=tmp_path,
        env=csfh_env(),
    )
    assert "--duration = '-1e-3' s must be > 0" in _one_line(proc)


@pytest.mark.parametrize("kind", ["not-a-zip", "combdrive"])
def test_csfh_fmu_that_is_not_csfhs_fmu_is_one_line(tmp_path: Path, kind: str) -> None:
    if kind == "not-a-zip":
        fmu = tmp_path / "csfh.fmu"
        fmu.write_text("not an archive\n")
        needle = "not an FMU"
    else:
        fmu = ROOT / "build/combdrive.fmu"
        if not fmu.is_file():
            pytest.skip("no build/combdrive.fmu")
        needle = "not csfh's FMU"
    env = csfh_env(CSFH_FMU=str(fmu))
    proc = run_csfh(
        "run",
        "central",
        "--law",
        "LN_spheres",
        "--out",
        str(tmp_path / "o"),
        cwd=tmp_path,
        env=env,
    )
    line = _one_line(proc)
    assert "$CSFH_FMU" in line and str(fmu) in line and needle in line, line


# ------------------------------------------------------------------------------------------
# the number of runs of a study is bounded like a run's length (csfh.model.limits)

TOLERANCE_FILE = (ROOT / "python/csfh/scenes/tolerance_csfh.toml").read_text()


@pytest.mark.parametrize(
    ("args", "needle"),
    [
        (["tolerance", "tolerance_csfh", "--runs", "100000000"], "--runs = 100000000"),
        (["tolerance", "FILE"], "montecarlo.runs = 100000000"),
        (["shock", "central", "--directions", "1000000000"], "--directions = 1000000000"),
        (
            ["shock", "central", "--tolerance", "tolerance_csfh", "--runs", "100000000"],
            "--runs = 100000000",
        ),
    ],
    ids=["tolerance-option", "tolerance-file", "shock-directions", "shock-runs"],
)
def test_too_many_runs_are_refused_before_any_runs(
    tmp_path: Path, args: list[str], needle: str
) -> None:
    from csfh.model.limits import MAX_DIRECTIONS, MAX_RUNS

    path = tmp_path / "mc.toml"
    lines = TOLERANCE_FILE.splitlines()
    i = next(k for k, line in enumerate(lines) if line.startswith("runs = "))
    path.write_text("\n".join([*lines[:i], "runs = 100000000", *lines[i + 1 :]]) + "\n")
    argv = [str(path) if a == "FILE" else a for a in args]
    proc = run_csfh(
        *argv, "--out", str(tmp_path / "o"), "--quiet", cwd=tmp_path, env=csfh_env(), timeout=60
    )
    line = _one_line(proc)
    limit = MAX_DIRECTIONS if "directions" in needle else MAX_RUNS
    assert needle in line and f"{limit:g}" in line, line
    assert not (tmp_path / "o").exists() or not any((tmp_path / "o").glob("*.jsonl"))


# ------------------------------------------------------------------------------------------
# a body so light that Moreau's Delassus matrix overflows: refused by the model's own check (the
# C core's, which the FMU, the scene loader and the Moreau stepper share), not run through the
# bore


@pytest.mark.parametrize("law", ["Moreau", "LN_spheres"])
def test_a_body_too_light_for_the_doubles_is_refused_for_every_model(
    tmp_path: Path, law: str
) -> None:
    scene = tmp_path / "light.toml"
    scene.write_text(
        (ROOT / "python/csfh/scenes/central.toml").read_text()
        + '\n[parameters]\n"body1.m" = 1e-200\n"body1.I" = 1e-200\n'
    )
    proc = run_csfh(
        "run",
        str(scene),
        "--law",
        law,
        "--out",
        str(tmp_path / "o"),
        cwd=tmp_path,
        env=csfh_env(),
    )
    line = _one_line(proc)
    assert str(scene) in line and "body1.m = 1e-200" in line and "is not finite" in line, line
    assert not (tmp_path / "o").exists()


# ------------------------------------------------------------------------------------------
# an output directory that cannot be used is found before anything is computed


class Unreachable:
    """A runner that fails the test if a run is computed."""

    batches = same_parameters = exclusive = False

    def __init__(self, interface: str, models: tuple[str, ...]) -> None:
        self.interface, self.models = interface, models

    def run(self, *args: object, **kwargs: object) -> object:
        raise AssertionError("computed before the output directory was checked")

    run_many = run


@pytest.mark.parametrize(
    "argv",
    [
        ["run", "central", "--law", "LN_spheres"],
        ["run", "central", "--law", "Moreau"],
        ["compare", "central"],
    ],
    ids=["run-me", "run-moreau", "compare"],
)
def test_an_unusable_out_is_found_before_computing(
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
    argv: list[str],
) -> None:
    from csfh.cli.main import main
    from csfh.runners import registry

    for key, runner in list(registry.RUNNERS.items()):
        monkeypatch.setitem(registry.RUNNERS, key, Unreachable(runner.interface, runner.models))
    blocker = tmp_path / "a file"
    blocker.write_text("x\n")
    assert main([*argv, "--out", str(blocker / "sub"), "--quiet"]) == 2
    err = capsys.readouterr().err.splitlines()
    assert err == [
        f"csfh: error: {blocker / 'sub'}: is not a usable output directory (Not a directory)"
    ]


@pytest.mark.parametrize(
    ("old", "new", "needle"),
    [
        (
            '"contact.R1" = {sigma = 2e-5}',
            f'"contact.R1" = {{sigma = {HUGE}}}',
            "sigma = 1.000e+400",
        ),
        (
            '"contact.R1" = {sigma = 2e-5}',
            f'"contact.R1" = {{sigma = 1e-5, mean = -{HUGE}}}',
            "mean = -1.000e+400",
        ),
        ("runs = 500", f"runs = -{HUGE}", "montecarlo.runs = -1.000e+400"),
    ],
    ids=["sigma", "mean", "runs"],
)
def test_a_tolerance_file_with_an_integer_beyond_a_double_names_its_key(
    tmp_path: Path, old: str, new: str, needle: str
) -> None:
    from csfh.studies.tolerance.study import load_study

    path = tmp_path / "tol.toml"
    assert old in TOLERANCE_FILE
    path.write_text(TOLERANCE_FILE.replace(old, new, 1))
    with pytest.raises(SceneError) as info:
        load_study(path)
    message = str(info.value)
    assert message.startswith(f"{path}: ") and needle in message and len(message) < 400, message


def test_fingers_beyond_the_fmus_integer_are_refused_not_wrapped(tmp_path: Path) -> None:
    """4294967301 = 2^32 + 5 would wrap to 5 in the FMU's 32-bit Integer."""
    path = tmp_path / "wrap.toml"
    path.write_text(_with(COSIM, "fingers", "4294967301"))
    with pytest.raises(SceneError, match=r"fingers = 4294967301 is out of range \[1, 2147483647\]"):
        load_scene(path)


def test_an_integer_beyond_a_double_is_one_line_on_the_command_line(tmp_path: Path) -> None:
    path = tmp_path / "big.toml"
    path.write_text(f"stop_time = {HUGE}\n")
    proc = run_csfh(
        "run",
        str(path),
        "--law",
        "Moreau",
        "--out",
        str(tmp_path / "o"),
        cwd=tmp_path,
        env=csfh_env(),
    )
    assert _one_line(proc) == f"csfh: error: {path}: stop_time = 1.000e+400 must be a finite number"
