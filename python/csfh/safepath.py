"""Paths in a results folder, which csfh treats as untrusted: a path read from one of its files
(a manifest, a commit journal, the result store's index) is used only if it names a file inside
the folder, reached without a symbolic link, and a file is replaced only if it is a regular file
(or missing). Anything else is refused with `ResultsError`, one line naming the file.

The folder itself (``--out``) is the user's choice and may be reached through symbolic links;
what lies below it is checked component by component (`confined`), and the directories that csfh
keeps its own files in (``.csfh``, ``signals``, ``claims``) must be real directories
(`own_directory`)."""

from __future__ import annotations

import errno
import os
import re
import stat
import threading
from pathlib import Path

from .errors import ResultsError

_NAME = re.compile(r"^[A-Za-z0-9_+=@,-][A-Za-z0-9_.+=@,-]{0,254}$")
"""A file or directory name csfh writes: no path separator, not hidden (so never '.' or '..')."""
_SHA256 = re.compile(r"^[0-9a-f]{64}$")
_TEMPORARY = re.compile(r"^\.(?P<name>.+)\.(?P<pid>[0-9]{1,10})\.[0-9]{1,20}\.tmp$")
"""The name of a temporary file (`temporary_name`): .NAME.PID.THREAD.tmp."""
_KINDS = (
    (stat.S_ISDIR, "a directory"),
    (stat.S_ISLNK, "a symbolic link"),
    (stat.S_ISFIFO, "a FIFO (named pipe)"),
    (stat.S_ISSOCK, "a socket"),
    (stat.S_ISCHR, "a character device"),
    (stat.S_ISBLK, "a block device"),
)


def shown(value: object) -> str:
    """`value` for a one-line message: its repr, at most 80 characters."""
    text = repr(value)
    return text if len(text) <= 80 else text[:77] + "..."


def is_sha256(value: object) -> bool:
    """A SHA-256 as csfh writes it: 64 lower-case hexadecimal digits."""
    return isinstance(value, str) and _SHA256.match(value) is not None


def is_size(value: object) -> bool:
    """A size in bytes or a count: an integer >= 0 (not a bool)."""
    return isinstance(value, int) and not isinstance(value, bool) and value >= 0


def relative_name(value: object, where: str) -> str:
    """`value` if it is a relative path ('/'-separated) of names csfh writes (letters, digits,
    '_', '.', '+', '=', '@', ',', '-'; no '..', no hidden names, no absolute path); else
    ResultsError naming `where`."""
    parts = value.split("/") if isinstance(value, str) else []
    if not parts or len(parts) > 16 or not all(_NAME.match(p) for p in parts):
        raise ResultsError(
            f"{where} = {shown(value)} is not a file inside the folder (a relative path of "
            "letters, digits and _ . + = @ , - without '..'): refused"
        )
    return str(value)


def kind(mode: int) -> str | None:
    """What a file of `mode` (st_mode) is, unless it is a regular file (None)."""
    for test, name in _KINDS:
        if test(mode):
            return name
    return None if stat.S_ISREG(mode) else "not a regular file"


def _lstat(path: Path) -> os.stat_result | None:
    try:
        return os.lstat(path)
    except (FileNotFoundError, NotADirectoryError):
        return None


def is_regular(path: Path) -> bool:
    """Whether `path` itself (not what a symbolic link points to) is a regular file."""
    st = _lstat(path)
    return st is not None and stat.S_ISREG(st.st_mode)


def check_target(path: Path) -> Path:
    """`path` if a rename may replace it: a regular file, or nothing there. Anything else (a
    device such as /dev/null, a FIFO, a socket, a directory, a symbolic link) is refused."""
    st = _lstat(Path(path))
    if st is not None and not stat.S_ISREG(st.st_mode):
        raise ResultsError(
            f"{path}: {kind(st.st_mode)}, not a regular file: refused (csfh replaces only "
            "regular files; choose another path)"
        )
    return Path(path)


def confined(directory: Path, rel: str, where: str) -> Path:
    """DIRECTORY/REL for a `rel` read from a file named by `where`: the name checked
    (`relative_name`), every component below `directory` but the last a real directory (or not
    there yet), so that the file's directory resolves inside `directory`. Else ResultsError."""
    relative_name(rel, where)
    path = Path(directory)
    for part in rel.split("/")[:-1]:
        path = path / part
        st = _lstat(path)
        if st is not None and not stat.S_ISDIR(st.st_mode):
            raise ResultsError(
                f"{where}: {rel!r} leads through {path}, {kind(st.st_mode)}: refused (csfh "
                "follows no symbolic link inside a results folder)"
            )
    base = os.path.realpath(directory)
    if os.path.commonpath([base, os.path.realpath(path)]) != base:
        raise ResultsError(f"{where}: {rel!r} leads out of {directory}: refused")
    return path / rel.split("/")[-1]  # what it is, the caller checks (check_target, is_regular)


def own_directory(path: Path, create: bool = True) -> Path:
    """A directory csfh keeps its own files in, inside a results folder (created if missing and
    `create`): refused if it is a symbolic link or anything but a directory."""
    path = Path(path)
    st = _lstat(path)
    if st is None and not create:
        return path
    if st is None:
        path.mkdir(exist_ok=True)
        st = os.lstat(path)
    if not stat.S_ISDIR(st.st_mode):
        raise ResultsError(
            f"{path}: {kind(st.st_mode)}, not a directory: refused (csfh keeps its own files "
            "only in a real directory of the results folder)"
        )
    return path


def check_output_directory(path: Path) -> Path:
    """An output directory (``--out``) that can be created or written, checked before a command
    computes anything (its files are written only at the end): `path` is a directory or missing,
    and the nearest existing directory above it (or itself) can be written. ResultsError naming
    `path` and the system's reason otherwise (the words `csfh.output.output_set` uses)."""
    path = Path(path)
    existing = path
    while not os.path.lexists(existing) and existing != existing.parent:
        existing = existing.parent
    reason = None
    if not os.path.isdir(existing):
        reason = os.strerror(errno.ENOTDIR)
    elif not os.access(existing, os.W_OK | os.X_OK):
        read_only = os.statvfs(existing).f_flag & os.ST_RDONLY
        reason = os.strerror(errno.EROFS if read_only else errno.EACCES)
    if reason is not None:
        raise ResultsError(f"{path}: is not a usable output directory ({reason})")
    return path


def open_regular(path: Path, flags: int, mode: int = 0o666) -> int:
    """os.open of a regular file, never through a symbolic link (the last component: O_NOFOLLOW)
    and never blocking on a FIFO; anything but a regular file is refused (ResultsError)."""
    path = Path(path)
    nofollow = getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_NONBLOCK", 0)
    try:
        fd = os.open(path, flags | nofollow | getattr(os, "O_CLOEXEC", 0), mode)
    except OSError:
        st = _lstat(path)
        if st is not None and not stat.S_ISREG(st.st_mode):
            raise ResultsError(f"{path}: {kind(st.st_mode)}, not a regular file: refused") from None
        raise
    st = os.fstat(fd)
    if not stat.S_ISREG(st.st_mode):
        os.close(fd)
        raise ResultsError(f"{path}: {kind(st.st_mode)}, not a regular file: refused")
    if nofollow & getattr(os, "O_NONBLOCK", 0):
        os.set_blocking(fd, True)
    return fd


def read_regular(path: Path) -> bytes:
    """The contents of a regular file (see `open_regular`)."""
    fd = open_regular(path, os.O_RDONLY)
    with os.fdopen(fd, "rb") as fh:
        return fh.read()


# ------------------------------------------------------------------------------------------
# temporary files of csfh.output.replace_file


def temporary_name(path: Path) -> Path:
    """The temporary file that `csfh.output.replace_file` writes `path` into: beside it, hidden,
    named after the process and thread (so that a later run can tell whether its writer ended)."""
    path = Path(path)
    return path.with_name(f".{path.name}.{os.getpid()}.{threading.get_ident()}.tmp")


def _alive(pid: int) -> bool:
    """Whether a process of id `pid` runs (on this machine)."""
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (PermissionError, OverflowError, ValueError):
        return pid > 0
    return True


def remove_stale_temporaries(directory: Path, names: set[str] | None = None) -> list[Path]:
    """Remove the temporary files of `replace_file` (for the files `names`, else all) in
    `directory` whose process has ended: a process killed while it wrote one leaves it behind.
    The removed ones, in order."""
    removed: list[Path] = []
    try:
        entries = sorted(os.listdir(directory))
    except OSError:
        return removed
    for entry in entries:
        m = _TEMPORARY.match(entry)
        if m is None or (names is not None and m["name"] not in names):
            continue
        path = Path(directory) / entry
        if is_regular(path) and not _alive(int(m["pid"])):
            path.unlink(missing_ok=True)
            removed.append(path)
    return removed
