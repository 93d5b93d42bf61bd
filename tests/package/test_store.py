"""The result store of sweeps and tolerance studies (csfh.batch.store): one bad record (a missing,
damaged or misplaced signals file, a damaged or torn line) is skipped and reported, every other
record is kept, its run alone is computed again, and the skipped lines are set aside byte for
byte, never lost."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
from csfh_command import run_csfh

from csfh.batch.executors import run_tasks
from csfh.batch.store import ResultStore, as_read_back
from csfh.batch.tasks import Task
from csfh.cli.main import main
from csfh.model.scene import load_scene

N = 12


@pytest.fixture(scope="module")
def tasks() -> list[Task]:
    """Twelve short Moreau runs with signals (cheap: one batch in the C core)."""
    scene = load_scene("central")
    return [
        Task(
            scene=scene,
            model="Moreau",
            parameters=(("body1.m", 9.0 + 0.1 * k),),
            stop_time=0.05,
            output_interval=1e-3,
        )
        for k in range(N)
    ]


@pytest.fixture(scope="module")
def full(tasks: list[Task], tmp_path_factory: pytest.TempPathFactory) -> dict[str, bytes]:
    """A complete store, as files."""
    out = tmp_path_factory.mktemp("store")
    report = run_tasks(tasks, ResultStore(out), workers=1, quiet=True, batch=1)
    assert report.computed == N
    return {p.relative_to(out).as_posix(): p.read_bytes() for p in out.rglob("*") if p.is_file()}


def restore(full: dict[str, bytes], out: Path) -> Path:
    for rel, data in full.items():
        (out / rel).parent.mkdir(parents=True, exist_ok=True)
        (out / rel).write_bytes(data)
    return out


def index_lines(out: Path) -> list[bytes]:
    return (out / "tasks.jsonl").read_bytes().splitlines(keepends=True)


def key_of(line: bytes) -> str:
    return str(json.loads(line)["key"])


def check_kept_all_but(store: ResultStore, tasks: list[Task], lost: set[str]) -> None:
    """Every record but `lost` is there with its summary and readable signals."""
    assert set(store.records) == {t.key for t in tasks} - lost
    for key in store.records:
        sig = store.signals(key)
        assert set(sig) == {"x", "y", "theta", "F_N", "F_T"} and len(sig["y"]) == 51


def recompute(tasks: list[Task], out: Path, expected: int) -> None:
    report = run_tasks(tasks, ResultStore(out), workers=1, quiet=True)
    assert (report.computed, report.reused) == (expected, N - expected)
    again = ResultStore(out)
    assert again.problems == [] and len(again) == N


def test_a_missing_signals_file_costs_one_run_only(
    tasks: list[Task], full: dict[str, bytes], tmp_path: Path
) -> None:
    out = restore(full, tmp_path)
    lines = index_lines(out)
    victim = key_of(lines[2])
    (out / "signals" / f"{victim}.npz").unlink()
    store = ResultStore(out)
    check_kept_all_but(store, tasks, {victim})
    assert len(store.problems) == 1
    assert "line 3" in store.problems[0] and f"signals/{victim}.npz is missing" in store.problems[0]
    # set aside byte for byte; the index holds every other line, in order
    assert (out / "tasks.rejected.jsonl").read_bytes() == lines[2]
    assert index_lines(out) == lines[:2] + lines[3:]
    recompute(tasks, out, 1)


@pytest.mark.parametrize(
    ("damage", "why"),
    [
        (lambda line: b"}{ not json\n", "not JSON"),
        (lambda line: line[: len(line) // 2] + b"\n", "not JSON"),
        (lambda line: b"[1, 2, 3]\n", "not a record"),
        (lambda line: b'{"summary": {}}\n', "no key"),
        (lambda line: line.replace(b'"signals/', b'"../../signals/'), "is not this store's"),
    ],
    ids=["garbage", "cut", "list", "no-key", "path-outside"],
)
def test_a_damaged_line_costs_one_run_only(
    tasks: list[Task], full: dict[str, bytes], tmp_path: Path, damage: object, why: str
) -> None:
    out = restore(full, tmp_path)
    lines = index_lines(out)
    bad = damage(lines[4])  # type: ignore[operator]
    (out / "tasks.jsonl").write_bytes(b"".join([*lines[:4], bad, *lines[5:]]))
    store = ResultStore(out)
    check_kept_all_but(store, tasks, {key_of(lines[4])})
    assert len(store.problems) == 1 and "line 5" in store.problems[0] and why in store.problems[0]
    assert (out / "tasks.rejected.jsonl").read_bytes() == bad
    recompute(tasks, out, 1)


def test_a_damaged_signals_file_is_found_by_its_hash(
    tasks: list[Task], full: dict[str, bytes], tmp_path: Path
) -> None:
    out = restore(full, tmp_path)
    lines = index_lines(out)
    victims = [key_of(lines[1]), key_of(lines[7])]
    path = out / "signals" / f"{victims[0]}.npz"
    path.write_bytes(path.read_bytes()[:-10])  # cut short
    data = bytearray((out / "signals" / f"{victims[1]}.npz").read_bytes())
    data[len(data) // 2] ^= 0xFF  # one flipped byte inside
    (out / "signals" / f"{victims[1]}.npz").write_bytes(bytes(data))
    store = ResultStore(out)
    check_kept_all_but(store, tasks, set(victims))
    assert len(store.problems) == 2 and all("damaged" in p for p in store.problems)
    recompute(tasks, out, 2)


def test_a_torn_last_line_and_a_later_append_stay_apart(
    tasks: list[Task], full: dict[str, bytes], tmp_path: Path
) -> None:
    out = restore(full, tmp_path)
    lines = index_lines(out)
    victim = key_of(lines[-1])
    (out / "tasks.jsonl").write_bytes(b"".join(lines[:-1]) + lines[-1][:40])
    store = ResultStore(out)
    check_kept_all_but(store, tasks, {victim})
    assert "incomplete (an interrupted write)" in store.problems[0]
    recompute(tasks, out, 1)
    # another writer's torn line after this store was opened: an append starts its own line
    store = ResultStore(out)
    with open(out / "tasks.jsonl", "ab") as fh:
        fh.write(b'{"key": "torn')
    task = Task(scene=tasks[0].scene, model="Moreau", stop_time=0.05, output_interval=1e-3)
    summary = {"first_contact": None, "contacts": 0, "peak_F_N": 0.0, "peak_abs_F_T": 0.0}
    store.add(task, {**summary, "steps": 500}, {"y": np.zeros(3)})
    last = index_lines(out)[-2:]
    assert last[0] == b'{"key": "torn\n' and key_of(last[1]) == task.key
    assert task.key in ResultStore(out)


def test_the_sweep_command_reports_the_skipped_records_and_recomputes_only_them(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A sweep that lost one signals file and has one damaged line keeps all its other records
    and computes exactly those two again."""
    args = ["sweep", "central", "--models", "Moreau", "LN_cylinders", "--params", "R1", "m1"]
    args += ["--stop-time", "0.1", "--quiet", "--workers", "1", "--out", str(tmp_path)]
    assert main(args) == 0
    first = capsys.readouterr().out
    total = int(first.split("sweep: ")[1].split(" runs")[0])
    lines = index_lines(tmp_path)
    assert len(lines) == total >= 8
    (tmp_path / "signals" / f"{key_of(lines[1])}.npz").unlink()
    (tmp_path / "tasks.jsonl").write_bytes(b"".join([*lines[:3], b"#%!\n", *lines[4:]]))
    assert main(args) == 0
    captured = capsys.readouterr()
    warnings = captured.err.strip().splitlines()
    assert len(warnings) == 2 and all(w.startswith("csfh: warning: ") for w in warnings)
    assert "line 2" in warnings[0] and "missing" in warnings[0]
    assert "line 4" in warnings[1] and "not JSON" in warnings[1]
    assert f"sweep: {total} runs (2 computed, {total - 2} reused" in captured.out


# ------------------------------------------------------------------------------------------
# record contents are checked (schema and checksum), never trusted


def _summary_of(line: bytes) -> dict[str, object]:
    return dict(json.loads(line)["summary"])


def _with_summary(line: bytes, change: Callable[[dict[str, object]], None]) -> bytes:
    rec = json.loads(line)
    change(rec["summary"])
    return (json.dumps(rec, sort_keys=True) + "\n").encode()


@pytest.mark.parametrize(
    ("change", "why"),
    [
        (lambda s: s.__setitem__("peak_F_N", float(s["peak_F_N"]) + 1.0), "checksum"),  # type: ignore[arg-type]
        (lambda s: s.__setitem__("steps", int(s["steps"]) + 1), "checksum"),  # type: ignore[call-overload]
        (lambda s: s.__setitem__("peak_F_N", "garbage"), "peak_F_N"),
        (lambda s: s.__setitem__("contacts", True), "contacts"),
        (lambda s: s.__setitem__("first_contact", [0.1]), "first_contact"),
        (lambda s: s.pop("steps"), "steps"),
    ],
    ids=["number", "count", "text", "bool", "list", "missing"],
)
def test_a_damaged_summary_is_not_reused(
    tasks: list[Task], full: dict[str, bytes], tmp_path: Path, change: object, why: str
) -> None:
    out = restore(full, tmp_path)
    lines = index_lines(out)
    good = _summary_of(lines[3])
    bad = _with_summary(lines[3], change)  # type: ignore[arg-type]
    (out / "tasks.jsonl").write_bytes(b"".join([*lines[:3], bad, *lines[4:]]))
    store = ResultStore(out)
    check_kept_all_but(store, tasks, {key_of(lines[3])})
    assert len(store.problems) == 1 and "line 4" in store.problems[0] and why in store.problems[0]
    recompute(tasks, out, 1)
    assert ResultStore(out).summary(key_of(lines[3])) == good


def test_a_record_without_a_checksum_is_computed_again(
    tasks: list[Task], full: dict[str, bytes], tmp_path: Path
) -> None:
    """A record as a store without checksums wrote it (no format, no record_sha256) is not
    trusted: its run is computed again."""
    out = restore(full, tmp_path)
    lines = index_lines(out)
    rec = json.loads(lines[0])
    old = {k: v for k, v in rec.items() if k not in ("format", "record_sha256")}
    (out / "tasks.jsonl").write_bytes(b"".join([json.dumps(old).encode() + b"\n", *lines[1:]]))
    store = ResultStore(out)
    check_kept_all_but(store, tasks, {rec["key"]})
    assert len(store.problems) == 1 and "checksum" in store.problems[0]
    recompute(tasks, out, 1)


def _tolerance(out: Path) -> list[str]:
    return ["tolerance", "central", "--runs", "3", "--models", "Moreau", "LN_cylinders",
            "--stop-time", "0.05", "--workers", "1", "--quiet", "--out", str(out)]  # fmt: skip


def test_the_tolerance_command_recomputes_a_damaged_summary_naming_the_file(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(_tolerance(tmp_path)) == 0
    first = (tmp_path / "tolerance.json").read_bytes()
    lines = index_lines(tmp_path)
    bad = _with_summary(lines[2], lambda s: s.__setitem__("first_contact", "garbage"))
    (tmp_path / "tasks.jsonl").write_bytes(b"".join([*lines[:2], bad, *lines[3:]]))
    capsys.readouterr()
    assert main(_tolerance(tmp_path)) == 0
    captured = capsys.readouterr()
    warning = captured.err.strip().splitlines()
    assert len(warning) == 1 and str(tmp_path / "tasks.jsonl") in warning[0], warning
    assert "line 3" in warning[0] and "first_contact" in warning[0]
    assert "(1 computed, 7 reused" in captured.out
    again = json.loads((tmp_path / "tolerance.json").read_bytes())
    before = json.loads(first)
    again.pop("run"), before.pop("run")
    assert again == before


def test_the_sweep_report_never_holds_a_damaged_summary(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    args = ["sweep", "central", "--models", "Moreau", "--params", "R1", "--stop-time", "0.05"]
    args += ["--quiet", "--workers", "1", "--out", str(tmp_path)]
    assert main(args) == 0
    lines = index_lines(tmp_path)
    bad = [_with_summary(line, lambda s: s.__setitem__("peak_F_N", "garbage")) for line in lines]
    (tmp_path / "tasks.jsonl").write_bytes(b"".join(bad))
    assert main(args) == 0
    assert "garbage" not in (tmp_path / "sweep.json").read_text()
    assert f"({len(lines)} computed, 0 reused" in capsys.readouterr().out


# ------------------------------------------------------------------------------------------
# the store's own files: regular files in real directories; temporaries of killed processes


def _dead_pid() -> int:
    proc = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True, check=True)  # fmt: skip
    return int(proc.stdout)


def test_temporary_files_of_killed_processes_are_removed(
    tasks: list[Task], full: dict[str, bytes], tmp_path: Path
) -> None:
    out = restore(full, tmp_path)
    dead, alive = _dead_pid(), os.getpid()
    key = key_of(index_lines(out)[0])
    stale = [out / "signals" / f".{key}.npz.{dead}.140234.tmp", out / f".tasks.jsonl.{dead}.1.tmp"]
    kept = [out / "signals" / f".{key}.npz.{alive}.140234.tmp", out / f".notes.txt.{dead}.1.tmp"]
    for path in stale + kept:
        path.write_bytes(b"PK\x03\x04 half an archive")
    store = ResultStore(out)
    assert store.problems == [] and len(store) == N
    assert [p.exists() for p in stale + kept] == [False, False, True, True]


@pytest.mark.parametrize("what", ["index-fifo", "index-link", "signals-link", "npz-link"])
def test_special_files_in_a_store_are_refused_or_skipped(
    tasks: list[Task], full: dict[str, bytes], tmp_path: Path, what: str
) -> None:
    out = restore(full, tmp_path / "out")
    victim = tmp_path / "victim"
    victim.mkdir()
    (victim / "x").write_bytes(full["tasks.jsonl"])
    key = key_of(index_lines(out)[0])
    if what == "index-fifo":
        (out / "tasks.jsonl").unlink()
        os.mkfifo(out / "tasks.jsonl")
    elif what == "index-link":
        (out / "tasks.jsonl").unlink()
        (out / "tasks.jsonl").symlink_to(victim / "x")
    elif what == "signals-link":
        (victim / "signals").mkdir()
        shutil.move(str(out / "signals"), str(victim / "signals" / "s"))
        (out / "signals").symlink_to(victim / "signals" / "s", target_is_directory=True)
    else:
        npz = out / "signals" / f"{key}.npz"
        shutil.move(str(npz), str(victim / "k.npz"))
        npz.symlink_to(victim / "k.npz")
    before = {p.name: p.read_bytes() for p in victim.rglob("*") if p.is_file()}
    proc = run_csfh_store(out)
    if what == "npz-link":  # one record skipped and computed again; the link not followed
        assert proc.returncode == 0, proc.stderr
        assert "line 1" in proc.stderr and "not a regular file" in proc.stderr
    else:
        assert proc.returncode == 2, proc.stderr
        err = proc.stderr.strip().splitlines()
        assert len(err) == 1 and "refused" in err[0] and str(out) in err[0], err
    assert {p.name: p.read_bytes() for p in victim.rglob("*") if p.is_file()} == before


def run_csfh_store(out: Path) -> subprocess.CompletedProcess[str]:
    """A tiny sweep into `out`, in a subprocess (a FIFO read in place would never return)."""
    args = ["sweep", "central", "--models", "Moreau", "--params", "R1", "--stop-time", "0.05"]
    return run_csfh(*args, "--quiet", "--workers", "1", "--out", str(out), timeout=60)


def test_refresh_reads_what_another_command_appended(
    tasks: list[Task], full: dict[str, bytes], tmp_path: Path
) -> None:
    out = restore(full, tmp_path)
    lines = index_lines(out)
    (out / "tasks.jsonl").write_bytes(b"".join(lines[:5]))
    mine, theirs = ResultStore(out), ResultStore(out)
    with open(out / "tasks.jsonl", "ab") as fh:  # another command's appends, one of them bad
        fh.write(b"".join([lines[5], b"#%!\n", lines[6]]))
    assert mine.refresh() == {key_of(lines[5]), key_of(lines[6])}
    assert mine.refresh() == set() and len(mine) == 7 and len(theirs) == 5
    check_kept_all_but(mine, tasks, {key_of(line) for line in lines[7:]})


def _types(value: object) -> object:
    """The types of a JSON value, nested as the value."""
    if isinstance(value, dict):
        return {k: _types(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_types(v) for v in value]
    return type(value)


def test_a_record_is_stored_as_it_reads_back() -> None:
    """as_read_back is json.loads(json.dumps(record)): the same text, values, types and key
    order, a copy of the record, for plain records (copied) and others (tuples, numpy floats,
    numbers as keys: through the text)."""
    records: list[dict[str, object]] = [
        {"key": "k", "parameters": {"a": 0.1, "b": True, "c": 3, "d": "x"}, "meta": {}},
        {"summary": {"first": None, "peak": float("nan"), "big": 1e308, "n": -0.0}},
        {"nested": [[1, 2.5], {"z": [None, False]}], "inf": float("inf")},
        {"numpy": np.float64(0.1), "list": [np.float64(1.0) / 3]},
        {"meta": {"pair": (1, 2), "k": {1: "one"}}},
    ]
    for rec in records:
        expected = json.loads(json.dumps(rec))
        got = as_read_back(rec)
        assert json.dumps(got, sort_keys=True) == json.dumps(expected, sort_keys=True)
        assert list(got) == list(expected) and _types(got) == _types(expected)
        assert got is not rec and all(got[k] is not rec[k] for k in rec if isinstance(rec[k], dict))
    with pytest.raises(TypeError):
        as_read_back({"x": np.float32(0.5)})  # not JSON, as json.dumps says
