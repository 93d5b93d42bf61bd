"""A results folder is untrusted input (csfh.safepath, csfh.output): a manifest or a commit journal
that names a file outside the folder, reaches one through a symbolic link or breaks the schema
is refused with one line naming it, and nothing outside the folder is touched; a rename replaces
only a regular file (or nothing), never a device, a FIFO, a socket, a directory or a link."""

from __future__ import annotations

import hashlib
import json
import os
import re
import stat
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

import csfh.cosim.ssp as ssp
import csfh.output as output
from csfh.cli.main import main
from csfh.model.scene import scene_from_dict
from csfh.studies.compare import compare


def drop_scene(tmp_path: Path) -> str:
    """A 0.05 s scene file for `csfh run`."""
    path = tmp_path / "drop.toml"
    path.write_text('name = "drop"\nstop_time = 0.05\n[initial]\nq = [0.0, 0.01, 0.0]\n')
    return str(path)


def sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def snapshot(directory: Path) -> dict[str, bytes]:
    return {
        p.relative_to(directory).as_posix(): p.read_bytes()
        for p in sorted(directory.rglob("*"))
        if p.is_file() and not p.is_symlink()
    }


@pytest.fixture
def victim(tmp_path: Path) -> Path:
    """Files outside the results folder that nothing may touch."""
    d = tmp_path / "victim"
    d.mkdir()
    (d / "x").write_text("precious")
    (d / "bashrc").write_text("original")
    (d / "other").write_text("keep")
    return d


def one_error(capsys: pytest.CaptureFixture[str]) -> str:
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("csfh: error: "), err
    return err[0]


def run_moreau(scene: str, out: Path) -> int:
    return main(["run", scene, "--law", "Moreau", "--out", str(out), "--quiet"])


def edit_json(path: Path, change: Callable[[dict[str, Any]], None]) -> None:
    data = json.loads(path.read_text())
    change(data)
    path.write_text(json.dumps(data))


# ------------------------------------------------------------------------------------------
# manifests


@pytest.mark.parametrize("where", ["relative", "absolute"])
def test_a_manifest_naming_a_file_outside_the_folder_is_refused(
    tmp_path: Path, victim: Path, where: str, capsys: pytest.CaptureFixture[str]
) -> None:
    scene, out = drop_scene(tmp_path), tmp_path / "out"
    assert run_moreau(scene, out) == 0
    target = victim / "x"
    rel = "../victim/x" if where == "relative" else str(target)
    info = {"sha256": sha256(target), "bytes": target.stat().st_size}
    manifest = out / ".csfh" / "run.Moreau.json"
    edit_json(manifest, lambda m: m["files"].__setitem__(rel, info))
    capsys.readouterr()
    assert run_moreau(scene, out) == 2
    assert str(manifest) in one_error(capsys)
    assert target.read_text() == "precious"


def test_a_manifest_naming_a_file_through_a_symbolic_link_is_refused(
    tmp_path: Path, victim: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    scene, out = drop_scene(tmp_path), tmp_path / "out"
    assert run_moreau(scene, out) == 0
    (out / "sub").symlink_to(victim, target_is_directory=True)
    info = {"sha256": sha256(victim / "x"), "bytes": 8}
    manifest = out / ".csfh" / "run.Moreau.json"
    edit_json(manifest, lambda m: m["files"].__setitem__("sub/x", info))
    capsys.readouterr()
    assert run_moreau(scene, out) == 2
    line = one_error(capsys)
    assert str(manifest) in line and "symbolic link" in line
    assert (victim / "x").read_text() == "precious"


def test_a_state_directory_that_is_a_symbolic_link_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    out = tmp_path / "out"
    out.mkdir()
    (out / ".csfh").symlink_to(elsewhere, target_is_directory=True)
    assert run_moreau(drop_scene(tmp_path), out) == 2
    line = one_error(capsys)
    assert str(out / ".csfh") in line and "symbolic link" in line
    assert list(elsewhere.iterdir()) == []


def _files(m: dict[str, Any]) -> dict[str, Any]:
    return m["files"]  # type: ignore[no-any-return]


def _first(m: dict[str, Any]) -> dict[str, Any]:
    return next(iter(_files(m).values()))  # type: ignore[no-any-return]


@pytest.mark.parametrize(
    "damage",
    [
        lambda m: _first(m).__setitem__("sha256", "not a hash"),
        lambda m: _first(m).__setitem__("sha256", "A" * 64),
        lambda m: _first(m).__setitem__("bytes", -1),
        lambda m: _first(m).__setitem__("bytes", True),
        lambda m: _first(m).pop("bytes"),
        lambda m: _files(m).__setitem__("a/../../b", _first(m)),
        lambda m: _files(m).__setitem__(".csfh/run.Moreau.json", _first(m)),
        lambda m: _files(m).__setitem__("a\nb", _first(m)),
        lambda m: m.__setitem__("files", ["Moreau.csv"]),
        lambda m: m.__setitem__("set", "compare"),
        lambda m: m.__setitem__("format", 99),
    ],
    ids=[
        "sha-text",
        "sha-upper",
        "bytes-negative",
        "bytes-bool",
        "bytes-missing",
        "dotdot-inside",
        "state-dir",
        "newline",
        "files-list",
        "other-set",
        "format",
    ],
)
def test_a_manifest_that_breaks_the_schema_is_refused_naming_it(
    tmp_path: Path, damage: Callable[[dict[str, Any]], None]
) -> None:
    out = tmp_path / "out"
    assert run_moreau(drop_scene(tmp_path), out) == 0
    manifest = out / ".csfh" / "run.Moreau.json"
    edit_json(manifest, damage)
    with pytest.raises(ValueError, match=re.escape(str(manifest))):
        output.read_manifest(out, "run.Moreau")
    manifest.write_bytes(b"\x00 not json")
    with pytest.raises(ValueError, match=re.escape(str(manifest))):
        output.read_manifest(out, "run.Moreau")


# ------------------------------------------------------------------------------------------
# commit journals


@pytest.fixture(scope="module")
def comparison(tmp_path_factory: pytest.TempPathFactory) -> dict[str, bytes]:
    """A comparison's folder (Moreau alone, 0.05 s), as files."""
    out = tmp_path_factory.mktemp("comparison")
    scene = scene_from_dict({"name": "s", "stop_time": 0.05, "initial": {"q": [0.0, 0.01, 0.0]}})
    compare(scene, out, models=("Moreau",))
    return snapshot(out)


def folder(comparison: dict[str, bytes], out: Path) -> Path:
    for rel, data in comparison.items():
        (out / rel).parent.mkdir(parents=True, exist_ok=True)
        (out / rel).write_bytes(data)
    return out


@pytest.mark.parametrize("where", ["relative", "absolute"])
def test_a_commit_journal_naming_files_outside_the_folder_touches_nothing(
    comparison: dict[str, bytes],
    tmp_path: Path,
    victim: Path,
    where: str,
    capsys: pytest.CaptureFixture[str],
) -> None:
    out = folder(comparison, tmp_path / "out")
    state = out / ".csfh"
    staged = state / "staging" / "victim" / "bashrc"  # where '../victim/bashrc' is staged
    staged.parent.mkdir(parents=True)
    staged.write_text("evil")
    other = victim / "other"
    rel = "../victim/{}" if where == "relative" else str(victim / "{}")
    journal = {
        "set": "compare",
        "stage": [rel.format("bashrc")],
        "remove": {rel.format("other"): sha256(other)},
        "manifest": json.loads((state / "compare.json").read_text()),
    }
    (state / "compare.commit.json").write_text(json.dumps(journal))
    before = snapshot(victim)
    assert main(["plot", str(out)]) == 2
    assert str(state / "compare.commit.json") in one_error(capsys)
    assert snapshot(victim) == before


@pytest.mark.parametrize(
    "damage",
    [
        lambda j: j.__setitem__("stage", "summary.json"),
        lambda j: j.__setitem__("stage", [1]),
        lambda j: j.__setitem__("remove", {"summary.json": "0" * 63}),
        lambda j: j.__setitem__("remove", ["summary.json"]),
        lambda j: j.__setitem__("set", "sweep"),
        lambda j: j.pop("manifest"),
        lambda j: j["manifest"]["files"].__setitem__("../x", {"sha256": "0" * 64, "bytes": 1}),
    ],
    ids=[
        "stage-text",
        "stage-number",
        "remove-short-hash",
        "remove-list",
        "set",
        "no-manifest",
        "manifest-outside",
    ],
)
def test_a_commit_journal_that_breaks_the_schema_is_refused(
    comparison: dict[str, bytes],
    tmp_path: Path,
    damage: Callable[[dict[str, Any]], None],
    capsys: pytest.CaptureFixture[str],
) -> None:
    out = folder(comparison, tmp_path / "out")
    state = out / ".csfh"
    journal = {
        "set": "compare",
        "stage": [],
        "remove": {},
        "manifest": json.loads((state / "compare.json").read_text()),
    }
    damage(journal)
    (state / "compare.commit.json").write_text(json.dumps(journal))
    before = snapshot(out)
    assert main(["plot", str(out)]) == 2
    assert str(state / "compare.commit.json") in one_error(capsys)
    assert snapshot(out) == before


# ------------------------------------------------------------------------------------------
# special files where a result goes


def _fifo(path: Path) -> None:
    os.mkfifo(path)


def _directory(path: Path) -> None:
    path.mkdir()


def _link(path: Path) -> None:
    path.symlink_to(path.parent.parent / "victim" / "x")


def _device(path: Path) -> None:
    if os.geteuid() != 0:
        pytest.skip("a device node needs root")
    os.mknod(path, stat.S_IFCHR | 0o666, os.makedev(1, 3))  # /dev/null's numbers, in tmp_path


SPECIAL = {"fifo": _fifo, "directory": _directory, "symlink": _link, "device": _device}


def kind_of(path: Path) -> int:
    return stat.S_IFMT(os.lstat(path).st_mode)


@pytest.mark.parametrize("special", SPECIAL)
def test_a_special_file_where_a_result_goes_is_refused(
    tmp_path: Path, victim: Path, special: str, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "out"
    out.mkdir()
    target = out / "Moreau.csv"
    SPECIAL[special](target)
    mode = kind_of(target)
    assert run_moreau(drop_scene(tmp_path), out) == 2
    line = one_error(capsys)
    assert str(target) in line and "not a regular file" in line
    assert kind_of(target) == mode
    assert (victim / "x").read_text() == "precious"
    assert not (out / ".csfh" / "run.Moreau.json").exists()


def test_a_set_with_one_special_target_replaces_none_of_its_files(
    comparison: dict[str, bytes], tmp_path: Path
) -> None:
    out = folder(comparison, tmp_path / "out")
    (out / "summary.json").unlink()
    os.mkfifo(out / "summary.json")
    before = snapshot(out)
    scene = scene_from_dict({"name": "s", "stop_time": 0.06, "initial": {"q": [0.0, 0.01, 0.0]}})
    with pytest.raises(ValueError, match=r"summary\.json"):
        compare(scene, out, models=("Moreau",))
    assert snapshot(out) == before
    assert stat.S_ISFIFO(os.lstat(out / "summary.json").st_mode)


@pytest.mark.parametrize("special", ["fifo", "device"])
def test_a_special_file_as_the_ssp_archive_is_refused_before_computing(
    tmp_path: Path,
    victim: Path,
    special: str,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    (tmp_path / "out").mkdir()
    target = tmp_path / "out" / "system.ssp"
    SPECIAL[special](target)

    def computed(*args: object, **kwargs: object) -> bytes:
        raise AssertionError("the archive was computed before its path was checked")

    monkeypatch.setattr(ssp, "ssp_bytes", computed)
    assert main(["cosim", "combdrive", "--export-ssp", str(target)]) == 2
    line = one_error(capsys)
    assert str(target) in line and "not a regular file" in line
    assert stat.S_ISFIFO(os.lstat(target).st_mode) or stat.S_ISCHR(os.lstat(target).st_mode)
