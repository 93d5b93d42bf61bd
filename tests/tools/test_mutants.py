"""tools/mutants.py, the mutation check of the test suite: on a tiny synthetic project it finds
the mutant its tests catch and the one they do not, reports a stale mutant, never touches the
source tree (also when interrupted), removes its scratch copy and the commands it started; and
every mutant of the repository's own list still applies to the sources (so the list follows the
code)."""

from __future__ import annotations

import hashlib
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
TOOL = ROOT / "tools" / "mutants.py"

CALC = """def add(a, b):
    return a + b


def mul(a, b):
    return a * b
"""

TESTS = """import os
import time

from calc import add


def test_add():
    assert add(2, 3) == 5


def test_slow():
    if os.environ.get("SLOW_PID_FILE"):
        with open(os.environ["SLOW_PID_FILE"], "w") as f:
            f.write(str(os.getpid()))
        time.sleep(60)
"""

LIST = """[settings]
setup = []
build = [["{python}", "-c", "import calc"]]
timeout = 120

[runners.Python]
command = ["{python}", "-m", "pytest", "-q", "-x", "-p", "no:cacheprovider", "{tests}"]

[[mutant]]
name = "add-minus"
file = "calc.py"
search = "return a + b"
replace = "return a - b"
tests = { Python = ["test_calc.py::test_add"] }

[[mutant]]
name = "mul-plus"
file = "calc.py"
search = "return a * b"
replace = "return a + b"
why = "no test looks at mul: survives"
tests = { Python = ["test_calc.py::test_add"] }

[[mutant]]
name = "broken"
file = "calc.py"
search = "def mul(a, b):"
replace = "def mul(a, b)"
why = "does not build"
tests = { Python = ["test_calc.py::test_add"] }
"""


def tree_digest(root: Path) -> dict[str, str]:
    return {
        str(p.relative_to(root)): hashlib.sha256(p.read_bytes()).hexdigest()
        for p in sorted(root.rglob("*"))
        if p.is_file() and ".git" not in p.parts
    }


@pytest.fixture
def project(tmp_path: Path) -> Path:
    src = tmp_path / "src"
    src.mkdir()
    (src / "calc.py").write_text(CALC)
    (src / "test_calc.py").write_text(TESTS)
    (src / "mutants.toml").write_text(LIST)
    git = ["git", "-c", "user.name=t", "-c", "user.email=t@t", "-C", str(src)]
    subprocess.run([*git, "init", "-q"], check=True)
    subprocess.run([*git, "add", "-A"], check=True)
    subprocess.run([*git, "commit", "-q", "-m", "init"], check=True)
    return src


def run_tool(project: Path, tmp: Path, *args: str, **kwargs) -> subprocess.CompletedProcess:
    env = {**os.environ, "TMPDIR": str(tmp), "PYTHONPATH": ""}
    return subprocess.run(
        [
            sys.executable,
            str(TOOL),
            "--list-file",
            str(project / "mutants.toml"),
            "--source",
            str(project),
            *args,
        ],
        capture_output=True,
        text=True,
        env=env,
        cwd=project,
        timeout=300,
        **kwargs,
    )


def test_caught_survived_invalid_and_the_tree_left_clean(project: Path, tmp_path: Path) -> None:
    scratch = tmp_path / "scratch"
    scratch.mkdir()
    # an uncommitted change is part of the copy: the tool measures the working tree
    (project / "test_calc.py").write_text(TESTS + "\n# edited\n")
    before = tree_digest(project)
    proc = run_tool(project, scratch, "--json", str(tmp_path / "out.json"))
    assert proc.returncode == 1, proc.stdout + proc.stderr  # a survivor (and an invalid one)
    rows = {
        line.split("|")[1].strip(): line
        for line in proc.stdout.splitlines()
        if line.startswith("| ") and not line.startswith("| mutant")
    }
    assert "| caught |" in rows["add-minus"] and "test_add" in rows["add-minus"]
    assert "| survived |" in rows["mul-plus"]
    assert "| invalid |" in rows["broken"]
    assert "3 mutants: 1 caught, 1 invalid, 1 survived" in proc.stdout
    assert tree_digest(project) == before  # the sources were never touched
    status = subprocess.run(
        ["git", "-C", str(project), "status", "--porcelain"],
        capture_output=True,
        text=True,
        check=True,
    ).stdout
    assert status.split() == ["M", "test_calc.py"]  # only the user's own edit
    assert not list(scratch.glob("csfh-mutants-*"))  # the scratch copy is gone
    assert '"mul-plus"' in (tmp_path / "out.json").read_text()


def test_stale_mutant_and_only(project: Path, tmp_path: Path) -> None:
    (project / "calc.py").write_text(CALC.replace("return a * b", "return b * a"))
    check = run_tool(project, tmp_path, "--check")
    assert check.returncode == 1 and "stale: mul-plus" in check.stdout
    proc = run_tool(project, tmp_path, "--only", "mul-*")
    assert proc.returncode == 1 and "| mul-plus | calc.py | stale |" in proc.stdout
    assert "add-minus" not in proc.stdout  # --only: the others do not run
    proc = run_tool(project, tmp_path, "--only", "nothing-*")
    assert proc.returncode == 2 and "no mutant matches" in proc.stderr


def test_baseline_must_pass(project: Path, tmp_path: Path) -> None:
    (project / "test_calc.py").write_text(TESTS.replace("== 5", "== 6"))
    proc = run_tool(project, tmp_path)
    assert proc.returncode == 2 and "fail without any mutant" in proc.stdout


def test_interrupted_run_kills_its_commands_and_cleans_up(project: Path, tmp_path: Path) -> None:
    """SIGINT while a mutant's tests run: the tool kills the test process it started, removes
    its scratch copy, leaves the sources as they were and exits 130."""
    (project / "mutants.toml").write_text(
        LIST.replace(
            'tests = { Python = ["test_calc.py::test_add"] }',
            'tests = { Python = ["test_calc.py::test_slow"] }',
            1,
        )
    )
    scratch = tmp_path / "scratch"
    scratch.mkdir()
    pid_file = tmp_path / "slow.pid"
    before = tree_digest(project)
    env = {**os.environ, "TMPDIR": str(scratch), "PYTHONPATH": "", "SLOW_PID_FILE": str(pid_file)}
    proc = subprocess.Popen(
        [
            sys.executable,
            str(TOOL),
            "--list-file",
            str(project / "mutants.toml"),
            "--source",
            str(project),
            "--no-baseline",
            "--only",
            "add-minus",
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
        cwd=project,
    )
    deadline = time.monotonic() + 60
    while not pid_file.exists() or not pid_file.read_text():
        assert time.monotonic() < deadline and proc.poll() is None, proc.communicate()
        time.sleep(0.05)
    test_pid = int(pid_file.read_text())
    assert list(scratch.glob("csfh-mutants-*"))  # the copy exists while it runs
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=60)
    assert proc.returncode == 130, out + err
    assert "interrupted" in err
    assert tree_digest(project) == before
    assert not list(scratch.glob("csfh-mutants-*"))
    deadline = time.monotonic() + 10
    while Path(f"/proc/{test_pid}").exists():  # killed with its process group
        assert time.monotonic() < deadline, "the test process survived the interruption"
        time.sleep(0.05)


def test_every_mutant_of_the_list_applies_to_the_sources() -> None:
    """tools/mutants.toml follows the code: each search text occurs exactly once (a change to
    the code a mutant refers to must update the mutant)."""
    proc = subprocess.run(
        [sys.executable, str(TOOL), "--check"], capture_output=True, text=True, cwd=ROOT, timeout=60
    )
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert proc.stdout.strip().endswith(f"apply to {ROOT}")


def test_bad_list_is_one_line(tmp_path: Path) -> None:
    bad = tmp_path / "bad.toml"
    bad.write_text(
        '[[mutant]]\nname = "x"\nfile = "a"\nsearch = "b"\nreplace = "b"\n'
        'tests = { Python = ["t"] }\n'
    )
    proc = subprocess.run(
        [sys.executable, str(TOOL), "--list-file", str(bad), "--check"],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert proc.returncode == 2
    assert proc.stderr.count("\n") == 1 and "search and replace are the same" in proc.stderr
