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

A results folder is untrusted input (`csfh.safepath`): a manifest or journal is used only if it
is well-formed (`_check_manifest`, `_check_journal`) and every path in it names a file inside the
folder, reached without a symbolic link; a rename replaces only a regular file (or nothing), so
a device, a FIFO, a socket, a directory or a link where a result goes is refused, before any file
of the set is renamed. Each refusal is a `ResultsError` naming the file. Temporary files that a
killed process left behind are removed by the next command (`remove_stale_temporaries`).

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
from .safepath import (
    check_target,
    confined,
    is_regular,
    is_sha256,
    is_size,
    open_regular,
    own_directory,
    read_regular,
    relative_name,
    remove_stale_temporaries,
    shown,
    temporary_name,
)

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
    removed and `path` is as it was. `path` must be a regular file or not exist (anything else
    is refused: `csfh.safepath.check_target`)."""
    path = check_target(Path(path))
    tmp = temporary_name(path)
    try:
        tmp.unlink(missing_ok=True)  # a leftover or a planted link: removed, not written through
        with os.fdopen(open_regular(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL), "wb") as fh:
            fh.write(data)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    _fsync_directory(path.parent)
    return path


def _write_bytes(path: Path, data: bytes) -> Path:
    """The one way a file reaches the disk: staged in the open output set that holds `path`,
    else written whole by `replace_file`. A file system error is a ResultsError naming `path`."""
    path = Path(path)
    active = _set_for(path)
    with file_errors(path):
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
    """The SHA-256 of a regular file; None for anything else (a link, a FIFO, ...) or none."""
    h = hashlib.sha256()
    try:
        with os.fdopen(open_regular(path, os.O_RDONLY), "rb") as fh:
            for block in iter(lambda: fh.read(1 << 20), b""):
                h.update(block)
    except (OSError, ResultsError):
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
def locked(path: Path) -> Iterator[None]:
    """An exclusive lock on the file `path`, created if missing, never through a symbolic link
    (POSIX; elsewhere none)."""
    try:
        import fcntl
    except ImportError:  # pragma: no cover - not POSIX
        yield
        return
    fd = open_regular(path, os.O_RDWR | os.O_CREAT)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX)
        yield
    finally:
        os.close(fd)  # releases the lock


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
        own_directory(self.staging.parent)
        target = confined(own_directory(self.staging), rel, str(path))
        target.parent.mkdir(parents=True, exist_ok=True)
        replace_file(target, data)
        self.staged[rel] = {"sha256": _sha256(data), "bytes": len(data)}

    def commit(self) -> None:
        """Rename the staged files into place, remove the previous run's files that this run
        did not write (each only if it is unchanged), and write the manifest; journalled. Every
        target is checked before the first rename."""
        previous = read_manifest(self.directory, self.name)
        old = previous["files"] if previous else {}
        files = {**old, **self.staged} if self.merge else dict(self.staged)
        remove = (
            {}
            if self.merge
            else {rel: info["sha256"] for rel, info in old.items() if rel not in self.staged}
        )
        for rel in self.staged:  # refused before the journal: nothing of the set is renamed
            check_target(confined(self.directory, rel, str(self.directory / rel)))
        for rel in remove:
            confined(self.directory, rel, str(self.manifest_path))
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
            _apply(self.directory, self.name, journal, str(self.journal_path))


_ACTIVE: contextvars.ContextVar[tuple[OutputSet, ...]] = contextvars.ContextVar(
    "csfh_output_sets", default=()
)
"""The output sets open in this context, innermost last."""
_REFUSED = "refused (changed by hand or by another program; remove it to start the set afresh)"


def _read_json(path: Path) -> Any:
    """The JSON value of a state file (a regular file: csfh.safepath.read_regular)."""
    data = read_regular(path)
    try:
        return json.loads(data.decode("utf-8"))
    except (ValueError, RecursionError):  # UnicodeDecodeError is a ValueError
        raise ResultsError(f"{path}: not JSON: {_REFUSED}") from None


def _check_manifest(data: Any, name: str, where: str) -> dict[str, Any]:
    """`data` if it is a manifest of set `name` as `OutputSet.commit` writes it; else
    ResultsError naming `where`."""
    if not isinstance(data, dict) or data.get("format") != 1 or data.get("set") != name:
        raise ResultsError(f"{where}: not a manifest of output set {name!r}: {_REFUSED}")
    files = data.get("files")
    if not isinstance(files, dict):
        raise ResultsError(f"{where}: files = {shown(files)} is not a table: {_REFUSED}")
    for rel, info in files.items():
        relative_name(rel, f"{where}: files")
        if not (isinstance(info, dict) and is_sha256(info.get("sha256"))) or not is_size(
            info.get("bytes")
        ):
            raise ResultsError(
                f"{where}: files[{rel!r}] = {shown(info)} needs sha256 (64 hex digits) and "
                f"bytes (an integer >= 0): {_REFUSED}"
            )
    return data


def _check_journal(data: Any, name: str, where: str) -> dict[str, Any]:
    """`data` if it is a commit journal of set `name` as `OutputSet.commit` writes it; else
    ResultsError naming `where`."""
    if not isinstance(data, dict) or data.get("set") != name:
        raise ResultsError(f"{where}: not a commit journal of output set {name!r}: {_REFUSED}")
    stage, remove = data.get("stage"), data.get("remove")
    if not isinstance(stage, list) or not isinstance(remove, dict):
        raise ResultsError(f"{where}: stage or remove is not a list or a table: {_REFUSED}")
    for rel in stage:
        relative_name(rel, f"{where}: stage")
    for rel, digest in remove.items():
        relative_name(rel, f"{where}: remove")
        if not is_sha256(digest):
            raise ResultsError(f"{where}: remove[{rel!r}] = {shown(digest)}: {_REFUSED}")
    _check_manifest(data.get("manifest"), name, where)
    return data


def _apply(directory: Path, name: str, journal: dict[str, Any], where: str) -> None:
    """Carry out a checked commit journal (read from `where`); idempotent (a staged file already
    renamed is skipped), so an interrupted one is completed by running it again. Every path is
    confined to `directory` and every target checked before the first rename."""
    state = directory / STATE_DIR
    staging = own_directory(own_directory(state / "staging") / name)
    moves = [
        (confined(staging, rel, where), check_target(confined(directory, rel, where)))
        for rel in journal["stage"]
    ]
    removals = [(confined(directory, rel, where), d) for rel, d in journal["remove"].items()]
    for source, target in moves:
        if is_regular(source):
            target.parent.mkdir(parents=True, exist_ok=True)
            os.replace(source, target)
    for target, digest in removals:
        if is_regular(target) and _sha256_file(target) == digest:
            target.unlink()
    _fsync_directory(directory)
    manifest = json.dumps(journal["manifest"], indent=1) + "\n"
    replace_file(state / f"{name}.json", manifest.encode())
    (state / f"{name}.commit.json").unlink(missing_ok=True)
    shutil.rmtree(staging, ignore_errors=True)


def _settle(directory: Path, name: str) -> None:
    """Complete a commit of set `name` that a killed process left half done, and remove what an
    interrupted run staged and the temporary files of killed processes (call with the set's
    lock held). A journal that is not one `OutputSet.commit` wrote is refused."""
    state = own_directory(directory / STATE_DIR)
    journal_path = state / f"{name}.commit.json"
    if os.path.lexists(journal_path):
        where = str(journal_path)
        _apply(directory, name, _check_journal(_read_json(journal_path), name, where), where)
    shutil.rmtree(state / "staging" / name, ignore_errors=True)
    remove_stale_temporaries(state)


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
        out.directory.mkdir(parents=True, exist_ok=True)
        lock = own_directory(out.state) / f"{name}.lock"
    with file_errors(lock), locked(lock):
        _settle(out.directory, name)
        token = _ACTIVE.set((*_ACTIVE.get(), out))
        try:
            yield out
            with file_errors(out.directory):
                out.commit()
        finally:
            _ACTIVE.reset(token)
            if not os.path.lexists(out.journal_path):  # else the next opener ends the commit
                shutil.rmtree(out.staging, ignore_errors=True)
            try:
                out.staging.parent.rmdir()  # when no other set is staging
            except OSError:
                pass


def read_manifest(directory: Path, name: str) -> dict[str, Any] | None:
    """The manifest of output set `name` in `directory`; None if there is none (the set is then
    treated as one written before manifests existed: nothing of it is removed or checked). One
    that is not what `OutputSet.commit` writes is refused (ResultsError naming it)."""
    path = own_directory(Path(directory) / STATE_DIR, create=False) / f"{name}.json"
    if not os.path.lexists(path):
        return None
    return _check_manifest(_read_json(path), name, str(path))


def check_set(directory: Path, name: str, files: list[str], command: str) -> None:
    """Check that `files` (relative to `directory`) are still the files the last run of set
    `name` wrote: ResultsError naming the first that is not (changed, or missing although the set
    lists it). A set written before manifests existed is not checked. A commit left half done by
    a killed process is completed first (if the directory is writable)."""
    directory = Path(os.path.abspath(directory))
    state = own_directory(directory / STATE_DIR, create=False)
    if os.path.lexists(state / f"{name}.commit.json"):
        try:
            with locked(state / f"{name}.lock"):
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
