"""Results are never overwritten in place (csfh.output): a file is written whole or not at all, a
command's run replaces the previous run's files as a whole (never a mix), a Ctrl-C while the
files are written leaves the previous run's files whole, a run with fewer files leaves none of
the previous run's behind, and nothing else in the output directory is touched."""

from __future__ import annotations

import ast
import json
import os
import signal
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest
from csfh_command import run_csfh

import csfh.output as output
from csfh.cli.main import main
from csfh.model.scene import scene_from_dict
from csfh.studies.compare import compare, read_comparison, replot

ROOT = Path(__file__).resolve().parents[2]
PACKAGE = ROOT / "python" / "csfh"


def short_scene(stop_time: float, name: str = "short") -> object:
    return scene_from_dict(
        {"name": name, "stop_time": stop_time, "initial": {"q": [0.0, 0.01, 0.0]}}
    )


def short_file(tmp_path: Path) -> str:
    """A 0.05 s scene file for `csfh run`."""
    path = tmp_path / "drop.toml"
    path.write_text('name = "drop"\nstop_time = 0.05\n[initial]\nq = [0.0, 0.01, 0.0]\n')
    return str(path)


def snapshot(directory: Path) -> dict[str, bytes]:
    """Every file under `directory` (the state directory .csfh included), by relative path."""
    return {
        p.relative_to(directory).as_posix(): p.read_bytes()
        for p in sorted(directory.rglob("*"))
        if p.is_file()
    }


def visible(directory: Path) -> set[str]:
    return {p.name for p in directory.iterdir() if not p.name.startswith(".")}


@pytest.fixture(scope="module")
def first(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, dict[str, bytes]]:
    """A comparison of two models (0.1 s), and a snapshot of its directory."""
    out = tmp_path_factory.mktemp("first")
    compare(short_scene(0.1), out, models=("LN_spheres", "Moreau"))
    return out, snapshot(out)


def copy_of(first: tuple[Path, dict[str, bytes]], tmp_path: Path) -> Path:
    out = tmp_path / "out"
    for rel, data in first[1].items():
        (out / rel).parent.mkdir(parents=True, exist_ok=True)
        (out / rel).write_bytes(data)
    return out


# ------------------------------------------------------------------------------------------
# one file


def test_a_file_is_replaced_whole_or_not_at_all(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    path = tmp_path / "table.csv"
    output.write_text(path, "old\n")

    def interrupted(fd: int) -> None:
        raise KeyboardInterrupt

    monkeypatch.setattr(output.os, "fsync", interrupted)
    with pytest.raises(KeyboardInterrupt):
        output.write_text(path, "new, longer contents\n" * 1000)
    assert path.read_text() == "old\n"
    assert [p.name for p in tmp_path.iterdir()] == ["table.csv"]  # no temporary file left


# ------------------------------------------------------------------------------------------
# a comparison's files as a whole


def test_ctrl_c_while_a_comparison_is_written_leaves_the_previous_one_whole(
    first: tuple[Path, dict[str, bytes]], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    out = copy_of(first, tmp_path)
    (out / "my notes.txt").write_text("mine")
    before = snapshot(out)
    calls = {"n": 0}
    original = output.replace_file

    def interrupt_at_the_fourth_file(path: Path, data: bytes) -> Path:
        calls["n"] += 1
        if calls["n"] == 4:  # two tables and a half-written third file are staged by now
            Path(path).write_bytes(data[: len(data) // 2])
            raise KeyboardInterrupt
        return original(path, data)

    monkeypatch.setattr(output, "replace_file", interrupt_at_the_fourth_file)
    with pytest.raises(KeyboardInterrupt):
        compare(short_scene(0.12), out, models=("LN_spheres", "Moreau"))
    monkeypatch.setattr(output, "replace_file", original)
    assert calls["n"] == 4
    assert snapshot(out) == before  # byte for byte, the staging area gone
    summary, runs = read_comparison(out)
    assert summary["stop_time"] == 0.1 and [tr.t[-1] for tr in runs] == [0.1, 0.1]


def test_ctrl_c_at_a_controlled_point_of_the_command_line(
    first: tuple[Path, dict[str, bytes]], tmp_path: Path
) -> None:
    """The same through `csfh compare` in a subprocess that receives SIGINT after writing its
    third file (a sitecustomize module wraps csfh.output.replace_file)."""
    out = copy_of(first, tmp_path)
    before = snapshot(out)
    hook = tmp_path / "hook"
    hook.mkdir()
    (hook / "sitecustomize.py").write_text(
        textwrap.dedent(
            """
            import importlib.abc, importlib.util, os, signal, sys


            def _patch(module):
                original, count = module.replace_file, [0]

                def replace_file(path, data):
                    count[0] += 1
                    if count[0] == 3:
                        os.kill(os.getpid(), signal.SIGINT)
                    return original(path, data)

                module.replace_file = replace_file


            class _Finder(importlib.abc.MetaPathFinder):
                def find_spec(self, name, path=None, target=None):
                    if name != "csfh.output":
                        return None
                    sys.meta_path.remove(self)
                    spec = importlib.util.find_spec(name)
                    exec_module = spec.loader.exec_module

                    def exec_and_patch(module):
                        exec_module(module)
                        _patch(module)

                    spec.loader.exec_module = exec_and_patch
                    return spec


            sys.meta_path.insert(0, _Finder())
            """
        )
    )
    scene = tmp_path / "short.toml"
    scene.write_text(
        'name = "short"\nstop_time = 0.12\nmodels = ["LN_spheres", "Moreau"]\n'
        "[initial]\nq = [0.0, 0.01, 0.0]\n"
    )
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(hook), str(ROOT / "python")]))
    proc = run_csfh("compare", str(scene), "--out", str(out), "--quiet", env=env, timeout=300)
    assert proc.returncode in (130, -signal.SIGINT), proc.stderr
    assert proc.stderr.strip().splitlines()[-1] == "csfh: interrupted", proc.stderr
    assert snapshot(out) == before


def test_a_commit_cut_short_by_a_killed_process_is_completed_by_the_next_reader(
    first: tuple[Path, dict[str, bytes]], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    out = copy_of(first, tmp_path)
    renames = {"n": 0}
    original = os.replace

    def killed_after_three_renames(src: object, dst: object) -> None:
        if str(dst).startswith(str(out)) and ".csfh" not in str(dst):
            renames["n"] += 1
            if renames["n"] == 4:
                raise SystemExit("killed")  # stands for SIGKILL in the middle of the renames
        original(src, dst)  # type: ignore[arg-type]

    monkeypatch.setattr(output.os, "replace", killed_after_three_renames)
    with pytest.raises(SystemExit):
        compare(short_scene(0.12), out, models=("Moreau",))
    monkeypatch.setattr(output.os, "replace", original)
    assert (out / ".csfh" / "compare.commit.json").exists()
    # the next reader completes the commit: one run's files, the stale ones gone
    summary, runs = read_comparison(out)
    assert summary["stop_time"] == 0.12 and list(summary["models"]) == ["Moreau"]
    assert runs[0].t[-1] == pytest.approx(0.12)
    assert not (out / "LN_spheres.csv").exists() and not (out / "LN_spheres.steps.csv").exists()
    assert not (out / ".csfh" / "compare.commit.json").exists()


def test_fewer_models_leave_no_stale_files_and_other_files_alone(
    first: tuple[Path, dict[str, bytes]], tmp_path: Path
) -> None:
    out = copy_of(first, tmp_path)
    (out / "my notes.txt").write_text("mine")
    (out / "sub").mkdir()
    (out / "sub" / "LN_spheres.csv").write_text("a user's file of the same name, elsewhere")
    # a file of another command in the same directory (csfh run writes MODEL.csv there too)
    assert main(["run", short_file(tmp_path), "--law", "Flores", "--out", str(out), "--quiet"]) == 0
    flores = (out / "Flores.csv").read_bytes()
    compare(short_scene(0.12), out, models=("Moreau",))
    assert visible(out) == {
        "Moreau.csv",
        "summary.json",
        *(name for name in visible(out) if name.endswith(".png")),
        "my notes.txt",
        "sub",
        "Flores.csv",
    }
    assert len([n for n in visible(out) if n.endswith(".png")]) == 5
    assert (out / "my notes.txt").read_text() == "mine"
    assert (out / "sub" / "LN_spheres.csv").read_text().startswith("a user's")
    assert (out / "Flores.csv").read_bytes() == flores
    summary = json.loads((out / "summary.json").read_text())
    assert list(summary["models"]) == ["Moreau"]
    manifest = json.loads((out / ".csfh" / "compare.json").read_text())
    assert set(manifest["files"]) == {n for n in visible(out)} - {
        "my notes.txt",
        "sub",
        "Flores.csv",
    }


def test_a_file_another_command_replaced_is_kept_and_named_by_plot(
    first: tuple[Path, dict[str, bytes]], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = copy_of(first, tmp_path)
    # csfh run writes LN_spheres.csv of another scene into the comparison's directory
    assert main(["run", short_file(tmp_path), "--law", "LN_spheres", "--out", str(out)]) == 0
    capsys.readouterr()
    assert main(["plot", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "LN_spheres.csv" in err[0] and "csfh compare again" in err[0]
    # a later comparison without LN_spheres leaves the run's file: it is not the comparison's
    theirs = (out / "LN_spheres.csv").read_bytes()
    compare(short_scene(0.12), out, models=("Moreau",))
    assert (out / "LN_spheres.csv").read_bytes() == theirs
    assert not (out / "LN_spheres.steps.csv").exists()


def test_plot_replaces_the_figures_and_keeps_the_tables(
    first: tuple[Path, dict[str, bytes]], tmp_path: Path
) -> None:
    out = copy_of(first, tmp_path)
    before = snapshot(out)
    files = replot(out)
    assert {p.name for p in files} <= visible(out)
    after = snapshot(out)
    tables = [rel for rel in before if rel.endswith((".csv", ".json")) and "/" not in rel]
    assert tables and all(after[rel] == before[rel] for rel in tables)
    manifest = json.loads(after[".csfh/compare.json"])
    assert set(manifest["files"]) == visible(out)


def test_temporary_files_of_killed_processes_in_the_state_directory_are_removed(
    first: tuple[Path, dict[str, bytes]], tmp_path: Path
) -> None:
    out = copy_of(first, tmp_path)
    ended = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                           capture_output=True, text=True, check=True)  # fmt: skip
    dead = int(ended.stdout)
    stale = out / ".csfh" / f".compare.json.{dead}.140213.tmp"
    live = out / ".csfh" / f".compare.json.{os.getpid()}.140213.tmp"  # being written
    theirs = out / f".notes.txt.{dead}.1.tmp"  # not csfh's state: the user's
    for path in (stale, live, theirs):
        path.write_text("half a file")
    replot(out)
    assert [p.exists() for p in (stale, live, theirs)] == [False, True, True]


def test_runs_of_different_models_keep_each_others_files(tmp_path: Path) -> None:
    scene = short_file(tmp_path)
    for law in ("Moreau", "Flores", "Moreau"):
        assert main(["run", scene, "--law", law, "--out", str(tmp_path / "out"), "--quiet"]) == 0
    tmp_path = tmp_path / "out"
    assert visible(tmp_path) == {"Moreau.csv", "Flores.csv"}


# ------------------------------------------------------------------------------------------
# every file goes through csfh.output


WRITING_METHODS = {"write_text", "write_bytes", "savefig", "touch", "tofile"}
WRITING_FUNCTIONS = {"np.save", "np.savez", "np.savez_compressed", "np.savetxt", "json.dump",
                     "pickle.dump", "shutil.copy", "shutil.copyfile", "shutil.copy2",
                     "shutil.copytree", "shutil.move"}  # fmt: skip


def test_every_file_is_written_through_csfh_output() -> None:
    """No module but csfh.output writes a file (open for writing, Path.write_*, savefig,
    numpy's savers, shutil's copies); the result store appends its index itself and writes its
    signal files with csfh.output.replace_file."""
    offenders = []
    for path in sorted(PACKAGE.rglob("*.py")):
        rel = path.relative_to(PACKAGE).as_posix()
        if rel == "output.py":
            continue
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if not isinstance(node, ast.Call):
                continue
            func = node.func
            name = func.attr if isinstance(func, ast.Attribute) else getattr(func, "id", "")
            if name == "open" and len(node.args) >= 2:
                mode = node.args[1]
                if isinstance(mode, ast.Constant) and set(str(mode.value)) & set("wax+"):
                    if rel != "batch/store.py":  # the append-only index and its lock
                        offenders.append(f"{rel}:{node.lineno} open(..., {mode.value!r})")
            else:
                target = ast.unparse(func)
                if target not in WRITING_FUNCTIONS and not (
                    isinstance(func, ast.Attribute) and name in WRITING_METHODS
                ):
                    continue
                first = node.args[0] if node.args else None
                if isinstance(first, ast.Name) and first.id == "buffer":
                    continue  # into memory (io.BytesIO), then written by csfh.output
                offenders.append(f"{rel}:{node.lineno} {target}")
    assert offenders == [], offenders
