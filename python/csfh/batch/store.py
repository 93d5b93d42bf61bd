"""The result store of batched runs: per-task results in a directory, appended as they complete,
so that an interrupted command resumes where it stopped.

Layout (DIR): tasks.jsonl, one line per finished task {"format", "key", "model", "parameters",
"summary", "signals", "signals_sha256", ..., "record_sha256"}; signals/KEY.npz with the output
signals on the grid (sweeps only). A signals file is written whole (temporary name, fsync,
rename) before the line that names it is appended (and fsync'ed), so an interrupted run leaves a
consistent store.

Reading never loses a good record, and trusts none: every line is checked on its own. A line
that is torn (an interrupted write), not JSON, not a record of this format (`_check_record`: the
types of its fields, the summary's keys and numbers), whose checksum (record_sha256, the SHA-256
of the record's canonical JSON without it) differs, or whose signals file is missing, not a
regular file, damaged (its SHA-256 differs) or not where a store puts it, is skipped and
reported (`ResultStore.problems`), and its run is computed again; every other record is kept. A
record without a checksum (an older csfh's) is computed again the same way. The store's own
files are never rewritten in place: the skipped lines are moved, byte for byte, to
tasks.rejected.jsonl (appended), and tasks.jsonl is replaced by its good lines in one atomic
rename. Writers take a lock (tasks.lock), so that two commands on one directory do not mix their
lines. The store's files must be regular files and signals/ a real directory (else ResultsError,
csfh.safepath); temporary files of killed processes are removed when the store is opened.

Claims (claims/PID-TOKEN.json): a command that computes runs claims the ones no other live
command has claimed (`ResultStore.claimed`, under the lock) and holds an exclusive lock on its
claim file while it computes them, so that a second command on the same directory computes only
the rest and waits for the claimed runs (`ResultStore.refresh` reads what the other appends).
The lock ends with its process, even a killed one: a claim whose lock can be taken is stale and
removed, and its runs are claimed again."""

from __future__ import annotations

import hashlib
import io
import json
import math
import os
import re
import secrets
import zipfile
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import Any, cast

import numpy as np

from ..errors import ResultsError, file_errors
from ..output import locked, replace_file
from ..safepath import (
    is_regular,
    is_sha256,
    open_regular,
    own_directory,
    read_regular,
    remove_stale_temporaries,
    shown,
)
from .tasks import KEY_DIGITS, SUMMARY_KEYS, Task

INDEX = "tasks.jsonl"
REJECTED = "tasks.rejected.jsonl"
LOCK = "tasks.lock"
SIGNALS = "signals"
CLAIMS = "claims"
_CLAIM = re.compile(r"^[0-9]{1,10}-[0-9a-f]{8}\.json$")
FORMAT = 2
"""The format of a record (2: with its checksum, record_sha256)."""
_KEY = re.compile(f"^[0-9a-f]{{{KEY_DIGITS}}}$")
_FIELDS: dict[str, tuple[type, ...]] = {
    "model": (str,),
    "parameters": (dict,),
    "stop_time": (int, float),
    "meta": (dict,),
    "wall_time": (int, float),
    "signals": (str, type(None)),
    "signals_sha256": (str, type(None)),
}
"""The types of a record's fields besides format, key, summary and record_sha256."""


def _sha256_file(path: Path) -> str:
    h = hashlib.sha256()
    with os.fdopen(open_regular(path, os.O_RDONLY), "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def record_sha256(rec: dict[str, Any]) -> str:
    """The checksum of a record: the SHA-256 of its canonical JSON (sorted keys, no spaces),
    without the checksum itself. JSON gives every number back exactly, so a record read back
    has the checksum it was written with."""
    body = {k: v for k, v in rec.items() if k != "record_sha256"}
    text = json.dumps(body, sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


_PLAIN = (str, int, float, bool, type(None))


class _NotPlain(Exception):
    """A value that JSON does not read back as itself."""


def _plain_copy(value: Any) -> Any:
    """A copy of value made of dicts with text keys, lists and plain scalars (raises _NotPlain
    for anything else)."""
    kind = type(value)
    if kind is dict:
        if not all(type(k) is str for k in value):
            raise _NotPlain
        return {k: _plain_copy(v) for k, v in value.items()}
    if kind is list:
        return [_plain_copy(v) for v in value]
    if kind in _PLAIN:
        return value
    if isinstance(value, float):  # e.g. numpy's float64: JSON writes it as the float it is
        return float(value)
    raise _NotPlain


def as_read_back(rec: dict[str, Any]) -> dict[str, Any]:
    """A record as it reads back from the index, json.loads(json.dumps(rec)) (tuples become
    lists, number types plain numbers, keys text): for a record that is plain JSON already
    (the common case) a copy, without the text."""
    try:
        return cast(dict[str, Any], _plain_copy(rec))
    except _NotPlain:
        return cast(dict[str, Any], json.loads(json.dumps(rec)))


def _is_number(value: object) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool)


def check_summary(summary: object) -> str:
    """Why `summary` is not a task summary (csfh.batch.tasks.SUMMARY_KEYS, every value a
    number or null), or ""."""
    if not isinstance(summary, dict):
        return f"summary = {shown(summary)} is not a table"
    for key in SUMMARY_KEYS:
        if key not in summary:
            return f"summary has no {key}"
    for key, value in summary.items():
        if not isinstance(key, str) or not (value is None or _is_number(value)):
            return f"summary.{key} = {shown(value)} is not a number"
    return ""


def _check_fields(rec: dict[str, Any]) -> str:
    """Why the fields of a record besides its key and summary are not of their types, or ""."""
    for name, types in _FIELDS.items():
        if not isinstance(rec.get(name), types) or isinstance(rec.get(name), bool):
            return f"{name} = {shown(rec.get(name))} is not a {types[0].__name__}"
    if not all(isinstance(v, str | int | float) for v in rec["parameters"].values()):
        return "a parameter value is not a number, a Boolean or a text"
    if not all(math.isfinite(rec[k]) and rec[k] >= 0 for k in ("stop_time", "wall_time")):
        return "stop_time or wall_time is not a finite number >= 0"
    return ""


def _check_signals(rec: dict[str, Any]) -> str:
    """Why the signals file a record names is not where this store puts it, or ""."""
    rel, expected = rec["signals"], f"{SIGNALS}/{rec['key']}.npz"
    if rel is not None and rel != expected:
        return f"signals = {rel!r} is not this store's {expected}"
    if rel is not None and not is_sha256(rec["signals_sha256"]):
        return f"signals_sha256 = {shown(rec['signals_sha256'])} is not a SHA-256"
    return ""


def _check_checksum(rec: dict[str, Any]) -> str:
    """Why a record's checksum does not vouch for its contents, or ""."""
    if rec.get("format") != FORMAT or not is_sha256(rec.get("record_sha256")):
        return "no checksum (written by an older csfh): not trusted"
    if record_sha256(rec) != rec["record_sha256"]:
        return "damaged (its checksum differs from the record's contents)"
    return ""


def _check_record(rec: dict[str, Any]) -> str:
    """Why a parsed line is not a record of this store's format, or ""."""
    key = rec.get("key")
    if not isinstance(key, str) or not _KEY.match(key):
        return f"not a record (no key of {KEY_DIGITS} hexadecimal digits)"
    why = check_summary(rec.get("summary"))
    for check in (_check_fields, _check_signals, _check_checksum):
        why = why or check(rec)
    return why


class ResultStore:
    """Per-task results in a directory, appended as they complete (see the module docstring).
    `problems` lists the records skipped when the store was opened, one line each."""

    def __init__(self, directory: Path) -> None:
        self.directory = Path(directory)
        self.index = self.directory / INDEX
        self.records: dict[str, dict[str, Any]] = {}
        self.problems: list[str] = []
        self._read_to = (0, 0)  # (inode, offset) of the index read so far
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
        except (ValueError, RecursionError):
            return None, "not JSON"
        if not isinstance(rec, dict):
            return None, "not a record"
        why = _check_record(rec)
        if why or rec["signals"] is None:
            return (None, why) if why else (rec, "")
        path = self.directory / rec["signals"]
        if not os.path.lexists(path):
            return None, f"{rec['signals']} is missing"
        if not is_regular(path):
            return None, f"{rec['signals']} is not a regular file"
        if _sha256_file(path) != rec["signals_sha256"]:
            return None, f"{rec['signals']} is damaged (its SHA-256 differs from the record's)"
        return rec, ""

    def _load(self) -> None:
        own_directory(self.directory / SIGNALS, create=False)
        with locked(self.directory / LOCK):
            remove_stale_temporaries(self.directory, {INDEX, REJECTED})
            remove_stale_temporaries(self.directory / SIGNALS)
            if not os.path.lexists(self.index):
                return
            lines = read_regular(self.index).splitlines(keepends=True)
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
            st = os.stat(self.index)  # after a set-aside, the index of the good lines
            self._read_to = (st.st_ino, st.st_size)

    def _set_aside(self, good: list[bytes], bad: list[tuple[int, bytes, str]]) -> None:
        """Move the skipped lines to tasks.rejected.jsonl (appended, byte for byte) and replace
        tasks.jsonl by its good lines atomically; report each."""
        rejected = self.directory / REJECTED
        try:
            fd = open_regular(rejected, os.O_WRONLY | os.O_CREAT | os.O_APPEND)
            with os.fdopen(fd, "ab") as fh:
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

    def refresh(self) -> set[str]:
        """Read the records that other commands appended since this store was opened or last
        refreshed, each checked like the others (a bad one is left for the next opener to
        report); the keys of the new ones."""
        with locked(self.directory / LOCK):
            if not os.path.lexists(self.index):
                return set()
            fd = open_regular(self.index, os.O_RDONLY)
            try:
                st = os.fstat(fd)
                inode, offset = self._read_to
                start = offset if st.st_ino == inode and st.st_size >= offset else 0
                data = os.pread(fd, st.st_size - start, start)
            finally:
                os.close(fd)
            self._read_to = (st.st_ino, start + len(data))
        new: set[str] = set()
        for line in data.splitlines(keepends=True):
            try:
                key = json.loads(line).get("key")
            except (ValueError, RecursionError, AttributeError):
                continue
            rec = None if key in self.records else self._check(line, last=False)[0]
            if rec is not None:
                self.records[rec["key"]] = rec
                new.add(rec["key"])
        return new

    @contextmanager
    def claimed(self, keys: Sequence[str]) -> Iterator[set[str]]:
        """Claim, for the block, those of `keys` that no other live command has claimed (module
        docstring), and yield them: the others are another command's to compute (wait for them
        with `refresh`). Without POSIX file locks every key is yielded."""
        try:
            import fcntl
        except ImportError:  # pragma: no cover - not POSIX
            yield set(keys)
            return
        claims = own_directory(self.directory / CLAIMS)
        path = claims / f"{os.getpid()}-{secrets.token_hex(4)}.json"
        with locked(self.directory / LOCK):
            taken = _claimed_by_others(claims)
            mine = [k for k in keys if k not in taken]
            fd = open_regular(path, os.O_RDWR | os.O_CREAT | os.O_EXCL) if mine else -1
            if mine:
                fcntl.flock(fd, fcntl.LOCK_EX)  # held while this process lives
                os.write(fd, json.dumps({"pid": os.getpid(), "keys": mine}).encode())
        try:
            yield set(mine)
        finally:
            if mine:
                path.unlink(missing_ok=True)
                os.close(fd)

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
            why = check_summary(summary)
            if why:
                raise ValueError(f"task {task.key}: {why}")
            rel, digest = None, None
            if signals is not None:
                rel = f"{SIGNALS}/{task.key}.npz"
                buffer = io.BytesIO()
                np.savez_compressed(buffer, **cast(dict[str, Any], signals))
                payload = buffer.getvalue()
                digest = hashlib.sha256(payload).hexdigest()
                with file_errors(self.directory / rel):
                    own_directory(self.directory / SIGNALS)
                    replace_file(self.directory / rel, payload)
            rec: dict[str, Any] = {
                "format": FORMAT,
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
            rec = as_read_back(rec)
            rec["record_sha256"] = record_sha256(rec)
            lines.append(json.dumps(rec, sort_keys=True) + "\n")
            records.append(rec)
        if lines:
            with file_errors(self.index):
                self._append("".join(lines).encode("utf-8"))
        for rec in records:
            self.records[rec["key"]] = rec

    def _append(self, text: bytes) -> None:
        """Append whole lines to the index under the lock, fsync'ed; after a torn line of
        someone else's, on a line of their own."""
        with locked(self.directory / LOCK):
            fd = open_regular(self.index, os.O_RDWR | os.O_CREAT | os.O_APPEND)
            try:
                size = os.fstat(fd).st_size
                if size > 0 and os.pread(fd, 1, size - 1) != b"\n":
                    text = b"\n" + text
                view = memoryview(text)
                while view:
                    view = view[os.write(fd, view) :]
                os.fsync(fd)
            finally:
                os.close(fd)

    # -- results ------------------------------------------------------------------------------

    def summary(self, key: str) -> dict[str, Any]:
        return self.records[key]["summary"]

    def signals(self, key: str) -> dict[str, np.ndarray]:
        rel = self.records[key]["signals"]
        if rel is None:
            raise KeyError(f"task {key} has no signals")
        path = self.directory / rel
        try:
            with os.fdopen(open_regular(path, os.O_RDONLY), "rb") as fh, np.load(fh) as data:
                return {name: data[name] for name in data.files}
        except ResultsError:
            raise
        except (OSError, ValueError, zipfile.BadZipFile) as exc:
            raise ResultsError(f"{path}: cannot be read ({exc}); run the command again") from None


def _claimed_by_others(claims: Path) -> set[str]:
    """The keys in the claims of other live commands (call with the store's lock held); a claim
    whose command has ended (its lock is free) is removed, one that is not a claim ignored."""
    import fcntl

    taken: set[str] = set()
    for entry in sorted(os.listdir(claims)):
        path = claims / entry
        if not _CLAIM.match(entry) or not is_regular(path):
            continue
        fd = open_regular(path, os.O_RDONLY)
        try:
            try:
                fcntl.flock(fd, fcntl.LOCK_SH | fcntl.LOCK_NB)
            except BlockingIOError:  # its command runs
                taken |= _claim_keys(os.pread(fd, 1 << 26, 0))
                continue
            path.unlink(missing_ok=True)
        finally:
            os.close(fd)
    return taken


def _claim_keys(data: bytes) -> set[str]:
    """The keys of a claim file's contents (none if it is not one)."""
    try:
        keys = json.loads(data).get("keys")
    except (ValueError, RecursionError, AttributeError):
        return set()
    if not isinstance(keys, list):
        return set()
    return {k for k in keys if isinstance(k, str) and _KEY.match(k)}
