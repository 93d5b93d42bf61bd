"""The result store of batched runs: per-task results in a directory, appended as they complete,
so that an interrupted command resumes where it stopped.

Layout (DIR): tasks.jsonl, one line per finished task {"key", "model", "parameters", "summary",
"signals", "signals_sha256", ...}; signals/KEY.npz with the output signals on the grid (sweeps
only). A signals file is written whole (temporary name, fsync, rename) before the line that names
it is appended (and fsync'ed), so an interrupted run leaves a consistent store.

Reading never loses a good record. Every line is checked on its own: a line that is torn (an
interrupted write), not JSON, not a record, or whose signals file is missing, damaged (its SHA-256
differs) or not where a store puts it, is skipped and reported (`ResultStore.problems`), and its
run is computed again; every other record is kept. The store's own files are never rewritten in
place: the skipped lines are moved, byte for byte, to tasks.rejected.jsonl (appended), and
tasks.jsonl is replaced by its good lines in one atomic rename. Writers take a lock
(tasks.lock), so that two commands on one directory do not mix their lines."""

from __future__ import annotations

import hashlib
import io
import json
import os
import zipfile
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import Any, cast

import numpy as np

from ..errors import ResultsError, file_errors
from ..output import replace_file
from .tasks import Task

INDEX = "tasks.jsonl"
REJECTED = "tasks.rejected.jsonl"
LOCK = "tasks.lock"


@contextmanager
def _locked(directory: Path) -> Iterator[None]:
    """An exclusive lock on the store (POSIX; elsewhere none)."""
    try:
        import fcntl
    except ImportError:  # pragma: no cover - not POSIX
        yield
        return
    with open(directory / LOCK, "a+b") as fh:
        fcntl.flock(fh.fileno(), fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(fh.fileno(), fcntl.LOCK_UN)


def _sha256_file(path: Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


class ResultStore:
    """Per-task results in a directory, appended as they complete (see the module docstring).
    `problems` lists the records skipped when the store was opened, one line each."""

    def __init__(self, directory: Path) -> None:
        self.directory = Path(directory)
        self.index = self.directory / INDEX
        self.records: dict[str, dict[str, Any]] = {}
        self.problems: list[str] = []
        with file_errors(self.directory, "is not a usable result store"):
            self.directory.mkdir(parents=True, exist_ok=True)
            self._load()

    # -- reading ------------------------------------------------------------------------------

    def _check(self, line: bytes, last: bool) -> tuple[dict[str, Any] | None, str]:
        """The record of one line, or None and why not."""
        if not line.endswith(b"\n"):
            return None, "incomplete (an interrupted write)" if last else "incomplete"
        try:
            rec = json.loads(line)
        except ValueError:
            return None, "not JSON"
        if not isinstance(rec, dict):
            return None, "not a record"
        key = rec.get("key")
        if not isinstance(key, str) or not key or not isinstance(rec.get("summary"), dict):
            return None, "not a record (no key or summary)"
        rel = rec.get("signals")
        if rel is None:
            return rec, ""
        if rel != f"signals/{key}.npz":
            return None, f"signals = {rel!r} is not this store's signals/{key}.npz"
        path = self.directory / rel
        if not path.is_file():
            return None, f"{rel} is missing"
        expected = rec.get("signals_sha256")
        if expected is not None:
            if _sha256_file(path) != expected:
                return None, f"{rel} is damaged (its SHA-256 differs from the record's)"
        else:  # a store written before the hash was recorded: at least a whole zip archive
            try:
                with zipfile.ZipFile(path) as archive:
                    if archive.testzip() is not None:
                        raise zipfile.BadZipFile
            except (zipfile.BadZipFile, OSError):
                return None, f"{rel} is damaged (not a whole .npz archive)"
        return rec, ""

    def _load(self) -> None:
        if not self.index.exists():
            return
        with _locked(self.directory):
            data = self.index.read_bytes()
            lines = data.splitlines(keepends=True)
            good: list[bytes] = []
            bad: list[tuple[int, bytes, str]] = []
            for number, line in enumerate(lines, start=1):
                if not line.strip():
                    continue
                rec, why = self._check(line, last=number == len(lines))
                if rec is None:
                    bad.append((number, line, why))
                    continue
                good.append(line)
                self.records[rec["key"]] = rec
            if bad:
                self._set_aside(good, bad)

    def _set_aside(self, good: list[bytes], bad: list[tuple[int, bytes, str]]) -> None:
        """Move the skipped lines to tasks.rejected.jsonl (appended, byte for byte) and replace
        tasks.jsonl by its good lines atomically; report each."""
        rejected = self.directory / REJECTED
        try:
            with open(rejected, "ab") as fh:
                for _, line, _ in bad:
                    fh.write(line if line.endswith(b"\n") else line + b"\n")
                fh.flush()
                os.fsync(fh.fileno())
            replace_file(self.index, b"".join(good))
            where = f"moved to {REJECTED}"
        except OSError as exc:  # e.g. a read-only directory: skipped all the same
            where = f"left in place ({exc.strerror or exc})"
        for number, _, why in bad:
            self.problems.append(
                f"{self.index} line {number}: {why}: skipped ({where}); its run, if it is "
                "needed, is computed again"
            )

    def __contains__(self, key: str) -> bool:
        return key in self.records

    def __len__(self) -> int:
        return len(self.records)

    # -- writing ------------------------------------------------------------------------------

    def add(
        self,
        task: Task,
        summary: dict[str, Any],
        signals: dict[str, np.ndarray] | None,
        wall_time: float = 0.0,
    ) -> None:
        self.add_many([(task, summary, signals, wall_time)])

    def add_many(
        self,
        results: Sequence[tuple[Task, dict[str, Any], dict[str, np.ndarray] | None, float]],
    ) -> None:
        """Store results: signal files first (each whole, then renamed), then one index line
        each, appended under the lock with one fsync for all."""
        lines: list[str] = []
        records: list[dict[str, Any]] = []
        for task, summary, signals, wall_time in results:
            rel, digest = None, None
            if signals is not None:
                rel = f"signals/{task.key}.npz"
                buffer = io.BytesIO()
                np.savez_compressed(buffer, **cast(dict[str, Any], signals))
                payload = buffer.getvalue()
                digest = hashlib.sha256(payload).hexdigest()
                with file_errors(self.directory / "signals"):
                    (self.directory / "signals").mkdir(exist_ok=True)
                replace_file(self.directory / rel, payload)
            rec: dict[str, Any] = {
                "key": task.key,
                "model": task.model,
                "parameters": dict(task.parameters),
                "stop_time": task.stop_time,
                "meta": dict(task.meta),
                "summary": summary,
                "signals": rel,
                "signals_sha256": digest,
                "wall_time": wall_time,
            }
            lines.append(json.dumps(rec, sort_keys=True) + "\n")
            records.append(rec)
        if not lines:
            return
        text = "".join(lines).encode("utf-8")
        with file_errors(self.index), _locked(self.directory), open(self.index, "a+b") as fh:
            fh.seek(0, os.SEEK_END)
            if fh.tell() > 0:  # after a torn line of someone else's: start a line of our own
                fh.seek(-1, os.SEEK_END)
                if fh.read(1) != b"\n":
                    text = b"\n" + text
            fh.write(text)
            fh.flush()
            os.fsync(fh.fileno())
        for rec in records:
            self.records[rec["key"]] = rec

    # -- results ------------------------------------------------------------------------------

    def summary(self, key: str) -> dict[str, Any]:
        return self.records[key]["summary"]

    def signals(self, key: str) -> dict[str, np.ndarray]:
        rel = self.records[key]["signals"]
        if rel is None:
            raise KeyError(f"task {key} has no signals")
        path = self.directory / rel
        try:
            with np.load(path) as data:
                return {name: data[name] for name in data.files}
        except (OSError, ValueError, zipfile.BadZipFile) as exc:
            raise ResultsError(f"{path}: cannot be read ({exc}); run the command again") from None
