"""Every file that csfh writes goes through this module, and so do the readers of the tables it
writes: text (reports), JSON, CSV tables with the unit of each column in the header, and figures.

All writers end in `_write_bytes`, the one place that decides how a file reaches the disk: never
in place. A file is written whole under a temporary name, fsync'ed, and renamed over its target,
so an interrupted write (Ctrl-C, a crash, a full disk) leaves the previous file as it was.

Output sets: the files of one command's run replace the previous run's files as a whole, never a
mix. A command writes them inside ``with output_set(directory, name):`` (name: the command, e.g.
``compare``); the writers then stage each file in ``DIRECTORY/.csfh/staging/NAME/``, and only
when the block ends without an error are they renamed into place together, with the manifest
``DIRECTORY/.csfh/NAME.json`` that lists them (SHA-256 and size of each). The files of the
previous run of the same set that this run did not write again are removed then, each only if it
is still the file that run wrote (a file that another command or the user has changed since is
left alone); nothing else in the directory is touched, so an output directory can hold other
files. A Ctrl-C while the files are staged leaves the previous run's files whole and discards
the staged ones; the commit itself (renames only) holds a Ctrl-C back until it is done, and is
journalled (``NAME.commit.json``) so that a process killed in the middle of it is completed by
the next command that opens the set. `check_set` tells a reader (``csfh plot``) whether the files
it reads are still one run's. (The result store of batched runs, `csfh.batch.store`, keeps its
own append-only index and writes its signal files with `replace_file`.)

CSV tables: one header line ``name [unit],name [unit],...``, then one row per sample, numbers with
ten significant digits (`read_table` gives the columns back to that precision)."""

from __future__ import annotations

import contextvars
import hashlib
import io
import json
import os
import re
import shutil
import signal
import threading
import time
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np

from .errors import ResultsError, file_errors

RESULTS = Path("results")
"""Where a command writes when it is given no output directory: results/<scene, ...>."""
CSV_DIGITS = 10
"""Significant digits of the numbers in a CSV table."""
_HEADER_FIELD = re.compile(r"^\s*(?P<name>[^\[\]]+?)\s*(?:\[(?P<unit>[^\[\]]*)\])?\s*$")


def results_dir(out: str | Path | None, *default: str) -> Path:
    """The output directory: `out` when given, else results/<default...>."""
    return Path(out) if out else RESULTS.joinpath(*default)


# ------------------------------------------------------------------------------------------
# files, never written in place


def _fsync_directory(directory: Path) -> None:
    """Make a rename in `directory` durable (POSIX; best effort elsewhere)."""
    try:
        fd = os.open(directory, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


def replace_file(path: Path, data: bytes) -> Path:
    """Write `data` to `path` whole or not at all: into a temporary file beside it (a hidden
    name), fsync'ed, then renamed over `path`. On any error or interrupt the temporary file is
    removed and `path` is as it was. A file system error is a ResultsError naming `path`."""
    path = Path(path)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.{threading.get_ident()}.tmp")
    try:
        with file_errors(path), open(tmp, "wb") as fh:
            fh.write(data)
            fh.flush()
            os.fsync(fh.fileno())
        with file_errors(path):
            os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    _fsync_directory(path.parent)
    return path


def _write_bytes(path: Path, data: bytes) -> Path:
    """The one way a file reaches the disk: staged in the open output set that holds `path`,
    else written whole by `replace_file`."""
    path = Path(path)
    active = _set_for(path)
    if active is not None:
        active.stage(path, data)
    else:
        replace_file(path, data)
    return path


# ------------------------------------------------------------------------------------------
# output sets

STATE_DIR = ".csfh"
"""The directory, inside an output directory, of the manifests, journals, locks and staging."""
_SET_NAME = re.compile(r"^[A-Za-z0-9_][A-Za-z0-9_.+-]*$")


def _sha256(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def _sha256_file(path: Path) -> str | None:
    h = hashlib.sha256()
    try:
        with open(path, "rb") as fh:
            for block in iter(lambda: fh.read(1 << 20), b""):
                h.update(block)
    except OSError:
        return None
    return h.hexdigest()


def _inside(path: Path, directory: Path) -> str | None:
    """`path` relative to `directory` (POSIX separators), or None if it is not inside."""
    full = Path(os.path.abspath(path))
    try:
        rel = full.relative_to(directory)
    except ValueError:
        return None
    if not rel.parts or rel.parts[0] == STATE_DIR:
        return None
    return rel.as_posix()


@contextmanager
def _lock(path: Path) -> Iterator[None]:
    """An exclusive lock on `path` (POSIX; elsewhere none)."""
    try:
        import fcntl
    except ImportError:  # pragma: no cover - not POSIX
        yield
        return
    with open(path, "a+b") as fh:
        fcntl.flock(fh.fileno(), fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(fh.fileno(), fcntl.LOCK_UN)


@contextmanager
def _interrupts_held() -> Iterator[None]:
    """A Ctrl-C (SIGINT) during the block is raised when the block has ended (main thread only;
    elsewhere Python delivers no KeyboardInterrupt anyway)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    caught: list[int] = []
    previous = signal.signal(signal.SIGINT, lambda signum, frame: caught.append(signum))
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, signal.default_int_handler if previous is None else previous)
    if caught:
        raise KeyboardInterrupt


class OutputSet:
    """The files of one command's run in one directory (see the module docstring); made by
    `output_set`."""

    def __init__(self, directory: Path, name: str, merge: bool) -> None:
        if not _SET_NAME.match(name):
            raise ValueError(f"output set name {name!r}: letters, digits, '_', '.', '+', '-'")
        self.directory = Path(os.path.abspath(directory))
        self.name = name
        self.merge = merge
        self.state = self.directory / STATE_DIR
        self.staging = self.state / "staging" / name
        self.manifest_path = self.state / f"{name}.json"
        self.journal_path = self.state / f"{name}.commit.json"
        self.staged: dict[str, dict[str, Any]] = {}

    def stage(self, path: Path, data: bytes) -> None:
        rel = _inside(path, self.directory)
        if rel is None:  # pragma: no cover - _set_for chose this set for the path
            raise ValueError(f"{path} is not in {self.directory}")
        target = self.staging / rel
        target.parent.mkdir(parents=True, exist_ok=True)
        replace_file(target, data)
        self.staged[rel] = {"sha256": _sha256(data), "bytes": len(data)}

    def commit(self) -> None:
        """Rename the staged files into place, remove the previous run's files that this run
        did not write (each only if it is unchanged), and write the manifest; journalled."""
        previous = read_manifest(self.directory, self.name)
        old = previous["files"] if previous else {}
        files = {**old, **self.staged} if self.merge else dict(self.staged)
        remove = (
            {}
            if self.merge
            else {rel: info["sha256"] for rel, info in old.items() if rel not in self.staged}
        )
        journal = {
            "set": self.name,
            "stage": sorted(self.staged),
            "remove": remove,
            "manifest": {
                "format": 1,
                "set": self.name,
                "written": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
                "files": files,
            },
        }
        with _interrupts_held():
            replace_file(self.journal_path, (json.dumps(journal, indent=1) + "\n").encode())
            _apply(self.directory, self.name, journal)


_ACTIVE: contextvars.ContextVar[tuple[OutputSet, ...]] = contextvars.ContextVar(
    "csfh_output_sets", default=()
)
"""The output sets open in this context, innermost last."""


def _apply(directory: Path, name: str, journal: dict[str, Any]) -> None:
    """Carry out a journalled commit; idempotent (a staged file already renamed is skipped), so
    an interrupted one is completed by running it again."""
    state = directory / STATE_DIR
    staging = state / "staging" / name
    for rel in journal["stage"]:
        source, target = staging / rel, directory / rel
        if source.exists():
            target.parent.mkdir(parents=True, exist_ok=True)
            os.replace(source, target)
    for rel, digest in journal["remove"].items():
        target = directory / rel
        if target.is_file() and _sha256_file(target) == digest:
            target.unlink()
    _fsync_directory(directory)
    manifest = json.dumps(journal["manifest"], indent=1) + "\n"
    replace_file(state / f"{name}.json", manifest.encode())
    (state / f"{name}.commit.json").unlink(missing_ok=True)
    shutil.rmtree(staging, ignore_errors=True)


def _settle(directory: Path, name: str) -> None:
    """Complete a commit of set `name` that a killed process left half done, and remove what an
    interrupted run staged (call with the set's lock held)."""
    state = directory / STATE_DIR
    journal_path = state / f"{name}.commit.json"
    if journal_path.exists():
        try:
            journal = json.loads(journal_path.read_text(encoding="utf-8"))
        except ValueError:  # a journal is written whole before it is used: never half
            journal = None
        if journal is not None:
            _apply(directory, name, journal)
    shutil.rmtree(state / "staging" / name, ignore_errors=True)


def _set_for(path: Path) -> OutputSet | None:
    """The innermost open output set whose directory holds `path`."""
    for active in reversed(_ACTIVE.get()):
        if _inside(path, active.directory) is not None:
            return active
    return None


@contextmanager
def output_set(directory: Path, name: str, *, merge: bool = False) -> Iterator[OutputSet]:
    """Write the files of one run of command `name` into `directory` as a whole (module
    docstring): every file the writers of this module write into `directory` inside the block
    is staged, and committed when the block ends without an error. `merge=True` keeps the
    previous run's other files in the set (``csfh plot`` redraws the figures of a comparison).
    Two commands on the same set wait for each other (a lock). A file system error is a
    ResultsError naming the file."""
    out = OutputSet(directory, name, merge)
    with file_errors(out.directory, "is not a usable output directory"):
        out.state.mkdir(parents=True, exist_ok=True)
    with file_errors(out.state / f"{name}.lock"), _lock(out.state / f"{name}.lock"):
        _settle(out.directory, name)
        token = _ACTIVE.set((*_ACTIVE.get(), out))
        try:
            yield out
            with file_errors(out.directory):
                out.commit()
        finally:
            _ACTIVE.reset(token)
            if not out.journal_path.exists():  # else a commit began: the next opener ends it
                shutil.rmtree(out.staging, ignore_errors=True)
            try:
                out.staging.parent.rmdir()  # when no other set is staging
            except OSError:
                pass


def read_manifest(directory: Path, name: str) -> dict[str, Any] | None:
    """The manifest of output set `name` in `directory`; None if there is none or it cannot be
    read (the set is then treated as one written before manifests existed: nothing of it is
    removed or checked)."""
    path = Path(directory) / STATE_DIR / f"{name}.json"
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    if not isinstance(data, dict) or not isinstance(data.get("files"), dict):
        return None
    files = data["files"]
    if not all(isinstance(v, dict) and isinstance(v.get("sha256"), str) for v in files.values()):
        return None
    return data


def check_set(directory: Path, name: str, files: list[str], command: str) -> None:
    """Check that `files` (relative to `directory`) are still the files the last run of set
    `name` wrote: ResultsError naming the first that is not (changed, or missing although the set
    lists it). A set written before manifests existed is not checked. A commit left half done by
    a killed process is completed first (if the directory is writable)."""
    directory = Path(os.path.abspath(directory))
    state = directory / STATE_DIR
    if (state / f"{name}.commit.json").exists():
        try:
            with _lock(state / f"{name}.lock"):
                _settle(directory, name)
        except OSError as exc:
            reason = exc.strerror or exc
            raise ResultsError(
                f"{directory}: an interrupted write of {command} cannot be completed ({reason})"
            ) from None
    manifest = read_manifest(directory, name)
    if manifest is None:
        return
    for rel in files:
        info = manifest["files"].get(rel)
        if info is None:
            continue
        if _sha256_file(directory / rel) != info.get("sha256"):
            raise ResultsError(
                f"{directory / rel}: not the file that {command} wrote with the others "
                f"(changed since, by another command or by hand): run {command} again"
            )


def write_bytes(path: Path, data: bytes) -> Path:
    """A binary file (e.g. an SSP archive), written whole or not at all."""
    return _write_bytes(path, data)


def write_text(path: Path, text: str) -> Path:
    """A text file (UTF-8)."""
    return _write_bytes(path, text.encode("utf-8"))


def write_json(path: Path, data: Any) -> Path:
    """A JSON file, indented, keys in the order given."""
    return write_text(path, json.dumps(data, indent=2, sort_keys=False) + "\n")


def write_table(
    path: Path, columns: Mapping[str, np.ndarray], units: Mapping[str, str] | None = None
) -> Path:
    """A CSV table of equally long columns, in the order given; the header names each column and
    its unit (`units`, "-" where it has none)."""
    names = list(columns)
    if not names:
        raise ValueError(f"{path}: a table needs at least one column")
    units = units or {}
    header = ",".join(f"{n} [{units.get(n, '-')}]" for n in names)
    data = np.column_stack([np.asarray(columns[n], dtype=float) for n in names])
    buffer = io.StringIO()
    np.savetxt(buffer, data, delimiter=",", header=header, comments="", fmt=f"%.{CSV_DIGITS}g")
    return write_text(path, buffer.getvalue())


def read_table(path: Path) -> tuple[dict[str, np.ndarray], dict[str, str]]:
    """The columns and units of a CSV table that `write_table` wrote. Raises ResultsError naming
    the file for anything else."""
    path = Path(path)
    try:
        with open(path, encoding="utf-8") as fh:
            header = fh.readline().rstrip("\r\n")
    except UnicodeDecodeError:
        raise ResultsError(f"{path}: not UTF-8 text, not a csfh table") from None
    except OSError as exc:
        raise ResultsError(f"{path}: cannot be read ({exc.strerror or exc})") from None
    if not header:
        raise ResultsError(f"{path}: empty file, not a csfh table")
    names: list[str] = []
    units: dict[str, str] = {}
    for field in header.split(","):
        m = _HEADER_FIELD.match(field)
        if m is None or not m.group("name"):
            raise ResultsError(f"{path}: header field {field!r} is not 'name [unit]'")
        name = m.group("name")
        if name in units:
            raise ResultsError(f"{path}: column {name!r} appears twice")
        names.append(name)
        units[name] = m.group("unit") if m.group("unit") is not None else "-"
    try:
        data = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    except ValueError as exc:
        raise ResultsError(f"{path}: not a table of numbers: {exc}") from None
    if data.size == 0:
        data = np.zeros((0, len(names)))
    if data.shape[1] != len(names):
        raise ResultsError(f"{path}: {data.shape[1]} values per row, {len(names)} columns named")
    return {n: data[:, i].copy() for i, n in enumerate(names)}, units


def save_figure(fig: Any, path: Path, **savefig: Any) -> Path:
    """A matplotlib figure, in the format of the file's suffix (default png)."""
    path = Path(path)
    buffer = io.BytesIO()
    fig.savefig(buffer, format=path.suffix.lstrip(".") or "png", **savefig)
    return _write_bytes(path, buffer.getvalue())
